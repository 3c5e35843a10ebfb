//! Where a ray meets the spheres of one cubic segment of a sphere sweep, exactly up to a stated
//! tolerance and without tessellation.
//!
//! Along a ray `o + t d` (`d` a unit vector) the sphere at parameter `s` covers the distances
//! `b(s) ± sqrt(D(s))`, where `b = d . (c(s) - o)` is a cubic and `D = r(s)^2 - |q(s)|^2` a
//! sextic (`q` the part of `c(s) - o` across the ray), wherever `D >= 0` and `r(s) > 0`. Over a
//! connected range of such `s` (a *piece*) the covered distances form one interval, from the
//! least near root to the greatest far root: the ray's entry and exit of that piece's spheres.
//! Both polynomials are kept in Bernstein form, whose coefficients bound the polynomial over the
//! range (the convex hull property) and split exactly in halves (de Casteljau). So:
//!
//! 1. the pieces are found by bisecting `[0, 1]`: a range whose bounds show `D < 0` or
//!    `r <= 0` throughout is dropped, one that shows `D >= 0` and `r > 0` throughout is kept,
//!    and the rest is split down to a width of 2^-32, where a range is kept if the spheres at
//!    its ends or middle meet the ray (a touch between them is at most ~1e-9 of the segment
//!    deep);
//! 2. in each piece a branch and bound finds the least near root (and the greatest far root):
//!    a range's lower bound is `min b - sqrt(max D)`, every range's midpoint whose sphere meets
//!    the ray gives an upper bound, and ranges whose lower bound is within the tolerance of the
//!    best root so far are dropped. The result is always a real sphere's root (so a hit never
//!    lies outside the sweep) and at most the tolerance beyond the true entry.
//!
//! Every search has a budget of ranges (the hostile case is a ray that runs exactly along a
//! tangent, where no bound decides); beyond it the ranges are decided by their sampled points.

use arrayvec::ArrayVec;
use glam::DVec3;

use crate::scene::SweepSegment;

/// The narrowest range the piece search splits (2^-32 of the segment).
const MIN_PIECE_WIDTH: f64 = 1.0 / 4_294_967_296.0;
/// The narrowest range the root search splits.
const MIN_ROOT_WIDTH: f64 = 1e-13;
/// Ranges one piece search, and one root search, may visit.
const BUDGET: usize = 4096;
/// The root search's tolerance, relative to the segment's size.
pub const ROOT_TOLERANCE: f64 = 1e-10;

#[cfg(test)]
thread_local! {
    /// Root searches that ran out of budget (the tests expect the tolerance to end them).
    static EXHAUSTED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// One interval of a ray inside the spheres of one piece of a segment: the distances where it
/// enters and leaves them, and the parameters of the spheres it touches there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    pub t_in: f64,
    pub s_in: f64,
    pub t_out: f64,
    pub s_out: f64,
}

/// The polynomials along one ray over the parameter range `[s0, s1]` in Bernstein form.
#[derive(Debug, Clone, Copy)]
struct Cell {
    s0: f64,
    s1: f64,
    b: [f64; 4],
    r: [f64; 4],
    d: [f64; 7],
}

const C3: [f64; 4] = [1.0, 3.0, 3.0, 1.0];
const C6: [f64; 7] = [1.0, 6.0, 15.0, 20.0, 15.0, 6.0, 1.0];

impl Cell {
    /// The whole segment along the ray `o + t d`; `d = 0` gives the spheres about the point `o`
    /// (`D = r^2 - |c - o|^2`, the inside test).
    fn new(seg: &SweepSegment, o: DVec3, d: DVec3) -> Cell {
        let q = seg.centres.map(|c| c - o);
        let b = q.map(|q| d.dot(q));
        // Across the ray, taken control point by control point (a linear map commutes with
        // the Bernstein form); far more precise than `|q|^2 - b^2` for a far origin.
        let p = [0, 1, 2, 3].map(|j| q[j] - b[j] * d);
        let r = seg.radii;
        let mut dd = [0.0; 7];
        for i in 0..4 {
            for j in 0..4 {
                dd[i + j] += C3[i] * C3[j] * (r[i] * r[j] - p[i].dot(p[j]));
            }
        }
        for (k, v) in dd.iter_mut().enumerate() {
            *v /= C6[k];
        }
        Cell {
            s0: 0.0,
            s1: 1.0,
            b,
            r,
            d: dd,
        }
    }

    fn halves(&self) -> (Cell, Cell) {
        let (b0, b1) = split(self.b, 0.5);
        let (r0, r1) = split(self.r, 0.5);
        let (d0, d1) = split(self.d, 0.5);
        let mid = 0.5 * (self.s0 + self.s1);
        (
            Cell {
                s0: self.s0,
                s1: mid,
                b: b0,
                r: r0,
                d: d0,
            },
            Cell {
                s0: mid,
                s1: self.s1,
                b: b1,
                r: r1,
                d: d1,
            },
        )
    }

    /// The cell over `[a, b]` within `[0, 1]`, from the whole segment's cell.
    fn range(&self, a: f64, b: f64) -> Cell {
        let right = |x: [f64; 7]| split(x, a).1;
        let (bb, rr) = (split(self.b, a).1, split(self.r, a).1);
        let dd = right(self.d);
        let u = if a < 1.0 { (b - a) / (1.0 - a) } else { 1.0 };
        Cell {
            s0: a,
            s1: b,
            b: split(bb, u).0,
            r: split(rr, u).0,
            d: split(dd, u).0,
        }
    }

    fn max_r(&self) -> f64 {
        self.r.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x))
    }
    fn min_r(&self) -> f64 {
        self.r.iter().fold(f64::INFINITY, |m, &x| m.min(x))
    }
    fn max_d(&self) -> f64 {
        self.d.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x))
    }
    fn min_d(&self) -> f64 {
        self.d.iter().fold(f64::INFINITY, |m, &x| m.min(x))
    }

    /// A lower bound of `sign * b - sqrt(D)` over the cell's spheres that meet the ray: the
    /// least `T` at which the ray's point lies outside or on every sphere and short of every
    /// centre's projection (`sign * b >= T`). The first condition is the sextic
    /// `h_T = (b - T)^2 - D >= 0`, which holds where each of its Bernstein coefficients
    /// `T^2 - 2 T b^_k + (b^2)_k - D_k` does (`b^` is `b` raised to degree 6): below the smaller
    /// root of each. Bounding `b` and `D` apart would lose their coupling, and with it the
    /// quadratic convergence in the cell's width.
    fn lower_bound(&self, sign: f64) -> f64 {
        let b = self.b.map(|x| sign * x);
        let mut lower = b.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        for k in 0..7usize {
            let (mut raised, mut square) = (0.0, 0.0);
            for i in k.saturating_sub(3)..=k.min(3) {
                let w = C3[i] * C3[k - i];
                raised += w * b[i];
                square += w * b[i] * b[k - i];
            }
            let (raised, square) = (raised / C6[k], square / C6[k]);
            let disc = raised * raised - square + self.d[k];
            if disc >= 0.0 {
                lower = lower.min(raised - disc.sqrt());
            }
        }
        lower
    }
}

/// de Casteljau: the Bernstein coefficients of the same polynomial over `[0, u]` and `[u, 1]`.
fn split<const N: usize>(a: [f64; N], u: f64) -> ([f64; N], [f64; N]) {
    let (mut left, mut right, mut w) = ([0.0; N], [0.0; N], a);
    for k in 0..N {
        left[k] = w[0];
        right[N - 1 - k] = w[N - 1 - k];
        for i in 0..N - 1 - k {
            w[i] += u * (w[i + 1] - w[i]);
        }
    }
    (left, right)
}

/// `b(s)` and `D(s)` along the unit ray `o + t d` from the segment itself (not a cell), when
/// the sphere at `s` has a positive radius and meets the ray.
fn meets(seg: &SweepSegment, o: DVec3, d: DVec3, s: f64) -> Option<(f64, f64)> {
    let (c, r) = seg.at(s);
    if r.is_nan() || r <= 0.0 {
        return None;
    }
    let q = c - o;
    let b = d.dot(q);
    let disc = r * r - (q - b * d).length_squared();
    (disc >= 0.0).then_some((b, disc))
}

/// Appends to `out` the intervals of the unit ray `o + t d` inside the spheres of `seg`, one
/// per piece, in the order of `s`. `size` is the segment's size (its box's diagonal), which
/// scales the root search's tolerance.
pub fn ray_spans(seg: &SweepSegment, o: DVec3, d: DVec3, size: f64, out: &mut Vec<Span>) {
    let whole = Cell::new(seg, o, d);
    let tol = ROOT_TOLERANCE * size;
    let mut open: Option<(f64, f64)> = None;
    let close = |piece: (f64, f64), out: &mut Vec<Span>| {
        let cell = whole.range(piece.0, piece.1);
        let entry = extreme(seg, o, d, &cell, 1.0, tol);
        let exit = extreme(seg, o, d, &cell, -1.0, tol);
        if let (Some((t_in, s_in)), Some((t_out, s_out))) = (entry, exit) {
            out.push(Span {
                t_in,
                s_in,
                t_out: -t_out,
                s_out,
            });
        }
    };
    let mut stack: ArrayVec<Cell, 80> = ArrayVec::new();
    stack.push(whole);
    let mut budget = BUDGET;
    while let Some(cell) = stack.pop() {
        budget = budget.saturating_sub(1);
        if cell.max_r() <= 0.0 || cell.max_d() < 0.0 {
            continue;
        }
        let keep = if cell.min_r() > 0.0 && cell.min_d() >= 0.0 {
            true
        } else if cell.s1 - cell.s0 <= MIN_PIECE_WIDTH || budget == 0 || stack.is_full() {
            [cell.s0, 0.5 * (cell.s0 + cell.s1), cell.s1]
                .iter()
                .any(|&s| meets(seg, o, d, s).is_some())
        } else {
            // Left half on top: the pieces come in the order of `s`.
            let (l, r) = cell.halves();
            stack.push(r);
            stack.push(l);
            continue;
        };
        if !keep {
            continue;
        }
        open = match open {
            Some((a, b)) if b == cell.s0 => Some((a, cell.s1)),
            Some(piece) => {
                close(piece, out);
                Some((cell.s0, cell.s1))
            }
            None => Some((cell.s0, cell.s1)),
        };
    }
    if let Some(piece) = open {
        close(piece, out);
    }
}

/// The least `sign * b(s) - sqrt(D(s))` over the spheres of `cell` that meet the ray, within
/// `tol`, and its `s`: the entry (`sign = 1`) or the negated exit (`sign = -1`).
fn extreme(
    seg: &SweepSegment,
    o: DVec3,
    d: DVec3,
    cell: &Cell,
    sign: f64,
    tol: f64,
) -> Option<(f64, f64)> {
    let mut best = (f64::INFINITY, f64::NAN);
    let try_at = |s: f64, best: &mut (f64, f64)| {
        if let Some((b, disc)) = meets(seg, o, d, s) {
            let f = sign * b - disc.sqrt();
            if f < best.0 {
                *best = (f, s);
            }
        }
    };
    try_at(cell.s0, &mut best);
    try_at(cell.s1, &mut best);
    let mut stack: ArrayVec<(Cell, f64), 80> = ArrayVec::new();
    stack.push((*cell, cell.lower_bound(sign)));
    let mut budget = BUDGET;
    while let Some((cell, lower)) = stack.pop() {
        if lower >= best.0 - tol || cell.max_r() <= 0.0 || cell.max_d() < 0.0 {
            continue;
        }
        try_at(0.5 * (cell.s0 + cell.s1), &mut best);
        budget = budget.saturating_sub(1);
        #[cfg(test)]
        if budget == 0 {
            EXHAUSTED.with(|e| e.set(e.get() + 1));
        }
        if budget == 0 || cell.s1 - cell.s0 <= MIN_ROOT_WIDTH || stack.len() + 2 > stack.capacity()
        {
            continue;
        }
        let (l, r) = cell.halves();
        let (ll, rl) = (l.lower_bound(sign), r.lower_bound(sign));
        // The more promising half on top.
        if ll <= rl {
            stack.push((r, rl));
            stack.push((l, ll));
        } else {
            stack.push((l, ll));
            stack.push((r, rl));
        }
    }
    best.0.is_finite().then_some(best)
}

/// Whether `p` lies strictly inside one of the segment's spheres of positive radius.
pub fn inside(seg: &SweepSegment, p: DVec3) -> bool {
    let mut stack: ArrayVec<Cell, 80> = ArrayVec::new();
    stack.push(Cell::new(seg, p, DVec3::ZERO));
    let mut budget = BUDGET;
    while let Some(cell) = stack.pop() {
        budget = budget.saturating_sub(1);
        if cell.max_r() <= 0.0 || cell.max_d() <= 0.0 {
            continue;
        }
        let (c, r) = seg.at(0.5 * (cell.s0 + cell.s1));
        if r > 0.0 && (p - c).length_squared() < r * r {
            return true;
        }
        if budget > 0 && cell.s1 - cell.s0 > MIN_PIECE_WIDTH && !stack.is_full() {
            let (l, r) = cell.halves();
            stack.push(r);
            stack.push(l);
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(a: DVec3, b: DVec3, ra: f64, rb: f64) -> SweepSegment {
        SweepSegment {
            centres: [a, a + (b - a) / 3.0, a + 2.0 * (b - a) / 3.0, b],
            radii: [ra, ra + (rb - ra) / 3.0, ra + 2.0 * (rb - ra) / 3.0, rb],
        }
    }

    fn spans(seg: &SweepSegment, o: DVec3, d: DVec3) -> Vec<Span> {
        let mut out = Vec::new();
        ray_spans(seg, o, d.normalize(), 4.0, &mut out);
        out
    }

    #[test]
    fn split_keeps_the_polynomial() {
        let a = [0.3, -1.0, 2.0, 0.5, -0.7, 1.1, 0.0];
        let eval = |c: &[f64; 7], s: f64| -> f64 {
            let mut w = *c;
            for k in (1..7).rev() {
                for i in 0..k {
                    w[i] += s * (w[i + 1] - w[i]);
                }
            }
            w[0]
        };
        let (l, r) = split(a, 0.3);
        for k in 0..=10 {
            let x = f64::from(k) / 10.0;
            assert!((eval(&l, x) - eval(&a, 0.3 * x)).abs() < 1e-14);
            assert!((eval(&r, x) - eval(&a, 0.3 + 0.7 * x)).abs() < 1e-14);
        }
    }

    #[test]
    fn a_straight_tube_is_a_cylinder_with_round_ends() {
        // Radius 0.5 along x from 0 to 2: a ray down the y axis at x = 1 enters at y = 0.5.
        let seg = straight(DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0), 0.5, 0.5);
        let s = spans(&seg, DVec3::new(1.0, 5.0, 0.0), -DVec3::Y);
        assert_eq!(s.len(), 1);
        assert!((s[0].t_in - 4.5).abs() < 1e-9, "{:?}", s[0]);
        assert!((s[0].t_out - 5.5).abs() < 1e-9, "{:?}", s[0]);
        // Along the axis: the end spheres' poles.
        let s = spans(&seg, DVec3::new(-3.0, 0.0, 0.0), DVec3::X);
        assert!((s[0].t_in - 2.5).abs() < 1e-9 && (s[0].t_out - 5.5).abs() < 1e-9);
        assert!(s[0].s_in.abs() < 1e-9 && (s[0].s_out - 1.0).abs() < 1e-9);
        // Beside it: nothing.
        assert!(spans(&seg, DVec3::new(1.0, 5.0, 0.51), -DVec3::Y).is_empty());
    }

    #[test]
    fn a_cone_of_spheres_enters_where_the_tangent_cone_does() {
        // Radii 1 to 0.5 over a length of 4: the envelope is the frustum tangent to the end
        // spheres (sin a = 1/8), whose radius at x = 2 is known in closed form.
        let (r0, r1, len) = (1.0f64, 0.5f64, 4.0f64);
        let seg = straight(DVec3::ZERO, DVec3::new(len, 0.0, 0.0), r0, r1);
        let sin = (r0 - r1) / len;
        let cos = (1.0 - sin * sin).sqrt();
        // The frustum's radius at x: linear between its tangent circles.
        let (x0, x1) = (r0 * sin, len + r1 * sin);
        let (rr0, rr1) = (r0 * cos, r1 * cos);
        let x = 2.0;
        let want = rr0 + (rr1 - rr0) * (x - x0) / (x1 - x0);
        let s = spans(&seg, DVec3::new(x, 5.0, 0.0), -DVec3::Y);
        assert!(
            (5.0 - s[0].t_in - want).abs() < 1e-8,
            "{:?} vs {want}",
            s[0]
        );
    }

    #[test]
    fn a_stretch_of_radius_below_zero_is_absent_and_pieces_split() {
        // Radius 1 at both ends and -1 in the middle stretch: two separate end pieces.
        let seg = SweepSegment {
            centres: [0.0, 1.0, 2.0, 3.0].map(|x| DVec3::new(x * 2.0, 0.0, 0.0)),
            radii: [0.5, -2.0, -2.0, 0.5],
        };
        let s = spans(&seg, DVec3::new(-5.0, 0.0, 0.0), DVec3::X);
        assert_eq!(s.len(), 2, "{s:?}");
        assert!((s[0].t_in - 4.5).abs() < 1e-9);
        assert!((s[1].t_out - 11.5).abs() < 1e-9);
        // Down through the middle, where the radius is negative: nothing.
        assert!(spans(&seg, DVec3::new(3.0, 5.0, 0.0), -DVec3::Y).is_empty());
        assert!(!inside(&seg, DVec3::new(3.0, 0.0, 0.0)));
        assert!(inside(&seg, DVec3::new(0.2, 0.0, 0.0)));
    }

    #[test]
    fn a_ray_along_a_tangent_line_terminates() {
        // A ray exactly along the tube's surface line: every bound is in doubt; the budgets
        // end the search.
        let seg = straight(DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0), 0.5, 0.5);
        let s = spans(&seg, DVec3::new(-1.0, 0.5, 0.0), DVec3::X);
        for sp in s {
            assert!(
                sp.t_in <= sp.t_out && sp.t_in >= 0.9 && sp.t_out <= 3.1,
                "{sp:?}"
            );
        }
    }

    #[test]
    fn a_curved_segment_is_entered_at_its_nearest_sphere() {
        // A quarter-ish arc: brute force over many spheres gives the least near root; the
        // search is never below it and within the tolerance above it, and the tolerance (not
        // the budget) ends every search.
        let seg = SweepSegment {
            centres: [
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.3),
                DVec3::new(2.0, 1.0, -0.2),
                DVec3::new(2.0, 2.0, 0.0),
            ],
            radii: [0.2, 0.6, 0.1, 0.4],
        };
        let mut rng = 0x2545f4914f6cdd1du64;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let o = DVec3::new(next() * 8.0 - 3.0, next() * 8.0 - 3.0, 4.0);
            let target = DVec3::new(next() * 2.4 - 0.2, next() * 2.4 - 0.2, next() - 0.5);
            let d = (target - o).normalize();
            let mut brute = f64::INFINITY;
            for k in 0..=200_000 {
                if let Some((b, disc)) = meets(&seg, o, d, f64::from(k) / 200_000.0) {
                    brute = brute.min(b - disc.sqrt());
                }
            }
            let got = spans(&seg, o, d).first().map_or(f64::INFINITY, |s| s.t_in);
            if brute.is_finite() {
                assert!(
                    got <= brute + 1e-9 && got >= brute - 1e-6,
                    "{got} vs {brute}"
                );
            } else {
                assert!(!got.is_finite(), "{got}");
            }
        }
        assert_eq!(EXHAUSTED.with(|e| e.get()), 0);
    }
}
