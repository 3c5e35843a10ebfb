//! Sphere.

use std::f32::consts::PI;

use glam::{Mat3A, Vec2, Vec3A};

use super::{
    AreaSample, SolidAngleSample, SplitShape, area_pdf_to_solid_angle, area_to_solid_angle,
};
use crate::geometry::{Aabb, Frame, Hit, Ray};
use crate::sampling::uniform_sphere;

#[derive(Debug, Clone, Copy)]
pub struct Sphere {
    pub center: Vec3A,
    pub radius: f32,
    /// World to the object's own frame (a rotation, or a rotation and a mirror): the `uv` of a
    /// sphere baked from a rotated object are counted in the object's frame, so they turn with
    /// it. Identity for a sphere made in world space.
    to_object: Mat3A,
}

impl Sphere {
    pub fn new(center: Vec3A, radius: f32) -> Result<Self, String> {
        if !(radius.is_finite() && radius > 0.0 && center.is_finite()) {
            return Err(format!(
                "sphere radius must be positive and finite, got {radius}"
            ));
        }
        Ok(Self {
            center,
            radius,
            to_object: Mat3A::IDENTITY,
        })
    }

    /// A sphere whose `uv` are counted in a frame turned by `to_object` (world to object; an
    /// orthogonal matrix: the object's transform without its scale and translation).
    pub fn with_frame(center: Vec3A, radius: f32, to_object: Mat3A) -> Result<Self, String> {
        let mut s = Self::new(center, radius)?;
        if to_object.is_finite() {
            s.to_object = to_object;
        }
        Ok(s)
    }

    /// [`Sphere::hit_at`], with `uv` left NaN unless `uv` is asked for: it costs an `atan2` and
    /// an `acos`, and only textures read it. Every other field is the same.
    #[inline]
    pub fn hit_at_uv(&self, ray: &Ray, t: f32, uv: bool) -> Hit {
        let mut rel = ray.at(t) - self.center;
        // Re-project onto the surface: removes most of the rounding error of the quadratic.
        rel *= self.radius / rel.length();
        let n = rel / self.radius;
        // u around the y axis from +z towards +x (½ facing -z), v from 0 at the -y pole to 1 at
        // the +y pole: the `spherical` mapping's coordinates, so an image (v up) shows upright
        // and not mirrored seen from outside by the right-handed camera.
        // The object's frame: `dpdu` stays the world-space tangent along the world's
        // longitudes (any tangent serves the isotropic materials' shading frame).
        let uv = if uv {
            let o = self.to_object * n;
            let phi = {
                let p = o.x.atan2(o.z);
                if p < 0.0 { p + 2.0 * PI } else { p }
            };
            let u = phi / (2.0 * PI);
            let theta = o.y.clamp(-1.0, 1.0).acos();
            Vec2::new(if u < 1.0 { u } else { 0.0 }, 1.0 - theta / PI)
        } else {
            Vec2::NAN
        };
        let dpdu = Vec3A::new(rel.z, 0.0, -rel.x) * (2.0 * PI);
        Hit::from_parts(t, self.center + rel, n, n, uv, dpdu)
    }

    #[inline]
    fn roots(&self, ray: &Ray) -> Option<(f32, f32)> {
        let oc = ray.o - self.center;
        let a = ray.d.length_squared();
        let b = oc.dot(ray.d);
        let c = oc.length_squared() - self.radius * self.radius;
        // Discriminant in the cancellation-free form (pbrt-v4, Hearn & Baker).
        let f = oc - ray.d * (b / a);
        let fl = f.length();
        let disc = a * (self.radius - fl) * (self.radius + fl);
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        let q = if b > 0.0 { -b - sq } else { -b + sq };
        let (t0, t1) = (c / q, q / a);
        Some(if t0 < t1 { (t0, t1) } else { (t1, t0) })
    }
}

/// The cone of directions a sphere subtends from a point outside it.
#[derive(Debug, Clone, Copy)]
struct Cone {
    /// Unit direction from the receiver to the center.
    axis: Vec3A,
    /// Distance from the receiver to the center.
    dist: f32,
    /// `sin^2` of the cone's half-angle, `r^2 / d^2`.
    sin2_max: f32,
    /// `1 - cos` of the half-angle, computed as `sin^2 / (1 + cos)`: exact where `1 - cos`
    /// would cancel to zero (a far or small sphere).
    one_minus_cos_max: f32,
}

impl Cone {
    #[inline]
    fn pdf(&self) -> f32 {
        1.0 / (2.0 * PI * self.one_minus_cos_max)
    }
}

impl Sphere {
    /// The cone the sphere subtends from `p`, if `p` is strictly outside and the cone's solid
    /// angle is representable; otherwise the sphere is sampled by area.
    #[inline]
    fn cone_from(&self, p: Vec3A) -> Option<Cone> {
        let to_center = self.center - p;
        let d2 = to_center.length_squared();
        let r2 = self.radius * self.radius;
        if !(d2 > r2 && d2.is_finite()) {
            return None;
        }
        let sin2_max = r2 / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        let one_minus_cos_max = sin2_max / (1.0 + cos_max);
        if one_minus_cos_max.is_nan() || one_minus_cos_max <= 0.0 {
            return None;
        }
        let dist = d2.sqrt();
        Some(Cone {
            axis: to_center / dist,
            dist,
            sin2_max,
            one_minus_cos_max,
        })
    }

    /// A point of the sphere for the receiver `p`, from `u` in [0,1)^2: from outside, uniform
    /// over the cone of directions the sphere subtends (every sample lands on the side facing
    /// `p`); from inside or on the surface, uniform by area. The density is per solid angle at
    /// `p` and is what [`Sphere::pdf_toward`] gives for the same point.
    pub fn sample_toward(&self, p: Vec3A, u: Vec2) -> Option<SolidAngleSample> {
        let Some(cone) = self.cone_from(p) else {
            let s = SplitShape::sample(self, u)?;
            return area_to_solid_angle(p, s.p, s.n, self.area());
        };
        // 1 - cos(theta) uniform in [0, 1 - cos_max]; sin^2 from it without cancellation.
        let omc = u.x * cone.one_minus_cos_max;
        let cos_t = 1.0 - omc;
        let sin2_t = (omc * (2.0 - omc)).min(cone.sin2_max);
        let sin_t = sin2_t.sqrt();
        let phi = 2.0 * PI * u.y;
        let local = Vec3A::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
        let wi = Frame::from_normal(cone.axis).to_world(local).normalize();
        // Nearest hit along wi, in the form without cancellation: t = (d^2 - r^2) /
        // (d cos + sqrt(r^2 - d^2 sin^2)), with r^2 - d^2 sin^2 = d^2 (sin^2_max - sin^2).
        let (d, r) = (cone.dist, self.radius);
        let t = (d - r) * (d + r) / (d * (cos_t + (cone.sin2_max - sin2_t).max(0.0).sqrt()));
        let n = (p + wi * t - self.center).normalize_or_zero();
        if n == Vec3A::ZERO {
            return None;
        }
        Some(SolidAngleSample {
            p: self.center + n * r,
            n,
            wi,
            pdf: cone.pdf(),
        })
    }

    /// Solid-angle density at `p` of [`Sphere::sample_toward`] choosing the point `pl` (normal
    /// `nl`) of the sphere; for a point outside, `pl` must be on the side facing `p` (the first
    /// hit of a ray from `p`).
    pub fn pdf_toward(&self, p: Vec3A, pl: Vec3A, nl: Vec3A) -> f32 {
        match self.cone_from(p) {
            Some(cone) => cone.pdf(),
            None => area_pdf_to_solid_angle(p, pl, nl, self.area()),
        }
    }
}

impl SplitShape for Sphere {
    /// Nearest `t` with `t_min < t < t_max`, without the surface data (see [`Sphere::hit_at`]).
    #[inline]
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let (t0, t1) = self.roots(ray)?;
        if t0 > t_min && t0 < t_max {
            Some(t0)
        } else if t1 > t_min && t1 < t_max {
            Some(t1)
        } else {
            None
        }
    }

    /// The full surface data at ray parameter `t` (a value [`Sphere::hit_t`] returned).
    fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        self.hit_at_uv(ray, t, true)
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(
            self.center - Vec3A::splat(self.radius),
            self.center + Vec3A::splat(self.radius),
        )
    }

    fn area(&self) -> f32 {
        4.0 * PI * self.radius * self.radius
    }

    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        let n = uniform_sphere(u);
        Some(AreaSample {
            p: self.center + n * self.radius,
            n,
            pdf: 1.0 / self.area(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::shapes::Shape;
    use crate::shapes::sampling_tests::{
        assert_density_integrates_to_one, assert_estimate, mean_se,
    };

    /// Irradiance (per unit radiance) at `p` with normal `m` from a sphere seen whole above
    /// the horizon is `pi sin^2(theta_max) cos(beta)`. Cone sampling must average to it from
    /// every distance: the receiver a hair off the surface (a cone of almost a hemisphere) and
    /// far away (`sin^2 = 1e-8`, where `1 - cos(theta_max)` computed directly is 0 in f32).
    #[test]
    fn cone_sampling_gives_the_analytic_irradiance() {
        let sphere = Sphere::new(Vec3A::new(0.5, -1.0, 2.0), 0.75).unwrap();
        let mut rng = Rng::new(7);
        for rel in [1.0 + 1e-5, 1.001, 1.05, 1.5, 3.0, 30.0, 1e4] {
            for beta in [0.0f64, 0.3] {
                let dist = sphere.radius as f64 * rel;
                let axis = Vec3A::new(0.3, 0.9, -0.2).normalize();
                let p = sphere.center - axis * dist as f32;
                let sin2 = (1.0 / (rel * rel)).min(1.0);
                let theta_max = sin2.sqrt().asin();
                if theta_max + beta >= std::f64::consts::FRAC_PI_2 {
                    continue; // part of the cap below the horizon: no closed form used here
                }
                let tilt = Frame::from_normal(axis).s;
                let m = (axis * beta.cos() as f32 + tilt * beta.sin() as f32).normalize();
                let want = std::f64::consts::PI * sin2 * beta.cos();
                let estimate = mean_se(40_000, || {
                    let s = sphere
                        .sample_toward(p, rng.vec2())
                        .expect("outside: a sample");
                    assert!(s.pdf.is_finite() && s.pdf > 0.0, "{rel}: pdf {}", s.pdf);
                    assert!(s.n.dot(s.wi) <= 1e-3, "{rel}: the sample faces away");
                    (m.dot(s.wi).max(0.0) / s.pdf) as f64
                });
                assert_estimate(&format!("d/r {rel}, beta {beta}"), estimate, want, 2e-5);
            }
        }
    }

    /// From inside, the sphere is sampled by area and every direction sees it: the
    /// cosine-weighted integral over the hemisphere is pi, at the center and near the wall.
    #[test]
    fn area_sampling_from_inside_gives_pi() {
        let sphere = Sphere::new(Vec3A::new(1.0, 2.0, 3.0), 2.0).unwrap();
        let mut rng = Rng::new(9);
        for (offset, m) in [
            (Vec3A::ZERO, Vec3A::Z),
            (Vec3A::new(0.0, 0.0, 1.9), Vec3A::Z),
            (Vec3A::new(0.0, 0.0, 1.9), -Vec3A::Z),
            (Vec3A::new(1.99999, 0.0, 0.0), -Vec3A::X),
        ] {
            let p = sphere.center + offset;
            let estimate = mean_se(200_000, || {
                sphere
                    .sample_toward(p, rng.vec2())
                    .map_or(0.0, |s| (m.dot(s.wi).max(0.0) / s.pdf) as f64)
            });
            assert_estimate(
                &format!("inside, {offset}"),
                estimate,
                std::f64::consts::PI,
                3e-5,
            );
        }
    }

    /// The density [`Sphere::pdf_toward`] gives a point a ray from `p` hits (what MIS uses
    /// when a BSDF sample hits the light) is a normalized density over the directions that
    /// hit: its integral over uniform directions is one; and it equals the sampler's own.
    #[test]
    fn pdf_toward_is_the_samplers_density() {
        let sphere = Sphere::new(Vec3A::new(0.0, 0.0, 0.0), 1.0).unwrap();
        let mut rng = Rng::new(13);
        for p in [
            Vec3A::new(0.0, 0.0, 1.5),
            Vec3A::new(1.2, 0.4, -0.3),
            Vec3A::new(0.0, 1.0 + 1e-4, 0.0),
            Vec3A::new(0.2, 0.1, -0.4),
            Vec3A::new(0.0, 0.0, 0.999),
        ] {
            for _ in 0..1000 {
                let s = sphere.sample_toward(p, rng.vec2()).unwrap();
                let back = sphere.pdf_toward(p, s.p, s.n);
                assert!(
                    (back / s.pdf - 1.0).abs() < 1e-3,
                    "{p}: {back} vs {}",
                    s.pdf
                );
            }
            assert_density_integrates_to_one(
                &sphere,
                p,
                |p, pl, nl| sphere.pdf_toward(p, pl, nl),
                &mut rng,
            );
        }
    }

    #[test]
    fn hits_from_outside_and_inside() {
        let s = Sphere::new(Vec3A::ZERO, 1.0).unwrap();
        let r = Ray::new(Vec3A::new(0.0, 0.0, -3.0), Vec3A::Z);
        let h = s.intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6 && (h.n + Vec3A::Z).length() < 1e-6);
        let r = Ray::new(Vec3A::ZERO, Vec3A::X);
        let h = s.intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6 && (h.n - Vec3A::X).length() < 1e-6);
        assert!(Sphere::new(Vec3A::ZERO, -1.0).is_err());
    }
}
