//! One profile segment: its Bernstein coordinates, bounds, and arc-length and area tables.

use glam::DVec2;

use super::shell::{PIECES, Shell};
use crate::bezier::bernstein::Bernstein;

/// Samples per segment of the arc-length and area tables.
pub(super) const TABLE_STEPS: usize = 32;

// 5-point Gauss-Legendre on [-1, 1].
const GL_X: [f64; 5] = [
    0.0,
    -0.538_469_310_105_683_1,
    0.538_469_310_105_683_1,
    -0.906_179_845_938_664,
    0.906_179_845_938_664,
];
const GL_W: [f64; 5] = [
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_5,
    0.478_628_670_499_366_5,
    0.236_926_885_056_189_1,
    0.236_926_885_056_189_1,
];

/// One profile segment.
#[derive(Debug, Clone)]
pub struct Segment {
    pub r: Bernstein,
    pub h: Bernstein,
    /// `r^2` (the same for every ray).
    pub(super) rr: Bernstein,
    /// `rr.max_abs()`.
    pub(super) rr_max: f64,
    pub(crate) rmax: f64,
    pub(crate) hmin: f64,
    pub(crate) hmax: f64,
    /// Cumulative arc length at `TABLE_STEPS + 1` uniform parameters.
    len_table: Vec<f64>,
    /// Cumulative `integral r |P'| ds` at the same parameters.
    pub(super) area_table: Vec<f64>,
    /// Annular shells of the segment's [`PIECES`] parameter pieces (culling).
    pub(super) shells: [Shell; PIECES],
    /// The union of `shells` (tested first).
    pub(super) shell: Shell,
    /// All control points coincide: the segment is a point (or circle) of zero area.
    pub degenerate: bool,
    /// Bounds of `|r'|` and `|h'|` on [0, 1] (the derivative's control polygon) and the
    /// rounding allowance of an evaluation of `r` and `h` ([`Segment::value_range`]).
    lip: (f64, f64),
    pad: (f64, f64),
}

/// `n max |c_{i+1} - c_i|` (a bound of `|p'|` on [0, 1]) and a rounding allowance for a value of
/// `p` computed by de Casteljau's algorithm: 256 (n + 1) ulps of the largest coefficient, far
/// above the `2n` ulps such an evaluation and the subtraction around it can lose.
fn slope_and_pad(p: &Bernstein) -> (f64, f64) {
    (
        p.derivative().max_abs(),
        256.0 * f64::EPSILON * (p.degree() as f64 + 1.0) * p.max_abs(),
    )
}

impl Segment {
    pub(super) fn new(points: &[DVec2]) -> Self {
        let rs: Vec<f64> = points.iter().map(|p| p.x).collect();
        let hs: Vec<f64> = points.iter().map(|p| p.y).collect();
        let r = Bernstein::new(&rs).expect("degree checked by the caller");
        let h = Bernstein::new(&hs).expect("degree checked by the caller");
        // Bounds from the control polygon, refined by subdividing it into 8 pieces.
        let (mut rmax, mut hmin, mut hmax) = (0.0f64, f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..8 {
            let (a, b) = (k as f64 / 8.0, (k + 1) as f64 / 8.0);
            let rp = r.restrict(a, b);
            let hp = h.restrict(a, b);
            rmax = rmax.max(rp.max_abs());
            for &c in hp.coeffs() {
                hmin = hmin.min(c);
                hmax = hmax.max(c);
            }
        }
        let degenerate = points.iter().all(|p| *p == points[0]);
        let shells = Shell::of_segment(&r, &h);
        let shell = shells.iter().fold(shells[0], |a, &b| a.union(b));
        let rr = r.mul(&r).expect("degree <= 7");
        let mut seg = Self {
            rr_max: rr.max_abs(),
            rr,
            r,
            h,
            rmax,
            hmin,
            hmax,
            len_table: vec![0.0],
            area_table: vec![0.0],
            shells,
            shell,
            degenerate,
            lip: (slope_and_pad(&r).0, slope_and_pad(&h).0),
            pad: (slope_and_pad(&r).1, slope_and_pad(&h).1),
        };
        for k in 0..TABLE_STEPS {
            let (a, b) = (
                k as f64 / TABLE_STEPS as f64,
                (k + 1) as f64 / TABLE_STEPS as f64,
            );
            let l = seg.len_table[k] + seg.integrate(a, b, |_| 1.0);
            let ar = seg.area_table[k] + seg.integrate(a, b, |r| r.abs());
            seg.len_table.push(l);
            seg.area_table.push(ar);
        }
        seg
    }

    /// `integral_a^b f(r(s)) |P'(s)| ds` by Gauss-Legendre.
    fn integrate(&self, a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
        let (m, hw) = (0.5 * (a + b), 0.5 * (b - a));
        let mut sum = 0.0;
        for (x, w) in GL_X.iter().zip(GL_W) {
            let s = m + hw * x;
            let (r, dr) = self.r.eval_with_derivative(s);
            let dh = self.h.eval_with_derivative(s).1;
            sum += w * f(r) * (dr * dr + dh * dh).sqrt();
        }
        sum * hw
    }

    pub(super) fn length(&self) -> f64 {
        self.len_table[TABLE_STEPS]
    }

    /// Arc length from the segment start to `s`.
    pub(super) fn arc(&self, s: f64) -> f64 {
        let s = s.clamp(0.0, 1.0);
        let k = ((s * TABLE_STEPS as f64) as usize).min(TABLE_STEPS - 1);
        self.len_table[k] + self.integrate(k as f64 / TABLE_STEPS as f64, s, |_| 1.0)
    }

    /// Intervals containing `r.eval(s)` and `h.eval(s)`, as computed, for every `s` in
    /// `[lo, hi]`: the value at the middle plus the slope bound times the half width and the
    /// rounding allowance.
    pub(super) fn value_range(&self, lo: f64, hi: f64) -> ((f64, f64), (f64, f64)) {
        let mid = 0.5 * (lo + hi);
        let half = 0.5 * (hi - lo);
        let around = |v: f64, lip: f64, pad: f64| {
            let e = lip * half + pad;
            (v - e, v + e)
        };
        (
            around(self.r.eval(mid), self.lip.0, self.pad.0),
            around(self.h.eval(mid), self.lip.1, self.pad.1),
        )
    }

    pub fn point(&self, s: f64) -> DVec2 {
        DVec2::new(self.r.eval(s), self.h.eval(s))
    }

    /// Unit tangent of the profile at `s` (robust to repeated control points).
    pub(super) fn tangent(&self, s: f64, size: f64) -> DVec2 {
        let t = DVec2::new(
            self.r.eval_with_derivative(s).1,
            self.h.eval_with_derivative(s).1,
        );
        if t.length() > 1e-9 * size {
            return t.normalize();
        }
        // A repeated control point makes P' vanish at an end: use a short chord instead.
        for eps in [1e-6, 1e-4, 1e-2] {
            let c = self.point((s + eps).min(1.0)) - self.point((s - eps).max(0.0));
            if c.length() > 1e-12 * size {
                return c.normalize();
            }
        }
        DVec2::Y
    }
}
