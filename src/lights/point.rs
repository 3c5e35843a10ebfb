//! Isotropic point light.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::{LightSample, PhotonSample};
use crate::sampling::uniform_sphere;

pub struct PointLight {
    pub position: Vec3A,
    /// Radiant intensity (W/sr).
    pub intensity: Vec3A,
}

impl PointLight {
    pub fn power(&self) -> Vec3A {
        self.intensity * (4.0 * PI)
    }

    pub fn sample_li(&self, p: Vec3A) -> Option<LightSample> {
        let d = self.position - p;
        let d2 = d.length_squared();
        if d2 == 0.0 {
            return None;
        }
        Some(LightSample {
            wi: d / d2.sqrt(),
            li: self.intensity / d2,
            pdf: 1.0,
            p: self.position,
            n: Vec3A::ZERO,
            delta: true,
        })
    }

    pub fn sample_photon(&self, u: Vec2) -> Option<PhotonSample> {
        Some(PhotonSample {
            p: self.position,
            n: Vec3A::ZERO,
            dir: uniform_sphere(u),
            beta: self.intensity * (4.0 * PI),
        })
    }
}
