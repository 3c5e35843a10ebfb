//! Root isolation on [0, 1] for Bernstein polynomials that cannot miss a root.
//!
//! Recursive subdivision with the convex-hull property: if every Bernstein coefficient on an
//! interval has the same strict sign beyond the rounding noise, the polynomial has no root there.
//! If the control polygon has exactly one sign change and the end values have opposite signs,
//! the interval holds exactly one simple root (Descartes' rule of signs for the Bernstein basis);
//! it is polished by Newton steps safeguarded by bisection inside that bracket. Anything else is
//! split in two. An interval that shrinks below [`LEAF_WIDTH`] while its coefficients still come
//! within the noise of zero is a cluster (a double root: a grazing ray) and is reported as one
//! [`RootKind::Multiple`] root at its middle. An interval whose coefficients all lie within the
//! noise (the polynomial vanishes there) is reported whole, without further splitting.

use super::bernstein::Bernstein;

pub mod bracket;

/// Width (in the original [0, 1] parameter) below which an unresolved interval becomes a cluster.
pub const LEAF_WIDTH: f64 = 1.0 / (1u64 << 40) as f64;

/// How a root was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RootKind {
    /// A sign change inside a bracket that holds exactly one root.
    Simple,
    /// An unresolvable cluster: a double (or higher) root, or a touch within rounding noise.
    Multiple,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Root {
    pub t: f64,
    /// A bracket known to contain the root (for `Multiple`, the cluster interval).
    pub lo: f64,
    pub hi: f64,
    pub kind: RootKind,
}

/// Rounding noise of a polynomial's values: a few ulps of its largest coefficient.
pub fn noise_of(p: &Bernstein) -> f64 {
    p.max_abs() * 64.0 * f64::EPSILON * (p.degree() as f64 + 1.0)
}

/// All roots of `p` in [0, 1], ascending, appended to `out`.
pub fn find_roots(p: &Bernstein, out: &mut Vec<Root>) {
    find_roots_with_noise(p, noise_of(p), out);
}

/// Like [`find_roots`] with an explicit noise level (values within `noise` of zero count as zero).
pub fn find_roots_with_noise(p: &Bernstein, noise: f64, out: &mut Vec<Root>) {
    isolate(p, 0.0, 1.0, noise, 0, out);
}

/// The roots of `p` in `[a, b]` (a sub-interval of [0, 1]), ascending, appended to `out`:
/// isolated on the restriction of `p` to `[a, b]` (smaller coefficients' hull, fewer splits) and
/// mapped back to `p`'s parameter.
pub fn find_roots_on(p: &Bernstein, a: f64, b: f64, noise: f64, out: &mut Vec<Root>) {
    isolate(&p.restrict(a, b), a, b, noise, 0, out);
}

fn isolate(p: &Bernstein, a: f64, b: f64, noise: f64, depth: u32, out: &mut Vec<Root>) {
    let c = p.coeffs();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    // Comparisons skip a NaN coefficient as `f64::min` and `f64::max` do (`lo` and `hi` start
    // as numbers), at one instruction each.
    for &v in c {
        if v < lo {
            lo = v;
        }
        if v > hi {
            hi = v;
        }
    }
    if !(lo <= noise && hi >= -noise) {
        // Every coefficient beyond the noise on one side (or NaN): no root by the hull property.
        return;
    }
    if lo >= -noise && hi <= noise {
        // The polynomial vanishes here within rounding: one cluster for the whole interval.
        push(out, a, b);
        return;
    }
    let (c0, cn) = (c[0], c[c.len() - 1]);
    if c0 * cn < 0.0 && sign_changes(c) == 1 {
        let (t, l, h, _) = polish(p, c0);
        out.push(Root {
            t: a + (b - a) * t,
            lo: a + (b - a) * l,
            hi: a + (b - a) * h,
            kind: RootKind::Simple,
        });
        return;
    }
    if b - a <= LEAF_WIDTH || depth > 64 {
        push(out, a, b);
        return;
    }
    // Split at the middle unless the middle is itself (nearly) a root: then move the split so
    // that the root lies inside one half rather than on the seam.
    // The split's shared end coefficient is the value at the split point.
    let (mut tau, mut halves) = (0.5, p.split(0.5));
    if halves.0.coeffs()[p.degree()].abs() <= noise {
        for cand in [0.4375, 0.5625, 0.40625, 0.59375] {
            if p.eval(cand).abs() > noise {
                tau = cand;
                halves = p.split(cand);
                break;
            }
        }
    }
    let (l, r) = halves;
    let m = a + (b - a) * tau;
    isolate(&l, a, m, noise, depth + 1, out);
    isolate(&r, m, b, noise, depth + 1, out);
}

/// Appends a cluster, merging it with a cluster that ends where this one starts.
fn push(out: &mut Vec<Root>, a: f64, b: f64) {
    if let Some(last) = out.last_mut()
        && last.kind == RootKind::Multiple
        && last.hi >= a
    {
        last.hi = b;
        last.t = 0.5 * (last.lo + last.hi);
        return;
    }
    out.push(Root {
        t: 0.5 * (a + b),
        lo: a,
        hi: b,
        kind: RootKind::Multiple,
    });
}

fn sign_changes(c: &[f64]) -> usize {
    let mut n = 0;
    let mut prev = 0.0;
    for &v in c {
        if v != 0.0 {
            if prev != 0.0 && (v < 0.0) != (prev < 0.0) {
                n += 1;
            }
            prev = v;
        }
    }
    n
}

/// Newton iteration safeguarded by bisection in [0, 1] where `p(0)` has the sign of `c0` and
/// `p(1)` the opposite one. Returns the root, its final bracket and the number of evaluations.
fn polish(p: &Bernstein, c0: f64) -> (f64, f64, f64, u32) {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    let c = p.coeffs();
    let n = p.degree();
    // Start where the control polygon crosses zero (its one sign change): after the
    // subdivision that isolated the root the polygon lies closer to the curve than the chord
    // between the end values, the start where a coefficient at the crossing is zero.
    let mut t = match c.windows(2).position(|w| (w[0] < 0.0) != (w[1] < 0.0)) {
        Some(k) if c[k] != 0.0 && c[k + 1] != 0.0 => {
            ((k as f64 + c[k] / (c[k] - c[k + 1])) / n as f64).clamp(0.0, 1.0)
        }
        _ => (c0 / (c0 - c[n])).clamp(0.0, 1.0),
    };
    let mut evals = 0;
    for _ in 0..200 {
        let (v, dv) = p.eval_with_derivative(t);
        evals += 1;
        if v == 0.0 {
            return (t, t, t, evals);
        }
        narrow(v, c0, t, &mut lo, &mut hi);
        if hi - lo <= f64::EPSILON * hi.max(1e-300) {
            break;
        }
        let newton = t - v / dv;
        // Converged to rounding: the step moves the point by a few ulps at most. It may round
        // onto `t` itself or just past the end of the bracket at `t`; bisecting then would only
        // walk the bracket down to `t` in about 50 steps.
        if newton.is_finite() && (newton - t).abs() <= 4.0 * f64::EPSILON * t.abs().max(1e-300) {
            // `t` is one end of the bracket; the root lies toward the other.
            let right = lo == t;
            if newton > lo && newton < hi {
                t = newton;
            }
            // Close the far end of the bracket onto the root: one evaluation a few ulps past
            // it (the callers search the bracket again, widened by the root's uncertainty).
            let e = 4.0 * f64::EPSILON * t.abs().max(1e-300);
            let q = if right { t + e } else { t - e };
            if q > lo && q < hi {
                let v = p.eval(q);
                evals += 1;
                if v == 0.0 {
                    return (q, q, q, evals);
                }
                narrow(v, c0, q, &mut lo, &mut hi);
            }
            break;
        }
        let next = if newton > lo && newton < hi && newton.is_finite() {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if next == t {
            break;
        }
        t = next;
    }
    (t.clamp(lo, hi), lo, hi, evals)
}

/// Moves the end of the bracket `[lo, hi]` whose value has the sign of `v` (the sign of `c0`
/// at `lo`) to `x`.
fn narrow(v: f64, c0: f64, x: f64, lo: &mut f64, hi: &mut f64) {
    if (v < 0.0) == (c0 < 0.0) {
        *lo = x;
    } else {
        *hi = x;
    }
}

/// How far a root of `f` at `s` may be from the computed one given value noise `noise`:
/// `noise / |f'|` near a simple root, `sqrt(2 noise / |f''|)` near a double one.
pub fn root_uncertainty(f: &Bernstein, s: f64, noise: f64) -> f64 {
    root_spread(f, s, noise).0
}

/// [`root_uncertainty`] and `|f'(s)|`, both from one de Casteljau pass at `s`.
pub fn root_spread(f: &Bernstein, s: f64, noise: f64) -> (f64, f64) {
    let (_, d1, d2) = f.eval_with_two_derivatives(s);
    let (d1, d2) = (d1.abs(), d2.abs());
    let ds = (noise / d1.max(1e-300)).min((2.0 * noise / d2.max(1e-300)).sqrt());
    (ds, d1)
}

/// The bracket of `root` widened by 4 times its uncertainty `ds` (see [`root_uncertainty`]),
/// within [0, 1]: where the lathe searches the factors of its polynomial again.
pub fn widened(root: &Root, ds: f64) -> (f64, f64) {
    ((root.lo - 4.0 * ds).max(0.0), (root.hi + 4.0 * ds).min(1.0))
}

/// Whether `f` is certified strictly monotone on `[lo, hi]`, an interval of [0, 1] holding
/// `s`, so that it has at most one root there: `|f'| >= slope - (bound + e2) w - e1 > 0` on
/// it, with `slope = |f'(s)|` as computed, `bound` = [`Bernstein::second_derivative_bound`]
/// of `f`, `w` the largest distance from `s` to an end, and allowances for the rounding:
/// `f`'s coefficients differ from the exact polynomial's by at most `noise` each, which moves
/// `f'` by at most `2 n noise` and `f''` by at most `4 n (n - 1) noise`; the computed slope
/// and bound are allowed twice that. NaN anywhere refuses.
pub fn strictly_monotone_on(
    degree: usize,
    slope: f64,
    bound: f64,
    noise: f64,
    s: f64,
    lo: f64,
    hi: f64,
) -> bool {
    let n = degree as f64;
    let w = (s - lo).max(hi - s);
    let e1 = 4.0 * n * noise;
    let e2 = 8.0 * n * (n - 1.0) * noise;
    slope - (bound + e2) * w - e1 > 0.0 && lo <= s && s <= hi
}

/// Newton iteration on `f` from `starts` evenly spaced starting guesses, keeping what converges
/// into [0, 1] (within `1e3 noise` of zero). It can miss roots: it is kept for comparison
/// ([`super::Solver::Newton`]).
pub fn newton_roots(f: &Bernstein, noise: f64, iterations: u32, starts: u32, out: &mut Vec<Root>) {
    let starts = starts.max(1);
    for k in 0..starts {
        let mut s = (k as f64 + 0.5) / starts as f64;
        for _ in 0..iterations {
            let (v, dv) = f.eval_with_derivative(s);
            if dv == 0.0 || !dv.is_finite() {
                break;
            }
            s -= v / dv;
            if !(-0.5..=1.5).contains(&s) {
                break;
            }
        }
        if (0.0..=1.0).contains(&s) && f.eval(s).abs() <= 1e3 * noise {
            out.push(Root {
                t: s,
                lo: s,
                hi: s,
                kind: RootKind::Simple,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_roots(roots: &[f64]) -> Bernstein {
        roots.iter().fold(Bernstein::constant(1.0), |p, &r| {
            p.mul(&Bernstein::new(&[-r, 1.0 - r]).unwrap()).unwrap()
        })
    }

    fn roots_of(p: &Bernstein) -> Vec<Root> {
        let mut v = Vec::new();
        find_roots(p, &mut v);
        v
    }

    #[test]
    fn finds_simple_roots_in_order() {
        let want = [0.01, 0.2, 0.2001, 0.5, 0.77, 0.999];
        let got = roots_of(&from_roots(&want));
        assert_eq!(got.len(), want.len(), "{got:?}");
        for (g, w) in got.iter().zip(want) {
            assert_eq!(g.kind, RootKind::Simple);
            assert!((g.t - w).abs() < 1e-13, "{} vs {w}", g.t);
            assert!(g.lo <= g.t && g.t <= g.hi);
        }
    }

    /// Newton's last step rounds onto the end of the bracket it stands on (or just past it):
    /// that is convergence, not a reason to bisect the rest of the bracket down to that end
    /// (which took about 30 evaluations on this polynomial, a ray's `F` on one bracket).
    #[test]
    fn polish_stops_when_the_newton_step_rounds_onto_the_bracket_end() {
        let c = [
            0.003631321892035835,
            0.0013817331620761433,
            -0.0009557917372353128,
            -0.0033226467764470168,
            -0.005667694120536526,
            -0.007946657657748126,
            -0.010121552698214875,
        ];
        let p = Bernstein::new(&c).unwrap();
        let (t, lo, hi, evals) = polish(&p, c[0]);
        assert!(evals <= 8, "{evals} evaluations");
        assert!(lo <= t && t <= hi && p.eval(lo) >= 0.0 && p.eval(hi) <= 0.0);
        // The root to the last bit by bisection, for comparison.
        let (mut a, mut b) = (0.0f64, 1.0f64);
        while b - a > f64::EPSILON * b {
            let m = 0.5 * (a + b);
            if p.eval(m) > 0.0 { a = m } else { b = m }
        }
        assert!((t - a).abs() <= 4.0 * f64::EPSILON * a, "{t} vs {a}");
        // Every root of a product of linear factors polishes in a few evaluations.
        for k in 1..100 {
            let r = k as f64 / 100.0;
            let p = from_roots(&[r, 1.3, -0.2, 0.5 * r - 0.7]);
            let c0 = p.coeffs()[0];
            let (t, _, _, evals) = polish(&p, c0);
            assert!((t - r).abs() <= 1e-15, "{t} vs {r}");
            assert!(evals <= 12, "root {r}: {evals} evaluations");
        }
    }

    /// The certificate of monotonicity: taken on a transversal root's widened bracket,
    /// refused where the bracket holds two roots (or a double one), and never given where the
    /// derivative changes sign on the interval (checked densely on random polynomials).
    #[test]
    fn monotone_certificate_is_sound_and_refuses_two_roots() {
        let certify = |p: &Bernstein, root: &Root| {
            let noise = noise_of(p);
            let (ds, slope) = root_spread(p, root.t, noise);
            let (lo, hi) = widened(root, ds);
            let bound = p.second_derivative_bound();
            strictly_monotone_on(p.degree(), slope, bound, noise, root.t, lo, hi)
        };
        // Transversal roots: every one certified.
        let p = from_roots(&[0.2, 0.5, 0.77, 1.3, -0.4, 0.9]);
        let roots = roots_of(&p);
        assert_eq!(roots.len(), 4);
        assert!(roots.iter().all(|r| certify(&p, r)), "{roots:?}");
        // Two roots 1e-9 apart: one cluster or two brackets, each refused.
        let p = from_roots(&[0.4, 0.4 + 1e-9, 1.5]);
        let roots = roots_of(&p);
        assert!(!roots.is_empty());
        assert!(roots.iter().all(|r| !certify(&p, r)), "{roots:?}");
        // The same pair given as one bracket around both (as a widened bracket can be).
        let two = Root {
            t: 0.4,
            lo: 0.4 - 1e-7,
            hi: 0.4 + 1e-7,
            kind: RootKind::Simple,
        };
        let p = from_roots(&[0.4, 0.4 + 1e-8, 1.5]);
        let noise = noise_of(&p);
        let slope = p.eval_with_derivative(two.t).1.abs();
        let bound = p.second_derivative_bound();
        assert!(!strictly_monotone_on(
            6, slope, bound, noise, two.t, two.lo, two.hi
        ));
        // Soundness: where certified, f' keeps its sign on the interval.
        let mut x = 0.5f64;
        let mut next = || {
            x = (x * 3.987_654_321 + 0.314_159).fract();
            x
        };
        let mut certified = 0;
        for _ in 0..20_000 {
            let n = 2 + (next() * 6.0) as usize;
            let c: Vec<f64> = (0..=n).map(|_| next() - 0.5).collect();
            let p = Bernstein::new(&c).unwrap();
            let s = next();
            let w = 10f64.powf(-1.0 - 8.0 * next());
            let (lo, hi) = ((s - w * next()).max(0.0), (s + w * next()).min(1.0));
            let noise = noise_of(&p);
            let slope = p.eval_with_derivative(s).1.abs();
            let bound = p.second_derivative_bound();
            if !strictly_monotone_on(n, slope, bound, noise, s, lo, hi) {
                continue;
            }
            certified += 1;
            let sign = p.eval_with_derivative(s).1 > 0.0;
            for k in 0..=64 {
                let q = lo + (hi - lo) * k as f64 / 64.0;
                let d = p.eval_with_derivative(q).1;
                assert!(
                    d != 0.0 && (d > 0.0) == sign,
                    "{c:?} on [{lo}, {hi}] at {q}: {d}"
                );
            }
        }
        assert!(certified > 5_000, "{certified}");
    }

    #[test]
    fn ignores_roots_outside_the_interval() {
        let got = roots_of(&from_roots(&[-0.5, 0.3, 1.5, 2.0]));
        assert_eq!(got.len(), 1);
        assert!((got[0].t - 0.3).abs() < 1e-14);
    }

    #[test]
    fn double_root_is_one_cluster() {
        // (t - 0.3)^2 (t - 0.8): a touch at 0.3 and a crossing at 0.8.
        let got = roots_of(&from_roots(&[0.3, 0.3, 0.8]));
        assert_eq!(got.len(), 2, "{got:?}");
        assert_eq!(got[0].kind, RootKind::Multiple);
        assert!((got[0].t - 0.3).abs() < 1e-7, "{}", got[0].t);
        assert_eq!(got[1].kind, RootKind::Simple);
        assert!((got[1].t - 0.8).abs() < 1e-14);
    }

    #[test]
    fn near_double_roots_are_separated_or_clustered_but_never_lost() {
        for k in 3..12 {
            let gap = 10f64.powi(-k);
            let got = roots_of(&from_roots(&[0.4, 0.4 + gap]));
            assert!(!got.is_empty(), "gap {gap}");
            for r in &got {
                assert!(r.t > 0.4 - 1e-6 && r.t < 0.4 + gap + 1e-6);
            }
            if got.len() == 2 && got.iter().all(|r| r.kind == RootKind::Simple) {
                // Conditioning: a coefficient error e moves a root by about e / |p'| = e / gap.
                let e = noise_of(&from_roots(&[0.4, 0.4 + gap]));
                assert!(
                    (got[1].t - got[0].t - gap).abs() < 4.0 * e / gap,
                    "{gap} {got:?}"
                );
            }
        }
        // A near miss by far more than the noise is no root.
        let miss = from_roots(&[0.4, 0.4]).add_constant(1e-9);
        assert!(roots_of(&miss).is_empty());
    }

    #[test]
    fn roots_at_the_ends_and_the_middle() {
        let got = roots_of(&from_roots(&[0.0, 0.5, 1.0]));
        assert_eq!(got.len(), 3, "{got:?}");
        assert!(got[0].t.abs() < 1e-9 && (got[1].t - 0.5).abs() < 1e-12);
        assert!((got[2].t - 1.0).abs() < 1e-9);
    }

    #[test]
    fn zero_polynomial_is_one_cluster_and_nan_is_nothing() {
        let got = roots_of(&Bernstein::new(&[0.0; 5]).unwrap());
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].lo, got[0].hi), (0.0, 1.0));
        assert!(roots_of(&Bernstein::new(&[f64::NAN, 1.0, -1.0]).unwrap()).len() <= 1);
        assert!(roots_of(&Bernstein::new(&[1.0, 2.0, 0.5]).unwrap()).is_empty());
    }
}
