//! Perfect specular reflection scaled by a tint.

use glam::Vec3A;

use super::BsdfSample;

pub fn sample(tint: Vec3A, wo: Vec3A) -> Option<BsdfSample> {
    Some(BsdfSample {
        wi: Vec3A::new(-wo.x, -wo.y, wo.z),
        weight: tint,
        pdf: 1.0,
        specular: true,
    })
}
