//! Sphere.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::{AreaSample, SplitShape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::sampling::uniform_sphere;

#[derive(Debug, Clone, Copy)]
pub struct Sphere {
    pub center: Vec3A,
    pub radius: f32,
}

impl Sphere {
    pub fn new(center: Vec3A, radius: f32) -> Result<Self, String> {
        if !(radius.is_finite() && radius > 0.0 && center.is_finite()) {
            return Err(format!(
                "sphere radius must be positive and finite, got {radius}"
            ));
        }
        Ok(Self { center, radius })
    }

    /// [`Sphere::hit_at`], with `uv` left NaN unless `uv` is asked for: it costs an `atan2` and
    /// an `acos`, and only textures read it. Every other field is the same.
    #[inline]
    pub fn hit_at_uv(&self, ray: &Ray, t: f32, uv: bool) -> Hit {
        let mut rel = ray.at(t) - self.center;
        // Re-project onto the surface: removes most of the rounding error of the quadratic.
        rel *= self.radius / rel.length();
        let n = rel / self.radius;
        let uv = if uv {
            let phi = {
                let p = rel.z.atan2(rel.x);
                if p < 0.0 { p + 2.0 * PI } else { p }
            };
            let theta = n.y.clamp(-1.0, 1.0).acos();
            Vec2::new(phi / (2.0 * PI), theta / PI)
        } else {
            Vec2::NAN
        };
        let dpdu = Vec3A::new(-rel.z, 0.0, rel.x) * (2.0 * PI);
        Hit {
            t,
            p: self.center + rel,
            n,
            ns: n,
            uv,
            dpdu,
        }
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
    use crate::shapes::Shape;

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
