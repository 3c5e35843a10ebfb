//! Ray intersection with a bicubic Bezier patch (f64 core).
//!
//! The robust method projects the control points into a frame where the ray is the z axis
//! (`x = (p - o).e1`, `y = (p - o).e2`, `z = (p - o).d`). By the convex-hull property a sub-patch
//! can only be hit if its projected control points cover the origin: their box in x and y
//! contains it and overlaps `(t_min, t_best)` in z, and two fat lines (bands along the net's u and
//! v directions) contain it. Sub-patches that pass are split (de Casteljau, along the parameter in
//! which the control net is longer), nearer halves first. As soon as a sub-patch provably meets
//! the ray at most once (its projected map is injective, see `injective`) Newton's method inside its
//! domain finds that hit; sub-patches where the ray is tangent go on to leaves of [`LEAF`] of the
//! patch size, polished by Newton in (a slightly enlarged copy of) their domain, falling back to
//! the leaf's centre at [`FINAL_LEAF`]. The nearest hit found prunes all farther sub-patches.

use glam::{DVec2, DVec3};

use super::Solver;

/// Leaf size of the robust subdivision, relative to the patch size.
pub const LEAF: f64 = 1e-7;
/// Leaf size (relative) at which a leaf's centre is accepted when Newton's method fails there.
pub const FINAL_LEAF: f64 = 1e-11;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PatchHit {
    /// In units of the given ray direction.
    pub t: f64,
    pub p: DVec3,
    /// `(u, v)`: the patch parameters.
    pub uv: DVec2,
    /// Unit normal `dpdu x dpdv` (falls back to a neighbour's at degenerate corners).
    pub n: DVec3,
    pub dpdu: DVec3,
    pub dpdv: DVec3,
}

/// A bicubic patch, control points row-major (`p[4 i + j]`, `i` along u).
#[derive(Debug, Clone)]
pub struct Patch {
    p: [DVec3; 16],
    size: f64,
    /// The part of the original patch's parameter square this one covers: its `(0, 0)` corner
    /// and its extent (`(0, 0)` and `(1, 1)` for a whole patch; see [`Patch::piece`]).
    domain: (DVec2, DVec2),
    /// A box around the control net aligned with the net's own directions, if they span a plane.
    oriented: Option<OrientedBox>,
}

/// A box around a control net (so around its surface) in an orthonormal frame of the net's
/// mean u direction and normal: for a piece of a curved surface it is far tighter than the
/// axis-aligned box the BVH holds, and it is tested before the net is projected.
#[derive(Debug, Clone, Copy)]
struct OrientedBox {
    axes: [DVec3; 3],
    center: DVec3,
    /// Half extents along the axes, padded by `1e-9` of the patch size.
    half: DVec3,
}

impl OrientedBox {
    fn around(q: &[DVec3; 16], size: f64) -> Option<Self> {
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
    fn may_meet(&self, o: DVec3, dn: DVec3, tmin: f64, tmax: f64) -> bool {
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

fn bern3(t: f64) -> ([f64; 4], [f64; 4]) {
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
fn split4(c: [DVec3; 4]) -> ([DVec3; 4], [DVec3; 4]) {
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
fn restrict4(c: [DVec3; 4], a: f64, b: f64) -> [DVec3; 4] {
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
fn split_net(q: &[DVec3; 16], along_u: bool) -> ([DVec3; 16], [DVec3; 16]) {
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

fn net_bounds(q: &[DVec3; 16]) -> (DVec3, DVec3) {
    q.iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
}

/// Product of two intervals.
fn imul(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
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
fn injective(q: &[DVec3; 16]) -> bool {
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
fn bands_hold_origin(q: &[DVec3; 16], eps: f64) -> bool {
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

impl Patch {
    pub fn new(points: &[DVec3; 16]) -> Result<Self, String> {
        if let Some(p) = points.iter().find(|p| !p.is_finite()) {
            return Err(format!("bezier_patch control point {p} is not finite"));
        }
        let (lo, hi) = net_bounds(points);
        let size = (hi - lo).max_element().max(1e-300);
        Ok(Self {
            p: *points,
            size,
            domain: (DVec2::ZERO, DVec2::ONE),
            oriented: OrientedBox::around(points, size),
        })
    }

    /// The patch cut into `n x n` pieces over equal parameter squares (see [`Patch::piece`]),
    /// row-major in u.
    pub fn pieces(&self, n: u32) -> Vec<Patch> {
        let n = n.max(1);
        let at = |k: u32| f64::from(k) / f64::from(n);
        (0..n * n)
            .map(|k| {
                let (i, j) = (k / n, k % n);
                self.piece((at(i), at(i + 1)), (at(j), at(j + 1)))
            })
            .collect()
    }

    /// The part of the patch over `u0 <= u <= u1`, `v0 <= v <= v1` (within `[0, 1]`) as a patch
    /// of its own: its control net (tighter bounds than the whole net's), and hits reported in
    /// this patch's parameters (`uv`, `dpdu`, `dpdv`), so that pieces covering the square
    /// together give the whole patch's hits. Tolerances stay relative to this patch's size.
    pub fn piece(&self, (u0, u1): (f64, f64), (v0, v1): (f64, f64)) -> Patch {
        let mut q = self.p;
        for i in 0..4 {
            let row = restrict4([q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]], v0, v1);
            q[4 * i..4 * i + 4].copy_from_slice(&row);
        }
        for j in 0..4 {
            let col = restrict4([q[j], q[4 + j], q[8 + j], q[12 + j]], u0, u1);
            for (i, c) in col.into_iter().enumerate() {
                q[4 * i + j] = c;
            }
        }
        let (lo, ext) = self.domain;
        Patch {
            p: q,
            size: self.size,
            domain: (
                lo + ext * DVec2::new(u0, v0),
                ext * DVec2::new(u1 - u0, v1 - v0),
            ),
            oriented: OrientedBox::around(&q, self.size),
        }
    }

    pub fn points(&self) -> &[DVec3; 16] {
        &self.p
    }

    pub fn size(&self) -> f64 {
        self.size
    }

    /// Bounds of the control net (contains the patch).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        net_bounds(&self.p)
    }

    /// Point and partial derivatives at `(u, v)`.
    pub fn eval(&self, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
        let (bu, dbu) = bern3(u);
        let (bv, dbv) = bern3(v);
        let (mut p, mut pu, mut pv) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for i in 0..4 {
            for j in 0..4 {
                let c = self.p[4 * i + j];
                p += c * (bu[i] * bv[j]);
                pu += c * (dbu[i] * bv[j]);
                pv += c * (bu[i] * dbv[j]);
            }
        }
        (p, pu, pv)
    }

    /// Unit normal at `(u, v)`, stepping inward when a partial derivative vanishes (a collapsed
    /// edge, as at the teapot's lid and spout ends).
    pub fn normal(&self, u: f64, v: f64) -> DVec3 {
        for eps in [0.0, 1e-6, 1e-4, 1e-2] {
            let uu = if u < 0.5 { u + eps } else { u - eps };
            let vv = if v < 0.5 { v + eps } else { v - eps };
            let (_, pu, pv) = self.eval(uu, vv);
            let n = pu.cross(pv);
            if n.length() > 1e-12 * self.size * self.size {
                return n.normalize();
            }
        }
        DVec3::Z
    }

    /// The hit at this patch's own `(u, v)`, reported in the original patch's parameters.
    fn record(&self, o: DVec3, d: DVec3, t: f64, uv: DVec2) -> PatchHit {
        let (_, pu, pv) = self.eval(uv.x, uv.y);
        let (lo, ext) = self.domain;
        PatchHit {
            t,
            p: o + t * d,
            uv: lo + ext * uv,
            n: self.normal(uv.x, uv.y),
            dpdu: pu / ext.x,
            dpdv: pv / ext.y,
        }
    }

    /// Newton on the projected equations from `(u, v)`; the converged parameters and `t`
    /// (unit direction) if the residual reached rounding level.
    fn newton(
        &self,
        o: DVec3,
        frame: [DVec3; 3],
        mut uv: DVec2,
        iterations: u32,
        keep_in: (DVec2, DVec2),
    ) -> Option<(DVec2, f64)> {
        let [e1, e2, dn] = frame;
        let tol = 1e-12 * self.size;
        for _ in 0..iterations {
            let (p, pu, pv) = self.eval(uv.x, uv.y);
            let r = DVec2::new((p - o).dot(e1), (p - o).dot(e2));
            if r.abs().max_element() <= tol {
                return Some((uv, (p - o).dot(dn)));
            }
            let (a, b) = (pu.dot(e1), pv.dot(e1));
            let (c, dd) = (pu.dot(e2), pv.dot(e2));
            let det = a * dd - b * c;
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let step = DVec2::new(dd * r.x - b * r.y, a * r.y - c * r.x) / det;
            uv -= step;
            if uv.cmplt(keep_in.0).any() || uv.cmpgt(keep_in.1).any() {
                return None;
            }
        }
        let (p, _, _) = self.eval(uv.x, uv.y);
        let r = DVec2::new((p - o).dot(e1), (p - o).dot(e2));
        (r.abs().max_element() <= tol).then(|| (uv, (p - o).dot(dn)))
    }

    /// Nearest hit with `t_min < t < t_max`.
    pub fn intersect(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        solver: Solver,
    ) -> Option<PatchHit> {
        let dl = d.length();
        if !(dl > 0.0 && dl.is_finite() && o.is_finite()) {
            return None;
        }
        let dn = d / dl;
        let (e1, e2) = dn.any_orthonormal_pair();
        let frame = [e1, e2, dn];
        let (tmin, tmax) = (t_min * dl, t_max * dl);
        let found = match solver {
            Solver::Robust => {
                if let Some(b) = &self.oriented
                    && !b.may_meet(o, dn, tmin, tmax)
                {
                    return None;
                }
                self.subdivide(o, frame, tmin, tmax, LEAF, true)
            }
            Solver::Newton { iterations, starts } => {
                let k = (starts.max(1) as f64).sqrt().ceil() as u32;
                let mut best: Option<(DVec2, f64)> = None;
                for a in 0..k {
                    for b in 0..k {
                        let uv0 =
                            DVec2::new((a as f64 + 0.5) / k as f64, (b as f64 + 0.5) / k as f64);
                        let keep = (DVec2::splat(-0.5), DVec2::splat(1.5));
                        if let Some((uv, t)) = self.newton(o, frame, uv0, iterations, keep)
                            && uv.cmpge(DVec2::ZERO).all()
                            && uv.cmple(DVec2::ONE).all()
                            && t > tmin
                            && t < best.map_or(tmax, |b| b.1)
                        {
                            best = Some((uv, t));
                        }
                    }
                }
                best
            }
        };
        found.map(|(uv, t)| {
            let mut h = self.record(o, dn, t, uv);
            h.t = t / dl;
            h
        })
    }

    /// Subdivision with projected bounds. `leaf` is relative to the patch size; `polish`
    /// applies Newton's method at leaves (the robust method), otherwise a leaf's centre is the
    /// answer (the reference). Returns `(u, v)` and `t` for the unit direction.
    pub fn subdivide(
        &self,
        o: DVec3,
        frame: [DVec3; 3],
        tmin: f64,
        tmax: f64,
        leaf: f64,
        polish: bool,
    ) -> Option<(DVec2, f64)> {
        let [e1, e2, dn] = frame;
        let q: [DVec3; 16] = std::array::from_fn(|k| {
            let r = self.p[k] - o;
            DVec3::new(r.dot(e1), r.dot(e2), r.dot(dn))
        });
        let mut search = Search {
            patch: self,
            o,
            frame,
            tmin,
            eps: 1e-12 * self.size,
            leaf_size: leaf * self.size,
            // Where Newton fails the robust method subdivides on to the reference's resolution.
            final_leaf: if polish { FINAL_LEAF.min(leaf) } else { leaf } * self.size,
            polish,
            best: None,
            best_t: tmax,
        };
        let (lo, hi) = net_bounds(&q);
        if search.may_hit(lo, hi) && search.bands(&q) {
            search.visit(&q, (0.0, 1.0), (0.0, 1.0), lo, hi);
        }
        search.best
    }
}

/// Where Newton's method starts in a sub-patch that meets the ray at most once, in the
/// sub-patch's own parameters: the point where the bilinear map through its four projected
/// corners (points of the surface) covers the origin, by three Newton steps on that map from
/// the centre. Near the hit the sub-patch is close to that map, so the patch's own Newton
/// iterations (each an evaluation of the patch) start closer than from the centre. The centre
/// itself where the steps fail or leave the sub-patch.
fn bilinear_start(q: &[DVec3; 16]) -> DVec2 {
    let xy = |k: usize| DVec2::new(q[k].x, q[k].y);
    // Corners: (u, v) = (0, 0), (1, 0), (0, 1), (1, 1).
    let (a, b, c, d) = (xy(0), xy(12), xy(3), xy(15));
    let centre = DVec2::splat(0.5);
    let mut st = centre;
    for _ in 0..3 {
        let (s, t) = (st.x, st.y);
        let f =
            a * ((1.0 - s) * (1.0 - t)) + b * (s * (1.0 - t)) + c * ((1.0 - s) * t) + d * (s * t);
        let fs = (b - a) * (1.0 - t) + (d - c) * t;
        let ft = (c - a) * (1.0 - s) + (d - b) * s;
        let det = fs.x * ft.y - fs.y * ft.x;
        if det == 0.0 || !det.is_finite() {
            return centre;
        }
        st -= DVec2::new(ft.y * f.x - ft.x * f.y, fs.x * f.y - fs.y * f.x) / det;
    }
    if st.is_finite() && st.cmpge(DVec2::ZERO).all() && st.cmple(DVec2::ONE).all() {
        st
    } else {
        centre
    }
}

/// One ray's subdivision of a patch: the ray's frame, the tolerances, and the nearest hit found.
/// Sub-patches are visited depth first, the nearer half of each split first, each net on the
/// call stack of its visit (the depth is bounded: a split halves `u` or `v`, and a parameter
/// interval narrower than `1e-15` is a leaf), so no net is copied or allocated.
struct Search<'a> {
    patch: &'a Patch,
    o: DVec3,
    frame: [DVec3; 3],
    tmin: f64,
    eps: f64,
    leaf_size: f64,
    final_leaf: f64,
    polish: bool,
    best: Option<(DVec2, f64)>,
    best_t: f64,
}

impl Search<'_> {
    /// Whether a sub-patch's bounds can hold a hit nearer than the nearest found.
    fn may_hit(&self, lo: DVec3, hi: DVec3) -> bool {
        let eps = self.eps;
        lo.x <= eps
            && hi.x >= -eps
            && lo.y <= eps
            && hi.y >= -eps
            && hi.z > self.tmin
            && lo.z < self.best_t
    }

    /// The fat lines are the robust method's; the reference (`polish` off) keeps to the boxes,
    /// so that the stress test checks them against a method without them.
    fn bands(&self, q: &[DVec3; 16]) -> bool {
        !self.polish || bands_hold_origin(q, self.eps)
    }

    fn offer(&mut self, uv: DVec2, t: f64) {
        if t > self.tmin && t < self.best_t {
            self.best_t = t;
            self.best = Some((uv, t));
        }
    }

    /// The sub-patch with projected net `q` over `u x v`, with bounds `lo`, `hi`, which passed
    /// the tests when it was made.
    fn visit(&mut self, q: &[DVec3; 16], u: (f64, f64), v: (f64, f64), lo: DVec3, hi: DVec3) {
        if lo.z >= self.best_t {
            return;
        }
        let patch = self.patch;
        let ext = (hi - lo).max_element();
        let depth_exhausted = u.1 - u.0 < 1e-15 || v.1 - v.0 < 1e-15;
        let c = DVec2::new(0.5 * (u.0 + u.1), 0.5 * (v.0 + v.1));
        let w = DVec2::new(u.1 - u.0, v.1 - v.0);
        if self.polish && !depth_exhausted && injective(q) {
            // At most one hit in this piece: Newton's method inside its domain finds it.
            // A root that converges inside the domain is the piece's only one, so the piece
            // is done whatever its `t`; one outside is still a genuine hit (it prunes), but
            // the piece must then be split on.
            let lo = DVec2::new(u.0, v.0) - 0.5 * w;
            let hi = DVec2::new(u.1, v.1) + 0.5 * w;
            let keep = (lo.max(DVec2::ZERO), hi.min(DVec2::ONE));
            let start = DVec2::new(u.0, v.0) + w * bilinear_start(q);
            if let Some((uv, t)) = patch.newton(self.o, self.frame, start, 12, keep) {
                self.offer(uv, t);
                if uv.x >= u.0 && uv.x <= u.1 && uv.y >= v.0 && uv.y <= v.1 {
                    return;
                }
            }
        } else if self.polish && ext <= self.leaf_size && !depth_exhausted {
            // Newton inside (an enlarged copy of) the leaf's domain. Where it does not
            // converge (a bound that holds the ray but a surface piece that misses it, near
            // a tangency) keep subdividing: accepting the leaf there would report a hit that
            // is not one, in front of the real one.
            // Newton may also converge to a root outside the leaf: that is still a genuine
            // hit, and it prunes everything behind it.
            let whole = (DVec2::ZERO, DVec2::ONE);
            if let Some((uv, t)) = patch.newton(self.o, self.frame, c, 12, whole) {
                self.offer(uv, t);
                if (uv - c).abs().cmple(w).all() {
                    return;
                }
            }
        }
        if ext <= self.final_leaf || depth_exhausted {
            // Below rounding of any polish: the leaf's centre is the answer.
            let (p, _, _) = patch.eval(c.x, c.y);
            self.offer(c, (p - self.o).dot(self.frame[2]));
            return;
        }
        // Split along the parameter in which the control net is longer (corner edges).
        let lu = (q[12] - q[0]).length_squared() + (q[15] - q[3]).length_squared();
        let lv = (q[3] - q[0]).length_squared() + (q[15] - q[12]).length_squared();
        let along_u = lu >= lv;
        let (a, b) = split_net(q, along_u);
        let ((ua, va), (ub, vb)) = if along_u {
            let mid = 0.5 * (u.0 + u.1);
            (((u.0, mid), v), ((mid, u.1), v))
        } else {
            let mid = 0.5 * (v.0 + v.1);
            ((u, (v.0, mid)), (u, (mid, v.1)))
        };
        let (la, ha) = net_bounds(&a);
        let (lb, hb) = net_bounds(&b);
        // Both halves are tested now, against the nearest hit found so far; the nearer is
        // examined first, and the farther only if it is still nearer than what that found.
        let take_a = self.may_hit(la, ha) && self.bands(&a);
        let take_b = self.may_hit(lb, hb) && self.bands(&b);
        if la.z <= lb.z {
            if take_a {
                self.visit(&a, ua, va, la, ha);
            }
            if take_b {
                self.visit(&b, ub, vb, lb, hb);
            }
        } else {
            if take_b {
                self.visit(&b, ub, vb, lb, hb);
            }
            if take_a {
                self.visit(&a, ua, va, la, ha);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// A bumpy height field over [0, 3]^2 whose rows also lean (not a graph along every ray).
    fn bumpy() -> Patch {
        let z = [
            [0.0, 0.8, -0.6, 0.2],
            [0.5, -1.2, 1.4, -0.3],
            [-0.4, 1.5, -1.1, 0.6],
            [0.3, -0.2, 0.7, 0.0],
        ];
        Patch::new(&std::array::from_fn(|k| {
            let (i, j) = (k / 4, k % 4);
            DVec3::new(i as f64 + 0.3 * z[i][j], j as f64, z[i][j])
        }))
        .unwrap()
    }

    fn f(rng: &mut Rng) -> f64 {
        f64::from(rng.f32())
    }

    #[test]
    fn a_restricted_cubic_is_the_same_curve() {
        let c = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 2.0, -1.0),
            DVec3::new(2.0, -1.0, 0.5),
            DVec3::new(3.0, 1.0, 2.0),
        ];
        let at = |c: &[DVec3; 4], t: f64| {
            let (b, _) = bern3(t);
            (0..4).map(|k| c[k] * b[k]).sum::<DVec3>()
        };
        for (a, b) in [
            (0.0, 1.0),
            (0.0, 0.375),
            (0.3, 0.7),
            (0.625, 1.0),
            (0.875, 1.0),
        ] {
            let r = restrict4(c, a, b);
            for s in [0.0, 0.1, 0.5, 0.93, 1.0] {
                let (want, got) = (at(&c, a + s * (b - a)), at(&r, s));
                assert!(
                    (want - got).length() < 1e-14,
                    "[{a}, {b}] at {s}: {got} vs {want}"
                );
            }
        }
    }

    /// A random unit direction.
    fn dir(rng: &mut Rng) -> DVec3 {
        let d = DVec3::new(f(rng) - 0.5, f(rng) - 0.5, f(rng) - 0.5);
        d.try_normalize().unwrap_or(DVec3::X)
    }

    /// The oriented box drops only rays that miss: on pieces of a bumpy, a flat, a tiny and a
    /// far-away patch, rays aimed at surface points (the pieces' corners among them, which lie on
    /// the box's faces), rays leaving surface points, rays in a surface point's tangent plane
    /// and random rays through the axis-aligned box get the same answer, bit for bit, as the
    /// subdivision without the box; and the box does drop a share of the random rays.
    #[test]
    fn the_oriented_box_drops_only_rays_that_miss() {
        let flat = Patch::new(&std::array::from_fn(|k| {
            DVec3::new((k / 4) as f64, (k % 4) as f64 * 0.7, 0.0)
        }))
        .unwrap();
        let moved = |p: &Patch, scale: f64, shift: DVec3| {
            Patch::new(&p.points().map(|q| q * scale + shift)).unwrap()
        };
        let b = bumpy();
        let patches = [
            b.clone(),
            flat.clone(),
            moved(&b, 1e-4, DVec3::new(0.3, -2.0, 1.0)),
            moved(&b, 1.0, DVec3::new(1e6, -3e5, 2e6)),
            moved(&flat, 1.0, DVec3::splat(-1e5)),
        ];
        let mut rng = Rng::new(31);
        let (mut random, mut missed, mut dropped) = (0u32, 0u32, 0u32);
        for whole in &patches {
            let size = whole.size();
            for piece in whole.pieces(8) {
                let ob = piece.oriented.expect("the pieces span a plane");
                let (lo, hi) = piece.bounds();
                for i in 0..400 {
                    let (uv, corner) = if i % 8 == 0 {
                        let c = DVec2::new((i / 8 % 2) as f64, (i / 16 % 2) as f64);
                        (c, true)
                    } else {
                        (DVec2::new(f(&mut rng), f(&mut rng)), false)
                    };
                    let (q, pu, pv) = piece.eval(uv.x, uv.y);
                    let (o, d, tmin) = match i % 4 {
                        // Aimed at the surface point from three sizes away.
                        0 | 1 => {
                            let d = dir(&mut rng);
                            (q - 3.0 * size * d, d, 1e-9)
                        }
                        // Leaving the surface point.
                        2 if !corner => (q, dir(&mut rng), 1e-9 * size),
                        // In the tangent plane, passing through the point.
                        2 => {
                            let t = (pu.normalize() + pv.normalize()).normalize();
                            (q - 2.0 * size * t, t, 1e-9)
                        }
                        // Random rays through the piece's axis-aligned box.
                        _ => {
                            let at =
                                lo + (hi - lo) * DVec3::new(f(&mut rng), f(&mut rng), f(&mut rng));
                            let d = dir(&mut rng);
                            random += 1;
                            (at - 2.0 * size * d, d, 1e-9)
                        }
                    };
                    // As `intersect` frames the ray.
                    let dl = d.length();
                    let dn = d / dl;
                    let (e1, e2) = dn.any_orthonormal_pair();
                    let want = piece
                        .subdivide(o, [e1, e2, dn], tmin * dl, f64::INFINITY, LEAF, true)
                        .map(|(uv, t)| (uv, t / dl));
                    let got = piece.intersect(o, d, tmin, f64::INFINITY, Solver::Robust);
                    assert_eq!(
                        want.map(|(_, t)| t),
                        got.map(|h| h.t),
                        "o {o} d {d} (case {})",
                        i % 4
                    );
                    if want.is_some() {
                        assert!(ob.may_meet(o, dn, tmin * dl, f64::INFINITY));
                    } else if i % 4 == 3 {
                        missed += 1;
                        dropped += u32::from(!ob.may_meet(o, dn, tmin * dl, f64::INFINITY));
                    }
                }
            }
        }
        println!("random rays {random}, missing {missed}, dropped by the box {dropped}");
        // Measured: about half of them (1643 of 3252).
        assert!(
            dropped * 3 > missed,
            "the box dropped {dropped} of the {missed} random rays that miss"
        );
    }

    /// The nearest hit over a patch's pieces is the whole patch's hit, reported in the whole
    /// patch's parameters: random rays through its box, and rays aimed at the seams between
    /// pieces (where a gap or an overlap would show), for dyadic and non-dyadic cuts.
    #[test]
    fn pieces_hit_where_the_whole_patch_does() {
        let whole = bumpy();
        let (lo, hi) = whole.bounds();
        let size = whole.size();
        let mut rng = Rng::new(9);
        for n in [3u32, 8] {
            let pieces = whole.pieces(n);
            let (mut hits, mut seam_hits, mut worst) = (0, 0, 0.0f64);
            for i in 0..6000 {
                let seam = i % 2 == 1;
                let target = if seam {
                    // A point on a seam: u (or v) a multiple of 1/n.
                    let k = f64::from(1 + (rng.f32() * (n - 1) as f32) as u32) / f64::from(n);
                    let w = f(&mut rng);
                    let (u, v) = if i % 4 == 1 { (k, w) } else { (w, k) };
                    whole.eval(u, v).0
                } else {
                    lo + (hi - lo) * DVec3::new(f(&mut rng), f(&mut rng), f(&mut rng))
                };
                let d = DVec3::new(f(&mut rng) - 0.5, f(&mut rng) - 0.5, f(&mut rng) - 0.5);
                if d.length() < 1e-3 {
                    continue;
                }
                let d = d.normalize();
                let o = target - d * 3.0 * size;
                let want = whole.intersect(o, d, 1e-9, f64::INFINITY, Solver::Robust);
                let mut got: Option<PatchHit> = None;
                for p in &pieces {
                    let t_max = got.map_or(f64::INFINITY, |h| h.t);
                    if let Some(h) = p.intersect(o, d, 1e-9, t_max, Solver::Robust) {
                        got = Some(h);
                    }
                }
                match (want, got) {
                    (None, None) => {}
                    (Some(w), Some(g)) => {
                        hits += 1;
                        seam_hits += seam as usize;
                        // Both are hits to the method's tolerance (residual 1e-12 of the size
                        // across the ray; along a grazing ray that is more in t).
                        worst = worst.max((w.t - g.t).abs() / w.t);
                        assert!(
                            (w.t - g.t).abs() <= 1e-7 * w.t,
                            "ray {i}: t {} vs {}",
                            g.t,
                            w.t
                        );
                        // The pieces report the whole patch's (u, v): it evaluates to the hit.
                        let (q, pu, pv) = whole.eval(g.uv.x, g.uv.y);
                        assert!((q - g.p).length() <= 1e-7 * size, "ray {i}: uv {}", g.uv);
                        assert!((pu - g.dpdu).length() <= 1e-9 * pu.length().max(size));
                        assert!((pv - g.dpdv).length() <= 1e-9 * pv.length().max(size));
                        assert!(g.n.dot(w.n) > 1.0 - 1e-6);
                    }
                    _ => panic!("ray {i} (n = {n}, seam {seam}): whole {want:?}, pieces {got:?}"),
                }
            }
            println!(
                "n = {n}: {hits} hits, {seam_hits} on seams, largest relative t gap {worst:.1e}"
            );
            assert!(
                hits > 2000 && seam_hits > 1000,
                "n = {n}: {hits} hits, {seam_hits} on seams"
            );
        }
    }
}
