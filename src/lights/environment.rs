//! Environment light: radiance at infinity around the scene, either an equirectangular map
//! (pbrt's `ImageInfiniteLight`, sampled by importance with `EnvironmentMap::sample`) or a
//! constant background colour (pbrt's `UniformInfiniteLight`, sampled uniformly over the
//! sphere). Photons start on a disk of the scene's bounding-sphere radius, perpendicular to the
//! sampled direction and outside the scene, and travel inward.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::{LightSample, PhotonSample};
use crate::geometry::Frame;
use crate::sampling::{concentric_disk, uniform_sphere};
use crate::textures::{EnvSample, EnvironmentMap};

/// What the environment light shows in each direction.
pub enum Sky {
    /// An image around the scene.
    Map(Box<EnvironmentMap>),
    /// The same radiance from every direction: a non-black background colour.
    Uniform(Vec3A),
}

impl Sky {
    #[inline]
    fn radiance(&self, dir: Vec3A) -> Vec3A {
        match self {
            Sky::Map(m) => m.radiance(dir),
            Sky::Uniform(c) => *c,
        }
    }

    #[inline]
    fn pdf(&self, dir: Vec3A) -> f32 {
        match self {
            Sky::Map(m) => m.pdf(dir),
            Sky::Uniform(_) => 1.0 / (4.0 * PI),
        }
    }

    fn sample(&self, u: Vec2) -> Option<EnvSample> {
        match self {
            Sky::Map(m) => m.sample(u),
            Sky::Uniform(c) => Some(EnvSample {
                direction: uniform_sphere(u),
                radiance: *c,
                pdf: 1.0 / (4.0 * PI),
            }),
        }
    }

    fn integrated_radiance(&self) -> Vec3A {
        match self {
            Sky::Map(m) => m.integrated_radiance(),
            Sky::Uniform(c) => *c * (4.0 * PI),
        }
    }
}

pub struct EnvironmentLight {
    pub sky: Sky,
    /// Bounding sphere of the scene's finite shapes.
    pub center: Vec3A,
    pub radius: f32,
}

impl EnvironmentLight {
    /// `radius` is clamped to a small positive value so an empty scene still works.
    pub fn new(sky: Sky, center: Vec3A, radius: f32) -> Self {
        let radius = if radius.is_finite() && radius > 0.0 {
            radius
        } else {
            1.0
        };
        let center = if center.is_finite() {
            center
        } else {
            Vec3A::ZERO
        };
        Self {
            sky,
            center,
            radius,
        }
    }

    /// Radiance arriving along a ray that leaves the scene in direction `dir`.
    #[inline]
    pub fn le(&self, dir: Vec3A) -> Vec3A {
        self.sky.radiance(dir)
    }

    /// Power sent into the scene: π r² ∫ L dω.
    pub fn power(&self) -> Vec3A {
        self.sky.integrated_radiance() * (PI * self.radius * self.radius)
    }

    /// Solid-angle density of `sample_li` choosing direction `wi`.
    #[inline]
    pub fn pdf_li(&self, wi: Vec3A) -> f32 {
        self.sky.pdf(wi)
    }

    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        let s = self.sky.sample(u)?;
        if s.pdf.is_nan() || s.pdf <= 0.0 || s.radiance == Vec3A::ZERO {
            return None;
        }
        // A point surely outside the scene along the direction: shadow rays stop there.
        let far = 2.0 * self.radius + (p - self.center).length();
        Some(LightSample {
            wi: s.direction,
            li: s.radiance,
            pdf: s.pdf,
            p: p + s.direction * far,
            n: -s.direction,
            delta: false,
        })
    }

    /// The densities of [`EnvironmentLight::sample_photon`] choosing a photon that travels in
    /// unit direction `dir` through the point `p`: per area of the disk it starts on and per
    /// solid angle (as pbrt-v4's `PDF_Le`). The area density is zero where no photon along
    /// `dir` passes `p` (beside the disk's cylinder, or before the disk): every point within
    /// the bounding sphere is covered, the far part of an infinite plane is not.
    pub fn emission_pdf(&self, p: Vec3A, dir: Vec3A) -> (f32, f32) {
        let w = -dir;
        let d = p - self.center;
        let along = d.dot(w);
        let across2 = (d - w * along).length_squared();
        // The disk's own points lie on the boundary: a rounding's slack keeps them in.
        let r = self.radius * (1.0 + 1e-4);
        let covered = along <= r && across2 <= r * r;
        let pdf_pos = if covered {
            1.0 / (PI * self.radius * self.radius)
        } else {
            0.0
        };
        (pdf_pos, self.sky.pdf(w))
    }

    pub fn sample_photon(&self, u1: Vec2, u2: Vec2) -> Option<PhotonSample> {
        let s = self.sky.sample(u1)?;
        if s.pdf.is_nan() || s.pdf <= 0.0 {
            return None;
        }
        let w = s.direction;
        let frame = Frame::from_normal(w);
        let d = concentric_disk(u2) * self.radius;
        let p = self.center + w * self.radius + frame.to_world(Vec3A::new(d.x, d.y, 0.0));
        let pdf_pos = 1.0 / (PI * self.radius * self.radius);
        Some(PhotonSample {
            p,
            n: Vec3A::ZERO,
            dir: -w,
            beta: s.radiance / (s.pdf * pdf_pos),
        })
    }
}
