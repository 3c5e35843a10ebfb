//! POV-Ray's `isosurface` in its own space: where a user function meets a threshold inside a
//! container box or sphere (see [`crate::scene::Isosurface`]); inside is where the function is
//! below the threshold.
//!
//! Along a ray, the chord through the container is cut in halves, nearest first; a stretch
//! whose interval of function values ([`crate::scene::interval`]) excludes the threshold holds
//! no crossing and is dropped. The same evaluation bounds the function's derivative along the
//! ray ([`crate::scene::slope`]): where that excludes 0 the function is monotone on the
//! stretch, which then holds one crossing if its ends lie on opposite sides and none
//! otherwise, decided without halving further. A stretch narrower than the accuracy whose ends
//! lie on opposite sides holds a crossing; one whose ends lie on one side is a graze (or a
//! feature thinner than the accuracy). A crossing is refined by a bracketed regula falsi to
//! full precision. No crossing between features
//! thicker than the accuracy is skipped, whatever the function's gradient: nothing is assumed
//! of it. A ray may visit at most [`MAX_VISITS`] stretches, fewer for a function of many
//! operations ([`visit_budget`]: a ray's work is bounded in operations, so that one ray of a
//! costly function cannot hold a render, or its interruption, for minutes); one that needs
//! more is counted ([`Isosurface::exhausted`]) and treated as a miss.
//!
//! Without `open`, the container's walls close the solid where the function is below the
//! threshold on them. The normal is the function's gradient by central differences (a wall's
//! own normal on a wall); the uv is spherical about the container's centre, as the sphere's.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use arrayvec::ArrayVec;
use glam::{DVec3, Vec2};

use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::interval::Interval;
use crate::scene::{self, Container, Function};

/// Most stretches one ray may visit (each one interval evaluation of the function).
pub const MAX_VISITS: u32 = 200_000;

/// Most function operations one ray may spend on its stretches: [`MAX_VISITS`] stretches of a
/// function of 64 operations (a 60 000-operation function gets 213 stretches; one ray then
/// costs about as much as one of the smallest functions' at its cap).
pub const MAX_RAY_OPS: u64 = MAX_VISITS as u64 * 64;

/// The stretches a ray of a function of `ops` operations may visit (195 at the largest
/// function allowed, [`crate::scene::function::MAX_OPS`]).
pub fn visit_budget(ops: usize) -> u32 {
    (MAX_RAY_OPS / ops.max(1) as u64).clamp(1, u64::from(MAX_VISITS)) as u32
}

pub use crate::scene::blob::DEFAULT_ACCURACY;

pub struct Isosurface {
    f: Arc<Function>,
    threshold: f64,
    container: Container,
    open: bool,
    accuracy: f64,
    /// The step of the normal's central differences.
    h: f64,
    exhausted: AtomicU64,
    /// The stretches one ray may visit ([`visit_budget`]).
    max_visits: u32,
}

/// What a ray meets: the surface, or a wall of the container.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Meet {
    Surface(f64),
    Wall(f64),
}

impl Meet {
    pub fn t(self) -> f64 {
        match self {
            Meet::Surface(t) | Meet::Wall(t) => t,
        }
    }
}

impl Isosurface {
    pub fn new(iso: &scene::Isosurface) -> Result<Self, String> {
        iso.check()?;
        let (lo, hi) = iso.container.bounds();
        Ok(Isosurface {
            f: iso.function.clone(),
            threshold: iso.threshold,
            container: iso.container,
            open: iso.open,
            accuracy: iso.accuracy,
            h: iso.accuracy.min(1e-7 * (hi - lo).length()),
            exhausted: AtomicU64::new(0),
            max_visits: visit_budget(iso.function.ops()),
        })
    }

    /// The stretches one ray may visit before it is taken as a miss.
    pub fn max_visits(&self) -> u32 {
        self.max_visits
    }

    /// Rays given up as misses since the shape was made, their stretches exhausted.
    pub fn exhausted(&self) -> u64 {
        self.exhausted.load(Ordering::Relaxed)
    }

    /// [`Isosurface::exhausted`], counted again from 0 (what a render's end reports).
    pub fn take_exhausted(&self) -> u64 {
        self.exhausted.swap(0, Ordering::Relaxed)
    }

    /// The function minus the threshold at `p` (below 0 inside).
    pub fn value(&self, p: DVec3) -> f64 {
        self.f.eval_point(p) - self.threshold
    }

    fn inside(&self, p: DVec3) -> bool {
        self.value(p) < 0.0
    }

    /// The ray's chord through the container, unclipped.
    fn chord(&self, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
        match self.container {
            Container::Box { .. } => {
                let (min, max) = self.container.bounds();
                let (mut a, mut b) = (f64::NEG_INFINITY, f64::INFINITY);
                for k in 0..3 {
                    if d[k] == 0.0 {
                        if o[k] < min[k] || o[k] > max[k] {
                            return None;
                        }
                        continue;
                    }
                    let (t0, t1) = ((min[k] - o[k]) / d[k], (max[k] - o[k]) / d[k]);
                    a = a.max(t0.min(t1));
                    b = b.min(t0.max(t1));
                }
                (a < b).then_some((a, b))
            }
            Container::Sphere { center, radius } => {
                let q = o - center;
                let (a, bh, c) = (
                    d.length_squared(),
                    q.dot(d),
                    q.length_squared() - radius * radius,
                );
                let disc = bh * bh - a * c;
                if disc.is_nan() || disc <= 0.0 {
                    return None;
                }
                let k = -(bh + bh.signum() * disc.sqrt());
                let (t0, t1) = if k == 0.0 {
                    (-(-c / a).sqrt(), (-c / a).sqrt())
                } else {
                    (k / a, c / k)
                };
                Some((t0.min(t1), t0.max(t1)))
            }
        }
    }

    /// The nearest meeting with `lo < t < hi` along `o + t d`.
    pub fn nearest(&self, o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<Meet> {
        if !(o.is_finite() && d.is_finite()) || d == DVec3::ZERO {
            return None;
        }
        let (ta, tb) = self.chord(o, d)?;
        let (a, b) = (ta.max(lo), tb.min(hi));
        if a.is_nan() || b.is_nan() || a >= b {
            return None;
        }
        let walls = !self.open;
        if walls && ta > lo && self.inside(o + ta * d) {
            return Some(Meet::Wall(ta));
        }
        if let Some(t) = self.crossing(o, d, a, b) {
            return t.map(Meet::Surface);
        }
        (walls && tb < hi && self.inside(o + tb * d)).then_some(Meet::Wall(tb))
    }

    /// The first crossing in `(a, b)`: `Some(None)` when the ray's budget ran out.
    fn crossing(&self, o: DVec3, d: DVec3, a: f64, b: f64) -> Option<Option<f64>> {
        let g = |t: f64| self.value(o + t * d);
        let side = |v: f64| v < 0.0;
        let leaf = (self.accuracy / d.length()).max(8.0 * f64::EPSILON * a.abs().max(b.abs()));
        let rates = d.to_array();
        // Halving is depth first, nearest half on top: at most one stretch waits per depth,
        // and a stretch of width below the leaf is never split (64 levels halve any f64 range).
        let mut stack: ArrayVec<(f64, f64, f64, f64), 128> = ArrayVec::new();
        stack.push((a, b, g(a), g(b)));
        let mut visits = 0;
        while let Some((lo, hi, glo, ghi)) = stack.pop() {
            visits += 1;
            if visits > self.max_visits {
                self.exhausted.fetch_add(1, Ordering::Relaxed);
                return Some(None);
            }
            let (p, q) = (o + lo * d, o + hi * d);
            let args = [0, 1, 2].map(|k| Interval::new(p[k], q[k]));
            let (range, slope) = self.f.eval_slope(&args, &rates);
            if !range.contains(self.threshold) {
                continue;
            }
            if slope.lo > 0.0 || slope.hi < 0.0 {
                // Strictly monotone along the stretch: one crossing at most, where the ends
                // lie on opposite sides.
                if side(glo) != side(ghi) {
                    return Some(Some(refine(&g, (lo, glo), (hi, ghi))));
                }
                continue;
            }
            let mid = 0.5 * (lo + hi);
            if hi - lo <= leaf || mid <= lo || mid >= hi {
                if side(glo) != side(ghi) {
                    return Some(Some(refine(&g, (lo, glo), (hi, ghi))));
                }
                continue;
            }
            let gm = g(mid);
            if stack.try_push((mid, hi, gm, ghi)).is_err()
                || stack.try_push((lo, mid, glo, gm)).is_err()
            {
                self.exhausted.fetch_add(1, Ordering::Relaxed);
                return Some(None);
            }
        }
        None
    }

    /// The outward unit normal of the surface at `p`: the function's gradient.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        let h = self.h;
        let mut g = DVec3::ZERO;
        for k in 0..3 {
            let mut e = DVec3::ZERO;
            e[k] = h;
            g[k] = self.value(p + e) - self.value(p - e);
        }
        if g.is_finite() && g != DVec3::ZERO {
            g.normalize()
        } else {
            self.wall_normal(p)
        }
    }

    /// The container's outward normal at (or nearest to) `p`.
    pub fn wall_normal(&self, p: DVec3) -> DVec3 {
        match self.container {
            Container::Sphere { center, .. } => (p - center).normalize_or(DVec3::Y),
            Container::Box { .. } => {
                let (min, max) = self.container.bounds();
                let c = 0.5 * (min + max);
                let half = 0.5 * (max - min);
                let q = (p - c) / half;
                let a = q.abs();
                let k = if a.x >= a.y && a.x >= a.z {
                    0
                } else if a.y >= a.z {
                    1
                } else {
                    2
                };
                let mut n = DVec3::ZERO;
                n[k] = q[k].signum();
                n
            }
        }
    }
}

/// A crossing in `[lo, hi]`, whose ends (with `g`'s values there) lie on opposite sides, to
/// full precision: regula falsi with the Illinois rule (an end kept twice has its value
/// halved), every third step a halving, so that the bracket at least halves every three
/// steps whatever the function; both ends close in on a simple root after a handful.
fn refine(
    g: &impl Fn(f64) -> f64,
    (mut lo, mut glo): (f64, f64),
    (mut hi, mut ghi): (f64, f64),
) -> f64 {
    let inside_lo = glo < 0.0;
    // Which end moved last: -1 the low one, 1 the high one.
    let mut moved = 0;
    for k in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let secant = (lo * ghi - hi * glo) / (ghi - glo);
        let s = if k % 3 == 2 || !(secant > lo && secant < hi) {
            mid
        } else {
            secant
        };
        let gs = g(s);
        if (gs < 0.0) == inside_lo {
            (lo, glo) = (s, gs);
            if moved == -1 {
                ghi *= 0.5;
            }
            moved = -1;
        } else {
            (hi, ghi) = (s, gs);
            if moved == 1 {
                glo *= 0.5;
            }
            moved = 1;
        }
    }
    0.5 * (lo + hi)
}

impl Shape for Isosurface {
    fn bounds(&self) -> Aabb {
        let (lo, hi) = self.container.bounds();
        Aabb::new(lo.as_vec3a(), hi.as_vec3a()).padded(1e-6)
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        let (lo, hi) = super::f64_range(t_min, t_max);
        let meet = self.nearest(o, d, lo, hi)?;
        let t = meet.t();
        let tf = t as f32;
        if !(tf > t_min && tf < t_max) {
            return None;
        }
        let p = o + t * d;
        let n = match meet {
            Meet::Surface(_) => self.normal(p),
            Meet::Wall(_) => self.wall_normal(p),
        }
        .as_vec3a();
        let (min, max) = self.container.bounds();
        Some(super::blob::spherical_hit(tf, p, n, 0.5 * (min + max)))
    }

    /// An isosurface is not a light's shape: it is never sampled.
    fn area(&self) -> f32 {
        0.0
    }

    fn sample(&self, _u: Vec2) -> Option<AreaSample> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::function::{Binary, Op, Unary};

    /// sqrt(x^2 + y^2 + z^2): the distance from the origin.
    fn radius_code() -> Vec<Op> {
        let mut code = Vec::new();
        for k in 0..3 {
            code.extend([Op::Load(k), Op::Load(k), Op::Binary(Binary::Mul)]);
        }
        code.extend([
            Op::Binary(Binary::Add),
            Op::Binary(Binary::Add),
            Op::Unary(Unary::Sqrt),
        ]);
        code
    }

    fn iso(code: Vec<Op>, threshold: f64, open: bool) -> Isosurface {
        Isosurface::new(&scene::Isosurface {
            function: Arc::new(Function::new(3, 3, code).unwrap()),
            threshold,
            container: Container::Box {
                min: DVec3::splat(-2.0),
                max: DVec3::splat(2.0),
            },
            open,
            accuracy: 1e-9,
        })
        .unwrap()
    }

    /// A ray's stretches are bounded in operations: a costly function gets fewer of them, so
    /// one undecided ray of it cannot hold a render (or its interruption) for minutes.
    #[test]
    fn a_costly_function_gets_fewer_stretches() {
        assert_eq!(visit_budget(1), MAX_VISITS);
        assert_eq!(visit_budget(64), MAX_VISITS);
        assert_eq!(visit_budget(60_000), 213);
        // The largest function allowed: 195 stretches.
        assert_eq!(visit_budget(crate::scene::function::MAX_OPS), 195);
        assert_eq!(visit_budget(usize::MAX), 1);
        assert_eq!(iso(radius_code(), 1.0, false).max_visits(), MAX_VISITS);
        let mut code = radius_code();
        for _ in 0..30_000 {
            code.extend([Op::Const(0.0), Op::Binary(Binary::Add)]);
        }
        let costly = iso(code, 1.0, false);
        assert_eq!(costly.max_visits(), visit_budget(60_012));
        // The same sphere: a ray through it still finds the surface.
        let m = costly.nearest(DVec3::new(0.0, 0.0, -3.0), DVec3::Z, 0.0, f64::INFINITY);
        assert!(
            matches!(m, Some(Meet::Surface(t)) if (t - 2.0).abs() < 1e-9),
            "{m:?}"
        );
    }

    #[test]
    fn a_sphere_by_its_distance_function() {
        let s = iso(radius_code(), 1.0, false);
        let o = DVec3::new(0.3, 0.2, -5.0);
        let want = 5.0 - (1.0f64 - 0.13).sqrt();
        let m = s.nearest(o, DVec3::Z, 0.0, f64::INFINITY).unwrap();
        assert!(matches!(m, Meet::Surface(_)));
        assert!((m.t() - want).abs() < 1e-9, "{m:?}");
        let n = s.normal(o + m.t() * DVec3::Z);
        assert!((n - (o + m.t() * DVec3::Z)).length() < 1e-6, "{n}");
    }

    #[test]
    fn a_shell_thinner_than_any_step_is_not_skipped() {
        // |r - 1| < 5e-4: a shell 1e-3 thick; rays through it at every angle hit it.
        let mut code = radius_code();
        code.extend([
            Op::Const(1.0),
            Op::Binary(Binary::Sub),
            Op::Unary(Unary::Abs),
        ]);
        let s = iso(code, 5e-4, true);
        let mut hits = 0;
        for i in 0..200 {
            let y = 0.999 * f64::from(i) / 200.0;
            let o = DVec3::new(0.0, y, -3.0);
            let m = s.nearest(o, DVec3::Z, 0.0, f64::INFINITY).unwrap();
            let p = o + m.t() * DVec3::Z;
            assert!((p.length() - (1.0 + 5e-4)).abs() < 1e-9, "{y}: {p}");
            hits += 1;
        }
        assert_eq!(hits, 200);
        assert_eq!(s.exhausted(), 0);
    }

    #[test]
    fn the_walls_close_a_function_that_is_inside_at_the_container() {
        // y < 0.5 everywhere below: closed by the box's walls, open without them.
        let code = vec![Op::Load(1)];
        let closed = iso(code.clone(), 0.5, false);
        let o = DVec3::new(0.0, 0.0, -5.0);
        assert_eq!(
            closed.nearest(o, DVec3::Z, 0.0, f64::INFINITY),
            Some(Meet::Wall(3.0))
        );
        let n = closed.wall_normal(DVec3::new(0.0, 0.0, -2.0));
        assert_eq!(n, DVec3::new(0.0, 0.0, -1.0));
        let open = iso(code, 0.5, true);
        assert_eq!(open.nearest(o, DVec3::Z, 0.0, f64::INFINITY), None);
        // From above, the plane y = 0.5.
        let m = open.nearest(DVec3::new(0.0, 5.0, 0.0), -DVec3::Y, 0.0, f64::INFINITY);
        assert!((m.unwrap().t() - 4.5).abs() < 1e-9, "{m:?}");
    }

    #[test]
    fn an_infinite_function_is_decided_by_its_interval_at_once() {
        // 1 / 0 everywhere: +inf, never below the threshold.
        let s = iso(
            vec![Op::Const(1.0), Op::Const(0.0), Op::Binary(Binary::Div)],
            0.0,
            true,
        );
        assert_eq!(
            s.nearest(DVec3::new(0.0, 0.0, -5.0), DVec3::Z, 0.0, f64::INFINITY),
            None
        );
        assert_eq!(s.exhausted(), 0);
    }
}
