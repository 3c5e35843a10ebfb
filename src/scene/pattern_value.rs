//! The scalar value of a pattern at a point, as POV-Ray's `function { pattern { ... } }` reads
//! it: a number in [0, 1] (`checker` 0 on the cube at the origin and 1 on its neighbours,
//! `gradient` a sawtooth, the noise patterns their noise). The textures colour the same values
//! (`textures::patterns`), so a pattern means one thing in a texture and in a function.

use glam::{DAffine3, DVec3};

use super::noise;

/// Offset added before taking cell indices (POV-Ray does the same for its checker), so that a
/// surface lying exactly on a boundary picks one side consistently.
pub const EDGE_NUDGE: f64 = 1e-5;

/// `floor` as an integer, by conversion (no libm call); saturates for huge values, NaN is 0.
#[inline]
pub fn floor_i64(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x { i - 1 } else { i }
}

/// The parity (0 or 1) of the unit cell `x` lies in. The saturating cast keeps huge coordinates
/// in range (and NaN is 0); two's complement keeps the parity right for negatives.
#[inline]
pub fn cell(x: f64) -> i64 {
    floor_i64(x + EDGE_NUDGE) & 1
}

/// 0 on the unit cube at the origin and on every cube an even number of steps from it, else 1.
#[inline]
pub fn checker_value(p: DVec3) -> f64 {
    ((cell(p.x) + cell(p.y) + cell(p.z)) & 1) as f64
}

/// Whether `p` lies in the mortar of POV-Ray's `brick`: bricks of `size` laid in rows along x,
/// stacked in y, every other row shifted by half a brick; joints `mortar_width` wide (half on
/// each side of a brick). In z, joints are a quarter of a brick away from `z = 0` (and shift by
/// half a brick every other row). Sizes that are not positive and finite fall back to POV-Ray's
/// `<8, 3, 4.5>`; NaN reads as brick.
pub fn brick_joint(p: DVec3, size: DVec3, mortar_width: f64) -> bool {
    let ok = |s: f64, d: f64| if s.is_finite() && s > 0.0 { s } else { d };
    let size = DVec3::new(ok(size.x, 8.0), ok(size.y, 3.0), ok(size.z, 4.5));
    let m = if mortar_width.is_finite() {
        mortar_width.max(0.0)
    } else {
        0.0
    };
    let half = 0.5 * m;
    let row = (p.y / size.y).floor();
    let odd = (row as i64) & 1 == 1;
    let within = |x: f64, s: f64| {
        let f = x - s * (x / s).floor();
        f < half || f > s - half
    };
    let shift = if odd { 0.5 } else { 0.0 };
    within(p.y, size.y)
        || within(p.x + shift * size.x, size.x)
        || within(p.z + (0.25 + shift) * size.z, size.z)
}

/// A pattern a function can evaluate.
#[derive(Debug, Clone, PartialEq)]
pub enum PatternKind {
    Checker,
    Stripes,
    /// A sawtooth of period 1 along the unit direction.
    Gradient(DVec3),
    /// 0 in the mortar, 1 in a brick (POV-Ray's colour order: mortar first).
    Brick {
        size: DVec3,
        mortar: f64,
    },
    Noise {
        octaves: u32,
    },
    Marble {
        turbulence: f64,
        octaves: u32,
    },
    Wood {
        turbulence: f64,
        octaves: u32,
    },
}

/// A pattern with the inverse of the transforms its block gave (`scale 2` makes it larger).
#[derive(Debug, Clone, PartialEq)]
pub struct PatternFn {
    pub kind: PatternKind,
    pub inverse: DAffine3,
}

impl PatternFn {
    /// The pattern's value at `p` (before the transform), in [0, 1]; 0 where `p` is not finite.
    pub fn value(&self, p: DVec3) -> f64 {
        let q = self.inverse.transform_point3(p);
        if !q.is_finite() {
            return 0.0;
        }
        match &self.kind {
            PatternKind::Checker => checker_value(q),
            PatternKind::Stripes => cell(q.x) as f64,
            PatternKind::Gradient(d) => {
                let t = q.dot(*d);
                t - t.floor()
            }
            PatternKind::Brick { size, mortar } => {
                if brick_joint(q, *size, *mortar) {
                    0.0
                } else {
                    1.0
                }
            }
            PatternKind::Noise { octaves } => noise::noise_value(q.x, q.y, q.z, *octaves),
            PatternKind::Marble {
                turbulence,
                octaves,
            } => noise::marble_value(q.x, q.y, q.z, *turbulence, *octaves),
            PatternKind::Wood {
                turbulence,
                octaves,
            } => noise::wood_value(q.x, q.y, q.z, *turbulence, *octaves),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(kind: PatternKind, p: DVec3) -> f64 {
        PatternFn {
            kind,
            inverse: DAffine3::IDENTITY,
        }
        .value(p)
    }

    #[test]
    fn checker_is_zero_at_the_origin_cube_and_alternates() {
        let c = |x, y, z| at(PatternKind::Checker, DVec3::new(x, y, z));
        assert_eq!(c(0.5, 0.5, 0.5), 0.0);
        assert_eq!(c(1.5, 0.5, 0.5), 1.0);
        assert_eq!(c(-0.5, 0.5, 0.5), 1.0);
        assert_eq!(c(1.5, 1.5, 0.5), 0.0);
    }

    #[test]
    fn gradient_is_a_sawtooth_and_values_stay_in_unit_range() {
        let g = |x| at(PatternKind::Gradient(DVec3::X), DVec3::new(x, 0.0, 0.0));
        assert!((g(0.25) - 0.25).abs() < 1e-12);
        assert!((g(-0.25) - 0.75).abs() < 1e-12);
        let kinds = [
            PatternKind::Noise { octaves: 6 },
            PatternKind::Marble {
                turbulence: 1.0,
                octaves: 6,
            },
            PatternKind::Wood {
                turbulence: 1.0,
                octaves: 6,
            },
            PatternKind::Brick {
                size: DVec3::new(0.2, 0.075, 0.1),
                mortar: 0.01,
            },
        ];
        for k in kinds {
            for i in 0..200 {
                let t = i as f64 * 0.137 - 13.0;
                let v = at(k.clone(), DVec3::new(t, t * 0.7, -t * 1.3));
                assert!((0.0..=1.0).contains(&v), "{k:?} at {t}: {v}");
            }
            // Non-finite points give 0, not a panic or NaN.
            assert_eq!(at(k.clone(), DVec3::splat(f64::NAN)), 0.0);
            assert_eq!(at(k, DVec3::splat(f64::INFINITY)), 0.0);
        }
    }
}
