//! A control net's geometry: Bernstein weights, de Casteljau splits and restrictions, bounds,
//! and the tests a projected sub-patch must pass (fat lines around the origin, a map that
//! meets the ray at most once, a box in the net's own frame).

use glam::{DVec2, DVec3};

/// A box around a control net (so around its surface) in an orthonormal frame of the net's
/// mean u direction and normal: for a piece of a curved surface it is far tighter than the
/// axis-aligned box the BVH holds, and it is tested before the net is projected.
#[derive(Debug, Clone, Copy)]
pub(super) struct OrientedBox {
    axes: [DVec3; 3],
    center: DVec3,
    /// Half extents along the axes, padded by `1e-9` of the patch size.
    half: DVec3,
}

impl OrientedBox {
    pub(super) fn around(q: &[DVec3; 16], size: f64) -> Option<Self> {
        let du = q[12] - q[0] + q[15] - q[3];
        let dv = q[3] - q[0] + q[15] - q[12];
        let n = du.cross(dv).try_normalize()?;
        let a = (du - n * du.dot(n)).try_normalize()?;
        let axes = [a, n.cross(a), n];
        let coords = |p: DVec3| DVec3::new(p.dot(axes[0]), p.dot(axes[1]), p.dot(axes[2]));
        let (lo, hi) = q
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                let c = coords(*p);
                (lo.min(c), hi.max(c))
            });
        let mid = 0.5 * (lo + hi);
        let center = axes[0] * mid.x + axes[1] * mid.y + axes[2] * mid.z;
        // The pad is far above the rounding of these projections (relative to the net's
        // distance from the world origin, added as well).
        let reach = q.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
        let half = 0.5 * (hi - lo) + DVec3::splat(1e-9 * size + 1e-12 * reach);
        (center.is_finite() && half.is_finite()).then_some(Self { axes, center, half })
    }

    /// Whether the ray `o + t dn` (unit `dn`) can meet the box at some `tmin < t < tmax`. The
    /// ray's coordinates in the box frame are rounded relative to its distance from the
    /// centre: the half extents are widened by `1e-12` of it, far above that rounding.
    pub(super) fn may_meet(&self, o: DVec3, dn: DVec3, tmin: f64, tmax: f64) -> bool {
        let oc = o - self.center;
        let half = self.half + DVec3::splat(1e-12 * oc.abs().max_element());
        let (mut near, mut far) = (tmin, tmax);
        for k in 0..3 {
            let (ok, dk) = (oc.dot(self.axes[k]), dn.dot(self.axes[k]));
            if dk == 0.0 {
                if ok.abs() > half[k] {
                    return false;
                }
                continue;
            }
            let (t0, t1) = ((-half[k] - ok) / dk, (half[k] - ok) / dk);
            let (t0, t1) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
            near = near.max(t0);
            far = far.min(t1);
        }
        near <= far
    }
}

pub(super) fn bern3(t: f64) -> ([f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    (
        [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t],
        [
            -3.0 * s * s,
            3.0 * s * s - 6.0 * t * s,
            6.0 * t * s - 3.0 * t * t,
            3.0 * t * t,
        ],
    )
}

/// Splits a cubic at 1/2.
pub(super) fn split4(c: [DVec3; 4]) -> ([DVec3; 4], [DVec3; 4]) {
    let m01 = (c[0] + c[1]) * 0.5;
    let m12 = (c[1] + c[2]) * 0.5;
    let m23 = (c[2] + c[3]) * 0.5;
    let a = (m01 + m12) * 0.5;
    let b = (m12 + m23) * 0.5;
    let mid = (a + b) * 0.5;
    ([c[0], m01, a, mid], [mid, b, m23, c[3]])
}

/// The control points of a cubic restricted to `[a, b]` (within `[0, 1]`), by de Casteljau's
/// algorithm: the right part after `a`, then the left part of that up to `b`.
pub(super) fn restrict4(c: [DVec3; 4], a: f64, b: f64) -> [DVec3; 4] {
    let split_at = |c: [DVec3; 4], t: f64| {
        let l = |p: DVec3, q: DVec3| p + (q - p) * t;
        let (m01, m12, m23) = (l(c[0], c[1]), l(c[1], c[2]), l(c[2], c[3]));
        let (a, b) = (l(m01, m12), l(m12, m23));
        let mid = l(a, b);
        ([c[0], m01, a, mid], [mid, b, m23, c[3]])
    };
    let right = if a > 0.0 { split_at(c, a).1 } else { c };
    if b < 1.0 {
        split_at(right, (b - a) / (1.0 - a)).0
    } else {
        right
    }
}

/// Splits a 4x4 net at u = 1/2 (`along_u`) or v = 1/2.
pub(super) fn split_net(q: &[DVec3; 16], along_u: bool) -> ([DVec3; 16], [DVec3; 16]) {
    let (mut l, mut r) = ([DVec3::ZERO; 16], [DVec3::ZERO; 16]);
    for k in 0..4 {
        let idx = |m: usize| if along_u { 4 * m + k } else { 4 * k + m };
        let (a, b) = split4([q[idx(0)], q[idx(1)], q[idx(2)], q[idx(3)]]);
        for m in 0..4 {
            l[idx(m)] = a[m];
            r[idx(m)] = b[m];
        }
    }
    (l, r)
}

pub(super) fn net_bounds(q: &[DVec3; 16]) -> (DVec3, DVec3) {
    q.iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
}

/// Product of two intervals.
pub(super) fn imul(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let p = [a.0 * b.0, a.0 * b.1, a.1 * b.0, a.1 * b.1];
    (
        p.iter().copied().fold(f64::INFINITY, f64::min),
        p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    )
}

/// Whether the sub-patch with projected net `q` meets the ray (the z axis) at most once.
///
/// The projected map `(u, v) -> (x, y)` is injective on the sub-patch's domain if every matrix
/// whose entries lie in the ranges of the partial derivatives `x_u, x_v, y_u, y_v` over the
/// domain is nonsingular: by the mean-value theorem `F(a) - F(b) = M (a - b)` with each row of `M`
/// a gradient at some point of the segment, so `M` is such a matrix. The ranges come from the
/// derivative nets (convex-hull property; the constant factor 3 does not change the sign), and
/// the determinant of the interval matrix evaluated in interval arithmetic encloses every such
/// matrix's determinant. If it excludes 0, the ray meets this piece of surface at most once.
pub(super) fn injective(q: &[DVec3; 16]) -> bool {
    let range = |f: &dyn Fn(DVec3) -> f64, pairs: &mut dyn Iterator<Item = (usize, usize)>| {
        pairs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (a, b)| {
            let d = f(q[b] - q[a]);
            (lo.min(d), hi.max(d))
        })
    };
    // Differences along u: p[4 (i + 1) + j] - p[4 i + j]; along v: p[4 i + j + 1] - p[4 i + j].
    let du = || (0..12).map(|k| (k, k + 4));
    let dv = || (0..16).filter(|k| k % 4 != 3).map(|k| (k, k + 1));
    let xu = range(&|d| d.x, &mut du());
    let yu = range(&|d| d.y, &mut du());
    let xv = range(&|d| d.x, &mut dv());
    let yv = range(&|d| d.y, &mut dv());
    let a = imul(xu, yv);
    let b = imul(yu, xv);
    let det = (a.0 - b.1, a.1 - b.0);
    // The bounds are computed in floating point: ask for a margin of a few rounding errors of
    // the products, so that a bound within rounding of 0 does not count as excluding it.
    let margin = 16.0 * f64::EPSILON * (a.0.abs().max(a.1.abs()) + b.0.abs().max(b.1.abs()));
    det.0 > margin || det.1 < -margin
}

/// Whether the projected net `q` can cover the origin, by two "fat lines" (as in Bezier
/// clipping): for the net's mean direction along u and along v, the band of the control
/// points' signed distances from the line through the origin in that direction must contain 0
/// (within `eps`). By the convex-hull property the sub-patch's projection lies in both bands. A
/// sub-patch seen edge-on projects to a thin sliver at an angle, whose axis-aligned box is far
/// larger than the sliver: these bands are not.
pub(super) fn bands_hold_origin(q: &[DVec3; 16], eps: f64) -> bool {
    let band = |dir: DVec2| {
        let len = dir.length();
        if !(len > 0.0 && len.is_finite()) {
            return true;
        }
        let n = DVec2::new(-dir.y, dir.x) / len;
        let (lo, hi) = q
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let d = n.x * p.x + n.y * p.y;
                (lo.min(d), hi.max(d))
            });
        lo <= eps && hi >= -eps
    };
    let xy = |k: usize| DVec2::new(q[k].x, q[k].y);
    band(xy(12) - xy(0) + xy(15) - xy(3)) && band(xy(3) - xy(0) + xy(15) - xy(12))
}
