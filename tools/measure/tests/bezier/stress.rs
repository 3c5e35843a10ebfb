//! Stress tests: the robust intersectors against the slow reference intersectors, 200 000 rays
//! per case by default, one million with `BEZIER_STRESS_RAYS=1000000`. Rays run in parallel
//! (rayon); ray `i` of a case is generated from its own stream seeded by `(seed, i)`, so the
//! results do not depend on the thread count. Every case prints its
//! counts; the robust method must show zero misses, zero false hits and a relative `t` error
//! below 1e-6 on every ray the reference can decide. The Newton method runs on the same rays and
//! its miss rate is printed for comparison (it is expected to miss; that is not a failure).

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use sppm_lang::internals::bezier::lathe::{Lathe, LatheHit, Part};
use sppm_lang::internals::bezier::patch::{Patch, PatchHit};
use sppm_lang::internals::bezier::{Solver, Solver as PatchSolver};
use sppm_lang::internals::sampling::SplitMix64;
use sppm_lang::internals::shapes::patch::PIECES;
use sppm_measure::bezier::{vase_profile, wavy_points};
use sppm_measure::reference;

const REL_T: f64 = 1e-6;

/// Rays per case. The default fits CI (about 3 minutes for all cases on 2 shared cores);
/// `BEZIER_STRESS_RAYS=1000000` runs a million rays per case (about 16 minutes here,
/// dominated by the partial-sweep and patch-grazing references). The count used is printed.
fn rays() -> usize {
    std::env::var("BEZIER_STRESS_RAYS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(200_000)
}

/// The seeded ray streams (shared with `sppm-measure bezier`).
type Rng = SplitMix64;

/// The generator of ray `i` of a case: its own stream seeded from `(seed, i)`, so the ray set does
/// not depend on the number of threads or on the order in which rays are run.
fn ray_rng(seed: u64, i: usize) -> Rng {
    Rng::for_item(seed, 0, i)
}

#[derive(Default, Debug)]
struct Stats {
    rays: usize,
    ambiguous: usize,
    ref_hits: usize,
    misses: usize,
    false_hits: usize,
    t_errors: usize,
    max_rel: f64,
    off_surface: usize,
    newton_misses: usize,
    newton_false: usize,
    newton_wrong_t: usize,
    /// Rays whose robust hit through the separate parts differs in any bit from the whole's.
    split_differs: usize,
    /// The first failing rays (by index), for the report.
    failing: Vec<(usize, String)>,
}

impl Stats {
    fn merge(mut self, o: Stats) -> Stats {
        self.rays += o.rays;
        self.ambiguous += o.ambiguous;
        self.ref_hits += o.ref_hits;
        self.misses += o.misses;
        self.false_hits += o.false_hits;
        self.t_errors += o.t_errors;
        self.max_rel = self.max_rel.max(o.max_rel);
        self.off_surface += o.off_surface;
        self.newton_misses += o.newton_misses;
        self.newton_false += o.newton_false;
        self.newton_wrong_t += o.newton_wrong_t;
        self.split_differs += o.split_differs;
        self.failing.extend(o.failing);
        self.failing.sort_by_key(|f| f.0);
        self.failing.truncate(3);
        self
    }

    fn failures(&self) -> (usize, usize, usize, usize) {
        (
            self.misses,
            self.false_hits,
            self.t_errors,
            self.off_surface,
        )
    }

    fn compare(&mut self, want: Option<f64>, got: Option<f64>) {
        match (want, got) {
            (Some(_), None) => self.misses += 1,
            (None, Some(_)) => self.false_hits += 1,
            (Some(w), Some(g)) => {
                let rel = (g - w).abs() / w.abs().max(1e-300);
                self.max_rel = self.max_rel.max(rel);
                if rel >= REL_T {
                    self.t_errors += 1;
                }
            }
            (None, None) => {}
        }
    }

    fn newton(&mut self, want: Option<f64>, got: Option<f64>) {
        match (want, got) {
            (Some(_), None) => self.newton_misses += 1,
            (None, Some(_)) => self.newton_false += 1,
            (Some(w), Some(g)) if (g - w).abs() >= REL_T * w.abs() => self.newton_wrong_t += 1,
            _ => {}
        }
    }

    /// Prints the counts and asserts them. `ambiguous_per_mille`: how many rays in a thousand
    /// the reference may leave undecided (1 everywhere but on the pointed-tip case, see there).
    fn report_and_check(&self, name: &str, ambiguous_per_mille: usize) {
        let decided = self.rays - self.ambiguous;
        for (i, f) in &self.failing {
            println!("  [{name}] failing ray #{i}: {f}");
        }
        println!(
            "[{name}] rays {} decided {} ambiguous {} reference hits {} | robust: misses {} \
             false hits {} t errors {} max rel t error {:.2e} off-surface {} | newton: misses {} \
             ({:.3}% of hits) false hits {} wrong t {} | split differs from whole {}",
            self.rays,
            decided,
            self.ambiguous,
            self.ref_hits,
            self.misses,
            self.false_hits,
            self.t_errors,
            self.max_rel,
            self.off_surface,
            self.newton_misses,
            100.0 * self.newton_misses as f64 / self.ref_hits.max(1) as f64,
            self.newton_false,
            self.newton_wrong_t,
            self.split_differs,
        );
        assert_eq!(self.misses, 0, "{name}: misses");
        assert_eq!(self.false_hits, 0, "{name}: false hits");
        assert_eq!(self.t_errors, 0, "{name}: t errors");
        assert_eq!(self.off_surface, 0, "{name}: hit points off the surface");
        assert!(self.max_rel < REL_T);
        assert!(
            self.ambiguous * 1000 <= self.rays * ambiguous_per_mille,
            "{name}: too many ambiguous rays"
        );
        assert!(
            self.ref_hits * 10 >= self.rays,
            "{name}: the rays must mostly hit"
        );
    }
}

fn profile(points: &[&[(f64, f64)]]) -> Vec<Vec<DVec2>> {
    points
        .iter()
        .map(|s| s.iter().map(|&(r, h)| DVec2::new(r, h)).collect())
        .collect()
}

/// A vase: flat bottom from a pole on the axis, a bulge, a neck and a flared lip.
fn vase(sweep: Option<(f64, f64)>) -> Lathe {
    Lathe::new(&vase_profile().segments, sweep).unwrap()
}

/// A spindle pointed at both ends (cone tips on the axis).
fn spindle() -> Lathe {
    Lathe::new(
        &profile(&[&[(0.0, 0.0), (0.8, 0.3), (0.6, 1.2), (0.0, 1.5)]]),
        None,
    )
    .unwrap()
}

const NEWTON: Solver = Solver::Newton {
    iterations: 16,
    starts: 4,
};

fn run_lathe(
    name: &str,
    lathe: &Lathe,
    seed: u64,
    make_ray: impl Fn(&mut Rng) -> (DVec3, DVec3) + Sync,
) {
    run_lathe_allowing(name, lathe, seed, 1, make_ray);
}

fn run_lathe_allowing(
    name: &str,
    lathe: &Lathe,
    seed: u64,
    ambiguous_per_mille: usize,
    make_ray: impl Fn(&mut Rng) -> (DVec3, DVec3) + Sync,
) {
    let size = lathe.size();
    let start = std::time::Instant::now();
    let st = (0..rays())
        .into_par_iter()
        .fold(Stats::default, |mut st, i| {
            let (o, d) = make_ray(&mut ray_rng(seed, i));
            st.rays += 1;
            let want = reference::lathe(lathe, o, d, 1e-9, f64::INFINITY);
            let (got, differs) = split_intersect(lathe, o, d);
            st.split_differs += differs as usize;
            let before = st.failures();
            // Every robust hit, also on rays the reference cannot decide, lies on the surface.
            if let Some(h) = got
                && let Part::Side(i) = h.part
            {
                let q = lathe.segments()[i].point(h.s);
                let m = DVec2::new(h.p.x.hypot(h.p.z), h.p.y);
                if (m - q).length() > 1e-6 * size {
                    st.off_surface += 1;
                }
            }
            if want.ambiguous {
                st.ambiguous += 1;
                return st;
            }
            st.ref_hits += want.t.is_some() as usize;
            st.compare(want.t, got.map(|h| h.t));
            if before != st.failures() && st.failing.len() < 3 {
                let msg = format!("o={o:?} d={d:?}: reference {:?}, robust {:?}", want.t, got);
                st.failing.push((i, msg));
            }
            let newton = lathe.intersect(o, d, 1e-9, f64::INFINITY, NEWTON);
            st.newton(want.t, newton.map(|h| h.t));
            st
        })
        .reduce(Stats::default, Stats::merge);
    println!("[{name}] {} rays in {:.1?}", st.rays, start.elapsed());
    st.report_and_check(name, ambiguous_per_mille);
}

/// The robust hit as the renderer finds it: the lathe's separate parts (one BVH primitive
/// each, see `Revolve::split`), each asked for a hit nearer than the nearest found so far.
/// Also whether it differs at all (any bit) from the whole lathe's [`Lathe::intersect`]: the
/// pieces of a segment whose shells the ray enters within the window are isolated together, so
/// a smaller window can change the last bits of a root.
fn split_intersect(lathe: &Lathe, o: DVec3, d: DVec3) -> (Option<LatheHit>, bool) {
    let mut best: Option<LatheHit> = None;
    for parts in lathe.separate_parts() {
        let t_max = best.map_or(f64::INFINITY, |h| h.t);
        if let Some(h) = lathe.intersect_parts(parts, o, d, 1e-9, t_max, Solver::Robust) {
            best = Some(h);
        }
    }
    let whole = lathe.intersect(o, d, 1e-9, f64::INFINITY, Solver::Robust);
    (best, best != whole)
}

fn random_rays(lo: DVec3, hi: DVec3) -> impl Fn(&mut Rng) -> (DVec3, DVec3) {
    let c = 0.5 * (lo + hi);
    let size = (hi - lo).max_element();
    move |rng| {
        let o = c + rng.unit() * 3.0 * size;
        let target = DVec3::new(
            rng.range(lo.x, hi.x),
            rng.range(lo.y, hi.y),
            rng.range(lo.z, hi.z),
        );
        (o, (target - o) * rng.range(0.2, 2.0))
    }
}

#[test]
fn lathe_random_rays() {
    let l = vase(None);
    let (lo, hi) = l.bounds();
    run_lathe("lathe random", &l, 1, random_rays(lo, hi));
}

#[test]
fn lathe_random_rays_partial_sweep() {
    let l = vase(Some((30.0, 300.0)));
    let (lo, hi) = l.bounds();
    run_lathe("lathe random, sweep 30..300", &l, 2, random_rays(lo, hi));
}

#[test]
fn lathe_grazing_rays() {
    let l = vase(None);
    let size = l.size();
    run_lathe("lathe grazing", &l, 3, |rng| {
        let (p, n) = l.sample(DVec2::new(rng.f(), rng.f())).unwrap();
        let mut t = rng.unit();
        t -= n * t.dot(n);
        let t = t.normalize();
        let delta =
            10f64.powf(rng.range(-5.0, -2.0)) * size * if rng.f() < 0.5 { 1.0 } else { -1.0 };
        let o = p + n * delta - t * 2.0 * size;
        (o, t)
    });
}

#[test]
fn lathe_axis_parallel_rays() {
    let l = vase(None);
    let (lo, hi) = l.bounds();
    let rmax = hi.x;
    run_lathe("lathe axis-parallel", &l, 4, |rng| {
        let (x, z) = if rng.f() < 0.01 {
            (0.0, 0.0)
        } else {
            let r = 1.1 * rmax * rng.f().sqrt();
            let a = rng.range(0.0, std::f64::consts::TAU);
            (r * a.cos(), r * a.sin())
        };
        if rng.f() < 0.5 {
            (DVec3::new(x, hi.y + 1.0, z), -DVec3::Y)
        } else {
            (DVec3::new(x, lo.y - 1.0, z), DVec3::Y * 2.0)
        }
    });
}

#[test]
fn lathe_perpendicular_rays() {
    let l = vase(None);
    let (lo, hi) = l.bounds();
    let rmax = hi.x;
    run_lathe("lathe perpendicular", &l, 5, |rng| {
        let a = rng.range(0.0, std::f64::consts::TAU);
        let (dir, side) = (
            DVec3::new(a.cos(), 0.0, a.sin()),
            DVec3::new(-a.sin(), 0.0, a.cos()),
        );
        let y = rng.range(lo.y - 0.1, hi.y + 0.1);
        let b = rng.range(-1.1, 1.1) * rmax;
        (DVec3::new(0.0, y, 0.0) - dir * 3.0 + side * b, dir)
    });
}

fn near_pole_ray(poles: Vec<DVec3>, size: f64) -> impl Fn(&mut Rng) -> (DVec3, DVec3) {
    move |rng: &mut Rng| {
        let pole = poles[(rng.f() * poles.len() as f64) as usize % poles.len()];
        let target = pole + rng.unit() * 10f64.powf(rng.range(-6.0, -3.0)) * size;
        let o = target + rng.unit() * 3.0 * size;
        (o, target - o)
    }
}

#[test]
fn lathe_near_pole_rays() {
    let vase = vase(None);
    run_lathe(
        "lathe near-pole (vase bottom)",
        &vase,
        6,
        near_pole_ray(vec![DVec3::ZERO], vase.size()),
    );
}

/// Rays that pass within 1e-6..1e-3 of a *pointed* tip (a cone point on the axis). This case
/// found false hits (rays passing about 1e-7 from the tip reported as hits; the reference and an
/// exact mpmath check said miss) and, after their fix, farther-than-nearest hits at the edge of
/// the reachable radius; both are fixed (docs/bezier.md, "Pointed tips"). About 1.2% of these
/// rays graze the cone so closely that the two roots of the reference's polynomial lie closer
/// than `AMBIGUOUS_WIDTH`: the reference cannot decide them, so this case allows 15 in a thousand
/// undecided (measured: 2 367 of 200 000), where the other cases allow 1. The robust hits on
/// undecided rays are still checked to lie on the surface.
#[test]
fn lathe_near_pole_rays_pointed_tips() {
    let spindle = spindle();
    run_lathe_allowing(
        "lathe near-pole (spindle tips)",
        &spindle,
        7,
        15,
        near_pole_ray(vec![DVec3::ZERO, DVec3::new(0.0, 1.5, 0.0)], spindle.size()),
    );
}

/// A bumpy height field over [0, 3]^2.
fn wavy() -> Patch {
    Patch::new(&wavy_points()).unwrap()
}

/// A quarter dome whose first row collapses to its apex (as the teapot's lid).
fn dome() -> Patch {
    let k = 0.552_284_749_8;
    let rows = [(0.0, 1.0), (k, 1.0), (1.0, k), (1.0, 0.0)];
    let cols = [(1.0, 0.0), (1.0, k), (k, 1.0), (0.0, 1.0)];
    Patch::new(&std::array::from_fn(|idx| {
        let (r, h) = rows[idx / 4];
        let (cx, cz) = cols[idx % 4];
        DVec3::new(r * cx, h, r * cz)
    }))
    .unwrap()
}

const PATCH_NEWTON: PatchSolver = PatchSolver::Newton {
    iterations: 16,
    starts: 9,
};

fn run_patch(
    name: &str,
    patch: &Patch,
    seed: u64,
    make_ray: impl Fn(&mut Rng) -> (DVec3, DVec3) + Sync,
) {
    let start = std::time::Instant::now();
    // The renderer cuts a patch into pieces, each its own BVH primitive (`BezierPatch::split`).
    let pieces = patch.pieces(PIECES);
    let st = (0..rays())
        .into_par_iter()
        .fold(Stats::default, |mut st, i| {
            let (o, d) = make_ray(&mut ray_rng(seed, i));
            st.rays += 1;
            let want = reference::patch(patch, o, d, 1e-9, f64::INFINITY);
            let got = patch.intersect(o, d, 1e-9, f64::INFINITY, PatchSolver::Robust);
            let mut split: Option<PatchHit> = None;
            for p in &pieces {
                let t_max = split.map_or(f64::INFINITY, |h| h.t);
                if let Some(h) = p.intersect(o, d, 1e-9, t_max, PatchSolver::Robust) {
                    split = Some(h);
                }
            }
            st.split_differs += (split.map(|h| h.t) != got.map(|h| h.t)) as usize;
            let before = st.failures();
            // Every robust hit, also on rays the reference cannot decide, lies on the surface
            // (the pieces' hits at the whole patch's (u, v)).
            for h in got.iter().chain(split.iter()) {
                let (q, _, _) = patch.eval(h.uv.x, h.uv.y);
                if (q - h.p).length() > 1e-6 * patch.size() {
                    st.off_surface += 1;
                }
            }
            if want.ambiguous {
                st.ambiguous += 1;
                return st;
            }
            let want = want.t;
            st.ref_hits += want.is_some() as usize;
            st.compare(want, got.map(|h| h.t));
            st.compare(want, split.map(|h| h.t));
            if before != st.failures() && st.failing.len() < 3 {
                let msg = format!(
                    "o={o:?} d={d:?}: reference {want:?}, robust {got:?}, pieces {split:?}"
                );
                st.failing.push((i, msg));
            }
            let newton = patch.intersect(o, d, 1e-9, f64::INFINITY, PATCH_NEWTON);
            st.newton(want, newton.map(|h| h.t));
            st
        })
        .reduce(Stats::default, Stats::merge);
    println!("[{name}] {} rays in {:.1?}", st.rays, start.elapsed());
    st.report_and_check(name, 1);
}

#[test]
fn patch_random_rays() {
    for (name, p, seed) in [
        ("patch random (wavy)", wavy(), 11),
        ("patch random (dome)", dome(), 12),
    ] {
        let (lo, hi) = p.bounds();
        run_patch(name, &p, seed, random_rays(lo, hi));
    }
}

#[test]
fn patch_grazing_rays() {
    for (name, p, seed) in [
        ("patch grazing (wavy)", wavy(), 13),
        ("patch grazing (dome)", dome(), 14),
    ] {
        let size = p.size();
        let pp = p.clone();
        run_patch(name, &p, seed, move |rng| {
            let (u, v) = (rng.range(0.02, 0.98), rng.range(0.02, 0.98));
            let (q, pu, pv) = pp.eval(u, v);
            let n = pp.normal(u, v);
            let a = rng.range(0.0, std::f64::consts::TAU);
            let t = (pu.normalize() * a.cos() + pv.normalize() * a.sin()).normalize();
            let t = (t - n * t.dot(n)).normalize();
            let delta =
                10f64.powf(rng.range(-5.0, -2.0)) * size * if rng.f() < 0.5 { 1.0 } else { -1.0 };
            (q + n * delta - t * 2.0 * size, t)
        });
    }
}

/// A profile aimed at the per-piece shell culling: a flat disk from the axis (its shells are
/// degenerate in height), a bulge, a flat annulus, a cusp (the tangent vanishes mid-segment) and
/// a dome closing on the axis (radius 0 at the pole).
fn culling_profile() -> Lathe {
    Lathe::new(
        &profile(&[
            &[(0.0, 0.0), (0.3, 0.0), (0.6, 0.0)],
            &[(0.6, 0.0), (0.6, 0.3), (0.2, 0.4), (0.5, 0.6)],
            &[(0.5, 0.6), (0.3, 0.6)],
            &[(0.3, 0.6), (0.6, 0.9), (0.3, 0.9), (0.6, 0.6)],
            &[(0.6, 0.6), (0.6, 1.0), (0.3, 1.2), (0.0, 1.2)],
        ]),
        None,
    )
    .unwrap()
}

/// Rays grazing the cylinders of the pieces' shells: each ray passes at a distance
/// `r (1 +- 10^-u)` (`u` in 2..9) from the axis, where `r` is the largest or smallest radius
/// of a piece of the profile, at a height inside the piece, tilted by 1e-6..1e-3. (Closer,
/// with `u` up to 12, a ray can pass within 1e-12 of the corner between the bulge and the flat
/// annulus: the robust method reports a touch of the corner there, on the surface, which the
/// reference does not see; that is a tie within rounding, not a decidable case.)
#[test]
fn lathe_culling_shell_grazing_rays() {
    let l = culling_profile();
    let size = l.size();
    // Many of these rays pass within 1e-9 of a silhouette at a shallow angle, where the
    // reference's two roots merge: it leaves 3.8% undecided (1 879 of 50 000, measured), so this
    // case allows 50 in 1000. Robust hits on them are still checked to lie on the surface.
    run_lathe_allowing("lathe culling: shell-grazing", &l, 8, 50, |rng| {
        let segs = l.segments();
        let seg = &segs[(rng.f() * segs.len() as f64) as usize % segs.len()];
        let k = (rng.f() * 8.0) as usize % 8;
        let (a, b) = (k as f64 / 8.0, (k + 1) as f64 / 8.0);
        let (rp, hp) = (seg.r.restrict(a, b), seg.h.restrict(a, b));
        let cs = rp.coeffs();
        let r = if rng.f() < 0.5 {
            cs.iter().fold(0.0f64, |m, &c| m.max(c))
        } else {
            cs.iter().fold(f64::INFINITY, |m, &c| m.min(c))
        };
        let rho = r * (1.0 + rng.sign() * 10f64.powf(-rng.range(2.0, 9.0)));
        let y = hp.eval(rng.f());
        let ang = rng.range(0.0, std::f64::consts::TAU);
        let (dir, side) = (
            DVec3::new(ang.cos(), 0.0, ang.sin()),
            DVec3::new(-ang.sin(), 0.0, ang.cos()),
        );
        // Never exactly 0: a ray lying in the plane of the flat disk or annulus makes the
        // reference's `F` vanish identically, and its subdivision then runs away in memory (the
        // robust intersector reports such an interval whole; see the closed-form test below).
        let tilt = rng.sign() * 10f64.powf(-rng.range(3.0, 6.0));
        let d = (dir + DVec3::Y * tilt).normalize();
        let o = DVec3::new(0.0, y, 0.0) + side * rho - d * 2.0 * size;
        (o, d)
    });
}

/// Rays within 1e-9..1e-3 of the axis, nearly parallel to it (tilt up to 1e-3), from above and
/// below: they meet the pole of the dome, the cusp's and the annulus's shells at their inner
/// radius, and the flat disk. (Rays exactly on the axis are a double root at both poles, which
/// the reference cannot decide: `lathe_culling_rays_on_the_axis` checks them in closed form.)
#[test]
fn lathe_culling_axis_rays() {
    let l = culling_profile();
    let size = l.size();
    // The reference leaves about 9% of these rays undecided (17 827 of 200 000, measured; not
    // yet analysed which roots it cannot separate): allowed 100 in 1000. Robust hits on them
    // are still checked to lie on the surface.
    run_lathe_allowing("lathe culling: along the axis", &l, 9, 100, |rng| {
        let off = 10f64.powf(-rng.range(3.0, 9.0)) * size;
        let ang = rng.range(0.0, std::f64::consts::TAU);
        let p = DVec3::new(off * ang.cos(), rng.range(0.0, 1.2), off * ang.sin());
        let tilt = if rng.f() < 0.3 {
            DVec3::ZERO
        } else {
            rng.unit() * rng.range(0.0, 1e-3)
        };
        let d = (DVec3::Y * rng.sign() + tilt).normalize();
        (p - d * 3.0 * size, d)
    });
}

/// Rays starting on the surface (inside the shells of their own piece, as every secondary ray
/// does) in a random direction, and rays starting at a random point inside the bounds.
#[test]
fn lathe_culling_rays_from_inside_the_shells() {
    let l = culling_profile();
    run_lathe(
        "lathe culling: from inside the shells",
        &l,
        10,
        from_inside_the_shells(&l),
    );
}

/// The generator of the case above.
fn from_inside_the_shells(l: &Lathe) -> impl Fn(&mut Rng) -> (DVec3, DVec3) + Sync + '_ {
    let (lo, hi) = l.bounds();
    move |rng| {
        let o = if rng.f() < 0.5 {
            l.sample(DVec2::new(rng.f(), rng.f())).unwrap().0
        } else {
            DVec3::new(
                rng.range(lo.x, hi.x),
                rng.range(lo.y, hi.y),
                rng.range(lo.z, hi.z),
            )
        };
        (o, rng.unit())
    }
}

/// Rays #511630 and #958799 of the case above (at 10^6 rays) leave the surface and meet it
/// again within 1e-4, nearly tangent (`tests/render/bezier_cases.rs` checks the robust method on
/// them). The reference must give the true `t` (60-digit decimal Newton on
/// `h(s) = o_y + t d_y`, `r(s)^2 = |o_xz + t d_xz|^2` from the exact f64 inputs) to well below
/// the stress test's 1e-6. In plain f64 its answer on the second ray was 9.5e-7 off (the
/// factor's rounding noise over a ray at about 2e-5 rad to the surface); the double-double
/// polish brings it to rounding.
#[test]
fn reference_gives_the_true_t_of_nearly_tangent_hits_from_the_surface() {
    let l = culling_profile();
    let make_ray = from_inside_the_shells(&l);
    for (i, want) in [
        (511_630, 8.031_811_035_709_652e-5),
        (958_799, 5.047_383_840_691_549e-6),
    ] {
        let (o, d) = make_ray(&mut ray_rng(10, i));
        let got = reference::lathe(&l, o, d, 1e-9, f64::INFINITY);
        assert!(!got.ambiguous, "ray #{i}");
        let t = got.t.unwrap_or_else(|| panic!("ray #{i}: no hit"));
        assert!(
            (t - want).abs() < 1e-9 * want,
            "ray #{i}: t {t} want {want}"
        );
    }
}

/// Random rays at the culling profile (flat disk, annulus, cusp, pole).
#[test]
fn lathe_culling_random_rays() {
    let l = culling_profile();
    let (lo, hi) = l.bounds();
    run_lathe("lathe culling: random", &l, 11, random_rays(lo, hi));
}

/// Rays exactly on the axis, from below and above, from outside and from inside the solid: the
/// first hit is the flat disk at height 0 or the dome's pole at 1.2, at a distance known exactly.
#[test]
fn lathe_culling_rays_on_the_axis() {
    let l = culling_profile();
    for k in 0..1000 {
        let y = -1.0 + 3.4 * k as f64 / 1000.0;
        for dir in [1.0, -1.0] {
            let o = DVec3::new(0.0, y, 0.0);
            let got = l.intersect(o, DVec3::Y * dir, 1e-9, f64::INFINITY, Solver::Robust);
            let want = match (dir > 0.0, y) {
                (true, y) if y < 0.0 => Some(-y),
                (true, y) if y < 1.2 => Some(1.2 - y),
                (false, y) if y > 1.2 => Some(y - 1.2),
                (false, y) if y > 0.0 => Some(y),
                _ => None,
            };
            match (want, got) {
                (None, None) => {}
                (Some(t), Some(h)) => assert!(
                    (h.t - t).abs() <= 1e-12 * t.max(1.0),
                    "y {y} dir {dir}: t {} want {t}",
                    h.t
                ),
                _ => panic!("y {y} dir {dir}: want {want:?}, got {got:?}"),
            }
        }
    }
}

/// Rays lying in the plane of the flat annulus (height 0.6) and of the flat disk (height 0),
/// perpendicular to the axis: `F` vanishes on those segments; the first hit is where the
/// profile is outermost at that height (radius 0.6 at 0.6, the disk's rim at 0), known exactly.
#[test]
fn lathe_culling_rays_in_the_flat_planes() {
    let l = culling_profile();
    for k in 0..360 {
        let a = (k as f64).to_radians();
        let dir = DVec3::new(a.cos(), 0.0, a.sin());
        for (y, r) in [(0.6, 0.6), (0.0, 0.6)] {
            let o = DVec3::new(0.0, y, 0.0) - dir * 3.0;
            let got = l.intersect(o, dir, 1e-9, f64::INFINITY, Solver::Robust);
            let t = got.map(|h| h.t);
            assert!(
                t.is_some_and(|t| (t - (3.0 - r)).abs() < 1e-9),
                "height {y}, angle {k}: {t:?}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// prism: the product's exact intersector against `sppm_measure::prism_reference`.

mod prism_stress {
    use glam::{DVec2, DVec3};
    use rayon::prelude::*;
    use sppm_lang::internals::sampling::SplitMix64;
    use sppm_lang::internals::scene::{Prism as ScenePrism, PrismSpline, prism_segments};
    use sppm_lang::internals::shapes::prism::{Prism, PrismPart};
    use sppm_measure::prism_reference::RefPrism;

    /// Rays per case: 10 000 by default (the ten cases take about 15 s together in the dev
    /// profile on two shared cores); `PRISM_STRESS_RAYS=1000000` runs a million per case.
    fn rays() -> usize {
        std::env::var("PRISM_STRESS_RAYS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(10_000)
    }

    fn pts(v: &[(f64, f64)]) -> Vec<DVec2> {
        v.iter().map(|&(x, z)| DVec2::new(x, z)).collect()
    }

    /// The profiles: holes, a thin sliver with a needle tip, sharp spikes, curves of every
    /// spline kind, and Bezier cusps (coincident control points).
    fn profiles() -> Vec<(&'static str, PrismSpline, Vec<DVec2>)> {
        let star: Vec<(f64, f64)> = (0..=14)
            .map(|i| {
                let a = std::f64::consts::TAU * f64::from(i % 14) / 14.0;
                let r = if i % 2 == 0 { 2.0 } else { 0.15 };
                (r * a.cos(), r * a.sin())
            })
            .collect();
        vec![
            (
                "square, hole and sliver",
                PrismSpline::Linear,
                pts(&[
                    (-2.0, -2.0),
                    (2.0, -2.0),
                    (2.0, 2.0),
                    (-2.0, 2.0),
                    (-2.0, -2.0),
                    (-1.0, -1.0),
                    (1.0, -1.0),
                    (1.0, 1.0),
                    (-1.0, 1.0),
                    (-1.0, -1.0),
                    (2.5, -2.0),
                    (2.502, -2.0),
                    (2.5, 2.0),
                    (2.5, -2.0),
                ]),
            ),
            ("star", PrismSpline::Linear, pts(&star)),
            (
                "quadratic",
                PrismSpline::Quadratic,
                pts(&[
                    (0.0, -2.0),
                    (2.0, 0.0),
                    (0.0, 2.0),
                    (-2.0, 0.0),
                    (0.0, -2.0),
                    (2.0, 0.0),
                ]),
            ),
            (
                "cubic with a hole",
                PrismSpline::Cubic,
                pts(&[
                    (0.0, -2.0),
                    (2.0, -0.5),
                    (1.0, 2.0),
                    (-1.5, 1.0),
                    (-2.0, -1.5),
                    (0.0, -2.0),
                    (2.0, -0.5),
                    (1.0, 2.0),
                    (0.3, 0.0),
                    (0.0, 0.5),
                    (-0.5, 0.0),
                    (0.0, -0.5),
                    (0.3, 0.0),
                    (0.0, 0.5),
                    (-0.5, 0.0),
                ]),
            ),
            (
                "bezier cusps",
                PrismSpline::Bezier,
                pts(&[
                    (0.0, -2.0),
                    (0.0, -2.0),
                    (2.0, -1.0),
                    (2.0, 0.5),
                    (2.0, 0.5),
                    (2.0, 2.0),
                    (0.5, 2.0),
                    (0.0, 0.8),
                    (0.0, 0.8),
                    (-0.5, 2.0),
                    (-2.0, 2.0),
                    (-2.0, 0.5),
                    (-2.0, 0.5),
                    (-2.0, -1.0),
                    (0.0, -2.0),
                    (0.0, -2.0),
                ]),
            ),
        ]
    }

    #[derive(Default)]
    struct Counts {
        rays: usize,
        ambiguous: usize,
        ref_hits: usize,
        misses: usize,
        false_hits: usize,
        t_errors: usize,
        max_t_err: f64,
        normal_checked: usize,
        normal_wrong: usize,
        failing: Vec<String>,
    }

    impl Counts {
        fn merge(mut self, o: Counts) -> Counts {
            self.rays += o.rays;
            self.ambiguous += o.ambiguous;
            self.ref_hits += o.ref_hits;
            self.misses += o.misses;
            self.false_hits += o.false_hits;
            self.t_errors += o.t_errors;
            self.max_t_err = self.max_t_err.max(o.max_t_err);
            self.normal_checked += o.normal_checked;
            self.normal_wrong += o.normal_wrong;
            self.failing.extend(o.failing);
            self.failing.truncate(3);
            self
        }
    }

    /// A ray of kind `i % 4`: random through the box, grazing the side at 1e-5..1e-2 of the
    /// size, aimed within 1e-9..1e-3 of a joint (a corner, a cusp, the sliver's needle), or
    /// at a cap's edge.
    fn ray(p: &ScenePrism, i: usize, rng: &mut SplitMix64) -> (DVec3, DVec3) {
        let (lo, hi) = (p.heights.0.min(p.heights.1), p.heights.0.max(p.heights.1));
        let seg = &p.segments[(rng.f() * p.segments.len() as f64) as usize % p.segments.len()];
        let at = |s: f64| {
            let u = 1.0 - s;
            seg[0] * (u * u * u)
                + seg[1] * (3.0 * u * u * s)
                + seg[2] * (3.0 * u * s * s)
                + seg[3] * (s * s * s)
        };
        let place = |q: DVec2, h: f64| {
            let w = if p.conic { h } else { 1.0 };
            DVec3::new(q.x * w, h, q.y * w)
        };
        match i % 4 {
            0 => {
                let o = rng.unit() * 9.0;
                let target = DVec3::new(
                    rng.range(-3.0, 3.0) * hi.abs().max(1.0),
                    rng.range(lo, hi),
                    rng.range(-3.0, 3.0) * hi.abs().max(1.0),
                );
                (o, (target - o).normalize())
            }
            1 => {
                let s = rng.range(0.001, 0.999);
                let h = rng.range(lo, hi);
                let q = at(s);
                let tq = (at(s + 1e-7) - at(s - 1e-7)).normalize();
                let point = place(q, h);
                let along = place(tq, h) - place(DVec2::ZERO, h);
                let up = if p.conic {
                    DVec3::new(q.x, 1.0, q.y)
                } else {
                    DVec3::Y
                };
                let n = along.cross(up).normalize();
                let a = rng.range(0.0, std::f64::consts::TAU);
                let dir = (along.normalize() * a.cos() + up.normalize() * a.sin()).normalize();
                let eps = 10f64.powf(rng.range(-5.0, -2.0)) * rng.sign();
                let d = (dir + n * eps).normalize();
                let o = point - d * 9.0 + n * (eps * rng.range(-2.0, 2.0));
                (o, d)
            }
            2 => {
                let h = rng.range(lo, hi);
                let point = place(seg[0], h);
                let off = rng.unit() * 10f64.powf(rng.range(-9.0, -3.0));
                let d = rng.unit();
                (point + off - d * 9.0, d)
            }
            _ => {
                let h = if rng.f() < 0.5 { lo } else { hi };
                let point = place(at(rng.f()), h);
                let off = rng.unit() * 10f64.powf(rng.range(-9.0, -2.0));
                let d = rng.unit();
                (point + off - d * 9.0, d)
            }
        }
    }

    fn run_case(name: &str, p: &ScenePrism, seed: u64) {
        let fast = Prism::new(p).unwrap();
        let reference = RefPrism::new(p);
        let n = rays();
        let c = (0..n)
            .into_par_iter()
            .map(|i| {
                let mut rng = SplitMix64::for_item(seed, 0, i);
                let (o, d) = ray(p, i, &mut rng);
                let mut c = Counts {
                    rays: 1,
                    ..Default::default()
                };
                let want = reference.nearest(o, d, 0.0);
                let got = fast.nearest(o, d, 0.0, f64::INFINITY);
                if want.ambiguous {
                    c.ambiguous = 1;
                    return c;
                }
                c.ref_hits = usize::from(want.t.is_some());
                match (want.t, got) {
                    (Some(w), None) => {
                        c.misses = 1;
                        c.failing.push(format!("miss #{i}: o {o} d {d} want {w}"));
                    }
                    (None, Some(g)) => {
                        c.false_hits = 1;
                        c.failing
                            .push(format!("false #{i}: o {o} d {d} got {:?}", g));
                    }
                    (Some(w), Some(g)) => {
                        let err = (g.t - w).abs();
                        c.max_t_err = err;
                        if err > 1e-7 * w.max(1.0) {
                            c.t_errors = 1;
                            c.failing
                                .push(format!("t #{i}: o {o} d {d} want {w} got {g:?}"));
                        }
                        // The normal points out of the solid: against the ray where the ray
                        // enters (inside just after the hit), along it where it leaves.
                        let (pt, nrm, _, _) = fast.surface(o, d, g);
                        let step = 1e-6;
                        if let (Some(before), Some(after)) = (
                            reference.inside(pt - d * step),
                            reference.inside(pt + d * step),
                        ) && before != after
                        {
                            c.normal_checked = 1;
                            if (nrm.dot(d) < 0.0) != after {
                                c.normal_wrong = 1;
                                c.failing
                                    .push(format!("normal #{i}: o {o} d {d} hit {g:?} n {nrm}"));
                            }
                        }
                        let _ = matches!(g.part, PrismPart::Cap { .. });
                    }
                    (None, None) => {}
                }
                c
            })
            .reduce(Counts::default, Counts::merge);
        for f in &c.failing {
            println!("  [{name}] {f}");
        }
        println!(
            "[{name}] rays {} ambiguous {} reference hits {} | misses {} false hits {} t errors {} \
             (max {:.2e}) | normals checked {} wrong {}",
            c.rays,
            c.ambiguous,
            c.ref_hits,
            c.misses,
            c.false_hits,
            c.t_errors,
            c.max_t_err,
            c.normal_checked,
            c.normal_wrong
        );
        assert_eq!(
            (c.misses, c.false_hits, c.t_errors, c.normal_wrong),
            (0, 0, 0, 0),
            "{name}"
        );
        // A quarter of the rays aim within 1e-9..1e-3 of a joint, where the reference cannot
        // tell which segment a ray passing within its tolerance crosses.
        assert!(
            c.ambiguous * 100 <= 15 * c.rays,
            "{name}: too many undecided rays"
        );
        assert!(c.ref_hits * 10 >= c.rays, "{name}: too few hits to test");
    }

    /// Every profile, swept straight and conic, against the reference: no miss, no false hit,
    /// `t` within 1e-7 (relative), and every normal out of the solid.
    #[test]
    fn prism_rays_against_the_reference() {
        for (k, (name, spline, points)) in profiles().into_iter().enumerate() {
            let segments = prism_segments(spline, &points).unwrap();
            for conic in [false, true] {
                let p = ScenePrism {
                    segments: segments.clone(),
                    heights: if conic { (0.5, 1.5) } else { (-0.5, 1.0) },
                    conic,
                    open: false,
                };
                let label = format!("{name}, {}", if conic { "conic" } else { "linear" });
                run_case(&label, &p, 0x9e1 + k as u64 * 2 + u64::from(conic));
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// superellipsoid: the product's interval subdivision against
// `sppm_measure::superellipsoid_reference`.

mod superellipsoid_stress {
    use glam::DVec3;
    use rayon::prelude::*;
    use sppm_lang::internals::sampling::SplitMix64;
    use sppm_lang::internals::shapes::superellipsoid::Superellipsoid;
    use sppm_measure::superellipsoid_reference::RefSuperellipsoid;

    /// Rays per case: 3 000 by default (the reference samples every ray 4 000 times; the seven
    /// cases take about 15 s together in the dev profile on two shared cores);
    /// `SUPERELLIPSOID_STRESS_RAYS` sets another count.
    fn rays() -> usize {
        std::env::var("SUPERELLIPSOID_STRESS_RAYS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(3_000)
    }

    /// The point of the surface in direction `u` (bisection of the reference function).
    fn on_surface(r: &RefSuperellipsoid, u: DVec3) -> DVec3 {
        let (mut lo, mut hi) = (0.0, 2.0);
        for _ in 0..100 {
            let m = 0.5 * (lo + hi);
            if r.f(u * m) < 0.0 {
                lo = m;
            } else {
                hi = m;
            }
        }
        u * lo
    }

    fn ray(r: &RefSuperellipsoid, i: usize, rng: &mut SplitMix64) -> (DVec3, DVec3) {
        match i % 3 {
            0 => {
                let o = rng.unit() * 5.0;
                let target = DVec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                );
                (o, (target - o).normalize())
            }
            1 => {
                // Grazing: nearly along the tangent plane (the reference's gradient by central
                // differences), offset 1e-5..1e-2 across it.
                let p = on_surface(r, rng.unit());
                let h = 1e-6;
                let g = DVec3::new(
                    r.f(p + DVec3::X * h) - r.f(p - DVec3::X * h),
                    r.f(p + DVec3::Y * h) - r.f(p - DVec3::Y * h),
                    r.f(p + DVec3::Z * h) - r.f(p - DVec3::Z * h),
                );
                let n = g.normalize_or(p.normalize());
                let tangent = n.cross(rng.unit()).normalize();
                let eps = 10f64.powf(rng.range(-5.0, -2.0)) * rng.sign();
                let d = (tangent + n * eps).normalize();
                (p - d * 4.0 + n * (eps * rng.range(-2.0, 2.0)), d)
            }
            _ => {
                // At an edge or tip: an axis or a diagonal direction, moved by 1e-9..1e-3.
                let dirs = [
                    DVec3::X,
                    DVec3::Z,
                    DVec3::new(1.0, 1.0, 0.0),
                    DVec3::new(1.0, 0.0, 1.0),
                    DVec3::new(1.0, 1.0, 1.0),
                ];
                let k = (rng.f() * dirs.len() as f64) as usize % dirs.len();
                let u = dirs[k].normalize() * DVec3::new(rng.sign(), rng.sign(), rng.sign())
                    + rng.unit() * 10f64.powf(rng.range(-9.0, -3.0));
                let p = on_surface(r, u.normalize());
                let d = rng.unit();
                (p - d * 4.0, d)
            }
        }
    }

    /// Near-box, sphere, octahedron, pinched and mixed exponents: no miss, no false hit (a hit
    /// the reference's sampling stepped over counts when `F` changes sign across it), `t`
    /// within 1e-6, and normals out of the solid.
    #[test]
    fn superellipsoid_rays_against_the_reference() {
        let cases = [
            (0.001, 0.001),
            (0.02, 0.3),
            (1.0, 1.0),
            (2.0, 2.0),
            (0.05, 2.5),
            (3.0, 4.0),
            (10.0, 10.0),
        ];
        for (c, &(e, n)) in cases.iter().enumerate() {
            let fast = Superellipsoid::new(e, n).unwrap();
            let r = RefSuperellipsoid::new(e, n);
            let count = rays();
            let (fails, confirmed, hits, normals, max_err) = (0..count)
                .into_par_iter()
                .map(|i| {
                    let mut rng = SplitMix64::for_item(0x5e11 + c as u64, 0, i);
                    let (o, d) = ray(&r, i, &mut rng);
                    let want = r.nearest(o, d, 0.0);
                    let got = fast.nearest(o, d, 0.0, f64::INFINITY);
                    // The reference's function changes sign across `t` (on some scale from 1e-7
                    // down to 1e-11: a ray that clips a sharp corner is inside only briefly).
                    let changes = |t: f64| {
                        [1e-7, 1e-9, 1e-11].iter().any(|dt| {
                            (r.f(o + (t - dt) * d) < 0.0) != (r.f(o + (t + dt) * d) < 0.0)
                        })
                    };
                    let mut out = (
                        Vec::new(),
                        0usize,
                        usize::from(want.is_some()),
                        0usize,
                        0.0f64,
                    );
                    match (want, got) {
                        (Some(w), None) => out.0.push(format!("miss: o {o} d {d} want {w}")),
                        (None, Some(g)) if !changes(g) => {
                            out.0.push(format!("false hit: o {o} d {d} got {g}"))
                        }
                        (None, Some(_)) => out.1 = 1,
                        (Some(w), Some(g)) => {
                            let err = (g - w).abs();
                            if err > 1e-6 * w.max(1.0) {
                                if g < w && changes(g) {
                                    out.1 = 1;
                                } else {
                                    out.0.push(format!("t: o {o} d {d} want {w} got {g}"));
                                }
                            } else {
                                out.4 = err;
                            }
                        }
                        (None, None) => {}
                    }
                    if let Some(g) = got {
                        let dt = 1e-7;
                        let (before, after) =
                            (r.f(o + (g - dt) * d) < 0.0, r.f(o + (g + dt) * d) < 0.0);
                        if before != after {
                            let (_, nrm, _, _) = fast.surface(o, d, g);
                            if (nrm.dot(d) < 0.0) != after {
                                out.0.push(format!("normal: o {o} d {d} t {g} n {nrm}"));
                            }
                            out.3 = 1;
                        }
                    }
                    out
                })
                .reduce(
                    || (Vec::new(), 0, 0, 0, 0.0),
                    |mut a, b| {
                        a.0.extend(b.0);
                        (a.0, a.1 + b.1, a.2 + b.2, a.3 + b.3, a.4.max(b.4))
                    },
                );
            for f in fails.iter().take(3) {
                println!("  [<{e}, {n}>] {f}");
            }
            println!(
                "[superellipsoid <{e}, {n}>] rays {count} reference hits {hits} failures {} \
                 (hits the reference stepped over, confirmed: {confirmed}) normals checked \
                 {normals} max t error {max_err:.2e}",
                fails.len()
            );
            assert!(fails.is_empty(), "<{e}, {n}>: {} failures", fails.len());
            assert!(hits * 10 >= count, "<{e}, {n}>: too few hits to test");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// blob and isosurface: the product's exact piecewise-quartic isolation (blob) and interval
// subdivision (isosurface) against `sppm_measure::blob_reference`.

mod blob_stress {
    use std::sync::Arc;
    use std::time::Instant;

    use glam::{DAffine3, DQuat, DVec3};
    use rayon::prelude::*;
    use sppm_lang::internals::sampling::SplitMix64;
    use sppm_lang::internals::scene::function::{Binary, Op, Unary};
    use sppm_lang::internals::scene::{
        Blob as SceneBlob, BlobComponent, Container, Function, Isosurface as SceneIso,
    };
    use sppm_lang::internals::shapes::blob::Blob;
    use sppm_lang::internals::shapes::isosurface::{DEFAULT_ACCURACY, Isosurface};
    use sppm_measure::blob_reference::{RefBlob, RefComponent, first_sign_change};

    /// Rays per case: 4 000 by default (the references sample every ray thousands of times);
    /// `BLOB_STRESS_RAYS` sets another count.
    fn rays() -> usize {
        std::env::var("BLOB_STRESS_RAYS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(4_000)
    }

    /// Counts of one case.
    #[derive(Default)]
    struct Tally {
        fails: Vec<String>,
        confirmed: usize,
        hits: usize,
        max_err: f64,
    }

    impl Tally {
        fn merge(mut self, o: Tally) -> Tally {
            self.fails.extend(o.fails);
            self.confirmed += o.confirmed;
            self.hits += o.hits;
            self.max_err = self.max_err.max(o.max_err);
            self
        }

        /// Judges one ray: `want` the reference's hit, `got` the product's, `changes(t)` whether
        /// the reference's function changes sign across `t` (a hit the sampling stepped over).
        fn judge(
            want: Option<f64>,
            got: Option<f64>,
            changes: impl Fn(f64) -> bool,
            what: String,
        ) -> Tally {
            let mut out = Tally {
                hits: usize::from(want.is_some()),
                ..Tally::default()
            };
            match (want, got) {
                (Some(w), None) => out.fails.push(format!("miss: {what} want {w}")),
                (None, Some(g)) if !changes(g) => {
                    out.fails.push(format!("false hit: {what} got {g}"))
                }
                (None, Some(_)) => out.confirmed = 1,
                (Some(w), Some(g)) => {
                    let err = (g - w).abs();
                    if err > 1e-6 * w.max(1.0) {
                        if g < w && changes(g) {
                            out.confirmed = 1;
                        } else {
                            out.fails.push(format!("t: {what} want {w} got {g}"));
                        }
                    } else {
                        out.max_err = err;
                    }
                }
                (None, None) => {}
            }
            out
        }
    }

    struct Case {
        name: &'static str,
        threshold: f64,
        /// (a, b, radius, strength, placement)
        comps: Vec<(DVec3, DVec3, f64, f64, DAffine3)>,
    }

    fn cases() -> Vec<Case> {
        let id = DAffine3::IDENTITY;
        // Two spheres whose fields meet at the midpoint just above the threshold: a neck of
        // radius about 3.5e-3 (2 (1 - c^2)^2 = 0.5 (1 + 1e-4)).
        let c = (1.0 - 0.5 * (1.0f64 + 1e-4).sqrt()).sqrt();
        let mut random = Vec::new();
        let mut rng = SplitMix64::new(0xb10b);
        for _ in 0..40 {
            let a = DVec3::new(
                rng.range(-1.5, 1.5),
                rng.range(-1.5, 1.5),
                rng.range(-1.5, 1.5),
            );
            let b = if rng.f() < 0.4 {
                a + rng.unit() * rng.range(0.2, 1.0)
            } else {
                a
            };
            let s = if rng.f() < 0.25 {
                -rng.range(0.5, 2.0)
            } else {
                rng.range(0.5, 2.0)
            };
            let place = if rng.f() < 0.3 {
                DAffine3::from_scale_rotation_translation(
                    DVec3::new(
                        rng.range(0.5, 1.5),
                        rng.range(0.5, 1.5),
                        rng.range(0.5, 1.5),
                    ),
                    DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 3.0)),
                    DVec3::ZERO,
                )
            } else {
                id
            };
            random.push((a, b, rng.range(0.3, 1.0), s, place));
        }
        vec![
            Case {
                name: "spheres, capsule and a negative sphere",
                threshold: 0.5,
                comps: vec![
                    (
                        DVec3::new(-0.4, 0.0, 0.0),
                        DVec3::new(-0.4, 0.0, 0.0),
                        1.0,
                        1.0,
                        id,
                    ),
                    (
                        DVec3::new(0.4, 0.1, 0.0),
                        DVec3::new(0.4, 0.1, 0.0),
                        1.0,
                        1.0,
                        id,
                    ),
                    (
                        DVec3::new(0.0, -0.8, 0.0),
                        DVec3::new(0.0, 0.8, 0.3),
                        0.6,
                        1.5,
                        id,
                    ),
                    (
                        DVec3::new(0.0, 0.6, -0.5),
                        DVec3::new(0.0, 0.6, -0.5),
                        0.5,
                        -2.0,
                        id,
                    ),
                ],
            },
            Case {
                name: "a neck where two spheres barely meet",
                threshold: 0.5,
                comps: vec![
                    (
                        DVec3::new(-c, 0.0, 0.0),
                        DVec3::new(-c, 0.0, 0.0),
                        1.0,
                        1.0,
                        id,
                    ),
                    (
                        DVec3::new(c, 0.0, 0.0),
                        DVec3::new(c, 0.0, 0.0),
                        1.0,
                        1.0,
                        id,
                    ),
                ],
            },
            Case {
                name: "40 random components, a quarter negative, some transformed",
                threshold: 0.6,
                comps: random,
            },
        ]
    }

    /// The first point where `f` (positive inside) turns negative going from `c` along `u`.
    fn surface_from(f: &impl Fn(DVec3) -> f64, c: DVec3, u: DVec3) -> Option<DVec3> {
        if f(c) <= 0.0 {
            return None;
        }
        let mut t0 = 0.0;
        for i in 1..=2000 {
            let t1 = 4.0 * f64::from(i) / 2000.0;
            if f(c + t1 * u) <= 0.0 {
                let (mut l, mut h) = (t0, t1);
                for _ in 0..100 {
                    let m = 0.5 * (l + h);
                    if f(c + m * u) > 0.0 {
                        l = m;
                    } else {
                        h = m;
                    }
                }
                return Some(c + l * u);
            }
            t0 = t1;
        }
        None
    }

    fn grad(f: &impl Fn(DVec3) -> f64, p: DVec3) -> DVec3 {
        let h = 1e-7;
        DVec3::new(
            f(p + DVec3::X * h) - f(p - DVec3::X * h),
            f(p + DVec3::Y * h) - f(p - DVec3::Y * h),
            f(p + DVec3::Z * h) - f(p - DVec3::Z * h),
        )
    }

    /// Random rays from afar (at points of the box), grazing rays (1e-5..1e-2 off a tangent
    /// plane) and rays through the origin's neighbourhood across the x axis.
    fn ray(
        f: &impl Fn(DVec3) -> f64,
        centres: &[DVec3],
        lo: DVec3,
        hi: DVec3,
        i: usize,
        rng: &mut SplitMix64,
    ) -> (DVec3, DVec3) {
        let random = |rng: &mut SplitMix64| {
            let o = rng.unit() * 6.0;
            let target = lo + (hi - lo) * DVec3::new(rng.f(), rng.f(), rng.f());
            (o, (target - o).normalize())
        };
        match i % 3 {
            0 => random(rng),
            1 => {
                let c = centres[(rng.f() * centres.len() as f64) as usize % centres.len()];
                let Some(p) = surface_from(f, c, rng.unit()) else {
                    return random(rng);
                };
                let n = (-grad(f, p)).normalize_or(DVec3::Y);
                let tangent = n.cross(rng.unit()).normalize();
                let eps = 10f64.powf(rng.range(-5.0, -2.0)) * rng.sign();
                let d = (tangent + n * eps).normalize();
                (p - d * 4.0 + n * (eps * rng.range(-2.0, 2.0)), d)
            }
            _ => {
                let target = DVec3::new(0.0, rng.range(-0.01, 0.01), rng.range(-0.01, 0.01));
                let d = DVec3::new(
                    rng.range(-0.05, 0.05),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                )
                .normalize();
                (target - d * 4.0, d)
            }
        }
    }

    /// No miss, no false hit (a hit the reference's 4 000 samples stepped over counts when the
    /// field changes sign across it), `t` within 1e-6, normals out of the solid.
    #[test]
    fn blob_rays_against_the_reference() {
        for (k, case) in cases().iter().enumerate() {
            let blob = Blob::new(&SceneBlob {
                threshold: case.threshold,
                components: case
                    .comps
                    .iter()
                    .map(|&(a, b, radius, strength, transform)| BlobComponent {
                        a,
                        b,
                        radius,
                        strength,
                        transform,
                    })
                    .collect(),
            })
            .unwrap();
            let r = RefBlob {
                threshold: case.threshold,
                comps: case
                    .comps
                    .iter()
                    .map(|&(a, b, r, s, t)| RefComponent {
                        a,
                        b,
                        r,
                        s,
                        to_local: t.inverse(),
                    })
                    .collect(),
            };
            // The reference's box: every positive component's box, placed.
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            let mut centres = Vec::new();
            for &(a, b, rad, s, t) in &case.comps {
                if s <= 0.0 {
                    continue;
                }
                centres.push(t.transform_point3(0.5 * (a + b)));
                let (l, h) = (a.min(b) - DVec3::splat(rad), a.max(b) + DVec3::splat(rad));
                for i in 0..8 {
                    let pick = |bit: i32, u: f64, v: f64| if i & bit == 0 { u } else { v };
                    let p = t.transform_point3(DVec3::new(
                        pick(1, l.x, h.x),
                        pick(2, l.y, h.y),
                        pick(4, l.z, h.z),
                    ));
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
            let f = |p: DVec3| r.f(p);
            let count = rays();
            let seed = 0xb10b0 + k as u64;
            let rays: Vec<(DVec3, DVec3)> = (0..count)
                .map(|i| {
                    ray(
                        &f,
                        &centres,
                        lo,
                        hi,
                        i,
                        &mut SplitMix64::for_item(seed, 0, i),
                    )
                })
                .collect();
            let start = Instant::now();
            let got: Vec<Option<f64>> = rays
                .iter()
                .map(|&(o, d)| blob.nearest(o, d, 0.0, f64::INFINITY))
                .collect();
            let per_ray = start.elapsed().as_secs_f64() / count as f64;
            let tally = rays
                .par_iter()
                .zip(&got)
                .map(|(&(o, d), &g)| {
                    let want = first_sign_change(f, lo, hi, o, d, 0.0, 4_000);
                    let changes = |t: f64| {
                        [1e-7, 1e-9].iter().any(|dt| {
                            (r.f(o + (t - dt) * d) > 0.0) != (r.f(o + (t + dt) * d) > 0.0)
                        })
                    };
                    let mut out = Tally::judge(want, g, changes, format!("o {o} d {d}"));
                    if let Some(t) = g {
                        let dt = 1e-7;
                        let after = r.f(o + (t + dt) * d) > 0.0;
                        if after != (r.f(o + (t - dt) * d) > 0.0) {
                            let n = blob.normal(o + t * d);
                            if (n.dot(d) < 0.0) != after {
                                out.fails.push(format!("normal: o {o} d {d} t {t} n {n}"));
                            }
                        }
                    }
                    out
                })
                .reduce(Tally::default, Tally::merge);
            for f in tally.fails.iter().take(3) {
                println!("  [{}] {f}", case.name);
            }
            println!(
                "[blob: {}] rays {count} reference hits {} failures {} (stepped over by the \
                 reference, confirmed: {}) max t error {:.2e}, {:.2} µs per ray",
                case.name,
                tally.hits,
                tally.fails.len(),
                tally.confirmed,
                tally.max_err,
                per_ray * 1e6
            );
            assert!(
                tally.fails.is_empty(),
                "{}: {} failures",
                case.name,
                tally.fails.len()
            );
            assert!(
                tally.hits * 5 >= count,
                "{}: too few hits to test",
                case.name
            );
        }
    }

    /// sqrt(x^2 + y^2 + z^2) as a compiled program.
    fn radius_ops() -> Vec<Op> {
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

    /// A shell 1e-3 thick (`|r - 1| < 5e-4`) and a needle (radius 2e-3 at y = 0 tapering to a
    /// point at y = 1): features a fixed step of 0.01 (or a `max_gradient` guess) steps over.
    /// The reference samples each ray 100 000 times (a step of about 3e-5).
    #[test]
    fn isosurface_thin_features_against_the_reference() {
        type Reference = fn(DVec3) -> f64;
        let shell_ops = {
            let mut c = radius_ops();
            c.extend([
                Op::Const(1.0),
                Op::Binary(Binary::Sub),
                Op::Unary(Unary::Abs),
            ]);
            c
        };
        // sqrt(x^2 + z^2) + 0.002 y
        let needle_ops = vec![
            Op::Load(0),
            Op::Load(0),
            Op::Binary(Binary::Mul),
            Op::Load(2),
            Op::Load(2),
            Op::Binary(Binary::Mul),
            Op::Binary(Binary::Add),
            Op::Unary(Unary::Sqrt),
            Op::Const(0.002),
            Op::Load(1),
            Op::Binary(Binary::Mul),
            Op::Binary(Binary::Add),
        ];
        let shell: Reference = |p| (p.length() - 1.0).abs() - 5e-4;
        let needle: Reference = |p| (p.x * p.x + p.z * p.z).sqrt() + 0.002 * p.y - 0.002;
        let cases: [(&str, Vec<Op>, f64, Reference); 2] = [
            ("shell 1e-3 thick", shell_ops, 5e-4, shell),
            ("needle 4e-3 wide", needle_ops, 0.002, needle),
        ];
        for (k, (name, ops, threshold, g)) in cases.into_iter().enumerate() {
            let iso = Isosurface::new(&SceneIso {
                function: Arc::new(Function::new(3, 3, ops).unwrap()),
                threshold,
                container: Container::Box {
                    min: DVec3::splat(-1.5),
                    max: DVec3::splat(1.5),
                },
                open: true,
                // The default: 1e-6 of the container's diagonal (5.2e-6 here). At 1e-9 the
                // rays that graze the shell's tangent cost about sqrt(2 / 1e-9) stretches
                // each: no failure either, but 13 ms a ray on average.
                accuracy: DEFAULT_ACCURACY * (2.0 * DVec3::splat(1.5)).length(),
            })
            .unwrap();
            let (lo, hi) = (DVec3::splat(-1.5), DVec3::splat(1.5));
            let count = rays() / 2;
            let rays: Vec<(DVec3, DVec3)> = (0..count)
                .map(|i| {
                    let mut rng = SplitMix64::for_item(0x150 + k as u64, 0, i);
                    let o = rng.unit() * 6.0;
                    // At the feature: a point of the shell's sphere or of the needle's axis,
                    // moved by up to 5e-3; a third of the rays graze (1e-5..1e-2 off the
                    // tangent of the sphere).
                    let target = if k == 0 {
                        rng.unit() * (1.0 + rng.range(-5e-3, 5e-3))
                    } else {
                        DVec3::new(
                            rng.range(-5e-3, 5e-3),
                            rng.range(-1.0, 1.0),
                            rng.range(-5e-3, 5e-3),
                        )
                    };
                    if k == 0 && i % 3 == 1 {
                        let p = target.normalize() * (1.0 + 5e-4);
                        let n = p.normalize();
                        let tangent = n.cross(rng.unit()).normalize();
                        let eps = 10f64.powf(rng.range(-5.0, -2.0)) * rng.sign();
                        let d = (tangent + n * eps).normalize();
                        return (p - d * 3.0, d);
                    }
                    (o, (target - o).normalize())
                })
                .collect();
            let start = Instant::now();
            let got: Vec<Option<f64>> = rays
                .iter()
                .map(|&(o, d)| iso.nearest(o, d, 0.0, f64::INFINITY).map(|m| m.t()))
                .collect();
            let per_ray = start.elapsed().as_secs_f64() / count as f64;
            let inside = |p: DVec3| -g(p);
            let tally = rays
                .par_iter()
                .zip(&got)
                .map(|(&(o, d), &t)| {
                    let want = first_sign_change(inside, lo, hi, o, d, 0.0, 100_000);
                    let changes = |t: f64| {
                        [1e-7, 1e-9]
                            .iter()
                            .any(|dt| (g(o + (t - dt) * d) < 0.0) != (g(o + (t + dt) * d) < 0.0))
                    };
                    Tally::judge(want, t, changes, format!("o {o} d {d}"))
                })
                .reduce(Tally::default, Tally::merge);
            for f in tally.fails.iter().take(3) {
                println!("  [{name}] {f}");
            }
            println!(
                "[isosurface: {name}] rays {count} reference hits {} failures {} (confirmed: {}) \
                 max t error {:.2e}, budget exhausted {}, {:.1} µs per ray",
                tally.hits,
                tally.fails.len(),
                tally.confirmed,
                tally.max_err,
                iso.exhausted(),
                per_ray * 1e6
            );
            assert!(
                tally.fails.is_empty(),
                "{name}: {} failures",
                tally.fails.len()
            );
            assert_eq!(iso.exhausted(), 0, "{name}: rays gave up");
            assert!(tally.hits * 5 >= count, "{name}: too few hits to test");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// height_field: the product's min/max hierarchy against every triangle tested one by one
// (`sppm_measure::height_field_reference`).

mod height_field_stress {
    use std::sync::Arc;
    use std::time::Instant;

    use glam::DVec3;
    use rayon::prelude::*;
    use sppm_lang::internals::sampling::SplitMix64;
    use sppm_lang::internals::scene::{self, HeightGrid};
    use sppm_lang::internals::shapes::height_field::HeightField;
    use sppm_measure::height_field_reference::RefHeightField;

    /// Rays per case: 20 000 by default (the reference tests every one of about 50 000
    /// triangles per ray); `HEIGHT_FIELD_STRESS_RAYS` sets another count.
    fn rays() -> usize {
        std::env::var("HEIGHT_FIELD_STRESS_RAYS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(20_000)
    }

    /// A rough terrain of `nx x nz` samples (a sum of waves, some of it under the water).
    fn terrain(nx: u32, nz: u32, water: f64, smooth: bool) -> scene::HeightField {
        let mut heights = Vec::new();
        for j in 0..nz {
            for i in 0..nx {
                let (x, z) = (
                    f64::from(i) / f64::from(nx - 1),
                    f64::from(j) / f64::from(nz - 1),
                );
                let h = 0.45
                    + 0.25 * (7.0 * x + 1.0).sin() * (5.0 * z).cos()
                    + 0.12 * (31.0 * x * z + 2.0).sin()
                    + 0.05 * (97.0 * x).sin() * (89.0 * z + 1.0).cos();
                heights.push(h.clamp(0.0, 1.0) as f32);
            }
        }
        scene::HeightField {
            grid: Arc::new(HeightGrid { nx, nz, heights }),
            water,
            smooth,
        }
    }

    /// Ray `i` of a case: random through the box; grazing a random sample's neighbourhood
    /// (nearly along the terrain, 1e-5..1e-2 across it); through a grid vertex or along a grid
    /// line or diagonal (shared edges and corners); nearly along the water plane.
    fn ray(f: &scene::HeightField, i: usize, rng: &mut SplitMix64) -> (DVec3, DVec3) {
        let g = &f.grid;
        let sample = |rng: &mut SplitMix64| {
            let (a, b) = (
                (rng.f() * f64::from(g.nx)) as u32 % g.nx,
                (rng.f() * f64::from(g.nz)) as u32 % g.nz,
            );
            DVec3::new(
                f64::from(a) / f64::from(g.nx - 1),
                f64::from(g.at(a, b)).max(f.water),
                f64::from(b) / f64::from(g.nz - 1),
            )
        };
        match i % 4 {
            0 => {
                let o = rng.unit() * 3.0 + DVec3::splat(0.5);
                let target = DVec3::new(rng.f(), rng.range(f.water, 1.0), rng.f());
                (o, (target - o).normalize())
            }
            1 => {
                let p = sample(rng);
                let mut tangent = DVec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0));
                tangent = tangent.normalize_or(DVec3::X);
                let eps = 10f64.powf(rng.range(-5.0, -2.0)) * rng.sign();
                let d = (tangent + DVec3::Y * eps).normalize();
                (p - d * 2.0 + DVec3::Y * (eps * rng.range(-1.0, 1.0)), d)
            }
            2 => {
                // Aimed exactly at a vertex, or run along a grid line or a cell diagonal.
                let p = sample(rng);
                let dirs = [
                    DVec3::new(1.0, rng.range(-0.3, 0.3), 0.0),
                    DVec3::new(0.0, rng.range(-0.3, 0.3), 1.0),
                    DVec3::new(
                        1.0 / f64::from(g.nx - 1),
                        rng.range(-0.01, 0.01),
                        -1.0 / f64::from(g.nz - 1),
                    ),
                ];
                let k = (rng.f() * 4.0) as usize;
                if k >= 3 {
                    let d = rng.unit();
                    return (p - d * 2.0, d);
                }
                let d = dirs[k].normalize() * rng.sign();
                (p - d * 2.0 + DVec3::Y * 1e-9, d)
            }
            _ => {
                let p = DVec3::new(rng.f(), f.water, rng.f());
                let eps = 10f64.powf(rng.range(-6.0, -2.0)) * rng.sign();
                let d = (DVec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0))
                    .normalize_or(DVec3::Z)
                    + DVec3::Y * eps)
                    .normalize();
                (p - d * 2.0, d)
            }
        }
    }

    /// Flat and smooth terrains, with and without a water level, of 129 x 97 samples (about
    /// 50 000 triangles with the sides and the bottom): no miss, no false hit, `t` within 1e-12
    /// of the reference's, and the speed of both per ray.
    #[test]
    fn height_field_rays_against_every_triangle() {
        for (c, &(water, smooth)) in [(0.0, false), (0.3, true), (0.55, false)]
            .iter()
            .enumerate()
        {
            let field = terrain(129, 97, water, smooth);
            let fast = HeightField::new(&field).unwrap();
            let reference = RefHeightField::new(&fast);
            let count = rays();
            let make = |i: usize| {
                let mut rng = SplitMix64::for_item(0x4f1e + c as u64, 0, i);
                ray(&field, i, &mut rng)
            };
            let start = Instant::now();
            let got: Vec<_> = (0..count)
                .into_par_iter()
                .map(|i| {
                    let (o, d) = make(i);
                    fast.hit_t(o, d, 0.0, f64::INFINITY)
                })
                .collect();
            let fast_time = start.elapsed().as_secs_f64();
            let start = Instant::now();
            let want: Vec<_> = (0..count)
                .into_par_iter()
                .map(|i| {
                    let (o, d) = make(i);
                    reference.nearest(o, d, 0.0)
                })
                .collect();
            let ref_time = start.elapsed().as_secs_f64();
            let (mut misses, mut false_hits, mut t_errors, mut hits) = (0, 0, 0, 0);
            let mut failing = Vec::new();
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                match (w, g) {
                    (Some(_), None) => misses += 1,
                    (None, Some(_)) => false_hits += 1,
                    (Some(w), Some(g)) => {
                        hits += 1;
                        if (g.0 - w.0).abs() > 1e-12 * w.0.max(1.0) {
                            t_errors += 1;
                        } else {
                            continue;
                        }
                    }
                    (None, None) => continue,
                }
                if failing.len() < 5 {
                    failing.push(format!("ray {i} {:?}: want {w:?} got {g:?}", make(i)));
                }
            }
            println!(
                "height field 129x97 water {water} smooth {smooth}: {count} rays, {hits} hits, \
                 {misses} misses, {false_hits} false hits, {t_errors} t errors; hierarchy \
                 {:.2} µs/ray, every triangle ({} of them) {:.1} µs/ray ({:.0}x); hierarchy \
                 {:.2} bytes per cell",
                fast_time / count as f64 * 1e6,
                reference.len(),
                ref_time / count as f64 * 1e6,
                ref_time / fast_time,
                fast.hierarchy_bytes() as f64 / (128.0 * 96.0)
            );
            assert!(
                misses + false_hits + t_errors == 0,
                "water {water}: {failing:#?}"
            );
            assert!(hits > count / 4, "too few hits to test anything: {hits}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// text: each glyph's prism against its own outline, flattened finely and filled by even-odd.

mod text_stress {
    use glam::{DVec2, DVec3, Vec3A};
    use rayon::prelude::*;
    use sppm_lang::internals::geometry::Ray;
    use sppm_lang::internals::sampling::SplitMix64;
    use sppm_lang::internals::scene::text::text_glyphs;
    use sppm_lang::internals::shapes::Shape;
    use sppm_lang::internals::shapes::prism::Prism;

    const DEJAVU: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

    /// The outline as a polygon: each cubic segment in 256 steps.
    fn flatten(segments: &[[DVec2; 4]]) -> Vec<(DVec2, DVec2)> {
        let mut edges = Vec::new();
        for c in segments {
            let at = |s: f64| {
                let u = 1.0 - s;
                c[0] * (u * u * u)
                    + c[1] * (3.0 * u * u * s)
                    + c[2] * (3.0 * u * s * s)
                    + c[3] * (s * s * s)
            };
            for k in 0..256 {
                edges.push((at(k as f64 / 256.0), at((k + 1) as f64 / 256.0)));
            }
        }
        edges
    }

    /// Even-odd inside, and the distance to the nearest edge.
    fn inside(edges: &[(DVec2, DVec2)], p: DVec2) -> (bool, f64) {
        let mut odd = false;
        let mut dist = f64::INFINITY;
        for &(a, b) in edges {
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                odd = !odd;
            }
            let ab = b - a;
            let s = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
            dist = dist.min((a + ab * s - p).length());
        }
        (odd, dist)
    }

    /// Rays straight down each glyph's sweep (DejaVu Sans, letters with holes, curves and
    /// corners): a hit exactly where the outline holds the point (points within 1e-4 em of the
    /// outline, closer than its flattening, are left out), at the cap.
    #[test]
    fn text_glyphs_against_their_outlines() {
        let font = std::fs::read(DEJAVU)
            .unwrap_or_else(|_| panic!("{DEJAVU} is missing: install fonts-dejavu-core"));
        let glyphs = text_glyphs(&font, "Sppm-lang 0@&gB%", 0.25, DVec3::ZERO).unwrap();
        let mut total = (0usize, 0usize, 0usize);
        for (k, g) in glyphs.glyphs.iter().enumerate() {
            let prism = Prism::new(&g.prism).unwrap();
            let edges = flatten(&g.prism.segments);
            let (lo, hi) = g
                .prism
                .segments
                .iter()
                .flatten()
                .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(*p), hi.max(*p))
                });
            let (wrong, hits, tested) = (0..20_000usize)
                .into_par_iter()
                .map(|i| {
                    let mut rng = SplitMix64::for_item(0x7e47 + k as u64, 0, i);
                    let p = DVec2::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y));
                    let (want, dist) = inside(&edges, p);
                    if dist < 1e-4 {
                        return (0, 0, 0);
                    }
                    let ray = Ray::new(Vec3A::new(p.x as f32, -1.0, p.y as f32), Vec3A::Y);
                    let got = prism.intersect(&ray, 0.0, f32::INFINITY);
                    let ok = match got {
                        Some(h) => want && (h.t - 1.0).abs() < 1e-6,
                        None => !want,
                    };
                    (usize::from(!ok), usize::from(want), 1)
                })
                .reduce(|| (0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
            assert_eq!(wrong, 0, "glyph {k}: {wrong} of {tested} rays disagree");
            total = (total.0 + wrong, total.1 + hits, total.2 + tested);
        }
        println!(
            "text: {} glyphs, {} rays, {} inside, {} disagreements",
            glyphs.glyphs.len(),
            total.2,
            total.1,
            total.0
        );
    }
}

// ---------------------------------------------------------------------------------------------
// sphere_sweep (cubic_spline, b_spline): the product's Bernstein branch and bound against
// `sppm_measure::sweep_reference`.

mod sweep_stress {
    use std::time::Instant;

    use glam::DVec3;
    use rayon::prelude::*;
    use sppm_lang::internals::sampling::SplitMix64;
    use sppm_lang::internals::scene::{SphereSweep as SceneSweep, SweepSpline};
    use sppm_lang::internals::shapes::sphere_sweep::SphereSweep;
    use sppm_measure::sweep_reference::RefSweep;

    /// Rays per case: 4 000 by default (the reference samples each ray's spheres 2 000 times
    /// per segment, four times over); `SWEEP_STRESS_RAYS` sets another count.
    fn rays() -> usize {
        std::env::var("SWEEP_STRESS_RAYS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(4_000)
    }

    const SAMPLES: usize = 2_000;

    struct Case {
        name: &'static str,
        spline: SweepSpline,
        pts: Vec<(DVec3, f64)>,
    }

    fn cases() -> Vec<Case> {
        let mut rng = SplitMix64::new(0x5eef);
        let wiggly: Vec<(DVec3, f64)> = (0..9)
            .map(|i| {
                (
                    DVec3::new(
                        f64::from(i) * 0.5 - 2.0,
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                    ),
                    rng.range(0.1, 0.5),
                )
            })
            .collect();
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        vec![
            Case {
                name: "cubic_spline, random",
                spline: SweepSpline::CatmullRom,
                pts: wiggly.clone(),
            },
            Case {
                name: "b_spline, random",
                spline: SweepSpline::BSpline,
                pts: wiggly,
            },
            Case {
                // A tripled control point: the curve stops there (a cusp, c' = 0), and the
                // radius grows faster than the centre moves on either side of it.
                name: "b_spline, cusp and fast radius",
                spline: SweepSpline::BSpline,
                pts: vec![
                    (v(-2.0, 0.0, 0.0), 0.1),
                    (v(-1.0, 1.0, 0.0), 0.2),
                    (v(0.0, 0.0, 0.0), 0.05),
                    (v(0.0, 0.0, 0.0), 0.9),
                    (v(0.0, 0.0, 0.0), 0.05),
                    (v(1.0, 1.0, 0.5), 0.2),
                    (v(2.0, -0.5, 0.0), 0.1),
                ],
            },
            Case {
                // Coincident points (a segment of zero length), a thin stretch of radius 2e-3
                // and a stretch where the interpolated radius goes below zero (absent).
                name: "cubic_spline, coincident points, thin and vanishing",
                spline: SweepSpline::CatmullRom,
                pts: vec![
                    (v(-2.0, 0.0, 0.0), 0.3),
                    (v(-1.5, 0.0, 0.0), 0.3),
                    (v(-1.5, 0.0, 0.0), 0.3),
                    (v(-0.5, 0.5, 0.0), 0.002),
                    (v(0.5, -0.5, 0.0), 0.002),
                    (v(1.0, 0.0, 0.5), -0.4),
                    (v(1.5, 0.0, 0.0), 0.5),
                    (v(2.0, 0.5, 0.0), 0.3),
                    (v(2.5, 0.0, 0.0), 0.3),
                ],
            },
        ]
    }

    /// A point on the surface: from a centre on the curve outward along `dir` until the
    /// reference's distance changes sign, bisected.
    fn surface_from(r: &RefSweep, c: DVec3, dir: DVec3) -> Option<DVec3> {
        let f = |t: f64| r.distance(c + t * dir, 200);
        if f(0.0) >= 0.0 {
            return None;
        }
        let (mut l, mut h) = (0.0, 3.0);
        if f(h) <= 0.0 {
            return None;
        }
        for _ in 0..60 {
            let m = 0.5 * (l + h);
            if f(m) < 0.0 {
                l = m;
            } else {
                h = m;
            }
        }
        Some(c + h * dir)
    }

    /// Random rays from afar, grazing rays (1e-5..1e-2 off a tangent plane of the surface)
    /// and rays at the curve's points across it (the cusp, the thin stretch).
    fn ray(r: &RefSweep, i: usize, rng: &mut SplitMix64) -> (DVec3, DVec3) {
        let random = |rng: &mut SplitMix64| {
            let o = rng.unit() * 8.0;
            let target = DVec3::new(
                rng.range(-2.5, 2.5),
                rng.range(-1.5, 1.5),
                rng.range(-1.5, 1.5),
            );
            (o, (target - o).normalize())
        };
        let seg = (rng.f() * r.segments() as f64) as usize % r.segments();
        let (c, _) = r.at(seg, rng.f());
        let (o, d) = match i % 3 {
            0 => random(rng),
            1 => {
                let Some(p) = surface_from(r, c, rng.unit()) else {
                    return random(rng);
                };
                let h = 1e-6;
                let g = |q: DVec3| r.distance(q, 400);
                let n = DVec3::new(
                    g(p + DVec3::X * h) - g(p - DVec3::X * h),
                    g(p + DVec3::Y * h) - g(p - DVec3::Y * h),
                    g(p + DVec3::Z * h) - g(p - DVec3::Z * h),
                )
                .normalize_or(DVec3::Y);
                let tangent = n.cross(rng.unit()).normalize();
                let eps = 10f64.powf(rng.range(-5.0, -2.0)) * rng.sign();
                let d = (tangent + n * eps).normalize();
                (p - d * 6.0 + n * (eps * rng.range(-2.0, 2.0)), d)
            }
            _ => {
                let d = rng.unit();
                let target = c + rng.unit() * rng.range(0.0, 0.01);
                (target - d * 6.0, d)
            }
        };
        // From outside only: the first crossing is then an entry.
        if r.distance(o, 200) < 0.01 {
            return random(rng);
        }
        (o, d)
    }

    /// No miss, no false hit, entry and last exit within 1e-6 (relative to the distance, at
    /// least 1). A ray that reaches less than 1e-8 into or past the spheres (the product's
    /// stated touch resolution) may count either way.
    #[test]
    fn sweep_rays_against_the_reference() {
        for (k, case) in cases().iter().enumerate() {
            let scene = SceneSweep {
                spline: case.spline,
                centres: case.pts.iter().map(|p| p.0).collect(),
                radii: case.pts.iter().map(|p| p.1).collect(),
            };
            let sweep = SphereSweep::new(&scene).unwrap();
            let r = RefSweep {
                b_spline: case.spline == SweepSpline::BSpline,
                centres: scene.centres.clone(),
                radii: scene.radii.clone(),
            };
            let count = rays();
            let rays: Vec<(DVec3, DVec3)> = (0..count)
                .map(|i| ray(&r, i, &mut SplitMix64::for_item(0x5eef0 + k as u64, 0, i)))
                .collect();
            let start = Instant::now();
            // The product's crossings along each ray, all of them.
            let got: Vec<Vec<(f64, bool)>> = rays
                .iter()
                .map(|&(o, d)| {
                    let mut out = Vec::new();
                    let mut lo = 0.0;
                    while let Some(c) = sweep.nearest(o, d, lo, f64::INFINITY, |a, b| b <= a) {
                        out.push((c.t, c.entering));
                        lo = c.t;
                        if out.len() > 64 {
                            break;
                        }
                    }
                    out
                })
                .collect();
            let per_ray = start.elapsed().as_secs_f64() / count as f64;
            let (fails, hits, confirmed, max_err) = rays
                .par_iter()
                .zip(&got)
                .map(|(&(o, d), got)| {
                    let mut fails = Vec::new();
                    let (mut hits, mut confirmed, mut max_err) = (0, 0, 0.0f64);
                    let what = format!("o {o} d {d}");
                    if got.len() % 2 == 1
                        || got.iter().enumerate().any(|(i, c)| c.1 != (i % 2 == 0))
                    {
                        fails.push(format!("crossings not in/out pairs: {what} {got:?}"));
                    }
                    let want = r.span(o, d, SAMPLES);
                    let near_touch = || r.reach(o, d, SAMPLES).abs() < 1e-8;
                    match (want, got.first(), got.last()) {
                        (Some(w), Some(&(gin, _)), Some(&(gout, _))) => {
                            hits = 1;
                            let err = (gin - w.entry).abs().max((gout - w.exit).abs());
                            if err > 1e-6 * w.exit.max(1.0) {
                                if near_touch() {
                                    confirmed = 1;
                                } else {
                                    fails.push(format!(
                                        "t: {what} want {}..{} got {gin}..{gout}",
                                        w.entry, w.exit
                                    ));
                                }
                            } else {
                                max_err = err;
                                if std::env::var("SWEEP_STRESS_WORST").is_ok() && err > 1e-7 {
                                    println!(
                                        "  worst? {what} want {}..{} got {gin}..{gout}",
                                        w.entry, w.exit
                                    );
                                }
                            }
                        }
                        (Some(w), None, _) => {
                            hits = 1;
                            if near_touch() {
                                confirmed = 1;
                            } else {
                                fails.push(format!("miss: {what} want {}", w.entry));
                            }
                        }
                        (None, Some(&(g, _)), _) => {
                            if near_touch() {
                                confirmed = 1;
                            } else {
                                fails.push(format!("false hit: {what} got {g}"));
                            }
                        }
                        _ => {}
                    }
                    (fails, hits, confirmed, max_err)
                })
                .reduce(
                    || (Vec::new(), 0, 0, 0.0),
                    |a, b| {
                        let mut f = a.0;
                        f.extend(b.0);
                        (f, a.1 + b.1, a.2 + b.2, a.3.max(b.3))
                    },
                );
            for f in fails.iter().take(3) {
                println!("  [{}] {f}", case.name);
            }
            println!(
                "[sphere_sweep: {}] rays {count} reference hits {hits} failures {} (touches \
                 within 1e-8: {confirmed}) max t error {max_err:.2e}, {:.2} µs per ray",
                case.name,
                fails.len(),
                per_ray * 1e6
            );
            assert!(fails.is_empty(), "{}: {} failures", case.name, fails.len());
            assert!(hits * 5 >= count, "{}: too few hits to test", case.name);
        }
    }
}
