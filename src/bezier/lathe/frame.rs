//! A ray prepared for one lathe, and the recovery of the ray parameter from a root of `F`.

use glam::DVec3;

use super::segment::Segment;
use crate::bezier::bernstein::Bernstein;
use crate::bezier::roots::bracket::{Refine, bracketed_root};
use crate::bezier::roots::{Root, widened};

/// A ray prepared for one lathe: unit direction and an origin shifted near the surface.
#[derive(Debug, Clone, Copy)]
pub struct RayFrame {
    pub o: DVec3,
    pub dn: DVec3,
    pub dh2: f64,
    /// `1 / d_y` (infinite for horizontal rays).
    pub(crate) inv_dy: f64,
    /// `|d_y| >= |d_xz|`: `t` is recovered from the height, otherwise from the radius.
    steep: bool,
    pub(crate) t0: f64,
    /// `o + t0 dn`: the point of closest approach to the axis (flat rays) or at mid-height.
    pub oc: DVec3,
    pub(crate) rho2: f64,
    /// Squared distance of the ray's line from the axis, and the `t` where it is reached.
    pub(crate) line_rho2: f64,
    pub(crate) tc: f64,
}

impl RayFrame {
    /// `dn` must be unit length.
    pub fn new(o: DVec3, dn: DVec3, hmin: f64, hmax: f64) -> Self {
        let dh2 = dn.x * dn.x + dn.z * dn.z;
        let steep = dn.y.abs() >= dh2.sqrt();
        // Shift the origin near the surface so that the polynomial's terms do not cancel.
        let t0 = if steep {
            (0.5 * (hmin + hmax) - o.y) / dn.y
        } else {
            -(o.x * dn.x + o.z * dn.z) / dh2
        };
        let oc = o + t0 * dn;
        let rho2 = oc.x * oc.x + oc.z * oc.z;
        let (line_rho2, tc) = if dh2 > 0.0 {
            let tc = -(oc.x * dn.x + oc.z * dn.z) / dh2;
            let q = oc + tc * dn;
            (q.x * q.x + q.z * q.z, t0 + tc)
        } else {
            (rho2, t0)
        };
        Self {
            o,
            dn,
            dh2,
            inv_dy: 1.0 / dn.y,
            steep,
            t0,
            oc,
            rho2,
            line_rho2,
            tc,
        }
    }

    /// The polynomial `F(s)` of the segment (see the module docs) and its rounding noise.
    pub fn polynomial(&self, seg: &Segment) -> (Bernstein, f64) {
        let (oc, dn) = (self.oc, self.dn);
        let (kx, kz) = (oc.x * dn.y - oc.y * dn.x, oc.z * dn.y - oc.y * dn.z);
        if let (Ok(h), Ok(rr)) = (
            <&[f64; 4]>::try_from(seg.h.coeffs()),
            <&[f64; 7]>::try_from(seg.rr.coeffs()),
        ) {
            // Cubic profiles (the usual case): the same operations on arrays of their length.
            let a: [f64; 4] = std::array::from_fn(|i| h[i] * dn.x + kx);
            let b: [f64; 4] = std::array::from_fn(|i| h[i] * dn.z + kz);
            let f = Bernstein::cubic_square_sum(&a, &b, rr, -dn.y * dn.y);
            let max_abs = |p: &[f64; 4]| p.iter().fold(0.0, |m: f64, c| m.max(c.abs()));
            let scale = max_abs(&a).powi(2) + max_abs(&b).powi(2) + dn.y * dn.y * seg.rr_max;
            return (f, scale * 64.0 * f64::EPSILON * 7.0);
        }
        let a = seg.h.scale_add(dn.x, kx);
        let b = seg.h.scale_add(dn.z, kz);
        let rr = &seg.rr;
        let f = Bernstein::square_sum(&a, &b, rr, -dn.y * dn.y).expect("degree <= 14");
        let scale = a.max_abs().powi(2) + b.max_abs().powi(2) + dn.y * dn.y * seg.rr_max;
        (f, scale * 64.0 * f64::EPSILON * (f.degree() as f64 + 1.0))
    }

    /// `F(s)` evaluated pointwise from the profile (no product polynomial), for the reference.
    pub fn eval_pointwise(&self, seg: &Segment, s: f64) -> (f64, f64) {
        let (oc, dn) = (self.oc, self.dn);
        let (r, dr) = seg.r.eval_with_derivative(s);
        let (h, dh) = seg.h.eval_with_derivative(s);
        let a = oc.x * dn.y + (h - oc.y) * dn.x;
        let b = oc.z * dn.y + (h - oc.y) * dn.z;
        let v = a * a + b * b - dn.y * dn.y * r * r;
        let dv = 2.0 * (a * dh * dn.x + b * dh * dn.z - dn.y * dn.y * r * dr);
        (v, dv)
    }

    /// Ray parameters (unit direction) of the hits a root `s` of `F` stands for; NaN for none.
    /// `ds` is the uncertainty of `s` from rounding (see
    /// [`root_uncertainty`](crate::bezier::roots::root_uncertainty)).
    ///
    /// `F` is a product of two well-conditioned factors; squaring makes its roots lose half
    /// their digits where the factors nearly vanish together (poles, flat rays). So the root's
    /// bracket, widened by `ds`, is searched again for a sign change of the factor itself:
    /// steep rays `g(s) = r(s) - |xz(t(s))|` with `t(s)` from the height; flat rays, for each
    /// side `sigma = +-1` of the point of closest approach, `g(s) = h(s) - y(t_sigma(s))` with
    /// `t_sigma = t_c + sigma sqrt(r^2 - rho^2) / |d_xz|`. Only where no factor changes sign (a
    /// tangency) is the root itself used.
    /// `refine` chooses how a sign change is refined: the production intersector uses
    /// [`Refine::FalsePosition`], the reference [`Refine::Bisection`] (so the stress test compares
    /// two refinements, not one with itself).
    /// Returns `(t, s)` pairs.
    ///
    /// `prune = Some((t_min, t_max))`: the caller keeps only candidates with
    /// `t_min < t < t_max`, and work that provably cannot give one is skipped: a side whose every
    /// candidate lies outside (bounds of `t` over the bracket, see [`RayFrame::ranges_of`]),
    /// and the scan of a factor that keeps one sign on the whole bracket (bounds of its computed
    /// value). A skipped side's candidate is NaN where the full search may give one outside the
    /// window; the candidates inside are the same, bit for bit. The reference passes `None`
    /// (the full search).
    ///
    /// `t_after`: where a side's bracket holds several sign changes, the nearest one with
    /// `t > t_after` is taken (the caller's `t_min`). A ray starting on the surface meets it at
    /// `t ~ 0` and may meet it again within the root uncertainty of `F` (both roots of `F` in
    /// one widened bracket, e.g. 8e-5 along a nearly tangent ray from the dome): taking the
    /// nearest one overall would return the origin's own root, which the caller then drops as
    /// `t <= t_min`, and the real hit behind it would be lost.
    ///
    /// `monotone`: the caller has certified that `F` is strictly monotone on the widened
    /// bracket ([`strictly_monotone_on`](crate::bezier::roots::strictly_monotone_on)), so `F`
    /// has at most one root there and each factor (whose roots are roots of `F`) at most one
    /// sign change. Then the pair of the scan's samples where a factor (never NaN on the
    /// bracket) changes sign is looked for around the root of `F` (2 or 3 samples), else by
    /// its ends (one sign: no sign change) and a bisection over the scan's points (7 samples),
    /// instead of 17, and refined as the scan refines it: the same root, bit for bit, unless
    /// two samples fall within the factor's rounding of its root (the scan may then see
    /// several sign changes there and pick another one within that rounding). Where the certificate fails (two roots of `F` in
    /// one bracket as above, a double root, a cluster) the full scan runs. Refining the whole
    /// bracket at once was tried: it took fewer samples but moved ill-conditioned hits (nearly
    /// tangent chords from the surface, whose factor's rounding spans 1e-11 in `s`) by up to
    /// 1.5e-6 of their `t`.
    #[allow(clippy::too_many_arguments)]
    pub fn candidates(
        &self,
        seg: &Segment,
        root: &Root,
        ds: f64,
        size: f64,
        refine: Refine,
        t_after: f64,
        prune: Option<(f64, f64)>,
        monotone: bool,
    ) -> [(f64, f64); 2] {
        let (oc, dn) = (self.oc, self.dn);
        let (lo, hi) = widened(root, ds);
        let mut cands = [(f64::NAN, root.t); 2];
        // Bounds of `r`, `h` and the half chord on the bracket (only where they are used).
        let bounds = (prune.is_some() || !self.steep).then(|| self.bracket_bounds(seg, lo, hi));
        let inside = match (prune, &bounds) {
            (Some(w), Some(b)) => self.ranges_of(b).map(|(a, b)| b > w.0 && a < w.1),
            _ => [true; 2],
        };
        if !inside[0] && !inside[1] {
            return cands;
        }
        if self.steep {
            let t_of = |s: f64| (seg.h.eval(s) - oc.y) / dn.y;
            let g = |s: f64| {
                let t = t_of(s);
                let (x, z) = (oc.x + t * dn.x, oc.z + t * dn.z);
                seg.r.eval(s) - (x * x + z * z).sqrt()
            };
            let t_at = |s: f64| self.t0 + t_of(s);
            let found = match monotone.then(|| single_sign_change(&g, lo, hi, root.t, refine)) {
                Some(Ends::Root(s)) => Some(s),
                Some(Ends::OneSign) => None,
                Some(Ends::Unknown) | None => {
                    nearest_sign_change(&g, &t_at, t_after, lo, hi, refine)
                }
            };
            if let Some(s) = found {
                cands[0] = (self.t0 + t_of(s), s);
                return cands;
            }
            // A tangency: keep it only where the factor really reaches zero.
            if let Some(s) = touch(&g, lo, hi, size) {
                cands[0] = (self.t0 + t_of(s), s);
            }
            return cands;
        }
        // The half chord at radius `r`.
        let w_at = |r: f64| ((r * r - self.rho2) / self.dh2).max(0.0).sqrt();
        let w_of = |s: f64| w_at(seg.r.eval(s));
        // The ray reaches radius `r` only where `r >= rho`. The slack is absolute in `r` (not in
        // `r^2`): near a pointed tip `rho` itself may be 1e-7 of the size, and a slack in `r^2`
        // of 1e-12 size^2 would let `r` fall far below `rho` and create a false hit at `t_c`.
        let rho = self.rho2.sqrt();
        let reach = rho - 1e-12 * size;
        let g = |sigma: f64, s: f64| {
            let r = seg.r.eval(s);
            if r < reach {
                // The ray does not reach radius r: no hit at this s.
                return f64::NAN;
            }
            seg.h.eval(s) - (oc.y + dn.y * sigma * w_at(r))
        };
        let b = bounds.unwrap_or_else(|| self.bracket_bounds(seg, lo, hi));
        let g_range = |sigma: f64| {
            // `g` is increasing in `h` and monotone in `w` (through `dn.y sigma w`), and so is
            // its computed value: the same expression at the bounds bounds it.
            let y = |w: f64| oc.y + dn.y * sigma * w;
            let (ya, yb) = (y(b.w.0), y(b.w.1));
            (b.h.0 - ya.max(yb), b.h.1 - ya.min(yb))
        };
        // Far enough from 0 that a product of two such values cannot underflow to 0.
        const TINY: f64 = 1e-140;
        let mut refined = false;
        let mut sign_kept = [false; 2];
        for (k, sigma) in [1.0, -1.0].into_iter().enumerate() {
            // A factor of one sign on the whole bracket (where the ray reaches it) has no sign
            // change between any of the scan's samples: the scan would find nothing.
            let (gl, gh) = g_range(sigma);
            if prune.is_some() && (gl > TINY || gh < -TINY) {
                sign_kept[k] = gl > 1e-10 * size || gh < -1e-10 * size;
                continue;
            }
            // A side outside the window matters only by whether it changes sign (which rules
            // out the tangency search below). Where `r` stays at or above `reach` on the whole
            // bracket its factor is never NaN, and then a sign change between the scan's end
            // samples means the scan would find one between some neighbouring samples.
            if !inside[k] {
                let (ga, gb) = (g(sigma, lo), g(sigma, lo + (hi - lo)));
                if b.r.0 >= reach && ((ga <= 0.0 && gb >= 0.0) || (ga >= 0.0 && gb <= 0.0)) {
                    refined = true;
                    continue;
                }
            }
            let t_at = |s: f64| self.t0 + sigma * w_of(s);
            let gs = |s| g(sigma, s);
            // The shortcut only where the factor cannot be NaN on the bracket (`r >= reach`).
            let ends = (monotone && b.r.0 >= reach)
                .then(|| single_sign_change(&gs, lo, hi, root.t, refine));
            let found = match ends {
                Some(Ends::Root(s)) => Some(s),
                Some(Ends::OneSign) => None,
                Some(Ends::Unknown) | None => {
                    nearest_sign_change(&gs, &t_at, t_after, lo, hi, refine)
                }
            };
            if let Some(s) = found {
                cands[k] = (self.t0 + sigma * w_of(s), s);
                refined = true;
            }
        }
        if refined {
            return cands;
        }
        // A tangency: no factor changes sign between samples. Keep a side only where its
        // factor really reaches zero (the root of `F` alone is not enough: near a pole its
        // uncertainty in `s` is large enough to turn a ray that passes 1e-7 away into a hit).
        for (k, sigma) in [1.0, -1.0].into_iter().enumerate() {
            // Outside the window, or `|g|` above the touch's threshold everywhere: no candidate.
            if !inside[k] || sign_kept[k] {
                continue;
            }
            if let Some(s) = touch(&|s| g(sigma, s), lo, hi, size) {
                cands[k] = (self.t0 + sigma * w_of(s), s);
            }
        }
        cands
    }
}

impl RayFrame {
    /// Intervals containing the `t` of every candidate [`RayFrame::candidates`] can compute
    /// from an `s` of a bracket with bounds `b` ([`RayFrame::bracket_bounds`]): for steep rays
    /// one interval (the second is empty), for flat rays one per side `sigma = +1, -1`. The
    /// candidates' `t` are computed from `r(s)` or `h(s)` by a chain of correctly rounded
    /// operations, each monotone in its input, so the same chain applied to the ends of an
    /// interval containing the computed `r(s)` or `h(s)` ([`Segment::value_range`]) bounds the
    /// computed `t`, rounding included.
    fn ranges_of(&self, b: &BracketBounds) -> [(f64, f64); 2] {
        if self.steep {
            let t_at = |h: f64| self.t0 + (h - self.oc.y) / self.dn.y;
            let (a, c) = (t_at(b.h.0), t_at(b.h.1));
            return [(a.min(c), a.max(c)), (f64::INFINITY, f64::NEG_INFINITY)];
        }
        let (wl, wh) = b.w;
        [
            (self.t0 + wl, self.t0 + wh),
            // `sigma * w` with `sigma = -1` is `-w` exactly.
            (self.t0 - wh, self.t0 - wl),
        ]
    }

    /// Bounds of the computed `r(s)`, `h(s)` and `w(s)` (the half chord at radius `r`, as
    /// `candidates` computes it) for every `s` in `[lo, hi]`.
    fn bracket_bounds(&self, seg: &Segment, lo: f64, hi: f64) -> BracketBounds {
        let (r, h) = seg.value_range(lo, hi);
        // The same expression as `w_of` in `candidates`, from a squared radius.
        let w_at = |r2: f64| ((r2 - self.rho2) / self.dh2).max(0.0).sqrt();
        let lo2 = if r.0 > 0.0 { r.0 * r.0 } else { 0.0 };
        let m = r.0.abs().max(r.1.abs());
        BracketBounds {
            r,
            h,
            w: (w_at(lo2), w_at(m * m)),
        }
    }
}

/// See [`RayFrame::bracket_bounds`]: `(lower, upper)` pairs.
#[derive(Clone, Copy)]
struct BracketBounds {
    r: (f64, f64),
    h: (f64, f64),
    w: (f64, f64),
}

/// Where a factor `g` touches zero on `[lo, hi]` without a sign change between samples (a
/// tangency, or two roots closer than the sample spacing): the point of smallest `|g|`, found by
/// 64 samples and a golden-section search between the best sample's neighbours, if `|g|` there is
/// within rounding of zero (`1e-10` of the surface size; `g` is a length, computed in f64 from
/// quantities of the size of the scene). NaN values of `g` mean "not reachable".
fn touch(g: &dyn Fn(f64) -> f64, lo: f64, hi: f64, size: f64) -> Option<f64> {
    let f = |s: f64| {
        let v = g(s).abs();
        if v.is_nan() { f64::INFINITY } else { v }
    };
    const N: usize = 64;
    let x = |k: usize| lo + (hi - lo) * k as f64 / N as f64;
    let (k, fk) = (0..=N)
        .map(|k| (k, f(x(k))))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    if !fk.is_finite() {
        return None;
    }
    let (mut a, mut b) = (x(k.saturating_sub(1)), x((k + 1).min(N)));
    let q = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - q * (b - a), a + q * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    let mut best = (x(k), fk);
    for _ in 0..100 {
        if fc < fd {
            (b, d, fd) = (d, c, fc);
            c = b - q * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + q * (b - a);
            fd = f(d);
        }
        for (s, v) in [(c, fc), (d, fd)] {
            if v < best.1 {
                best = (s, v);
            }
        }
        if b - a <= f64::EPSILON * b.abs().max(1e-300) {
            break;
        }
    }
    (best.1 <= 1e-10 * size).then_some(best.0)
}

/// What a factor's samples at the scan's points tell where it has at most one sign change on
/// the bracket.
enum Ends {
    /// The sign change, refined in the piece between the samples where the sign changes.
    Root(f64),
    /// One sign at both ends, and so no sign change.
    OneSign,
    /// A sample NaN or exactly zero: not decided here.
    Unknown,
}

/// Samples of the factor scan over `[lo, hi]` ([`nearest_sign_change`]'s points).
const SCAN_PIECES: usize = 16;

/// The scan's point `k` of `[lo, hi]`.
#[inline]
fn scan_point(lo: f64, hi: f64, k: usize) -> f64 {
    lo + (hi - lo) * k as f64 / SCAN_PIECES as f64
}

/// [`Ends`] of `g` on `[lo, hi]`, for a `g` known to change sign at most once there, whose
/// sign change is expected near `near` (the root of `F`).
///
/// Where the samples of `g` at the scan's points change sign once (as they do for such a `g`,
/// unless two samples fall within the rounding of its root) the pair of neighbouring samples
/// of opposite signs is the one [`nearest_sign_change`] refines, and any such pair found is it.
/// So the samples around `near` are tried first (2 or 3 samples); failing that, the two ends
/// (one sign: no sign change) and a bisection over the points (5 more samples). The pair is
/// refined as the scan refines it: the same root, bit for bit.
fn single_sign_change(g: &dyn Fn(f64) -> f64, lo: f64, hi: f64, near: f64, refine: Refine) -> Ends {
    let decided = |v: f64| v != 0.0 && !v.is_nan();
    let refined = |a: usize, b: usize, ga: f64, gb: f64| {
        let (xa, xb) = (scan_point(lo, hi, a), scan_point(lo, hi, b));
        match bracketed_root(g, xa, xb, ga, gb, refine) {
            Some(s) => Ends::Root(s),
            None => Ends::Unknown,
        }
    };
    // The piece holding `near`, and its neighbour on the side `near` is closer to.
    let f = (near - lo) / (hi - lo) * SCAN_PIECES as f64;
    if f > 0.0 && f < SCAN_PIECES as f64 {
        let k = (f as usize).min(SCAN_PIECES - 1);
        let (gk, gk1) = (g(scan_point(lo, hi, k)), g(scan_point(lo, hi, k + 1)));
        if !(decided(gk) && decided(gk1)) {
            return Ends::Unknown;
        }
        if (gk > 0.0) != (gk1 > 0.0) {
            return refined(k, k + 1, gk, gk1);
        }
        let j = if f - (k as f64) < 0.5 {
            k.checked_sub(1).map(|j| (j, j + 1))
        } else {
            (k + 2 <= SCAN_PIECES).then_some((k + 1, k + 2))
        };
        if let Some((a, b)) = j {
            let (ga, gb) = if a == k + 1 {
                (gk1, g(scan_point(lo, hi, b)))
            } else {
                (g(scan_point(lo, hi, a)), gk)
            };
            if !(decided(ga) && decided(gb)) {
                return Ends::Unknown;
            }
            if (ga > 0.0) != (gb > 0.0) {
                return refined(a, b, ga, gb);
            }
        }
    }
    let (mut a, mut b) = (0, SCAN_PIECES);
    let (mut ga, mut gb) = (g(scan_point(lo, hi, a)), g(scan_point(lo, hi, b)));
    if !(decided(ga) && decided(gb)) {
        return Ends::Unknown;
    }
    if (ga > 0.0) == (gb > 0.0) {
        return Ends::OneSign;
    }
    while b - a > 1 {
        let m = (a + b) / 2;
        let gm = g(scan_point(lo, hi, m));
        if !decided(gm) {
            return Ends::Unknown;
        }
        if (gm > 0.0) == (ga > 0.0) {
            (a, ga) = (m, gm);
        } else {
            (b, gb) = (m, gm);
        }
    }
    refined(a, b, ga, gb)
}

/// Scans `[lo, hi]` in 16 pieces for sign changes of `g` (NaN: no hit there) and returns the
/// refined root with the smallest `t(s)` above `t_after`, else the one with the smallest
/// `t(s)` (the caller drops it). Neighbouring pieces share their end samples.
fn nearest_sign_change(
    g: &dyn Fn(f64) -> f64,
    t: &dyn Fn(f64) -> f64,
    t_after: f64,
    lo: f64,
    hi: f64,
    refine: Refine,
) -> Option<f64> {
    let mut best: Option<(f64, f64)> = None;
    let n = SCAN_PIECES;
    let x = |k: usize| scan_point(lo, hi, k);
    let (mut a, mut ga) = (x(0), g(x(0)));
    for k in 0..n {
        let b = x(k + 1);
        let gb = g(b);
        // No sign change (both values of one sign; a product with a NaN is not above 0):
        // what `bracketed_root` answers first, without the call.
        if ga * gb > 0.0 {
            (a, ga) = (b, gb);
            continue;
        }
        if let Some(s) = bracketed_root(g, a, b, ga, gb, refine) {
            let ts = t(s);
            // Ordered by (beyond `t_after`, nearest): a root beyond `t_after` beats one before.
            let better = |bt: f64| match (ts > t_after, bt > t_after) {
                (a, b) if a != b => a,
                _ => ts < bt,
            };
            if best.is_none_or(|(_, bt)| better(bt)) {
                best = Some((s, ts));
            }
        }
        (a, ga) = (b, gb);
    }
    best.map(|b| b.0)
}
