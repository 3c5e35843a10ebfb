//! What a closest hit of the BVH is on, and its full record from the lazy hit.

use crate::geometry::{Hit, Ray};
use crate::shapes::mesh::TriangleMesh;
use crate::shapes::primitive::{AnyShape, LazyHit};

/// What a closest hit is on: a shape, or triangle `k` of a mesh (with the hit's barycentric
/// coordinates of its second and third vertex).
#[derive(Clone, Copy)]
pub enum Surface<'a> {
    Shape(&'a AnyShape),
    MeshTriangle(&'a TriangleMesh, usize, [f32; 2]),
}

impl<'a> Surface<'a> {
    /// The full hit for a [`LazyHit`] returned for `ray` (see [`AnyShape::hit_at_uv`]).
    #[inline]
    pub fn hit_at_uv(&self, ray: &Ray, lazy: LazyHit, uv: bool) -> Hit {
        match self {
            Surface::Shape(s) => s.hit_at_uv(ray, lazy, uv),
            Surface::MeshTriangle(m, k, b) => match lazy {
                // A triangle's hit is always `T`.
                LazyHit::T(t) | LazyHit::Deferred(t, _) => m.hit_at(*k, t, *b),
                LazyHit::Full(h) | LazyHit::Part(h, _) => h,
            },
        }
    }

    /// The shape hit, unless it is a mesh triangle.
    pub fn shape(self) -> Option<&'a AnyShape> {
        match self {
            Surface::Shape(s) => Some(s),
            Surface::MeshTriangle(..) => None,
        }
    }
}
