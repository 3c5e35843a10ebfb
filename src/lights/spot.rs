//! Spot light: intensity inside a cone, smooth falloff between the falloff and cone angles.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::{LightSample, PhotonSample};
use crate::geometry::Frame;
use crate::sampling::{uniform_cone, uniform_cone_pdf};

pub struct SpotLight {
    pub position: Vec3A,
    pub frame: Frame,
    pub intensity: Vec3A,
    pub cos_total: f32,
    pub cos_falloff: f32,
}

fn smoothstep(x: f32, a: f32, b: f32) -> f32 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl SpotLight {
    /// Angles in degrees; the falloff angle is clamped into the cone.
    pub fn new(
        position: Vec3A,
        direction: Vec3A,
        intensity: Vec3A,
        cone: f32,
        falloff: f32,
    ) -> Self {
        let cone = cone.clamp(0.0, 180.0);
        let falloff = falloff.clamp(0.0, cone);
        Self {
            position,
            frame: Frame::from_normal(direction.normalize_or(Vec3A::NEG_Y)),
            intensity,
            cos_total: cone.to_radians().cos(),
            cos_falloff: falloff.to_radians().cos(),
        }
    }

    fn falloff(&self, cos: f32) -> f32 {
        smoothstep(cos, self.cos_total, self.cos_falloff)
    }

    pub fn power(&self) -> Vec3A {
        self.intensity * (2.0 * PI * (1.0 - 0.5 * (self.cos_falloff + self.cos_total)))
    }

    pub fn sample_li(&self, p: Vec3A) -> Option<LightSample> {
        let d = self.position - p;
        let d2 = d.length_squared();
        if d2 == 0.0 {
            return None;
        }
        let wi = d / d2.sqrt();
        let f = self.falloff((-wi).dot(self.frame.n));
        (f > 0.0).then_some(LightSample {
            wi,
            li: self.intensity * f / d2,
            pdf: 1.0,
            p: self.position,
            n: Vec3A::ZERO,
            delta: true,
        })
    }

    pub fn sample_photon(&self, u: Vec2) -> Option<PhotonSample> {
        let l = uniform_cone(u, self.cos_total);
        let f = self.falloff(l.z);
        (f > 0.0).then(|| PhotonSample {
            p: self.position,
            n: Vec3A::ZERO,
            dir: self.frame.to_world(l),
            beta: self.intensity * f / uniform_cone_pdf(self.cos_total),
        })
    }
}
