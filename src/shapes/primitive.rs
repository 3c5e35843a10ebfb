//! Enum dispatch over the renderer's shapes (no virtual call for the common ones).

use glam::Vec2;

use super::{
    AreaSample, BoxedHit, Deferred, Shape, csg::Csg, cylinder::Cylinder, disk::Disk, plane::Plane,
    quad::Quad, sphere::Sphere, triangle::Triangle,
};
use crate::geometry::{Aabb, Hit, Ray};

pub enum AnyShape {
    Sphere(Sphere),
    Quad(Quad),
    Disk(Disk),
    Cylinder(Cylinder),
    Triangle(Triangle),
    Plane(Plane),
    Other(Box<dyn Shape>),
    /// A CSG tree: its hits name the part (leaf) they are on.
    Csg(Box<Csg>),
}

macro_rules! dispatch {
    ($self:ident, $s:ident => $e:expr) => {
        match $self {
            AnyShape::Sphere($s) => $e,
            AnyShape::Quad($s) => $e,
            AnyShape::Disk($s) => $e,
            AnyShape::Cylinder($s) => $e,
            AnyShape::Triangle($s) => $e,
            AnyShape::Plane($s) => $e,
            AnyShape::Other($s) => $e,
            AnyShape::Csg($s) => $e,
        }
    };
}

/// The result of a cheap intersection test: the analytic shapes give only `t` (their surface
/// data is computed once, for the closest hit, by [`AnyShape::hit_at`]); boxed shapes give
/// their full hit at once, or `t` and a [`Deferred`] record (see [`Shape::intersect_boxed`]),
/// and a CSG tree its full hit with the id of the part hit.
#[derive(Debug, Clone, Copy)]
pub enum LazyHit {
    T(f32),
    Full(Hit),
    Part(Hit, u32),
    Deferred(f32, Deferred),
}

impl LazyHit {
    #[inline]
    pub fn t(&self) -> f32 {
        match self {
            LazyHit::T(t) | LazyHit::Deferred(t, _) => *t,
            LazyHit::Full(h) | LazyHit::Part(h, _) => h.t,
        }
    }

    /// The id of the CSG part hit (its primitive id in the prepared scene).
    #[inline]
    pub fn part(&self) -> Option<u32> {
        match self {
            LazyHit::Part(_, id) => Some(*id),
            _ => None,
        }
    }
}

impl AnyShape {
    /// A shape whose intersection costs far more than a box test: a boxed shape (a revolve's
    /// segment, a patch, a torus, a transformed object) or a CSG tree. The BVH gives each a
    /// leaf of its own (above its median split's depth).
    pub fn is_heavy(&self) -> bool {
        matches!(self, AnyShape::Other(_) | AnyShape::Csg(_))
    }

    /// Nearest hit with `t_min < t < t_max`, deferring the surface data where the shape can.
    #[inline]
    pub fn intersect_lazy(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<LazyHit> {
        use super::SplitShape;
        match self {
            AnyShape::Sphere(s) => s.hit_t(ray, t_min, t_max).map(LazyHit::T),
            AnyShape::Quad(s) => s.hit_t(ray, t_min, t_max).map(LazyHit::T),
            AnyShape::Disk(s) => s.hit_t(ray, t_min, t_max).map(LazyHit::T),
            AnyShape::Cylinder(s) => s.hit_t(ray, t_min, t_max).map(LazyHit::T),
            AnyShape::Triangle(s) => s.hit_t(ray, t_min, t_max).map(LazyHit::T),
            AnyShape::Plane(s) => s.hit_t(ray, t_min, t_max).map(LazyHit::T),
            AnyShape::Other(_) | AnyShape::Csg(_) => self.boxed_hit(ray, t_min, t_max),
        }
    }

    /// The hit of a shape that has no split intersection: a boxed shape's (full or
    /// deferred), a CSG tree's full hit with the part hit.
    #[inline]
    pub(crate) fn boxed_hit(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<LazyHit> {
        match self {
            AnyShape::Csg(c) => c
                .intersect_part(ray, t_min, t_max)
                .map(|(h, id)| LazyHit::Part(h, id)),
            AnyShape::Other(s) => s.intersect_boxed(ray, t_min, t_max).map(|h| match h {
                BoxedHit::Full(h) => LazyHit::Full(h),
                BoxedHit::Deferred(t, rec) => LazyHit::Deferred(t, rec),
            }),
            s => s.intersect(ray, t_min, t_max).map(LazyHit::Full),
        }
    }

    /// Nearest `t` with `t_min < t < t_max` of an analytic shape (surface data deferred to
    /// [`AnyShape::hit_at`]); `Err(())` for a boxed shape, whose hit must come from
    /// [`Shape::intersect`]. The BVH's inner loop calls this: it moves 4 bytes, where an
    /// `Option<LazyHit>` moved a whole `Hit` at every test.
    #[inline(always)]
    pub(crate) fn analytic_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Result<Option<f32>, ()> {
        use super::SplitShape;
        Ok(match self {
            AnyShape::Sphere(s) => s.hit_t(ray, t_min, t_max),
            AnyShape::Quad(s) => s.hit_t(ray, t_min, t_max),
            AnyShape::Disk(s) => s.hit_t(ray, t_min, t_max),
            AnyShape::Cylinder(s) => s.hit_t(ray, t_min, t_max),
            AnyShape::Triangle(s) => s.hit_t(ray, t_min, t_max),
            AnyShape::Plane(s) => s.hit_t(ray, t_min, t_max),
            AnyShape::Other(_) | AnyShape::Csg(_) => return Err(()),
        })
    }

    /// The full hit for a [`LazyHit`] this shape returned for `ray`; identical to what
    /// [`Shape::intersect`] gives.
    pub fn hit_at(&self, ray: &Ray, lazy: LazyHit) -> Hit {
        self.hit_at_uv(ray, lazy, true)
    }

    /// [`AnyShape::hit_at`], where `uv: false` lets the shapes whose `uv` needs trigonometry
    /// (sphere, disk, cylinder, and a boxed shape's deferred hit: a revolve's arc length) leave
    /// it NaN: for primitives whose material reads no texture. Every other field is the same.
    /// Shapes whose `uv` is cheap, and boxed shapes' full hits, fill it.
    #[inline]
    pub fn hit_at_uv(&self, ray: &Ray, lazy: LazyHit, uv: bool) -> Hit {
        use super::SplitShape;
        let t = match lazy {
            LazyHit::Full(h) | LazyHit::Part(h, _) => return h,
            LazyHit::Deferred(t, rec) => return self.complete(ray, t, rec, uv),
            LazyHit::T(t) => t,
        };
        match self {
            AnyShape::Sphere(s) => s.hit_at_uv(ray, t, uv),
            AnyShape::Quad(s) => s.hit_at(ray, t),
            AnyShape::Disk(s) => s.hit_at_uv(ray, t, uv),
            AnyShape::Cylinder(s) => s.hit_at_uv(ray, t, uv),
            AnyShape::Triangle(s) => s.hit_at(ray, t),
            AnyShape::Plane(s) => s.hit_at(ray, t),
            // Boxed shapes always answer `Full`, CSG trees `Part`; recompute if ever asked
            // otherwise.
            AnyShape::Other(_) | AnyShape::Csg(_) => self
                .intersect(ray, t * (1.0 - 1e-6), f32::INFINITY)
                .unwrap_or(Hit {
                    t,
                    p: ray.at(t),
                    n: glam::Vec3A::Z,
                    ns: glam::Vec3A::Z,
                    uv: Vec2::ZERO,
                    dpdu: glam::Vec3A::X,
                }),
        }
    }
}

impl Shape for AnyShape {
    fn bounds(&self) -> Aabb {
        dispatch!(self, s => s.bounds())
    }
    fn intersect_boxed(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<BoxedHit> {
        dispatch!(self, s => s.intersect_boxed(ray, t_min, t_max))
    }
    fn complete(&self, ray: &Ray, t: f32, rec: Deferred, uv: bool) -> Hit {
        dispatch!(self, s => s.complete(ray, t, rec, uv))
    }
    #[inline]
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        dispatch!(self, s => s.intersect(ray, t_min, t_max))
    }
    #[inline]
    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        dispatch!(self, s => s.occluded(ray, t_min, t_max))
    }
    fn area(&self) -> f32 {
        dispatch!(self, s => s.area())
    }
    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        dispatch!(self, s => s.sample(u))
    }
}
