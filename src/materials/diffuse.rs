//! Lambertian reflection (two-sided).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3A};

use super::BsdfSample;
use crate::sampling::cosine_hemisphere;

pub fn f(albedo: Vec3A) -> Vec3A {
    albedo * FRAC_1_PI
}

pub fn pdf(wi: Vec3A) -> f32 {
    pdf_cos(wi.z)
}

/// [`pdf`] of a direction whose local cosine is `cos`.
#[inline]
pub fn pdf_cos(cos: f32) -> f32 {
    cos.abs() * FRAC_1_PI
}

#[inline]
pub fn sample(albedo: Vec3A, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
    let mut wi = cosine_hemisphere(u);
    if wo.z < 0.0 {
        wi.z = -wi.z;
    }
    let pdf = pdf(wi);
    (pdf > 0.0).then_some(BsdfSample {
        wi,
        weight: albedo,
        pdf,
        specular: false,
    })
}
