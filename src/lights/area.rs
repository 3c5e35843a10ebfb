//! Diffuse area light on one shape: uniform radiance on the side the normal faces, or on both.
//! Direct lighting samples spheres and rectangles by the solid angle they subtend (their
//! shapes' `sample_toward`), other shapes by area; photons leave uniformly by area.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::{LightSample, PhotonSample};
use crate::geometry::Frame;
use crate::sampling::cosine_hemisphere;
use crate::shapes::primitive::AnyShape;
use crate::shapes::{Shape, area_pdf_to_solid_angle, area_to_solid_angle};

/// How direct lighting picks points on an area light.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LightSampling {
    /// Spheres and rectangles by the solid angle they subtend, other shapes by area (the
    /// renderer's choice for every light).
    #[default]
    SolidAngle,
    /// Every shape uniformly by area (kept for measurements against the solid-angle samplers).
    Area,
}

pub struct AreaLight {
    pub shape: AnyShape,
    pub radiance: Vec3A,
    pub two_sided: bool,
    pub area: f32,
    pub sampling: LightSampling,
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

    /// Solid-angle density of `sample_li` from `p` choosing the light point `pl` (normal `nl`),
    /// for weighing a BSDF sample that hit the light (MIS): the same density the light sampler
    /// used, per solid angle.
    pub fn pdf_li(&self, p: Vec3A, pl: Vec3A, nl: Vec3A) -> f32 {
        self.pdf_li_from(p, pl, nl, false)
    }

    /// [`AreaLight::pdf_li`] for a receiver that may be a point of this light's own surface
    /// (`on_light`), where a sphere is sampled by area ([`AreaLight::sample_li_from`]).
    pub fn pdf_li_from(&self, p: Vec3A, pl: Vec3A, nl: Vec3A, on_light: bool) -> f32 {
        match (&self.shape, self.sampling) {
            (AnyShape::Sphere(_), _) if on_light => area_pdf_to_solid_angle(p, pl, nl, self.area),
            (AnyShape::Sphere(s), LightSampling::SolidAngle) => s.pdf_toward(p, pl, nl),
            (AnyShape::Quad(q), LightSampling::SolidAngle) => q.pdf_toward(p, pl, nl),
            _ => area_pdf_to_solid_angle(p, pl, nl, self.area),
        }
    }

    /// A point of the light for direct lighting at `p`: spheres by the cone of directions they
    /// subtend (by area from inside), rectangles by the spherical rectangle they subtend, other
    /// shapes uniformly by area. The density is per solid angle.
    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        self.sample_li_from(p, u, false)
    }

    /// [`AreaLight::sample_li`] for a receiver that may be a point of this light's own surface
    /// (`on_light`). Such a point is inside or outside a sphere by rounding alone: from just
    /// outside, the cone toward the sphere is nearly a hemisphere whose every sample lands next
    /// to the point, where no shadow ray is blocked, so light that an object inside the sphere
    /// hides would be counted. From its own surface a sphere is sampled by area (exact: from the
    /// inner side every point is in view, from the outer side none is above the horizon).
    pub fn sample_li_from(&self, p: Vec3A, u: Vec2, on_light: bool) -> Option<LightSample> {
        // Behind a one-sided rectangle nothing arrives: skip the sampling.
        if let AnyShape::Quad(q) = &self.shape
            && !self.two_sided
            && q.height_above(p) <= 0.0
        {
            return None;
        }
        let s = match (&self.shape, self.sampling) {
            (AnyShape::Sphere(s), LightSampling::SolidAngle) if !on_light => s.sample_toward(p, u),
            (AnyShape::Quad(q), LightSampling::SolidAngle) => q.sample_toward(p, u),
            (shape, _) => {
                let s = shape.sample(u)?;
                area_to_solid_angle(p, s.p, s.n, self.area)
            }
        }?;
        let li = self.le(s.n, -s.wi);
        if li == Vec3A::ZERO {
            return None;
        }
        Some(LightSample {
            wi: s.wi,
            li,
            pdf: s.pdf,
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
