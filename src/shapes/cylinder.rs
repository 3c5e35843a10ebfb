//! Open cylinder tube between `base` and `cap` (end caps are separate disks, see
//! `render::prepared`).

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::{AreaSample, SplitShape};
use crate::geometry::Frame;
use crate::geometry::{Aabb, Hit, Ray};

#[derive(Debug, Clone, Copy)]
pub struct Cylinder {
    base: Vec3A,
    frame: Frame,
    height: f32,
    radius: f32,
}

impl Cylinder {
    pub fn new(base: Vec3A, cap: Vec3A, radius: f32) -> Result<Self, String> {
        let axis = cap - base;
        let height = axis.length();
        if !(radius.is_finite() && radius > 0.0) {
            return Err(format!("cylinder radius must be positive, got {radius}"));
        }
        if !(height.is_finite() && height > 0.0) {
            return Err("cylinder base and cap are the same point".into());
        }
        Ok(Self {
            base,
            frame: Frame::from_normal(axis / height),
            height,
            radius,
        })
    }

    /// The ray in the cylinder's local frame.
    #[inline]
    fn local(&self, ray: &Ray) -> (Vec3A, Vec3A) {
        (
            self.frame.to_local(ray.o - self.base),
            self.frame.to_local(ray.d),
        )
    }

    /// [`Cylinder::hit_at`], with `uv` left NaN unless `uv` is asked for (it costs an `atan2`).
    #[inline]
    pub fn hit_at_uv(&self, ray: &Ray, t: f32, uv: bool) -> Hit {
        let (o, d) = self.local(ray);
        let l = o + d * t;
        let radial = Vec2::new(l.x, l.y);
        let radial = radial * (self.radius / radial.length());
        let uv = if uv {
            let phi = radial.y.atan2(radial.x);
            let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
            Vec2::new(phi / (2.0 * PI), l.z / self.height)
        } else {
            Vec2::NAN
        };
        let nl = Vec3A::new(radial.x, radial.y, 0.0) / self.radius;
        let n = self.frame.to_world(nl);
        let p = self.base + self.frame.to_world(Vec3A::new(radial.x, radial.y, l.z));
        let dpdu = self.frame.to_world(Vec3A::new(-radial.y, radial.x, 0.0)) * (2.0 * PI);
        Hit {
            t,
            p,
            n,
            ns: n,
            uv,
            dpdu,
        }
    }

    #[inline]
    fn roots(&self, ray: &Ray) -> Option<(f32, f32, Vec3A, Vec3A)> {
        let (o, d) = self.local(ray);
        let a = d.x * d.x + d.y * d.y;
        if a == 0.0 {
            return None;
        }
        let b = o.x * d.x + o.y * d.y;
        let c = o.x * o.x + o.y * o.y - self.radius * self.radius;
        // Cancellation-free discriminant, as for the sphere.
        let f = Vec2::new(o.x - d.x * b / a, o.y - d.y * b / a).length();
        let disc = a * (self.radius - f) * (self.radius + f);
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        let q = if b > 0.0 { -b - sq } else { -b + sq };
        let (t0, t1) = (c / q, q / a);
        let (t0, t1) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
        Some((t0, t1, o, d))
    }
}

impl SplitShape for Cylinder {
    /// Nearest `t` with `t_min < t < t_max`, without the surface data (see [`Cylinder::hit_at`]).
    #[inline]
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let (t0, t1, o, d) = self.roots(ray)?;
        [t0, t1].into_iter().find(|&t| {
            let z = (o + d * t).z;
            t > t_min && t < t_max && !(z < 0.0 || z > self.height)
        })
    }

    /// The full surface data at ray parameter `t` (a value [`Cylinder::hit_t`] returned).
    fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        self.hit_at_uv(ray, t, true)
    }

    fn bounds(&self) -> Aabb {
        let top = self.base + self.frame.n * self.height;
        let n = self.frame.n;
        let e = (Vec3A::ONE - n * n).max(Vec3A::ZERO).powf(0.5) * self.radius;
        Aabb::from_points([self.base - e, self.base + e, top - e, top + e])
    }

    fn area(&self) -> f32 {
        2.0 * PI * self.radius * self.height
    }

    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        let phi = 2.0 * PI * u.y;
        let nl = Vec3A::new(phi.cos(), phi.sin(), 0.0);
        let n = self.frame.to_world(nl);
        Some(AreaSample {
            p: self.base + n * self.radius + self.frame.n * (u.x * self.height),
            n,
            pdf: 1.0 / self.area(),
        })
    }
}
