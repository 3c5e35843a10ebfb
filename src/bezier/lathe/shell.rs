//! Per-segment culling: each profile segment is cut into [`PIECES`] parameter pieces, each
//! bounded by an annular shell (radii `rmin..rmax`, heights `hmin..hmax` from the piece's
//! control polygon, so the shell contains the swept piece). A ray can meet the piece's surface
//! only at a `t` where it is inside the shell; [`RayFrame::shells_entered`] decides that in
//! closed form (the ray's squared distance from the axis is a quadratic in `t`) and gives the ray's
//! entry into the shell's height slab, a lower bound on the `t` of any hit in the piece.

use super::frame::RayFrame;
use crate::bezier::bernstein::Bernstein;

/// Pieces per segment (uniform in the segment's parameter).
pub const PIECES: usize = 8;

/// The annular shell of one piece of a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shell {
    pub rmin: f64,
    pub rmax: f64,
    pub hmin: f64,
    pub hmax: f64,
}

impl Shell {
    /// The smallest shell holding both.
    pub fn union(self, o: Shell) -> Shell {
        Shell {
            rmin: self.rmin.min(o.rmin),
            rmax: self.rmax.max(o.rmax),
            hmin: self.hmin.min(o.hmin),
            hmax: self.hmax.max(o.hmax),
        }
    }

    /// The shells of the [`PIECES`] pieces of the segment `(r, h)`.
    pub fn of_segment(r: &Bernstein, h: &Bernstein) -> [Shell; PIECES] {
        std::array::from_fn(|k| {
            let (a, b) = (k as f64 / PIECES as f64, (k + 1) as f64 / PIECES as f64);
            let (rp, hp) = (r.restrict(a, b), h.restrict(a, b));
            let range = |p: &Bernstein| {
                p.coeffs()
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &c| {
                        (lo.min(c), hi.max(c))
                    })
            };
            let ((rmin, rmax), (hmin, hmax)) = (range(&rp), range(&hp));
            Shell {
                rmin: rmin.max(0.0),
                rmax,
                hmin,
                hmax,
            }
        })
    }
}

/// Padding of the shells, relative to the surface size: far above the rounding of the
/// quantities compared (f64, values of the size of the scene), far below any visible margin.
pub const SHELL_PAD: f64 = 1e-7;

/// `n` shells padded for a lathe of a given size, stored lane by lane as the test reads them:
/// heights `h0..h1` (padded), squared radii `r0sq` (inner, padded, at least 0) and `r1sq_slack`
/// (outer, padded, plus the slack allowed for the rounding of the ray's squared distance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellLanes<const N: usize> {
    h0: [f64; N],
    h1: [f64; N],
    r0sq: [f64; N],
    r1sq_slack: [f64; N],
}

/// The slack in squared distances from the axis: the ray's `q(t)` is computed from terms of the
/// size of the scene, which cancel in it.
pub fn shell_slack(size: f64) -> f64 {
    1e-12 * size * size
}

impl<const N: usize> ShellLanes<N> {
    /// The shells `s`, padded by [`SHELL_PAD`] of `size`.
    pub fn new(s: &[Shell; N], size: f64) -> Self {
        let pad = SHELL_PAD * size;
        let slack = shell_slack(size);
        Self {
            h0: std::array::from_fn(|k| s[k].hmin - pad),
            h1: std::array::from_fn(|k| s[k].hmax + pad),
            r0sq: std::array::from_fn(|k| {
                let r0 = (s[k].rmin - pad).max(0.0);
                r0 * r0
            }),
            r1sq_slack: std::array::from_fn(|k| {
                let r1 = s[k].rmax + pad;
                r1 * r1 + slack
            }),
        }
    }
}

/// The union shell of a segment and the shells of its [`PIECES`] pieces, padded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentShells {
    pub union: ShellLanes<1>,
    pub pieces: ShellLanes<PIECES>,
}

impl SegmentShells {
    pub fn new(union: &Shell, pieces: &[Shell; PIECES], size: f64) -> Self {
        Self {
            union: ShellLanes::new(&[*union], size),
            pieces: ShellLanes::new(pieces, size),
        }
    }
}

impl RayFrame {
    /// Which of the padded shells `s` the ray (unit direction) is inside somewhere on
    /// `(ta0, tb0)` (the caller's `(t_min, t_max)` widened by the pad), as a bit mask (bit `k`:
    /// shell `k`), and the smallest of their entries into the shells' height slabs (a lower
    /// bound on the `t` of every point of the interval inside them; infinite when none is
    /// entered). `slack` is [`shell_slack`] of the size.
    ///
    /// Each shell's test is branch-free arithmetic on its lane (the shells of a segment are
    /// tested in one pass); the ray's kind (`d_y` zero, or too small for a finite reciprocal)
    /// is decided once.
    #[inline(always)]
    pub fn shells_entered<const N: usize>(
        &self,
        s: &ShellLanes<N>,
        ta0: f64,
        tb0: f64,
        slack: f64,
    ) -> (u32, f64) {
        let (oy, dy, inv) = (self.o.y, self.dn.y, self.inv_dy);
        // Minimum and maximum as one comparison each, where no operand can be NaN for a
        // finite ray (or only the second, which a comparison ignores as `f64::min` does).
        let min = |a: f64, b: f64| if b < a { b } else { a };
        let max = |a: f64, b: f64| if b > a { b } else { a };
        let mut ta = [ta0; N];
        let mut tb = [tb0; N];
        if dy != 0.0 && inv.is_finite() {
            for k in 0..N {
                // A product with the reciprocal (no division per shell), its rounding (a few
                // ulps of the quotient) allowed for on the safe side.
                let (u, v) = ((s.h0[k] - oy) * inv, (s.h1[k] - oy) * inv);
                let (lo, hi) = (min(u, v), max(u, v));
                let lo = lo - 4.0 * f64::EPSILON * lo.abs();
                let hi = hi + 4.0 * f64::EPSILON * hi.abs();
                // Where the product overflows (`d_y` near the smallest normal) `lo` or `hi`
                // is an infinity minus itself, NaN: `f64::min` and `f64::max` take the other.
                ta[k] = max(ta0, lo.min(hi));
                tb[k] = min(tb0, lo.max(hi));
            }
        } else if dy != 0.0 {
            for k in 0..N {
                let (u, v) = ((s.h0[k] - oy) / dy, (s.h1[k] - oy) / dy);
                ta[k] = max(ta0, min(u, v));
                tb[k] = min(tb0, max(u, v));
            }
        } else {
            for k in 0..N {
                if !(oy >= s.h0[k] && oy <= s.h1[k]) {
                    // Outside the slab of a horizontal ray: an empty interval.
                    ta[k] = f64::INFINITY;
                    tb[k] = f64::NEG_INFINITY;
                }
            }
        }
        let (tc, rho2, dh2) = (self.tc, self.line_rho2, self.dh2);
        // Squared distance from the axis along the ray: line_rho2 + dh2 (t - tc)^2.
        let q = |t: f64| {
            let dt = t - tc;
            rho2 + dh2 * dt * dt
        };
        let mut inside = [false; N];
        if dh2 > 0.0 {
            for k in 0..N {
                let (a, b) = (ta[k], tb[k]);
                // `tc.clamp(a, b)` without its check of `a <= b` (tested here).
                let c = min(max(tc, a), b);
                let (qmin, qmax) = (q(c), max(q(a), q(b)));
                // `a <= b` is false also where either is NaN.
                inside[k] = (a <= b)
                    & (qmin * (1.0 - 1e-12) <= s.r1sq_slack[k])
                    & (qmax * (1.0 + 1e-12) + slack >= s.r0sq[k]);
            }
        } else {
            for k in 0..N {
                inside[k] = (ta[k] <= tb[k])
                    & (rho2 * (1.0 - 1e-12) <= s.r1sq_slack[k])
                    & (rho2 * (1.0 + 1e-12) + slack >= s.r0sq[k]);
            }
        }
        let mut mask = 0u32;
        let mut entry = f64::INFINITY;
        for k in 0..N {
            if inside[k] {
                mask |= 1 << k;
                entry = min(entry, ta[k]);
            }
        }
        (mask, entry)
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    /// The test of one shell as it was written before the lanes: each shell's values padded per
    /// call, `f64::clamp` after the check of the interval.
    fn shell_entry(f: &RayFrame, s: &Shell, tmin: f64, tmax: f64, size: f64) -> Option<f64> {
        let (o, dn) = (f.o, f.dn);
        let pad = SHELL_PAD * size;
        let (h0, h1) = (s.hmin - pad, s.hmax + pad);
        let (mut ta, mut tb) = (tmin - pad, tmax + pad);
        if dn.y != 0.0 {
            let (u, v) = if f.inv_dy.is_finite() {
                let (u, v) = ((h0 - o.y) * f.inv_dy, (h1 - o.y) * f.inv_dy);
                let (lo, hi) = (u.min(v), u.max(v));
                (
                    lo - 4.0 * f64::EPSILON * lo.abs(),
                    hi + 4.0 * f64::EPSILON * hi.abs(),
                )
            } else {
                ((h0 - o.y) / dn.y, (h1 - o.y) / dn.y)
            };
            ta = ta.max(u.min(v));
            tb = tb.min(u.max(v));
        } else if !(o.y >= h0 && o.y <= h1) {
            return None;
        }
        if ta.is_nan() || tb.is_nan() || ta > tb {
            return None;
        }
        let q = |t: f64| {
            let dt = t - f.tc;
            f.line_rho2 + f.dh2 * dt * dt
        };
        let (qmin, qmax) = if f.dh2 > 0.0 {
            (q(f.tc.clamp(ta, tb)), q(ta).max(q(tb)))
        } else {
            (f.line_rho2, f.line_rho2)
        };
        let (r0, r1) = ((s.rmin - pad).max(0.0), s.rmax + pad);
        let slack = 1e-12 * size * size;
        (qmin * (1.0 - 1e-12) <= r1 * r1 + slack && qmax * (1.0 + 1e-12) + slack >= r0 * r0)
            .then_some(ta)
    }

    /// The lanes decide as the one-shell test, bit for bit (mask and entry), on rays of every
    /// kind: random, horizontal (`d_y = 0`), with a subnormal `d_y` (no finite reciprocal),
    /// vertical, along the axis, grazing the shells' cylinders and slabs, with infinite `t_max`.
    #[test]
    fn lanes_decide_as_the_one_shell_test() {
        let mut rng = crate::sampling::Rng::new(7);
        // 53 random bits in [0, 1).
        let mut rnd = move || {
            let hi = (rng.next_u32() as u64) << 21;
            (hi | (rng.next_u32() as u64 >> 11)) as f64 / (1u64 << 53) as f64
        };
        let size = 1.3;
        let mut compared = [0usize; 2];
        for case in 0..200_000 {
            let shells: [Shell; PIECES] = std::array::from_fn(|_| {
                let (r0, r1) = (rnd() * 0.8, rnd() * 0.8);
                let (h0, h1) = (rnd() * 1.3, rnd() * 1.3);
                Shell {
                    rmin: r0.min(r1) * if rnd() < 0.2 { 0.0 } else { 1.0 },
                    rmax: r0.max(r1),
                    hmin: h0.min(h1),
                    hmax: if rnd() < 0.1 { h0.min(h1) } else { h0.max(h1) },
                }
            });
            let lanes = ShellLanes::new(&shells, size);
            let target = DVec3::new(rnd() - 0.5, rnd() * 1.3, rnd() - 0.5) * 1.6;
            let o = DVec3::new(rnd() - 0.5, rnd() * 1.3, rnd() - 0.5) * 4.0;
            let mut d = (target - o).normalize();
            match case % 8 {
                0 => d.y = 0.0,
                // A reciprocal that overflows (no finite `1 / d_y`), and one that is finite
                // but overflows in the products.
                1 => d.y = if rnd() < 0.5 { 1e-310 } else { 6e-309 },
                2 => d = DVec3::Y * if rnd() < 0.5 { 1.0 } else { -1.0 },
                3 => d.y *= 1e-9,
                _ => {}
            }
            let d = d.normalize();
            let d = if d.is_finite() { d } else { DVec3::X };
            let o = if case % 16 == 5 {
                // On the axis.
                DVec3::new(0.0, o.y, 0.0)
            } else {
                o
            };
            let frame = RayFrame::new(o, d, 0.0, 1.3);
            let tmin = if rnd() < 0.5 { 0.0 } else { rnd() };
            let tmax = if rnd() < 0.3 {
                f64::INFINITY
            } else {
                tmin + rnd() * 5.0
            };
            let pad = SHELL_PAD * size;
            let (mask, entry) =
                frame.shells_entered(&lanes, tmin - pad, tmax + pad, shell_slack(size));
            let mut want = (0u32, f64::INFINITY);
            for (k, s) in shells.iter().enumerate() {
                if let Some(t) = shell_entry(&frame, s, tmin, tmax, size) {
                    want = (want.0 | 1 << k, want.1.min(t));
                }
            }
            assert_eq!((mask, entry), want, "case {case}: o {o}, d {d}");
            compared[(mask != 0) as usize] += 1;
        }
        // Both outcomes occur often enough for the comparison to mean something.
        assert!(compared[0] > 10_000 && compared[1] > 10_000, "{compared:?}");
    }
}
