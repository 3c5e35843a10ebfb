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
use net::{OrientedBox, bern3, net_bounds, restrict4};
use search::{MAX_VISITS, Search};

mod net;
mod search;
#[cfg(test)]
mod tests;

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
        self.search(o, frame, (tmin, tmax), leaf, polish).best
    }

    /// [`Patch::subdivide`]'s search, finished.
    fn search(
        &self,
        o: DVec3,
        frame: [DVec3; 3],
        (tmin, tmax): (f64, f64),
        leaf: f64,
        polish: bool,
    ) -> Search<'_> {
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
            // The reference (measurement only) may visit as many as it needs.
            visits_left: if polish { MAX_VISITS } else { u32::MAX },
        };
        let (lo, hi) = net_bounds(&q);
        if search.may_hit(lo, hi) && search.bands(&q) {
            search.visit(&q, (0.0, 1.0), (0.0, 1.0), lo, hi);
        }
        search
    }
}
