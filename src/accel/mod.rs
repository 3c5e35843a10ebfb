//! Ray-query acceleration and robust ray spawning.

mod build;
mod bvh;
mod flat;
mod instance;
mod leaf;
mod stack;
mod triangles;
mod unbuilt;
mod wide;

pub use bvh::{Bvh, NgHit, Surface};
pub use unbuilt::{MAX_PRIMITIVES, Unbuilt};

use glam::Vec3A;

use crate::geometry::Ray;

/// Relative size of the offset that moves a spawned ray's origin off its surface. f32 hit points
/// carry a rounding error of a few ulps of their largest coordinate (more for quadrics); 2^-15
/// covers it with a wide margin while staying far below any feature size a scene uses.
const OFFSET_REL: f32 = 1.0 / 32768.0;
/// The offset's floor (for points near the origin, whose error is that of the coordinates they
/// were computed from) in a scene whose coordinates reach 1 or more; a smaller scene's floor is
/// as much smaller (see [`offset_floor`]), so that a scene renders the same at any scale.
const OFFSET_ABS: f32 = 1e-6;

/// The offset's floor for a scene whose coordinates (finite objects and camera) reach `extent`:
/// 1e-6 from an extent of 1 up, 1e-6 x `extent` below (a scene scaled by 1e-4 kept 1e-6, 2 % of
/// its balls' radii, and lost a third of its photon deposits).
pub fn offset_floor(extent: f32) -> f32 {
    if extent.is_finite() && extent > 0.0 {
        OFFSET_ABS * extent.min(1.0)
    } else {
        OFFSET_ABS
    }
}

/// The error bound used to offset from a hit at `p`, with the scene's floor.
#[inline]
pub fn offset_scale(p: Vec3A, floor: f32) -> f32 {
    p.abs().max_element() * OFFSET_REL + floor
}

/// Origin moved off the surface at `p` (geometric normal `n`) to the side `dir` leaves on, so
/// the new ray never re-hits its own surface and never starts behind a touching wall.
#[inline]
pub fn offset_origin(p: Vec3A, n: Vec3A, dir: Vec3A, floor: f32) -> Vec3A {
    let off = n * offset_scale(p, floor);
    if n.dot(dir) >= 0.0 { p + off } else { p - off }
}

/// A ray leaving the surface point `p` in direction `dir`.
#[inline]
pub fn spawn_ray(p: Vec3A, n: Vec3A, dir: Vec3A, floor: f32) -> Ray {
    Ray::new(offset_origin(p, n, dir, floor), dir)
}

/// A shadow ray from `p` to `target` (itself on a surface with normal `nt`); `t` runs to 1
/// minus a margin, so the target's own surface does not occlude it.
#[inline]
pub fn spawn_ray_to(p: Vec3A, n: Vec3A, target: Vec3A, nt: Vec3A, floor: f32) -> (Ray, f32) {
    let o = offset_origin(p, n, target - p, floor);
    let t_end = offset_origin(target, nt, o - target, floor);
    let d = t_end - o;
    (Ray::new(o, d), 1.0)
}
