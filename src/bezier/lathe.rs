//! Ray intersection with a surface of revolution of a piecewise Bezier profile (f64 core).
//!
//! The profile `(r(s), h(s))`, `s` in [0, 1] per segment, is swept around the y axis:
//! `P(s, phi) = (r cos phi, h, r sin phi)`, `phi = atan2(z, x)` in [0, 2 pi).
//!
//! A ray `o + t d` (unit `d`) meets the surface where its height is `h(s)` and its distance from
//! the axis is `r(s)`. Eliminating `t = (h(s) - o_y) / d_y` gives one polynomial of degree `2n`:
//!
//! `F(s) = (o_x d_y + (h - o_y) d_x)^2 + (o_z d_y + (h - o_y) d_z)^2 - d_y^2 r^2`,
//!
//! formed exactly in the Bernstein basis (products of the profile's coordinate polynomials), and
//! its roots in [0, 1] are isolated by [`super::roots`]. How `t` is recovered from `s` depends on
//! the ray: for steep rays (`|d_y| >= |d_xz|`) from the height, for flat rays from the distance to
//! the axis (`t = t_c +- sqrt(r^2 - rho^2) / |d_xz|` around the point of closest approach), which
//! stays well conditioned as `d_y -> 0` where the roots of `F` merge into double roots.

use std::f64::consts::TAU;

use glam::{DVec2, DVec3};

use super::Solver;
use super::bernstein::Bernstein;
use super::roots::{Root, RootKind, find_roots, find_roots_with_noise};

/// Samples per segment of the arc-length and area tables.
const TABLE_STEPS: usize = 32;

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
    pub(crate) rmax: f64,
    pub(crate) hmin: f64,
    pub(crate) hmax: f64,
    /// Cumulative arc length at `TABLE_STEPS + 1` uniform parameters.
    len_table: Vec<f64>,
    /// Cumulative `integral r |P'| ds` at the same parameters.
    area_table: Vec<f64>,
    /// All control points coincide: the segment is a point (or circle) of zero area.
    pub degenerate: bool,
}

impl Segment {
    fn new(points: &[DVec2]) -> Self {
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
        let mut seg = Self {
            r,
            h,
            rmax,
            hmin,
            hmax,
            len_table: vec![0.0],
            area_table: vec![0.0],
            degenerate,
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

    fn length(&self) -> f64 {
        self.len_table[TABLE_STEPS]
    }

    /// Arc length from the segment start to `s`.
    fn arc(&self, s: f64) -> f64 {
        let s = s.clamp(0.0, 1.0);
        let k = ((s * TABLE_STEPS as f64) as usize).min(TABLE_STEPS - 1);
        self.len_table[k] + self.integrate(k as f64 / TABLE_STEPS as f64, s, |_| 1.0)
    }

    pub fn point(&self, s: f64) -> DVec2 {
        DVec2::new(self.r.eval(s), self.h.eval(s))
    }

    /// Unit tangent of the profile at `s` (robust to repeated control points).
    fn tangent(&self, s: f64, size: f64) -> DVec2 {
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

/// Which part of the surface was hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// The swept profile (segment index).
    Side(usize),
    /// The flat cap at the start angle of a partial sweep.
    StartCap,
    /// The flat cap at the end angle.
    EndCap,
}

/// A hit in the lathe's own space, `t` in units of the ray direction given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatheHit {
    pub t: f64,
    pub p: DVec3,
    /// Unit outward geometric normal (outward is to the right of the profile's direction).
    pub n: DVec3,
    pub uv: DVec2,
    pub dpdu: DVec3,
    pub part: Part,
    /// Profile parameter within the segment (0 on caps).
    pub s: f64,
}

/// A surface of revolution, ready for intersection.
#[derive(Debug, Clone)]
pub struct Lathe {
    segs: Vec<Segment>,
    /// Partial sweep: start angle in [0, 2 pi) and span in (0, 2 pi), radians.
    sweep: Option<(f64, f64)>,
    rmax: f64,
    hmin: f64,
    hmax: f64,
    size: f64,
    /// Arc length before each segment, and in total.
    len_before: Vec<f64>,
    total_len: f64,
    /// Cumulative side area over all segments' table steps (for sampling).
    area_cdf: Vec<f64>,
}

impl Lathe {
    /// Validates the profile. `sweep` is `(start, end)` in degrees.
    pub fn new(segments: &[Vec<DVec2>], sweep: Option<(f64, f64)>) -> Result<Self, String> {
        if segments.is_empty() {
            return Err("a revolve profile needs at least one segment".into());
        }
        for (i, seg) in segments.iter().enumerate() {
            if seg.len() < 2 || seg.len() > 8 {
                return Err(format!(
                    "profile segment {} has {} control points; a Bezier segment needs 2 to 8 \
                     (degree 1 to 7)",
                    i + 1,
                    seg.len()
                ));
            }
            if let Some(p) = seg.iter().find(|p| !p.is_finite()) {
                return Err(format!(
                    "profile segment {} has a non-finite control point <{}, {}>",
                    i + 1,
                    p.x,
                    p.y
                ));
            }
            if let Some(p) = seg.iter().find(|p| p.x < 0.0) {
                return Err(format!(
                    "profile segment {} has a negative radius at <{}, {}>; radii must be >= 0 \
                     (the profile is swept around the axis)",
                    i + 1,
                    p.x,
                    p.y
                ));
            }
        }
        let sweep = match sweep {
            None => None,
            Some((a0, a1)) => {
                if !a0.is_finite() || !a1.is_finite() {
                    return Err("the sweep angles must be finite".into());
                }
                let span = a1 - a0;
                if span <= 0.0 {
                    return Err(format!(
                        "the sweep `angle {a0}, {a1}` is empty; the end angle must exceed the start"
                    ));
                }
                if span >= 360.0 {
                    None
                } else {
                    Some((a0.to_radians().rem_euclid(TAU), span.to_radians()))
                }
            }
        };
        let segs: Vec<Segment> = segments.iter().map(|s| Segment::new(s)).collect();
        let rmax = segs.iter().map(|s| s.rmax).fold(0.0, f64::max);
        let hmin = segs.iter().map(|s| s.hmin).fold(f64::INFINITY, f64::min);
        let hmax = segs
            .iter()
            .map(|s| s.hmax)
            .fold(f64::NEG_INFINITY, f64::max);
        let size = rmax.max(hmax - hmin).max(1e-300);
        let mut len_before = Vec::new();
        let mut total_len = 0.0;
        for s in &segs {
            len_before.push(total_len);
            total_len += s.length();
        }
        let mut area_cdf = vec![0.0];
        for s in &segs {
            let base = *area_cdf.last().unwrap_or(&0.0);
            area_cdf.extend(s.area_table[1..].iter().map(|a| base + a));
        }
        Ok(Self {
            segs,
            sweep,
            rmax,
            hmin,
            hmax,
            size,
            len_before,
            total_len,
            area_cdf,
        })
    }

    /// Object-space bounds `(min, max)`: the control polygon's, limited to the swept sector.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let r = self.rmax;
        let (mut lo, mut hi) = (
            DVec3::new(0.0, self.hmin, 0.0),
            DVec3::new(0.0, self.hmax, 0.0),
        );
        let mut add = |a: f64| {
            let p = DVec3::new(r * a.cos(), 0.0, r * a.sin());
            lo = lo.min(p);
            hi = hi.max(p);
        };
        match self.sweep {
            None => {
                lo = DVec3::new(-r, self.hmin, -r);
                hi = DVec3::new(r, self.hmax, r);
            }
            Some((a0, span)) => {
                add(a0);
                add(a0 + span);
                for k in 0..8 {
                    let a = k as f64 * TAU / 4.0;
                    if (a - a0).rem_euclid(TAU) <= span {
                        add(a);
                    }
                }
            }
        }
        (lo, hi)
    }

    /// The size used for relative tolerances (largest of radius and height).
    pub fn size(&self) -> f64 {
        self.size
    }

    pub fn segments(&self) -> &[Segment] {
        &self.segs
    }

    pub fn sweep(&self) -> Option<(f64, f64)> {
        self.sweep
    }

    fn in_sweep(&self, p: DVec3) -> bool {
        match self.sweep {
            None => true,
            Some((a0, span)) => (p.z.atan2(p.x) - a0).rem_euclid(TAU) <= span,
        }
    }

    /// Nearest hit with `t_min < t < t_max`.
    pub fn intersect(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        solver: Solver,
    ) -> Option<LatheHit> {
        let dl = d.length();
        if !(dl > 0.0 && dl.is_finite() && o.is_finite()) {
            return None;
        }
        let frame = RayFrame::new(o, d / dl, self.hmin, self.hmax);
        let dn = frame.dn;
        let (tmin, mut best) = (t_min * dl, t_max * dl);
        let mut found: Option<(f64, Part, f64)> = None;
        let mut roots = Vec::new();
        for (i, seg) in self.segs.iter().enumerate() {
            if !frame.may_hit(seg, tmin, best, self.size) {
                continue;
            }
            let (f, noise) = frame.polynomial(seg);
            roots.clear();
            match solver {
                Solver::Robust => find_roots_with_noise(&f, noise, &mut roots),
                Solver::Newton { iterations, starts } => {
                    newton_roots(&f, noise, iterations, starts, &mut roots)
                }
            }
            for root in &roots {
                let ds = root_uncertainty(&f, root.t, noise);
                for (t, s) in frame.candidates(seg, root, ds, self.size, Refine::FalsePosition) {
                    if t > tmin && t < best && self.in_sweep(o + t * dn) {
                        best = t;
                        found = Some((t, Part::Side(i), s));
                    }
                }
            }
        }
        self.cap_hits(&frame, tmin, &mut best, &mut found);
        let (t, part, s) = found?;
        Some(self.hit_record(o + t * dn, t / dl, part, s))
    }

    /// The nearer of the two side caps of a partial sweep, if nearer than `best`.
    pub fn cap_hits(
        &self,
        frame: &RayFrame,
        tmin: f64,
        best: &mut f64,
        found: &mut Option<(f64, Part, f64)>,
    ) {
        let (o, dn) = (frame.o, frame.dn);
        if let Some((a0, span)) = self.sweep {
            for (angle, part) in [(a0, Part::StartCap), (a0 + span, Part::EndCap)] {
                let e = DVec3::new(angle.cos(), 0.0, angle.sin());
                let m = DVec3::new(-angle.sin(), 0.0, angle.cos());
                let den = dn.dot(m);
                if den == 0.0 {
                    continue;
                }
                let t = -o.dot(m) / den;
                if !(t > tmin && t < *best) {
                    continue;
                }
                let p = o + t * dn;
                let rp = p.dot(e);
                if rp >= 0.0 && self.inside_profile(rp, p.y) {
                    *best = t;
                    *found = Some((t, part, 0.0));
                }
            }
        }
    }

    /// Whether `(r, y)` of the meridian half-plane lies inside the region the profile encloses
    /// together with the axis (even-odd rule along a ray toward `+r`).
    pub fn inside_profile(&self, r: f64, y: f64) -> bool {
        let mut crossings = 0;
        let mut roots = Vec::new();
        let last = self.segs.len() - 1;
        for (i, seg) in self.segs.iter().enumerate() {
            if y < seg.hmin || y > seg.hmax {
                continue;
            }
            roots.clear();
            find_roots(&seg.h.add_constant(-y), &mut roots);
            for root in &roots {
                // A shared end point belongs to the next segment only.
                if root.kind == RootKind::Simple
                    && (i == last || root.t < 1.0 - 1e-12)
                    && seg.r.eval(root.t) > r
                {
                    crossings += 1;
                }
            }
        }
        crossings % 2 == 1
    }

    pub fn hit_record(&self, p: DVec3, t: f64, part: Part, s: f64) -> LatheHit {
        let (a0, span) = self.sweep.unwrap_or((0.0, TAU));
        match part {
            Part::Side(i) => {
                let seg = &self.segs[i];
                let rxz = (p.x * p.x + p.z * p.z).sqrt();
                let phi = p.z.atan2(p.x);
                let (c, sn) = if rxz > 0.0 {
                    (p.x / rxz, p.z / rxz)
                } else {
                    (phi.cos(), phi.sin())
                };
                let tan = seg.tangent(s, self.size);
                let n = DVec3::new(tan.y * c, -tan.x, tan.y * sn).normalize();
                let dpdu = DVec3::new(tan.x * c, tan.y, tan.x * sn) * self.total_len.max(1e-300);
                let u = (self.len_before[i] + seg.arc(s)) / self.total_len.max(1e-300);
                let v = (phi - a0).rem_euclid(TAU) / span;
                LatheHit {
                    t,
                    p,
                    n,
                    uv: DVec2::new(u.clamp(0.0, 1.0), v.clamp(0.0, 1.0)),
                    dpdu,
                    part,
                    s,
                }
            }
            Part::StartCap | Part::EndCap => {
                let angle = if part == Part::StartCap {
                    a0
                } else {
                    a0 + span
                };
                let e = DVec3::new(angle.cos(), 0.0, angle.sin());
                let m = DVec3::new(-angle.sin(), 0.0, angle.cos());
                let n = if part == Part::StartCap { -m } else { m };
                let h = (self.hmax - self.hmin).max(1e-300);
                LatheHit {
                    t,
                    p,
                    n,
                    uv: DVec2::new(
                        (p.dot(e) / self.rmax.max(1e-300)).clamp(0.0, 1.0),
                        ((p.y - self.hmin) / h).clamp(0.0, 1.0),
                    ),
                    dpdu: e * self.rmax,
                    part,
                    s: 0.0,
                }
            }
        }
    }

    /// Area of the swept side (caps excluded), from the tabulated `integral r |P'| ds`.
    pub fn area(&self) -> f64 {
        let span = self.sweep.map_or(TAU, |s| s.1);
        span * self.area_cdf.last().copied().unwrap_or(0.0)
    }

    /// A point on the side, distributed by area up to the table's piecewise-uniform
    /// approximation within each of the `TABLE_STEPS` parameter steps of a segment.
    /// Returns the point and its unit outward normal.
    pub fn sample(&self, u: DVec2) -> Option<(DVec3, DVec3)> {
        let total = *self.area_cdf.last()?;
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = u.x.clamp(0.0, 1.0) * total;
        let k = self
            .area_cdf
            .partition_point(|&a| a <= target)
            .clamp(1, self.area_cdf.len() - 1)
            - 1;
        let (lo, hi) = (self.area_cdf[k], self.area_cdf[k + 1]);
        let frac = if hi > lo {
            (target - lo) / (hi - lo)
        } else {
            0.5
        };
        let seg_i = k / TABLE_STEPS;
        let step = k % TABLE_STEPS;
        let s = (step as f64 + frac.clamp(0.0, 1.0)) / TABLE_STEPS as f64;
        let (a0, span) = self.sweep.unwrap_or((0.0, TAU));
        let phi = a0 + u.y.clamp(0.0, 1.0) * span;
        let seg = &self.segs[seg_i];
        let q = seg.point(s);
        let p = DVec3::new(q.x * phi.cos(), q.y, q.x * phi.sin());
        let tan = seg.tangent(s, self.size);
        let n = DVec3::new(tan.y * phi.cos(), -tan.x, tan.y * phi.sin()).normalize();
        Some((p, n))
    }

    /// The surface point of segment `i` at `(s, phi)`.
    pub fn surface_point(&self, i: usize, s: f64, phi: f64) -> DVec3 {
        let q = self.segs[i].point(s);
        DVec3::new(q.x * phi.cos(), q.y, q.x * phi.sin())
    }
}

/// A ray prepared for one lathe: unit direction and an origin shifted near the surface.
#[derive(Debug, Clone, Copy)]
pub struct RayFrame {
    pub o: DVec3,
    pub dn: DVec3,
    pub dh2: f64,
    /// `|d_y| >= |d_xz|`: `t` is recovered from the height, otherwise from the radius.
    steep: bool,
    pub(crate) t0: f64,
    /// `o + t0 dn`: the point of closest approach to the axis (flat rays) or at mid-height.
    pub oc: DVec3,
    pub(crate) rho2: f64,
    line_rho2: f64,
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
        let line_rho2 = if dh2 > 0.0 {
            let tc = -(oc.x * dn.x + oc.z * dn.z) / dh2;
            let q = oc + tc * dn;
            q.x * q.x + q.z * q.z
        } else {
            rho2
        };
        Self {
            o,
            dn,
            dh2,
            steep,
            t0,
            oc,
            rho2,
            line_rho2,
        }
    }

    /// Cheap culling: the ray's line passes outside the segment's bounding cylinder or its
    /// height range lies outside `(tmin, tmax)`.
    pub fn may_hit(&self, seg: &Segment, tmin: f64, tmax: f64, size: f64) -> bool {
        let (o, dn) = (self.o, self.dn);
        if seg.degenerate || self.line_rho2 > seg.rmax * seg.rmax * (1.0 + 1e-12) {
            return false;
        }
        if dn.y != 0.0 {
            let ta = (seg.hmin - o.y) / dn.y;
            let tb = (seg.hmax - o.y) / dn.y;
            let (ta, tb) = (ta.min(tb), ta.max(tb));
            let slack = 1e-9 * size;
            !(tb < tmin - slack || ta > tmax + slack)
        } else {
            o.y >= seg.hmin - 1e-12 * size && o.y <= seg.hmax + 1e-12 * size
        }
    }

    /// The polynomial `F(s)` of the segment (see the module docs) and its rounding noise.
    pub fn polynomial(&self, seg: &Segment) -> (Bernstein, f64) {
        let (oc, dn) = (self.oc, self.dn);
        let a = seg.h.scale(dn.x).add_constant(oc.x * dn.y - oc.y * dn.x);
        let b = seg.h.scale(dn.z).add_constant(oc.z * dn.y - oc.y * dn.z);
        let rr = seg.r.mul(&seg.r).expect("degree <= 14");
        let f = a
            .mul(&a)
            .and_then(|aa| aa.add(&b.mul(&b)?))
            .and_then(|s| s.add(&rr.scale(-dn.y * dn.y)))
            .expect("degree <= 14");
        let scale = a.max_abs().powi(2) + b.max_abs().powi(2) + dn.y * dn.y * rr.max_abs();
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
    /// `ds` is the uncertainty of `s` from rounding (see [`root_uncertainty`]).
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
    pub fn candidates(
        &self,
        seg: &Segment,
        root: &Root,
        ds: f64,
        size: f64,
        refine: Refine,
    ) -> [(f64, f64); 2] {
        let (oc, dn) = (self.oc, self.dn);
        let lo = (root.lo - 4.0 * ds).max(0.0);
        let hi = (root.hi + 4.0 * ds).min(1.0);
        let mut cands = [(f64::NAN, root.t); 2];
        if self.steep {
            let t_of = |s: f64| (seg.h.eval(s) - oc.y) / dn.y;
            let g = |s: f64| {
                let t = t_of(s);
                let (x, z) = (oc.x + t * dn.x, oc.z + t * dn.z);
                seg.r.eval(s) - (x * x + z * z).sqrt()
            };
            if let Some(s) = nearest_sign_change(&g, &|s| t_of(s), lo, hi, refine) {
                cands[0] = (self.t0 + t_of(s), s);
                return cands;
            }
            // A tangency: keep it only where the factor really reaches zero.
            if let Some(s) = touch(&g, lo, hi, size) {
                cands[0] = (self.t0 + t_of(s), s);
            }
            return cands;
        }
        let w_of = |s: f64| {
            let r = seg.r.eval(s);
            ((r * r - self.rho2) / self.dh2).max(0.0).sqrt()
        };
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
            seg.h.eval(s) - (oc.y + dn.y * sigma * w_of(s))
        };
        let mut refined = false;
        for (k, sigma) in [1.0, -1.0].into_iter().enumerate() {
            if let Some(s) =
                nearest_sign_change(&|s| g(sigma, s), &|s| sigma * w_of(s), lo, hi, refine)
            {
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
            if let Some(s) = touch(&|s| g(sigma, s), lo, hi, size) {
                cands[k] = (self.t0 + sigma * w_of(s), s);
            }
        }
        cands
    }
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

/// Scans `[lo, hi]` in 16 pieces for sign changes of `g` (NaN: no hit there) and returns the
/// refined root with the smallest `t(s)`. Neighbouring pieces share their end samples.
fn nearest_sign_change(
    g: &dyn Fn(f64) -> f64,
    t: &dyn Fn(f64) -> f64,
    lo: f64,
    hi: f64,
    refine: Refine,
) -> Option<f64> {
    let mut best: Option<(f64, f64)> = None;
    let n = 16;
    let x = |k: usize| lo + (hi - lo) * k as f64 / n as f64;
    let (mut a, mut ga) = (x(0), g(x(0)));
    for k in 0..n {
        let b = x(k + 1);
        let gb = g(b);
        if let Some(s) = bracketed_root(g, a, b, ga, gb, refine) {
            let ts = t(s);
            if best.is_none_or(|(_, bt)| ts < bt) {
                best = Some((s, ts));
            }
        }
        (a, ga) = (b, gb);
    }
    best.map(|b| b.0)
}

/// How a sign change of a factor is refined to the last bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refine {
    /// False position with the Illinois modification, a bisection every third step (the bracket
    /// at least halves every three steps); plain bisection from the start once a NaN is met.
    FalsePosition,
    /// Plain bisection (about 50 evaluations): the reference's method.
    Bisection,
}

/// A root of `g` in `[lo, hi]` (`ga`, `gb`: the values at the ends) if `g` changes sign there.
/// Where one end is not reachable (NaN: the ray does not get to that radius), that end is first
/// moved to the edge of the reachable part, where the two sides of the ray meet (`w = 0`); a sign
/// change between the other end and that edge is a hit close to the ray's closest approach to
/// the axis.
///
/// With one sign change in the bracket both refinements find the same root (to the last bit).
/// With several (roots closer than a sixteenth of the bracket of `F`'s root) each finds one of
/// them, not necessarily the same one; neither promises the nearest. A NaN met inside the
/// bracket sends false position back to plain bisection of the whole bracket, so that case
/// gives bisection's answer; a NaN stretch that false position steps over is not seen, and then
/// it may return a root where bisection returns the edge of the stretch (which is not one).
fn bracketed_root(
    g: &dyn Fn(f64) -> f64,
    lo: f64,
    hi: f64,
    ga: f64,
    gb: f64,
    refine: Refine,
) -> Option<f64> {
    let (mut lo, mut hi, mut ga, mut gb) = (lo, hi, ga, gb);
    if ga.is_nan() != gb.is_nan() {
        let (mut ok, mut bad) = if ga.is_nan() { (hi, lo) } else { (lo, hi) };
        for _ in 0..200 {
            let m = 0.5 * (ok + bad);
            if m == ok || m == bad {
                break;
            }
            if g(m).is_nan() {
                bad = m;
            } else {
                ok = m;
            }
        }
        if ga.is_nan() {
            (lo, ga) = (ok, g(ok));
        } else {
            (hi, gb) = (ok, g(ok));
        }
    }
    if ga * gb > 0.0 || (ga * gb).is_nan() {
        return None;
    }
    if ga == 0.0 {
        return Some(lo);
    }
    if gb == 0.0 {
        return Some(hi);
    }
    match refine {
        Refine::Bisection => Some(bisection(g, lo, hi, ga)),
        Refine::FalsePosition => Some(false_position(g, lo, hi, ga, gb)),
    }
}

/// Bisection of a bracket with `g(lo) = ga` of the other sign than `g(hi)`, to the last bit. A NaN
/// counts as the sign opposite to `ga`'s when `ga` is negative, as `ga`'s otherwise.
fn bisection(g: &dyn Fn(f64) -> f64, lo: f64, hi: f64, ga: f64) -> f64 {
    let (mut a, mut b) = (lo, hi);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let gm = g(m);
        if gm == 0.0 {
            return m;
        }
        if (gm < 0.0) == (ga < 0.0) {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// False position with the Illinois modification on a bracket with `g(lo) = ga` and
/// `g(hi) = gb` of opposite signs, a bisection every third step; falls back to
/// [`bisection`] of the whole bracket when it meets a NaN.
fn false_position(g: &dyn Fn(f64) -> f64, lo: f64, hi: f64, ga: f64, gb: f64) -> f64 {
    let (mut a, mut b, mut fa, mut fb) = (lo, hi, ga, gb);
    let a_negative = ga < 0.0;
    let mut last_side = 0i8;
    for step in 0..300 {
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            break;
        }
        let m = if step % 3 == 2 {
            mid
        } else {
            let m = (a * fb - b * fa) / (fb - fa);
            if m > a && m < b { m } else { mid }
        };
        let gm = g(m);
        if gm == 0.0 {
            return m;
        }
        if gm.is_nan() {
            return bisection(g, lo, hi, ga);
        }
        if (gm < 0.0) == a_negative {
            a = m;
            fa = gm;
            if last_side == -1 {
                fb *= 0.5;
            }
            last_side = -1;
        } else {
            b = m;
            fb = gm;
            if last_side == 1 {
                fa *= 0.5;
            }
            last_side = 1;
        }
    }
    0.5 * (a + b)
}

/// How far a root of `f` at `s` may be from the computed one given value noise `noise`:
/// `noise / |f'|` near a simple root, `sqrt(2 noise / |f''|)` near a double one.
pub fn root_uncertainty(f: &Bernstein, s: f64, noise: f64) -> f64 {
    let d1 = f.eval_with_derivative(s).1.abs();
    let d2 = f.derivative().eval_with_derivative(s).1.abs();
    (noise / d1.max(1e-300)).min((2.0 * noise / d2.max(1e-300)).sqrt())
}

/// The seed reports' approach: Newton iteration on `F` from evenly spaced starting guesses,
/// keeping what converges into [0, 1]. It can miss roots (that is what it is kept for).
fn newton_roots(f: &Bernstein, noise: f64, iterations: u32, starts: u32, out: &mut Vec<Root>) {
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

    /// False position stalls on one end for convex functions and crawls on flat ones; the
    /// forced bisections bound that. Each case must land within a few ulps of bisection's root.
    #[test]
    fn bracketed_root_agrees_with_bisection_where_false_position_is_slow() {
        type Case = (&'static str, Box<dyn Fn(f64) -> f64>, f64, f64);
        let cases: Vec<Case> = vec![
            ("linear", Box::new(|s| s - 0.3), 0.0, 1.0),
            (
                "steep convex",
                Box::new(|s: f64| s.powi(20) - 1e-3),
                0.0,
                1.0,
            ),
            ("flat cubic", Box::new(|s: f64| (s - 0.7).powi(3)), 0.0, 1.0),
            (
                "decreasing",
                Box::new(|s: f64| (1.0 - s).exp() - 1.5),
                0.0,
                1.0,
            ),
            (
                "tiny bracket",
                Box::new(|s: f64| s - 0.5),
                0.5 - 1e-15,
                0.5 + 1e-15,
            ),
            (
                "huge slope",
                Box::new(|s: f64| 1e12 * (s - 0.123456789)),
                0.0,
                1.0,
            ),
        ];
        for (name, g, a, b) in &cases {
            let fp = Refine::FalsePosition;
            let got = bracketed_root(g.as_ref(), *a, *b, g(*a), g(*b), fp).expect(name);
            let want =
                bracketed_root(g.as_ref(), *a, *b, g(*a), g(*b), Refine::Bisection).expect(name);
            assert!(
                (got - want).abs() <= 4.0 * f64::EPSILON * want.abs().max(1e-300) || g(got) == 0.0,
                "{name}: {got} vs {want}"
            );
        }
        // No sign change: no root; both ends NaN: no root.
        assert_eq!(
            bracketed_root(&|s| s + 1.0, 0.0, 1.0, 1.0, 2.0, Refine::FalsePosition),
            None
        );
        assert_eq!(
            bracketed_root(
                &|_| f64::NAN,
                0.0,
                1.0,
                f64::NAN,
                f64::NAN,
                Refine::FalsePosition
            ),
            None
        );
    }

    /// One end unreachable (NaN beyond s = 0.6): the bracket is first cut back to the edge of
    /// the reachable part, and the sign change between the other end and the edge is found.
    #[test]
    fn bracketed_root_finds_a_root_at_the_edge_of_reach() {
        let g = |s: f64| if s > 0.6 { f64::NAN } else { s - 0.4 };
        let got = bracketed_root(&g, 0.0, 1.0, g(0.0), g(1.0), Refine::FalsePosition).unwrap();
        assert!((got - 0.4).abs() < 1e-15, "{got}");
        // The sign change only at the edge itself: the root is the edge.
        let g = |s: f64| if s > 0.6 { f64::NAN } else { s - 0.6 };
        let got = bracketed_root(&g, 0.0, 1.0, g(0.0), g(1.0), Refine::FalsePosition).unwrap();
        assert!((got - 0.6).abs() < 1e-15, "{got}");
    }

    /// NaN stretches inside the bracket. Where false position meets one it falls back to
    /// bisection of the whole bracket and gives bisection's answer. Where it steps over one
    /// (here its first step lands on the root) it returns that root, while bisection stops at
    /// the edge of the stretch, which is not a root: the two differ, false position for the
    /// better.
    #[test]
    fn nan_stretches_inside_the_bracket() {
        let nan_between = |lo: f64, hi: f64, root: f64| {
            move |s: f64| {
                if s > lo && s < hi { f64::NAN } else { s - root }
            }
        };
        let both = |g: &dyn Fn(f64) -> f64| {
            (
                bracketed_root(g, 0.0, 1.0, g(0.0), g(1.0), Refine::FalsePosition).unwrap(),
                bracketed_root(g, 0.0, 1.0, g(0.0), g(1.0), Refine::Bisection).unwrap(),
            )
        };
        let g = nan_between(0.25, 0.35, 0.3);
        let (fp, bi) = both(&g);
        assert_eq!(fp, bi);
        let g = nan_between(0.45, 0.55, 0.9);
        let (fp, bi) = both(&g);
        assert_eq!(g(fp), 0.0, "{fp}");
        assert!((bi - 0.45).abs() < 1e-15 && g(bi) != 0.0, "{bi}");
    }
}
