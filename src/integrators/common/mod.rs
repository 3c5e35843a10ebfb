//! Code more than one integrator uses: the eye path to the first non-specular surface, direct
//! lighting, photon emission and tracing, absorption inside dielectrics, the progressive
//! iteration loop and the random streams.

pub(crate) mod camera_path;
pub(crate) mod direct;
pub(crate) mod photons;
pub(crate) mod progressive;
pub(crate) mod streams;

use glam::Vec3A;

use crate::geometry::Ray;
use crate::prepare::{PreparedScene, SurfaceHit};

/// Beer–Lambert absorption along a segment that ran inside an absorbing dielectric (the ray
/// hits the surface from its inner side).
#[inline]
pub(crate) fn attenuate_inside(
    scene: &PreparedScene,
    sh: &SurfaceHit,
    ray: &Ray,
    beta: &mut Vec3A,
) {
    if ray.d.dot(sh.hit.n) > 0.0
        && let Some(sigma) = scene.absorption(sh)
    {
        let dist = sh.hit.t * ray.d.length();
        *beta *= (-sigma * dist).exp();
    }
}
