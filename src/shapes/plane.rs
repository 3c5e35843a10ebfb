//! Infinite plane `dot(n, p) = offset`. It has no finite bounds: the accelerator keeps planes
//! outside the BVH.

use glam::{Vec2, Vec3A};

use super::{AreaSample, SplitShape};
use crate::geometry::Frame;
use crate::geometry::{Aabb, Hit, Ray};

#[derive(Debug, Clone, Copy)]
pub struct Plane {
    frame: Frame,
    offset: f32,
}

impl Plane {
    pub fn new(normal: Vec3A, offset: f32) -> Result<Self, String> {
        let len = normal.length();
        if !(len.is_finite() && len > 0.0 && offset.is_finite()) {
            return Err("plane normal must be a non-zero vector".into());
        }
        Ok(Self {
            frame: Frame::from_normal(normal / len),
            offset: offset / len,
        })
    }
}

impl Plane {
    /// Whether `p` lies in the plane's half-space, the side opposite its normal (POV-Ray's
    /// inside of a plane).
    #[inline]
    pub fn contains(&self, p: Vec3A) -> bool {
        self.frame.n.dot(p) < self.offset
    }
}

impl SplitShape for Plane {
    /// Nearest `t` with `t_min < t < t_max`, without the surface data (see [`Plane::hit_at`]).
    #[inline]
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let n = self.frame.n;
        let denom = n.dot(ray.d);
        if denom == 0.0 {
            return None;
        }
        let t = (self.offset - n.dot(ray.o)) / denom;
        (t > t_min && t < t_max).then_some(t)
    }

    /// The full surface data at ray parameter `t` (a value [`Plane::hit_t`] returned).
    fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        let n = self.frame.n;
        let p = ray.at(t);
        Hit {
            t,
            p,
            n,
            ns: n,
            uv: Vec2::new(p.dot(self.frame.s), p.dot(self.frame.t)),
            dpdu: self.frame.s,
        }
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(Vec3A::splat(f32::NEG_INFINITY), Vec3A::splat(f32::INFINITY))
    }

    fn area(&self) -> f32 {
        f32::INFINITY
    }

    fn sample(&self, _u: Vec2) -> Option<AreaSample> {
        None
    }
}
