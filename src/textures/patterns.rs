//! The geometric patterns: `checker`, `stripes`, `gradient` (through a color map), `brick`, and
//! color-map evaluation shared with the noise patterns.
//!
//! All patterns take a texture-space point (after mapping and the texture's transform). Cell
//! boundaries are nudged by [`EDGE_NUDGE`] so that a surface lying exactly on a boundary (the
//! plane `y = 0` under a checker) picks one side consistently instead of flickering with
//! rounding noise.

use glam::{DVec3, Vec3A};

use crate::scene::{Color, ColorMap};

pub use crate::scene::pattern_value::{EDGE_NUDGE, floor_i64};
use crate::scene::pattern_value::{brick_joint, cell, checker_value};

/// Unit cubes alternating between `a` (the cube at the origin) and `b`. On 2-D mappings
/// (`z = 0`) a checkerboard of unit squares.
#[inline]
pub fn checker(p: DVec3, a: Color, b: Color) -> Vec3A {
    if checker_value(p) == 0.0 {
        a.as_vec3a()
    } else {
        b.as_vec3a()
    }
}

/// Slabs one unit thick perpendicular to x, alternating `a` (for `0 <= x < 1`) and `b`.
#[inline]
pub fn stripes(p: DVec3, a: Color, b: Color) -> Vec3A {
    if cell(p.x) == 0 {
        a.as_vec3a()
    } else {
        b.as_vec3a()
    }
}

/// A sawtooth of period 1 along `direction` (normalised; a zero or non-finite direction means
/// +y): `fract(dot(p, d))` through `map`.
#[inline]
pub fn gradient(p: DVec3, direction: DVec3, map: &ColorMap) -> Vec3A {
    let d = direction.try_normalize().unwrap_or(DVec3::Y);
    let t = p.dot(d);
    color_map(map, t - t.floor())
}

/// POV-Ray's `brick`: bricks of `size` laid in rows along x, stacked in y, every other row
/// shifted by half a brick; joints `mortar_width` wide (half on each side of a brick).
/// In z, joints are a quarter of a brick away from `z = 0` (and shift by half a brick every
/// other row), so a wall in the x-y plane shows whole bricks and the side faces of a box show
/// the bond. Sizes that are not positive and finite fall back to POV-Ray's `<8, 3, 4.5>`.
pub fn brick(p: DVec3, brick: Color, mortar: Color, size: DVec3, mortar_width: f64) -> Vec3A {
    if brick_joint(p, size, mortar_width) {
        mortar.as_vec3a()
    } else {
        brick.as_vec3a()
    }
}

/// The color of `map` at `t`: piecewise-linear between entries, constant beyond the first and
/// last. An empty map is a black-to-white ramp; NaN reads as 0. No allocation.
pub fn color_map(map: &ColorMap, t: f64) -> Vec3A {
    let t = if t.is_nan() { 0.0 } else { t };
    let entries = &map.0;
    let (Some(first), Some(last)) = (entries.first(), entries.last()) else {
        return Vec3A::splat(t.clamp(0.0, 1.0) as f32);
    };
    if t <= first.0 {
        return first.1.as_vec3a();
    }
    if t >= last.0 {
        return last.1.as_vec3a();
    }
    let mut prev = first;
    for entry in &entries[1..] {
        if t <= entry.0 {
            let span = entry.0 - prev.0;
            let f = if span > 0.0 { (t - prev.0) / span } else { 1.0 };
            return prev.1.lerp(entry.1, f.clamp(0.0, 1.0)).as_vec3a();
        }
        prev = entry;
    }
    last.1.as_vec3a()
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: Color = DVec3::new(1.0, 0.0, 0.0);
    const B: Color = DVec3::new(0.0, 0.0, 1.0);

    #[test]
    fn checker_alternates_and_is_stable_on_boundaries() {
        assert_eq!(checker(DVec3::new(0.5, 0.5, 0.5), A, B), A.as_vec3a());
        assert_eq!(checker(DVec3::new(1.5, 0.5, 0.5), A, B), B.as_vec3a());
        assert_eq!(checker(DVec3::new(1.5, 1.5, 0.5), A, B), A.as_vec3a());
        assert_eq!(checker(DVec3::new(-0.5, 0.5, 0.5), A, B), B.as_vec3a());
        assert_eq!(checker(DVec3::new(-0.5, -0.5, -0.5), A, B), B.as_vec3a());
        // A plane at y = 0 with rounding noise in y: one color, not a flicker.
        for y in [-1e-7, 0.0, 1e-7] {
            assert_eq!(checker(DVec3::new(0.5, y, 0.5), A, B), A.as_vec3a());
        }
        assert!(checker(DVec3::splat(f64::NAN), A, B).is_finite());
        assert!(checker(DVec3::splat(1e300), A, B).is_finite());
    }

    #[test]
    fn integer_floor_matches_floor() {
        for x in [
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            0.3,
            1.0,
            7.99,
            -1e12 - 0.5,
            4.5e15,
        ] {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
        assert_eq!(floor_i64(f64::NAN), 0);
        assert_eq!(floor_i64(1e300), i64::MAX);
    }

    #[test]
    fn stripes_follow_x_only() {
        assert_eq!(stripes(DVec3::new(0.5, 7.3, -2.0), A, B), A.as_vec3a());
        assert_eq!(stripes(DVec3::new(1.5, 7.3, -2.0), A, B), B.as_vec3a());
        assert_eq!(stripes(DVec3::new(-0.5, 0.0, 0.0), A, B), B.as_vec3a());
        assert_eq!(stripes(DVec3::new(2.5, -9.0, 4.0), A, B), A.as_vec3a());
    }

    #[test]
    fn color_map_interpolates_and_clamps() {
        let map = ColorMap(vec![
            (0.2, DVec3::ZERO),
            (0.6, DVec3::new(1.0, 2.0, 4.0)),
            (0.6, DVec3::ONE),
            (1.0, DVec3::splat(3.0)),
        ]);
        assert_eq!(color_map(&map, 0.0), Vec3A::ZERO);
        assert!((color_map(&map, 0.4) - Vec3A::new(0.5, 1.0, 2.0)).length() < 1e-6);
        assert!((color_map(&map, 0.8) - Vec3A::splat(2.0)).length() < 1e-6);
        assert_eq!(color_map(&map, 5.0), Vec3A::splat(3.0));
        assert_eq!(color_map(&map, f64::NAN), Vec3A::ZERO);
        assert_eq!(color_map(&ColorMap(vec![]), 0.25), Vec3A::splat(0.25));
    }

    #[test]
    fn gradient_is_a_sawtooth_along_its_direction() {
        let map = ColorMap(vec![(0.0, DVec3::ZERO), (1.0, DVec3::ONE)]);
        let g = |p| gradient(p, DVec3::new(0.0, 2.0, 0.0), &map).x;
        assert!((g(DVec3::new(9.0, 0.25, 3.0)) - 0.25).abs() < 1e-6);
        assert!((g(DVec3::new(0.0, 1.75, 0.0)) - 0.75).abs() < 1e-6);
        assert!((g(DVec3::new(0.0, -0.25, 0.0)) - 0.75).abs() < 1e-6);
        // Zero direction: +y.
        assert!((gradient(DVec3::new(0.0, 0.5, 0.0), DVec3::ZERO, &map).x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn brick_rows_are_offset_and_mortar_has_its_width() {
        let size = DVec3::new(4.0, 2.0, 4.0);
        let b = |x, y, z| brick(DVec3::new(x, y, z), A, B, size, 0.2) == A.as_vec3a();
        // Middle of a brick in row 0, at z = 0.
        assert!(b(2.0, 1.0, 0.0));
        // The vertical joint of row 0 at x = 4 (within 0.1), but not 0.15 away.
        assert!(!b(4.05, 1.0, 0.0));
        assert!(!b(3.95, 1.0, 0.0));
        assert!(b(4.15, 1.0, 0.0));
        // Row 1 is shifted by half a brick: x = 4 is mid-brick, x = 2 and 6 are joints.
        assert!(b(4.0, 3.0, 0.0));
        assert!(!b(2.0, 3.0, 0.0));
        assert!(!b(6.0, 3.0, 0.0));
        // Horizontal joints at y = 0, 2, 4.
        assert!(!b(1.0, 2.02, 0.0));
        assert!(!b(1.0, -0.05, 0.0));
        // The x-y plane at z = 0 shows no z joints in either row.
        for i in 0..200 {
            let x = 0.37 + i as f64 * 0.05;
            let on_x_joint = |row_shift: f64| {
                let f = (x + row_shift).rem_euclid(4.0);
                !(0.1..=3.9).contains(&f)
            };
            assert_eq!(b(x, 1.0, 0.0), !on_x_joint(0.0), "x = {x}");
            assert_eq!(b(x, 3.0, 0.0), !on_x_joint(2.0), "x = {x}");
        }
        // But z joints exist: a quarter brick from z = 0.
        assert!(!b(2.0, 1.0, 1.0) || !b(2.0, 1.0, 3.0));
        assert!(brick(DVec3::splat(f64::NAN), A, B, DVec3::ZERO, f64::NAN).is_finite());
    }
}
