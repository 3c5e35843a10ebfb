//! A coarse test in f32, before any f64 work: does the ray come near a lathe part's union shell
//! at all?
//!
//! Most rays that reach a segment's BVH box pass through the hole of its annulus or above or
//! below its heights (the box of a ring holds the disk inside it). The f64 test of the union
//! shell ([`RayFrame::shells_entered`](super::RayFrame::shells_entered)) rejects them, but only
//! after the ray's frame is made: a chain of square roots and divisions, each waiting for the
//! last. This test takes the renderer's f32 ray as it is, with two independent divisions, and
//! pads the shell far beyond its own rounding: by `1e-4` of the lathe's size and of the ray
//! origin's largest coordinate (f32 rounding is about `6e-8` of the magnitudes involved). So it
//! rejects a ray only where the f64 test would (whose padding is `1e-7` of the size): it changes
//! no hit, only how soon a miss is known.

use glam::Vec3A;

use super::Shell;

/// Padding relative to the lathe's size and to the ray origin's magnitude.
const COARSE_PAD: f32 = 1e-4;

/// The magnitudes the test works with: a lathe's size and its shells' values, the ray origin's
/// coordinates and the largest component of its direction. Within `1 / TAME..TAME` no product
/// or square below can overflow or fall into f32's subnormal range where it matters; outside it
/// the test does not judge (the lathe gets no coarse test, the ray is let through).
const TAME: f32 = 1e15;

/// A union shell for the coarse test: heights and radii padded by `COARSE_PAD` of the size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoarseShell {
    h0: f32,
    h1: f32,
    r0: f32,
    r1: f32,
    size: f32,
}

impl CoarseShell {
    /// The shell `s` of a lathe of size `size`. `None` for a lathe whose size or shell lies
    /// outside the magnitudes the f32 test judges ([`TAME`]): the caller then skips the coarse
    /// test.
    pub fn new(s: &Shell, size: f64) -> Option<Self> {
        let tame = f64::from(TAME);
        let judged = (1.0 / tame..=tame).contains(&size)
            && [s.hmin, s.hmax, s.rmin, s.rmax]
                .iter()
                .all(|v| v.abs() <= tame);
        if !judged {
            return None;
        }
        // The f64 values rounded to f32 move by at most an ulp of f32 (6e-8 relative, normal
        // numbers at these magnitudes), far inside the padding of each value's own magnitude.
        let pad = |v: f64| f64::from(COARSE_PAD) * (size + v.abs());
        Some(Self {
            h0: (s.hmin - pad(s.hmin)) as f32,
            h1: (s.hmax + pad(s.hmax)) as f32,
            r0: (s.rmin - pad(s.rmin)).max(0.0) as f32,
            r1: (s.rmax + pad(s.rmax)) as f32,
            size: size as f32,
        })
    }

    /// Whether the ray `o + t d` may come within the shell for some `t` in `(t_min, t_max)`:
    /// `false` only where it certainly does not (then the f64 test finds no hit either). Rays
    /// the test does not judge are let through: an origin or direction outside [`TAME`]'s
    /// magnitudes, an infinite `t_min`, and any whose slab ends or nearest approach to the
    /// axis do not come out finite.
    #[inline]
    pub fn may_meet(&self, o: Vec3A, d: Vec3A, t_min: f32, t_max: f32) -> bool {
        let (oa, da) = (o.abs(), d.abs());
        let tame = Vec3A::splat(TAME);
        // Lane by lane (a NaN lane fails its comparison; `max_element` would skip it).
        let judged = oa.cmple(tame).all()
            && da.cmple(tame).all()
            && da.max_element() >= 1.0 / TAME
            && t_min.is_finite();
        if !judged {
            return true;
        }
        let om = oa.max_element();
        // Every position computed below is off by a few f32 ulps of the origin's and the
        // shell's magnitudes at most: `slack` covers that a thousand times over.
        let slack = COARSE_PAD * (om + self.size);
        let (h0, h1) = (self.h0 - slack, self.h1 + slack);
        let (mut ta, mut tb) = (t_min, t_max);
        if d.y != 0.0 {
            let inv = 1.0 / d.y;
            let (u, v) = ((h0 - o.y) * inv, (h1 - o.y) * inv);
            // A reciprocal or slab end that overflows (a tiny `d_y`): not judged here.
            if !(u.is_finite() && v.is_finite()) {
                return true;
            }
            ta = ta.max(u.min(v));
            tb = tb.min(u.max(v));
        } else if !(o.y >= h0 && o.y <= h1) {
            return false;
        }
        // The slab's ends carry the rounding of a product and a quotient: widen them. (`ta`
        // came out finite, `t_min` and the slab's ends being finite, but the widening can
        // overflow for a `t_min` near `-f32::MAX`: not judged.)
        let (ta, tb) = (ta - COARSE_PAD * ta.abs(), tb + COARSE_PAD * tb.abs());
        if !ta.is_finite() {
            return true;
        }
        if ta > tb {
            return false;
        }
        // Squared distance from the axis at `t`: finite or a true overflow (`|o| <= TAME`, so
        // an infinite `t d` component means a point far beyond the shell), never NaN for a
        // finite `t`.
        let q = |t: f32| {
            let (x, z) = (o.x + t * d.x, o.z + t * d.z);
            x * x + z * z
        };
        let dh2 = d.x * d.x + d.z * d.z;
        let (qmin, qmax) = if dh2 >= f32::MIN_POSITIVE {
            // The nearest approach to the axis, clamped into the interval: the smallest
            // distance there (the interval widened above contains the exact one, so its
            // minimum is no larger).
            let tc = -(o.x * d.x + o.z * d.z) / dh2;
            if !tc.is_finite() {
                return true;
            }
            let c = tc.max(ta).min(tb);
            // (`q` of a finite `t` is never NaN, see above; a NaN would count as infinite.)
            let (qa, qb) = (q(ta), if tb.is_finite() { q(tb) } else { f32::NAN });
            let far = if qa.is_nan() || qb.is_nan() {
                f32::INFINITY
            } else {
                qa.max(qb)
            };
            (q(c), far)
        } else if d.x == 0.0 && d.z == 0.0 {
            let q0 = o.x * o.x + o.z * o.z;
            (q0, q0)
        } else {
            // A horizontal component too small to square: not judged here.
            return true;
        };
        let r1 = self.r1 + slack;
        let r0 = (self.r0 - slack).max(0.0);
        !(qmin > r1 * r1 || qmax < r0 * r0)
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::*;
    use crate::bezier::Solver;
    use crate::bezier::lathe::Lathe;
    use crate::sampling::Rng;

    /// A profile with a flat disk, a bulge, an annulus, a cusp and a pole, and a thin ring far
    /// from the origin (whose f32 coordinates round coarsely).
    fn lathes() -> Vec<Lathe> {
        let p = |pts: &[(f64, f64)]| pts.iter().map(|&(r, h)| DVec2::new(r, h)).collect();
        let mixed = Lathe::new(
            &[
                p(&[(0.0, 0.0), (0.3, 0.0), (0.6, 0.0)]),
                p(&[(0.6, 0.0), (0.6, 0.3), (0.2, 0.4), (0.5, 0.6)]),
                p(&[(0.5, 0.6), (0.3, 0.6)]),
                p(&[(0.3, 0.6), (0.6, 0.9), (0.3, 0.9), (0.6, 0.6)]),
                p(&[(0.6, 0.6), (0.6, 1.0), (0.3, 1.2), (0.0, 1.2)]),
            ],
            None,
        )
        .unwrap();
        let far_ring = Lathe::new(
            &[p(&[
                (3000.0, 5000.0),
                (3000.2, 5000.1),
                (3000.1, 5000.3),
                (3000.0, 5000.2),
            ])],
            None,
        )
        .unwrap();
        vec![mixed, far_ring]
    }

    /// Every hit the f64 intersector finds on a part, the coarse test lets through: rays at
    /// random, from the surface (as secondary rays leave it), grazing the shells' cylinders and
    /// slabs, horizontal, vertical, along the axis, from far away, with directions of lengths
    /// from 1e-20 to 1e18, and short windows. Both outcomes occur, so the test also shows that
    /// it rejects.
    #[test]
    fn the_coarse_test_lets_every_hit_through() {
        let mut rng = Rng::new(3);
        let mut f = move || rng.f32();
        let mut counts = [0usize; 3];
        for lathe in lathes() {
            let (lo, hi) = lathe.bounds();
            let (lo, hi) = (lo.as_vec3a(), hi.as_vec3a());
            let size = (hi - lo).max_element();
            let parts = lathe.separate_parts();
            let coarse: Vec<CoarseShell> = parts
                .iter()
                .map(|p| CoarseShell::new(&lathe.parts_shell(p).unwrap(), lathe.size()).unwrap())
                .collect();
            for case in 0..200_000 {
                let inside = lo + (hi - lo) * Vec3A::new(f(), f(), f());
                let dir = Vec3A::new(f() - 0.5, f() - 0.5, f() - 0.5).normalize_or(Vec3A::X);
                let (mut o, mut d) = (inside - dir * size * 2.0, dir);
                match case % 8 {
                    // From the surface, in any direction.
                    0 => {
                        let (p, _) = lathe.sample(DVec2::new(f() as f64, f() as f64)).unwrap();
                        o = p.as_vec3a();
                    }
                    1 => d.y = 0.0,
                    2 => d = Vec3A::new(0.0, if f() < 0.5 { 1.0 } else { -1.0 }, 0.0),
                    // Along the axis, or close to it.
                    3 => o = Vec3A::new(0.0, o.y, (f() - 0.5) * 1e-6 * size),
                    4 => {
                        o = inside - dir * size * 1e4;
                        d *= 1e-3;
                    }
                    // Grazing a part's shell cylinder at its inner or outer radius.
                    5 => {
                        let s = lathe.parts_shell(&parts[case / 8 % parts.len()]).unwrap();
                        let r = if f() < 0.5 { s.rmin } else { s.rmax } as f32;
                        let r = r * (1.0 + (f() - 0.5) * 1e-5);
                        let y = (s.hmin + (s.hmax - s.hmin) * f() as f64) as f32;
                        o = Vec3A::new(r, y, -2.0 * size - 3000.0);
                        d = Vec3A::new((f() - 0.5) * 1e-4, (f() - 0.5) * 1e-4, 1.0);
                    }
                    // Directions far from unit length, inside and outside the magnitudes
                    // the test judges.
                    6 => d *= [1e-20, 1e-12, 1e12, 1e18][case / 8 % 4],
                    _ => {}
                }
                let (t_min, t_max) = if case % 3 == 0 {
                    (0.0, f32::INFINITY)
                } else {
                    let a = f() * 4.0 * size / d.length();
                    (a, a + f() * size / d.length())
                };
                for (part, c) in parts.iter().zip(&coarse) {
                    let hit = lathe.intersect_parts(
                        part.clone(),
                        o.as_dvec3(),
                        d.as_dvec3(),
                        t_min as f64,
                        t_max as f64,
                        Solver::Robust,
                    );
                    let meets = c.may_meet(o, d, t_min, t_max);
                    assert!(
                        meets || hit.is_none(),
                        "case {case}: o {o}, d {d}, t in ({t_min}, {t_max}): rejected a hit {hit:?}"
                    );
                    counts[hit.is_some() as usize + meets as usize] += 1;
                }
            }
        }
        // Rejected, let through without a hit, let through with one: each often.
        assert!(counts.iter().all(|&n| n > 20_000), "{counts:?}");
    }

    /// Inputs that overflowed or underflowed an earlier version of the test into rejecting a
    /// hit: a horizontal direction of 1e20 (its square overflows), an origin at 1e20 (the dot
    /// product overflows), an infinite `t_min` or one near `-f32::MAX` (infinity times a zero
    /// component), a lathe of size 1e-44 (f32's subnormal steps exceed the padding), a slab
    /// beyond f32's range (`d_y` of 1.5e-38). Each either has no coarse test, is let through,
    /// or has no hit.
    #[test]
    fn extreme_magnitudes_are_let_through() {
        let p = |pts: &[(f64, f64)]| -> Vec<Vec<DVec2>> {
            vec![pts.iter().map(|&(r, h)| DVec2::new(r, h)).collect()]
        };
        let cylinder = Lathe::new(&p(&[(0.5, 0.0), (0.5, 1.0)]), None).unwrap();
        let huge = Lathe::new(&p(&[(1e17, -1e17), (1e17, 1e17)]), None).unwrap();
        let cone = Lathe::new(&p(&[(1.0, -1.0), (1.5, 1.0)]), None).unwrap();
        let tiny_h = 1.49 * f64::from(f32::from_bits(1));
        let tiny = Lathe::new(&p(&[(0.0, tiny_h), (1e-44, tiny_h)]), None).unwrap();
        let disk = Lathe::new(&p(&[(0.0, 0.0), (1.0, 0.0)]), None).unwrap();
        let inf = f32::INFINITY;
        let sub = f32::from_bits(1);
        let cases: [(&Lathe, Vec3A, Vec3A, f32, f32); 9] = [
            // `t_min` finite but its widening overflows.
            (
                &cylinder,
                Vec3A::new(0.0, 0.5, 0.0),
                Vec3A::Z,
                f32::MIN,
                0.1,
            ),
            (
                &cylinder,
                Vec3A::new(0.0, 0.5, 0.0),
                Vec3A::X,
                -3.4025e38,
                0.1,
            ),
            (
                &cylinder,
                Vec3A::new(-1.0, 0.5, 0.0),
                Vec3A::new(1e20, 0.0, 0.0),
                0.0,
                inf,
            ),
            (
                &cylinder,
                Vec3A::new(-1.0, 0.5, 0.0),
                Vec3A::new(1e20, 1e19, 0.0),
                0.0,
                1.0,
            ),
            (
                &huge,
                Vec3A::new(-1e20, 0.0, 0.0),
                Vec3A::new(1e19, 0.0, 0.0),
                0.0,
                100.0,
            ),
            (&cone, Vec3A::ZERO, Vec3A::Z, -inf, 0.5),
            (
                &tiny,
                Vec3A::new(3.0 * sub, 0.0, 0.0),
                Vec3A::new(0.0, 0.25, 0.0),
                5.0 * sub,
                1.0,
            ),
            (
                &disk,
                Vec3A::new(0.5, -10.0, 0.0),
                Vec3A::new(0.0, 1.5e-38, 0.0),
                0.0,
                inf,
            ),
            (
                &cylinder,
                Vec3A::new(-1.0, 0.5, 0.0),
                Vec3A::new(1.0, 0.0, 1e-30),
                0.0,
                inf,
            ),
        ];
        for (k, (lathe, o, d, t_min, t_max)) in cases.into_iter().enumerate() {
            for part in lathe.separate_parts() {
                let Some(c) = CoarseShell::new(&lathe.parts_shell(&part).unwrap(), lathe.size())
                else {
                    continue;
                };
                let hit = lathe.intersect_parts(
                    part,
                    o.as_dvec3(),
                    d.as_dvec3(),
                    t_min as f64,
                    t_max as f64,
                    Solver::Robust,
                );
                assert!(
                    c.may_meet(o, d, t_min, t_max) || hit.is_none(),
                    "case {k}: rejected a hit {hit:?}"
                );
            }
        }
    }
}
