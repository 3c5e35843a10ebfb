//! The tests of the unbounded shapes (planes), which every query runs before the tree.

use crate::geometry::Ray;
use crate::shapes::primitive::{AnyShape, LazyHit};
use crate::shapes::{Shape, SplitShape};

/// [`AnyShape::intersect_lazy`] of an unbounded shape, a plane's test inlined: every query
/// tests each of a scene's planes (its walls and floor), and the call and the dispatch cost
/// more than a plane's own test (the same function, so the same hits).
#[inline(always)]
pub(super) fn unbounded_hit(s: &AnyShape, ray: &Ray, t_min: f32, t_max: f32) -> Option<LazyHit> {
    match s {
        AnyShape::Plane(p) => p.hit_t(ray, t_min, t_max).map(LazyHit::T),
        s => s.intersect_lazy(ray, t_min, t_max),
    }
}

/// [`Shape::occluded`] of an unbounded shape, a plane's test inlined as in [`unbounded_hit`].
#[inline(always)]
pub(super) fn unbounded_occludes(s: &AnyShape, ray: &Ray, t_min: f32, t_max: f32) -> bool {
    match s {
        AnyShape::Plane(p) => p.hit_t(ray, t_min, t_max).is_some(),
        s => s.occluded(ray, t_min, t_max),
    }
}
