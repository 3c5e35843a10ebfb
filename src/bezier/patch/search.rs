//! One ray's subdivision of a patch and where Newton's method starts in a sub-patch.

use glam::{DVec2, DVec3};

use super::Patch;
use super::net::{bands_hold_origin, injective, net_bounds, split_net};

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
pub(super) struct Search<'a> {
    pub(super) patch: &'a Patch,
    pub(super) o: DVec3,
    pub(super) frame: [DVec3; 3],
    pub(super) tmin: f64,
    pub(super) eps: f64,
    pub(super) leaf_size: f64,
    pub(super) final_leaf: f64,
    pub(super) polish: bool,
    pub(super) best: Option<(DVec2, f64)>,
    pub(super) best_t: f64,
    /// How many more sub-patches this ray may visit ([`MAX_VISITS`]).
    pub(super) visits_left: u32,
}

/// Most sub-patches one ray's robust search visits. The stress tests' rays (random, grazing,
/// near cusps and poles) need at most about 150; a net of wildly different magnitudes (two
/// control points 10^11 from a unit patch) made the search visit sub-patches by the billion
/// and a render stop answering. Past the bound the search ends with the nearest hit found so
/// far.
pub(super) const MAX_VISITS: u32 = 1 << 11;

impl Search<'_> {
    /// Whether a sub-patch's bounds can hold a hit nearer than the nearest found.
    pub(super) fn may_hit(&self, lo: DVec3, hi: DVec3) -> bool {
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
    pub(super) fn bands(&self, q: &[DVec3; 16]) -> bool {
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
    pub(super) fn visit(
        &mut self,
        q: &[DVec3; 16],
        u: (f64, f64),
        v: (f64, f64),
        lo: DVec3,
        hi: DVec3,
    ) {
        if self.visits_left == 0 || lo.z >= self.best_t {
            return;
        }
        self.visits_left -= 1;
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
