//! Flat disk.

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use super::{AreaSample, SplitShape};
use crate::geometry::Frame;
use crate::geometry::{Aabb, Hit, Ray};
use crate::sampling::concentric_disk;

#[derive(Debug, Clone, Copy)]
pub struct Disk {
    center: Vec3A,
    frame: Frame,
    radius: f32,
}

impl Disk {
    pub fn new(center: Vec3A, normal: Vec3A, radius: f32) -> Result<Self, String> {
        let len = normal.length();
        if !(radius.is_finite() && radius > 0.0) {
            return Err(format!("disk radius must be positive, got {radius}"));
        }
        if !(len.is_finite() && len > 0.0 && center.is_finite()) {
            return Err("disk normal must be a non-zero vector".into());
        }
        Ok(Self {
            center,
            frame: Frame::from_normal(normal / len),
            radius,
        })
    }
}

impl Disk {
    /// [`Disk::hit_at`], with `uv` left NaN unless `uv` is asked for (it costs an `atan2`).
    #[inline]
    pub fn hit_at_uv(&self, ray: &Ray, t: f32, uv: bool) -> Hit {
        let n = self.frame.n;
        let p = ray.at(t);
        let l = self.frame.to_local(p - self.center);
        let uv = if uv {
            let r2 = l.x * l.x + l.y * l.y;
            let phi = l.y.atan2(l.x);
            let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
            Vec2::new(phi / (2.0 * PI), 1.0 - r2.sqrt() / self.radius)
        } else {
            Vec2::NAN
        };
        let dpdu = self.frame.t * l.x - self.frame.s * l.y;
        Hit {
            t,
            p,
            n,
            ns: n,
            uv,
            dpdu: if dpdu.length_squared() > 0.0 {
                dpdu * (2.0 * PI)
            } else {
                self.frame.s
            },
        }
    }
}

impl SplitShape for Disk {
    /// Nearest `t` with `t_min < t < t_max`, without the surface data (see [`Disk::hit_at`]).
    #[inline]
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let n = self.frame.n;
        let denom = n.dot(ray.d);
        if denom == 0.0 {
            return None;
        }
        let t = n.dot(self.center - ray.o) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let l = self.frame.to_local(ray.at(t) - self.center);
        let r2 = l.x * l.x + l.y * l.y;
        (r2 <= self.radius * self.radius).then_some(t)
    }

    /// The full surface data at ray parameter `t` (a value [`Disk::hit_t`] returned).
    fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        self.hit_at_uv(ray, t, true)
    }

    fn bounds(&self) -> Aabb {
        let n = self.frame.n;
        let e = (Vec3A::ONE - n * n).max(Vec3A::ZERO).powf(0.5) * self.radius;
        Aabb::new(self.center - e, self.center + e)
    }

    fn area(&self) -> f32 {
        PI * self.radius * self.radius
    }

    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        let d = concentric_disk(u) * self.radius;
        Some(AreaSample {
            p: self.center + self.frame.s * d.x + self.frame.t * d.y,
            n: self.frame.n,
            pdf: 1.0 / self.area(),
        })
    }
}
