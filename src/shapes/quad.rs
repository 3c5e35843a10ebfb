//! Parallelogram `origin + s*edge_u + t*edge_v`.

use glam::{Vec2, Vec3A};

use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};

#[derive(Debug, Clone, Copy)]
pub struct Quad {
    origin: Vec3A,
    eu: Vec3A,
    ev: Vec3A,
    n: Vec3A,
    /// Dual vectors of the edges in the quad's plane: for a point `q` (relative to `origin`)
    /// in the plane, `s = q . du` and `t = q . dv` (`du = ev x w`, `dv = w x eu` with
    /// `w = cross / |cross|^2`): two dot products per test instead of two cross products.
    du: Vec3A,
    dv: Vec3A,
    area: f32,
}

impl Quad {
    pub fn new(origin: Vec3A, eu: Vec3A, ev: Vec3A) -> Result<Self, String> {
        let c = eu.cross(ev);
        let area = c.length();
        if !(area.is_finite() && area > 0.0 && origin.is_finite()) {
            return Err("quad edges are parallel or degenerate (zero area)".into());
        }
        let n = c / area;
        let w = c / c.length_squared();
        Ok(Self {
            origin,
            eu,
            ev,
            n,
            du: ev.cross(w),
            dv: w.cross(eu),
            area,
        })
    }
}

impl Quad {
    /// Nearest `t` with `t_min < t < t_max`, without the surface data (see [`Quad::hit_at`]).
    #[inline]
    pub fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let denom = self.n.dot(ray.d);
        if denom == 0.0 {
            return None;
        }
        let t = self.n.dot(self.origin - ray.o) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let (s, v) = self.st(ray, t);
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&v)).then_some(t)
    }

    #[inline]
    fn st(&self, ray: &Ray, t: f32) -> (f32, f32) {
        let q = ray.at(t) - self.origin;
        (q.dot(self.du), q.dot(self.dv))
    }

    /// The full surface data at ray parameter `t` (a value [`Quad::hit_t`] returned).
    pub fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        let (s, v) = self.st(ray, t);
        Hit {
            t,
            p: ray.at(t),
            n: self.n,
            ns: self.n,
            uv: Vec2::new(s, v),
            dpdu: self.eu,
        }
    }
}

impl Shape for Quad {
    fn bounds(&self) -> Aabb {
        Aabb::from_points([
            self.origin,
            self.origin + self.eu,
            self.origin + self.ev,
            self.origin + self.eu + self.ev,
        ])
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let t = self.hit_t(ray, t_min, t_max)?;
        Some(self.hit_at(ray, t))
    }

    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.hit_t(ray, t_min, t_max).is_some()
    }

    fn area(&self) -> f32 {
        self.area
    }

    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        Some(AreaSample {
            p: self.origin + self.eu * u.x + self.ev * u.y,
            n: self.n,
            pdf: 1.0 / self.area,
        })
    }
}
