//! Photons for the far part of an infinite plane under an environment light.
//!
//! An environment light's photons start on a disk as wide as the bounding sphere of the finite
//! shapes ([`super::EnvironmentLight::sample_photon`]), so they reach an infinite plane only
//! where the plane lies under that disk. The sky lights the rest of the plane too, and that
//! light bounces onto the objects (a sphere on a grey ground under a uniform sky lost about a
//! third of its light around its middle). A [`GroundPhotons`] emitter covers exactly the rest:
//! a point `p` of the plane and a sky direction `w` whose ray `p + t w` (`t > 0`) does not pass
//! through the environment light's disk, the photon arriving at `p` along `-w`. Pairs the disk
//! covers get no weight here, so the two strategies together count every pair once.
//!
//! Points are drawn with the area density `a / (2 pi (rho^2 + a^2)^(3/2))` around the foot of
//! the bounding sphere's centre (`rho` the distance from it, `a` the larger of the sphere's
//! radius and its centre's height), which falls off as fast as the light a far point sends to
//! the objects (their solid angle times the cosine at the plane, `~ 1 / rho^3`). The bounce
//! leaving `p` goes toward the bounding sphere, uniformly over the cone it subtends, so a far
//! point's photon goes where it can matter and its power stays bounded. Not covered: what the
//! far part of a plane sends to anything outside that sphere (the far part of another infinite
//! plane), and specular planes (a mirror ground reflects into one direction).

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use crate::geometry::Frame;
use crate::sampling::{uniform_cone, uniform_cone_pdf};

/// One infinite plane's far-part emitter (see the module docs).
#[derive(Debug, Clone)]
pub struct GroundPhotons {
    /// Index of the environment light in the scene's lights.
    pub env: usize,
    /// The plane's primitive id (a photon's point must lie on it).
    pub prim: u32,
    /// Unit normal toward the side of the bounding sphere's centre.
    pub normal: Vec3A,
    /// The foot of the bounding sphere's centre on the plane.
    pub origin: Vec3A,
    frame: Frame,
    /// Scale `a` of the point density.
    pub scale: f32,
    /// The environment light's bounding sphere.
    pub center: Vec3A,
    pub radius: f32,
}

impl GroundPhotons {
    /// `normal` (unit) and `point` (on the plane) in world space; `None` where they are not
    /// usable numbers.
    pub fn new(
        env: usize,
        prim: u32,
        normal: Vec3A,
        point: Vec3A,
        center: Vec3A,
        radius: f32,
    ) -> Option<Self> {
        let height = (center - point).dot(normal);
        let normal = if height < 0.0 { -normal } else { normal };
        let origin = center - normal * height.abs();
        let scale = radius.max(height.abs());
        let ok = normal.is_finite()
            && (normal.length() - 1.0).abs() < 1e-3
            && origin.is_finite()
            && scale.is_finite()
            && scale > 0.0;
        ok.then(|| Self {
            env,
            prim,
            normal,
            origin,
            frame: Frame::from_normal(normal),
            scale,
            center,
            radius,
        })
    }

    /// A point of the plane and its area density.
    pub fn sample_point(&self, u: Vec2) -> (Vec3A, f32) {
        let a = self.scale;
        // Inverse of the radial distribution `1 - a / sqrt(rho^2 + a^2)`.
        let k = 1.0 / (1.0 - u.x.min(0.999_999));
        let rho = a * (k * k - 1.0).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let p = self.origin
            + self
                .frame
                .to_world(Vec3A::new(rho * phi.cos(), rho * phi.sin(), 0.0));
        (p, self.density(rho))
    }

    fn density(&self, rho: f32) -> f32 {
        let a = self.scale;
        a / (2.0 * PI * (rho * rho + a * a).powf(1.5))
    }

    /// Whether the environment light's disk sends photons along `-w` to `p`: the ray
    /// `p + t w` (`t > 0`) passes through the disk of radius `radius` perpendicular to `w`
    /// at `center + w radius`.
    pub fn covered_by_disk(&self, p: Vec3A, w: Vec3A) -> bool {
        let c = self.center - p;
        let along = c.dot(w);
        let perp2 = (c.length_squared() - along * along).max(0.0);
        along + self.radius > 0.0 && perp2 < self.radius * self.radius
    }

    /// A direction from `p` toward the bounding sphere and its solid-angle density (`None`
    /// from inside it).
    pub fn sample_toward_objects(&self, p: Vec3A, u: Vec2) -> Option<(Vec3A, f32)> {
        let (axis, cos_max) = self.cone(p)?;
        let d = Frame::from_normal(axis).to_world(uniform_cone(u, cos_max));
        Some((d, uniform_cone_pdf(cos_max)))
    }

    /// The density [`GroundPhotons::sample_toward_objects`] gives direction `d` from `p`.
    pub fn pdf_toward_objects(&self, p: Vec3A, d: Vec3A) -> f32 {
        match self.cone(p) {
            Some((axis, cos_max)) if d.dot(axis) >= cos_max => uniform_cone_pdf(cos_max),
            _ => 0.0,
        }
    }

    /// The cone from `p` around the bounding sphere: axis and cosine of its half-angle.
    fn cone(&self, p: Vec3A) -> Option<(Vec3A, f32)> {
        let to = self.center - p;
        let d2 = to.length_squared();
        let r2 = self.radius * self.radius;
        // From inside the sphere (or NaN) there is no cone.
        if d2.partial_cmp(&(r2 * 1.0001)) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let cos_max = ((d2 - r2) / d2).max(0.0).sqrt();
        (cos_max < 1.0).then(|| (to / d2.sqrt(), cos_max))
    }

    /// This emitter's weight among the lights, as a share of the environment light's photon
    /// power (any positive weight keeps the estimate unbiased): about the power the far plane
    /// sends toward the bounding sphere for a ground of albedo 1/2, `2 pi albedo E radius^2`
    /// with the sky's irradiance `E` a quarter of `∫ L dw`, against the environment's
    /// `pi radius^2 ∫ L dw`.
    pub const SHARE: f64 = 0.25;
}
