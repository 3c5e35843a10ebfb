//! Ray-query acceleration and robust ray spawning.

mod build;
mod bvh;
mod instance;
mod leaf;
mod triangles;
mod wide;

pub use bvh::{Bvh, Surface};

use glam::Vec3A;

use crate::geometry::Ray;

/// Relative size of the offset that moves a spawned ray's origin off its surface. f32 hit points
/// carry a rounding error of a few ulps of their largest coordinate (more for quadrics); 2^-15
/// covers it with a wide margin while staying far below any feature size a scene uses.
const OFFSET_REL: f32 = 1.0 / 32768.0;
const OFFSET_ABS: f32 = 1e-6;

/// The error bound used to offset from a hit at `p`.
#[inline]
pub fn offset_scale(p: Vec3A) -> f32 {
    p.abs().max_element() * OFFSET_REL + OFFSET_ABS
}

/// Origin moved off the surface at `p` (geometric normal `n`) to the side `dir` leaves on, so
/// the new ray never re-hits its own surface and never starts behind a touching wall.
#[inline]
pub fn offset_origin(p: Vec3A, n: Vec3A, dir: Vec3A) -> Vec3A {
    let off = n * offset_scale(p);
    if n.dot(dir) >= 0.0 { p + off } else { p - off }
}

/// A ray leaving the surface point `p` in direction `dir`.
#[inline]
pub fn spawn_ray(p: Vec3A, n: Vec3A, dir: Vec3A) -> Ray {
    Ray::new(offset_origin(p, n, dir), dir)
}

/// A shadow ray from `p` to `target` (itself on a surface with normal `nt`); `t` runs to 1
/// minus a margin, so the target's own surface does not occlude it.
#[inline]
pub fn spawn_ray_to(p: Vec3A, n: Vec3A, target: Vec3A, nt: Vec3A) -> (Ray, f32) {
    let o = offset_origin(p, n, target - p);
    let t_end = offset_origin(target, nt, o - target);
    let d = t_end - o;
    (Ray::new(o, d), 1.0)
}
