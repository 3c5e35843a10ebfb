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
//!
//! [`Segment`] (`segment.rs`) holds one profile segment and its tables; [`RayFrame`] (`frame.rs`)
//! forms `F` for a ray and turns its roots into ray parameters.

use std::f64::consts::TAU;

use glam::{DVec2, DVec3};

mod coarse;
mod frame;
mod hit;
mod segment;
mod shell;

pub use coarse::CoarseShell;
pub use frame::RayFrame;

thread_local! {
    /// [`Lathe::search`]'s roots, reused by the thread's next search.
    static ROOTS: std::cell::Cell<Vec<Root>> = const { std::cell::Cell::new(Vec::new()) };
}
pub use hit::{LatheHit, NearestHit};
pub use segment::Segment;
use segment::TABLE_STEPS;
pub use shell::{PIECES, SHELL_PAD, SegmentShells, Shell, ShellLanes, shell_slack};

use super::Solver;
use super::roots::bracket::Refine;
use super::roots::{
    Root, RootKind, find_roots, find_roots_on, find_roots_with_noise, newton_roots, root_spread,
    strictly_monotone_on, widened,
};
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

/// Some parts of a lathe (see [`Lathe::intersect_parts`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Parts {
    /// Segment indices.
    pub segs: std::ops::Range<usize>,
    /// The flat caps of a partial sweep.
    pub caps: bool,
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
    /// Each segment's shells, padded for this size (culling).
    shells: Vec<SegmentShells>,
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
        let (rmax, hmin, hmax) = extent(&segs);
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
        if !(area_cdf.last().is_some_and(|&a| a > 0.0)) {
            return Err(
                "the profile sweeps no surface: its points all lie on the axis or at one \
                 point, so it would draw nothing (give the profile a radius)"
                    .into(),
            );
        }
        let shells = segs
            .iter()
            .map(|s| SegmentShells::new(&s.shell, &s.shells, size))
            .collect();
        Ok(Self {
            shells,
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
        self.sector_box(self.rmax, self.hmin, self.hmax)
    }

    /// The box of the radii up to `r` and heights `hmin..hmax`, limited to the swept sector.
    fn sector_box(&self, r: f64, hmin: f64, hmax: f64) -> (DVec3, DVec3) {
        let (mut lo, mut hi) = (DVec3::new(0.0, hmin, 0.0), DVec3::new(0.0, hmax, 0.0));
        let mut add = |a: f64| {
            let p = DVec3::new(r * a.cos(), 0.0, r * a.sin());
            lo = lo.min(p);
            hi = hi.max(p);
        };
        match self.sweep {
            None => {
                lo = DVec3::new(-r, hmin, -r);
                hi = DVec3::new(r, hmax, r);
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

    /// Bytes a lathe holds per profile segment (the segment with its tables and shells, and
    /// its share of the lathe's own tables), for a memory estimate made before building one.
    pub fn bytes_per_segment() -> usize {
        use std::mem::size_of;
        let f = size_of::<f64>();
        size_of::<Segment>()
            + 2 * (TABLE_STEPS + 1) * f
            + size_of::<SegmentShells>()
            + TABLE_STEPS * f
            + f
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
        self.intersect_parts(self.all_parts(), o, d, t_min, t_max, solver)
    }

    /// Every part of the surface: all segments, and the caps of a partial sweep.
    pub fn all_parts(&self) -> Parts {
        Parts {
            segs: 0..self.segs.len(),
            caps: self.sweep.is_some(),
        }
    }

    /// The parts a renderer can keep apart in its BVH: one per segment of nonzero area, and
    /// the caps of a partial sweep. Their nearest hits give the nearest hit of the whole.
    pub fn separate_parts(&self) -> Vec<Parts> {
        let mut out: Vec<Parts> = (0..self.segs.len())
            .filter(|&i| !self.segs[i].degenerate)
            .map(|i| Parts {
                segs: i..i + 1,
                caps: false,
            })
            .collect();
        if self.sweep.is_some() {
            out.push(Parts {
                segs: 0..0,
                caps: true,
            });
        }
        out
    }

    /// Object-space bounds `(min, max)` of some parts: their segments' control polygons (the
    /// whole profile's for the caps), limited to the swept sector.
    pub fn parts_bounds(&self, parts: &Parts) -> (DVec3, DVec3) {
        if parts.caps {
            return self.bounds();
        }
        let (rmax, hmin, hmax) = extent(&self.segs[parts.segs.clone()]);
        self.sector_box(rmax, hmin, hmax)
    }

    /// The union of the shells of the segments in `parts` (those of nonzero area), for the
    /// coarse test ([`CoarseShell`]); `None` for parts with the caps of a partial sweep (not
    /// inside the shells) or with no segment of nonzero area.
    pub fn parts_shell(&self, parts: &Parts) -> Option<Shell> {
        if parts.caps {
            return None;
        }
        self.segs[parts.segs.clone()]
            .iter()
            .filter(|s| !s.degenerate)
            .map(|s| s.shell)
            .reduce(Shell::union)
    }

    /// Nearest hit with `t_min < t < t_max` on the parts given: the segments in `parts.segs`
    /// and, if `parts.caps`, the caps of a partial sweep.
    pub fn intersect_parts(
        &self,
        parts: Parts,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        solver: Solver,
    ) -> Option<LatheHit> {
        let h = self.nearest(parts, o, d, t_min, t_max, solver)?;
        Some(self.complete(o, d, &h, true))
    }

    /// [`Lathe::intersect_parts`] without the surface data: where the nearest hit is, from
    /// which [`Lathe::complete`] gives the same [`LatheHit`].
    pub fn nearest(
        &self,
        parts: Parts,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        solver: Solver,
    ) -> Option<NearestHit> {
        let dl = d.length();
        if !(dl > 0.0 && dl.is_finite() && o.is_finite()) {
            return None;
        }
        let frame = RayFrame::new(o, d / dl, self.hmin, self.hmax);
        let (tmin, best) = (t_min * dl, t_max * dl);
        // Most rays that reach a segment's box miss its union shell: they end here, before
        // the search's setup (which, for one segment without caps, relies on this test).
        let (pad, slack) = (SHELL_PAD * self.size, shell_slack(self.size));
        let missed = |i: usize| {
            self.segs[i].degenerate
                || frame
                    .shells_entered(&self.shells[i].union, tmin - pad, best + pad, slack)
                    .0
                    == 0
        };
        if !parts.caps && parts.segs.clone().all(missed) {
            return None;
        }
        let (t, part, s) = self.search(parts, &frame, tmin, best, solver)?;
        Some(NearestHit {
            t: t / dl,
            t_unit: t,
            part,
            s,
        })
    }

    /// The nearest hit `(t, part, s)` with `tmin < t < best` along the frame's unit direction.
    #[inline(never)]
    fn search(
        &self,
        parts: Parts,
        frame: &RayFrame,
        tmin: f64,
        mut best: f64,
        solver: Solver,
    ) -> Option<(f64, Part, f64)> {
        let (o, dn) = (frame.o, frame.dn);
        let mut found: Option<(f64, Part, f64)> = None;
        // The roots' buffer is the thread's, kept from search to search: allocating one per
        // search showed in the photon pass's profile (docs/measurements.md, "Cost per ray").
        let mut roots = ROOTS.take();
        roots.clear();
        // Segments whose shells the ray enters, nearest entry first: (entry, segment, pieces).
        // On the stack for up to 8 segments (the renderer asks for one at a time).
        let mut stack = [(0.0, 0usize, 0u32); 8];
        let (mut heap, mut len) = (Vec::new(), 0);
        let (pad, slack) = (SHELL_PAD * self.size, shell_slack(self.size));
        let ta0 = tmin - pad;
        let first = parts.segs.start;
        // [`Lathe::nearest`] has tested the union shell of a single segment without caps (the
        // renderer's parts) on this interval: it is entered.
        let union_entered = !parts.caps && parts.segs.len() == 1;
        for (i, seg) in self.segs[parts.segs].iter().enumerate() {
            let i = first + i;
            let shells = &self.shells[i];
            if seg.degenerate
                || !union_entered
                    && frame
                        .shells_entered(&shells.union, ta0, best + pad, slack)
                        .0
                        == 0
            {
                continue;
            }
            let (mask, entry) = frame.shells_entered(&shells.pieces, ta0, best + pad, slack);
            if mask == 0 {
                continue;
            }
            if len < stack.len() {
                stack[len] = (entry, i, mask);
                len += 1;
            } else {
                heap.push((entry, i, mask));
            }
        }
        let order = if heap.is_empty() {
            &mut stack[..len]
        } else {
            heap.extend_from_slice(&stack[..len]);
            &mut heap[..]
        };
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let best_at_entry = best;
        for &(entry, i, mut mask) in order.iter() {
            if entry >= best {
                // Every later segment's hits lie beyond the nearest hit found.
                break;
            }
            let seg = &self.segs[i];
            if best < best_at_entry {
                // A nearer hit was found since the shells were tested: drop the pieces the ray
                // now enters only beyond it.
                mask &= frame
                    .shells_entered(&self.shells[i].pieces, ta0, best + pad, slack)
                    .0;
                if mask == 0 {
                    continue;
                }
            }
            let (f, noise) = frame.polynomial(seg);
            roots.clear();
            match solver {
                Solver::Robust => isolate_in_pieces(&f, noise, mask, &mut roots),
                Solver::Newton { iterations, starts } => {
                    newton_roots(&f, noise, iterations, starts, &mut roots)
                }
            }
            // A bound of |F''| on the segment, computed for the first simple root.
            let mut bound = None;
            for root in &roots {
                let (ds, monotone) = spread_and_certificate(&f, root, noise, &mut bound);
                let prune = Some((tmin, best));
                let refine = Refine::FalsePosition;
                let cands =
                    frame.candidates(seg, root, ds, self.size, refine, tmin, prune, monotone);
                for (t, s) in cands {
                    if t > tmin && t < best && self.in_sweep(o + t * dn) {
                        best = t;
                        found = Some((t, Part::Side(i), s));
                    }
                }
            }
        }
        ROOTS.set(roots);
        if parts.caps {
            self.cap_hits(frame, tmin, &mut best, &mut found);
        }
        found
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

/// The uncertainty `ds` of a root of `f` and whether `f` is certified strictly monotone on its
/// widened bracket (see [`RayFrame::candidates`]); `bound` caches `f`'s bound of `|f''|`.
#[inline(never)]
fn spread_and_certificate(
    f: &super::bernstein::Bernstein,
    root: &Root,
    noise: f64,
    bound: &mut Option<f64>,
) -> (f64, bool) {
    let (ds, slope) = root_spread(f, root.t, noise);
    let monotone = root.kind == RootKind::Simple && {
        let (lo, hi) = widened(root, ds);
        let b = *bound.get_or_insert_with(|| f.second_derivative_bound());
        strictly_monotone_on(f.degree(), slope, b, noise, root.t, lo, hi)
    };
    (ds, monotone)
}

/// The largest radius and the lowest and highest heights of some segments' bounds.
fn extent(segs: &[Segment]) -> (f64, f64, f64) {
    segs.iter()
        .fold((0.0, f64::INFINITY, f64::NEG_INFINITY), |(r, lo, hi), s| {
            (r.max(s.rmax), lo.min(s.hmin), hi.max(s.hmax))
        })
}

/// Roots of `f` on the union of the segment's pieces set in `mask` (bit `k`: the parameter
/// piece `[k, k + 1] / PIECES`), each maximal run of set pieces isolated on its own.
fn isolate_in_pieces(f: &super::bernstein::Bernstein, noise: f64, mask: u32, out: &mut Vec<Root>) {
    let full = (1u32 << PIECES) - 1;
    if mask & full == full {
        find_roots_with_noise(f, noise, out);
        return;
    }
    let mut k = 0;
    while k < PIECES {
        if mask & (1 << k) == 0 {
            k += 1;
            continue;
        }
        let start = k;
        while k < PIECES && mask & (1 << k) != 0 {
            k += 1;
        }
        find_roots_on(
            f,
            start as f64 / PIECES as f64,
            k as f64 / PIECES as f64,
            noise,
            out,
        );
    }
}
