//! Reference intersectors: slow, simple, and obviously right, for the stress tests.
//!
//! They share no root finder with the production code. The lathe reference evaluates `F(s)`
//! pointwise from the profile (never through the product polynomial) and isolates roots by
//! coarse-to-fine subdivision with global Lipschitz bounds: an interval is dropped when
//! `|F(mid)| > min(L1 * w / 2, |F'(mid)| w / 2 + L2 w^2 / 8)` (no root can be reached), a monotone interval (`|F'(mid)| > L2 * w / 2`)
//! holds at most one root, found by plain bisection. An interval that is neither by the time it is
//! [`AMBIGUOUS_WIDTH`] wide is a near-double root the reference cannot decide: the ray is flagged
//! ambiguous and left out of the comparison (and counted). Rays exactly perpendicular to the axis
//! take a separate route (roots of `h(s) = o_y` and the circle at that height).
//! The patch reference is uniform quadtree subdivision with projected bounds down to leaves
//! [`PATCH_LEAF`] of the patch size, no Newton step.

use glam::{DVec2, DVec3};

use sppm_lang::internals::bezier::lathe::{Lathe, Part, RayFrame, Segment};
use sppm_lang::internals::bezier::roots::bracket::Refine;
use sppm_lang::internals::bezier::roots::{Root, RootKind};

/// Width in `s` below which the lathe reference gives up deciding.
pub const AMBIGUOUS_WIDTH: f64 = 1e-11;
/// Leaf size of the patch reference, relative to the patch size.
pub const PATCH_LEAF: f64 = 1e-10;

/// The reference's answer for one ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefHit {
    /// Nearest hit `t` (in units of the given direction), if any.
    pub t: Option<f64>,
    /// The reference met a root it cannot decide (a near tangency): do not compare.
    pub ambiguous: bool,
}

struct Bounds {
    l1: f64,
    l2: f64,
    noise: f64,
}

fn deriv_bounds(p: &[f64]) -> (f64, f64, f64) {
    let n = p.len() - 1;
    let b0 = p.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let b1 = p.windows(2).fold(0.0f64, |m, w| m.max((w[1] - w[0]).abs())) * n as f64;
    let b2 = if n >= 2 {
        p.windows(3)
            .fold(0.0f64, |m, w| m.max((w[2] - 2.0 * w[1] + w[0]).abs()))
            * (n * (n - 1)) as f64
    } else {
        0.0
    };
    (b0, b1, b2)
}

fn lipschitz(frame: &RayFrame, seg: &Segment) -> Bounds {
    let (oc, dn) = (frame.oc, frame.dn);
    let (r0, r1, r2) = deriv_bounds(seg.r.coeffs());
    let hs: Vec<f64> = seg.h.coeffs().iter().map(|h| h - oc.y).collect();
    let (h0, h1, h2) = deriv_bounds(&hs);
    let amax = (oc.x * dn.y).abs() + h0 * dn.x.abs();
    let bmax = (oc.z * dn.y).abs() + h0 * dn.z.abs();
    let dy2 = dn.y * dn.y;
    let l1 = 2.0 * (amax * h1 * dn.x.abs() + bmax * h1 * dn.z.abs() + dy2 * r0 * r1);
    let l2 = 2.0
        * (h1 * h1 * frame.dh2
            + amax * h2 * dn.x.abs()
            + bmax * h2 * dn.z.abs()
            + dy2 * (r1 * r1 + r0 * r2));
    let noise = 64.0 * f64::EPSILON * (amax * amax + bmax * bmax + dy2 * r0 * r0);
    Bounds { l1, l2, noise }
}

fn isolate(g: &dyn Fn(f64) -> (f64, f64), b: &Bounds, lo: f64, hi: f64, out: &mut Vec<Root>) {
    let (m, w) = (0.5 * (lo + hi), hi - lo);
    let (fm, dfm) = g(m);
    // Drop the interval when no root can be reached from the midpoint, by either bound:
    // first order (global Lipschitz bound of F) or second order (Taylor at the midpoint with the
    // global bound of F''). The second is needed near a pole, where F' -> 0 and F grows
    // quadratically: there the first-order bound alone cannot drop an interval wider than ~F,
    // which pushed near-pole rays to the ambiguity width.
    let reach2 = dfm.abs() * (1.0 + 1e-9) * 0.5 * w + b.l2 * 0.125 * w * w;
    if fm.abs() - b.noise > (b.l1 * 0.5 * w).min(reach2) {
        return;
    }
    if dfm.abs() > b.l2 * 0.5 * w {
        let (fa, fb) = (g(lo).0, g(hi).0);
        if fa * fb <= 0.0 {
            let (mut a, mut c) = (lo, hi);
            for _ in 0..200 {
                let mid = 0.5 * (a + c);
                if mid <= a || mid >= c {
                    break;
                }
                if (g(mid).0 < 0.0) == (fa < 0.0) && fa != 0.0 {
                    a = mid;
                } else {
                    c = mid;
                }
            }
            let t = 0.5 * (a + c);
            out.push(Root {
                t,
                lo: a,
                hi: c,
                kind: RootKind::Simple,
            });
        }
        return;
    }
    if w <= AMBIGUOUS_WIDTH {
        out.push(Root {
            t: m,
            lo,
            hi,
            kind: RootKind::Multiple,
        });
        return;
    }
    isolate(g, b, lo, m, out);
    isolate(g, b, m, hi, out);
}

/// Reference intersection with a lathe (side and caps).
pub fn lathe(lathe: &Lathe, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> RefHit {
    let dl = d.length();
    let (lo, hi) = lathe.bounds();
    let frame = RayFrame::new(o, d / dl, lo.y, hi.y);
    let dn = frame.dn;
    let (tmin, mut best) = (t_min * dl, t_max * dl);
    let mut found: Option<(f64, Part, f64)> = None;
    let mut ambiguous = false;
    let size = lathe.size();
    let mut roots = Vec::new();
    for (i, seg) in lathe.segments().iter().enumerate() {
        if seg.degenerate {
            continue;
        }
        roots.clear();
        let mut cands: Vec<(f64, f64)> = Vec::new();
        if dn.x == 0.0 && dn.z == 0.0 && o.x == 0.0 && o.z == 0.0 {
            // Along the axis itself: only the profile's points on the axis (its poles) are hit.
            for s in [0.0, 1.0] {
                if seg.r.eval(s) == 0.0 {
                    cands.push(((seg.h.eval(s) - o.y) / dn.y, s));
                }
            }
        } else if dn.y == 0.0 {
            // Perpendicular to the axis: the heights h(s) = o_y, then the circle there.
            let g = |s: f64| {
                let (h, dh) = seg.h.eval_with_derivative(s);
                (h - o.y, dh)
            };
            let hs: Vec<f64> = seg.h.coeffs().iter().map(|h| h - o.y).collect();
            let (h0, h1, h2) = deriv_bounds(&hs);
            let b = Bounds {
                l1: h1,
                l2: h2,
                noise: 64.0 * f64::EPSILON * h0,
            };
            for k in 0..16 {
                isolate(&g, &b, k as f64 / 16.0, (k + 1) as f64 / 16.0, &mut roots);
            }
            for root in &roots {
                if root.kind == RootKind::Multiple {
                    ambiguous = true;
                    continue;
                }
                let r = seg.r.eval(root.t);
                // Ray o + t dn in the plane y = o_y: |o_xz + t dn_xz|^2 = r^2.
                let (p, q) = (DVec2::new(o.x, o.z), DVec2::new(dn.x, dn.z));
                let (a, bq, c) = (q.dot(q), 2.0 * p.dot(q), p.dot(p) - r * r);
                let disc = bq * bq - 4.0 * a * c;
                if disc >= 0.0 {
                    let sq = disc.sqrt();
                    cands.push(((-bq - sq) / (2.0 * a), root.t));
                    cands.push(((-bq + sq) / (2.0 * a), root.t));
                }
            }
        } else {
            let b = lipschitz(&frame, seg);
            let g = |s: f64| frame.eval_pointwise(seg, s);
            for k in 0..16 {
                isolate(&g, &b, k as f64 / 16.0, (k + 1) as f64 / 16.0, &mut roots);
            }
            for root in &roots {
                if root.kind == RootKind::Multiple {
                    ambiguous = true;
                    continue;
                }
                let (_, df) = g(root.t);
                let ds = b.noise / df.abs().max(1e-300);
                for (t, s) in
                    frame.candidates(seg, root, ds, size, Refine::Bisection, tmin, None, false)
                {
                    if t.is_finite() {
                        cands.push(polish_hit(seg, o, dn, t, s));
                    }
                }
            }
        }
        for (t, s) in cands {
            let p = o + t * dn;
            let in_sweep = match lathe.sweep() {
                None => true,
                Some((a0, span)) => (p.z.atan2(p.x) - a0).rem_euclid(std::f64::consts::TAU) <= span,
            };
            if t > tmin && t < best && in_sweep {
                best = t;
                found = Some((t, Part::Side(i), s));
            }
        }
    }
    lathe.cap_hits(&frame, tmin, &mut best, &mut found);
    RefHit {
        t: found.map(|f| f.0 / dl),
        ambiguous,
    }
}

/// Newton steps on the pair `h(s) = o_y + t d_y`, `r(s)^2 = |o_xz + t d_xz|^2` (unit `d`) from
/// a candidate `(t, s)`, the residuals in double-double arithmetic (a value of `g` in f64 is
/// noisy at 1e-16 of the size, and along a nearly tangent ray that noise moves `t` by
/// `1e-16 / sin(angle)`: 1e-11 at an angle of 2e-5, over 1e-6 of a `t` of 5e-6). Kept only if
/// the steps converge and move `s` by less than 1e-9 (the same root); else the candidate as is.
fn polish_hit(seg: &Segment, o: DVec3, d: DVec3, t0: f64, s0: f64) -> (f64, f64) {
    let (mut t, mut s) = (t0, s0);
    let mut last_step = f64::INFINITY;
    for _ in 0..8 {
        let (r, dr) = seg.r.eval_with_derivative(s);
        let (_, dh) = seg.h.eval_with_derivative(s);
        let (x, z) = (dd_fma(o.x, t, d.x), dd_fma(o.z, t, d.z));
        let f1 = dd_add(dd_bezier(seg.h.coeffs(), s), dd_neg(dd_fma(o.y, t, d.y))).0;
        let rr = dd_bezier(seg.r.coeffs(), s);
        let f2 = dd_add(dd_mul(rr, rr), dd_neg(dd_add(dd_mul(x, x), dd_mul(z, z)))).0;
        // J = [[h', -d_y], [2 r r', -2 (x d_x + z d_z)]]
        let (a, b, c, e) = (dh, -d.y, 2.0 * r * dr, -2.0 * (x.0 * d.x + z.0 * d.z));
        let det = a * e - b * c;
        if det == 0.0 || !det.is_finite() {
            return (t0, s0);
        }
        let (step_s, step_t) = ((f1 * e - b * f2) / det, (a * f2 - c * f1) / det);
        (s, t) = (s - step_s, t - step_t);
        if !(s.is_finite() && t.is_finite()) || (s - s0).abs() > 1e-9 {
            return (t0, s0);
        }
        if step_t.abs() <= 4.0 * f64::EPSILON * t.abs() && step_s.abs() <= 4.0 * f64::EPSILON {
            return (t, s);
        }
        last_step = step_s.abs();
    }
    // Still moving by an ulp or two: converged to rounding.
    if last_step <= 64.0 * f64::EPSILON {
        (t, s)
    } else {
        (t0, s0)
    }
}

/// Double-double numbers `(hi, lo)`, value `hi + lo`.
type Dd = (f64, f64);

fn two_sum(a: f64, b: f64) -> Dd {
    let s = a + b;
    let v = s - a;
    (s, (a - (s - v)) + (b - v))
}

fn dd_add(a: Dd, b: Dd) -> Dd {
    let (s, e) = two_sum(a.0, b.0);
    let (h, l) = two_sum(s, e + a.1 + b.1);
    (h, l)
}

fn dd_neg(a: Dd) -> Dd {
    (-a.0, -a.1)
}

fn dd_mul(a: Dd, b: Dd) -> Dd {
    let p = a.0 * b.0;
    let e = a.0.mul_add(b.0, -p) + (a.0 * b.1 + a.1 * b.0);
    two_sum(p, e)
}

/// `a + t b` for f64 inputs, in double-double.
fn dd_fma(a: f64, t: f64, b: f64) -> Dd {
    dd_add((a, 0.0), dd_mul((t, 0.0), (b, 0.0)))
}

/// de Casteljau's algorithm in double-double at an f64 parameter.
fn dd_bezier(c: &[f64], s: f64) -> Dd {
    let u = two_sum(1.0, -s);
    let mut b: Vec<Dd> = c.iter().map(|&v| (v, 0.0)).collect();
    for k in (1..b.len()).rev() {
        for i in 0..k {
            b[i] = dd_add(dd_mul(b[i], u), dd_mul(b[i + 1], (s, 0.0)));
        }
    }
    b[0]
}

/// Reference intersection with a bicubic patch: subdivision with projected bounds to leaves of
/// [`PATCH_LEAF`] of the patch size, the leaf centre as the answer (`t` for `d` as given).
/// A leaf fixes the hit's position to its size, so along a ray at angle `theta` to the surface
/// it fixes `t` only to `leaf / sin(theta)`: when that exceeds 1e-7 of `t` the ray is flagged
/// ambiguous (a near-tangent ray whose `t` no method can pin down to 1e-6).
pub fn patch(
    patch: &sppm_lang::internals::bezier::patch::Patch,
    o: DVec3,
    d: DVec3,
    t_min: f64,
    t_max: f64,
) -> RefHit {
    let dl = d.length();
    let dn = d / dl;
    let (e1, e2) = dn.any_orthonormal_pair();
    let found = patch.subdivide(o, [e1, e2, dn], t_min * dl, t_max * dl, PATCH_LEAF, false);
    let ambiguous = found.is_some_and(|(uv, t)| {
        let sin = patch.normal(uv.x, uv.y).dot(dn).abs();
        PATCH_LEAF * patch.size() > 1e-7 * t * sin
    });
    RefHit {
        t: found.map(|(_, t)| t / dl),
        ambiguous,
    }
}
