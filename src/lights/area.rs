//! Diffuse area light on one shape: uniform radiance on the side the normal faces, or on both.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::{LightSample, PhotonSample};
use crate::geometry::Frame;
use crate::sampling::cosine_hemisphere;
use crate::shapes::Shape;
use crate::shapes::primitive::AnyShape;

pub struct AreaLight {
    pub shape: AnyShape,
    pub radiance: Vec3A,
    pub two_sided: bool,
    pub area: f32,
}

impl AreaLight {
    /// Radiance leaving the light at a point with normal `n` toward `w`.
    #[inline]
    pub fn le(&self, n: Vec3A, w: Vec3A) -> Vec3A {
        if self.two_sided || n.dot(w) > 0.0 {
            self.radiance
        } else {
            Vec3A::ZERO
        }
    }

    pub fn power(&self) -> Vec3A {
        self.radiance * (PI * self.area * if self.two_sided { 2.0 } else { 1.0 })
    }

    /// Solid-angle density of `sample_li` from `p` choosing the light point `pl` (normal `nl`).
    pub fn pdf_li(&self, p: Vec3A, pl: Vec3A, nl: Vec3A) -> f32 {
        let d = pl - p;
        let d2 = d.length_squared();
        let cos = nl.dot(d).abs() / d2.sqrt();
        if cos == 0.0 {
            return 0.0;
        }
        d2 / (cos * self.area)
    }

    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let s = self.shape.sample(u)?;
        let d = s.p - p;
        let d2 = d.length_squared();
        if d2 == 0.0 {
            return None;
        }
        let wi = d / d2.sqrt();
        let li = self.le(s.n, -wi);
        let cos = s.n.dot(wi).abs();
        if cos == 0.0 || li == Vec3A::ZERO {
            return None;
        }
        Some(LightSample {
            wi,
            li,
            pdf: d2 / (cos * self.area),
            p: s.p,
            n: s.n,
            delta: false,
        })
    }

    pub fn sample_photon(&self, u1: Vec2, u2: Vec2) -> Option<PhotonSample> {
        let s = self.shape.sample(u1)?;
        let (mut n, mut u2) = (s.n, u2);
        let mut side = 1.0;
        if self.two_sided {
            // Reuse u2.x for the side choice.
            if u2.x < 0.5 {
                u2.x *= 2.0;
            } else {
                u2.x = (u2.x - 0.5) * 2.0;
                n = -n;
            }
            side = 2.0;
        }
        let l = cosine_hemisphere(u2);
        if l.z <= 0.0 {
            return None;
        }
        // beta = Le cos / (pdf_area * pdf_dir / side), pdf_dir = cos / pi.
        Some(PhotonSample {
            p: s.p,
            n,
            dir: Frame::from_normal(n).to_world(l),
            beta: self.radiance * (PI * side / s.pdf),
        })
    }
}
