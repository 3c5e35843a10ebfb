//! Property tests of the robust intersectors: hits lie on the surface, normals are perpendicular
//! to the surface tangents, and a ray from just outside toward a sampled surface point hits it.
//! Each property prints its counts (`cargo test -p sppm-measure --test bezier props:: -- --nocapture`).

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestRunner};
use sppm_lang::internals::bezier::lathe::{Lathe, Part};
use sppm_lang::internals::bezier::patch::Patch;
use sppm_lang::internals::bezier::{Solver, Solver as PatchSolver};
use sppm_measure::bezier::{vase_profile, wavy_points};

fn vase() -> Lathe {
    Lathe::new(&vase_profile().segments, Some((0.0, 270.0))).unwrap()
}

fn wavy() -> Patch {
    Patch::new(&wavy_points()).unwrap()
}

/// A direction in the hemisphere around `n`, at least ~17 degrees above the tangent plane.
fn toward_outside(n: DVec3, a: f64, b: f64) -> DVec3 {
    let (e1, e2) = n.any_orthonormal_pair();
    let phi = a * std::f64::consts::TAU;
    let cos_theta = 0.3 + 0.7 * b;
    let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
    n * cos_theta + (e1 * phi.cos() + e2 * phi.sin()) * sin_theta
}

/// Cases per property.
const CASES: u32 = 4000;

/// Runs `test` on `CASES` values of `(u, v, a, b)` drawn from the given `u`/`v` range, then
/// prints how many cases ran, passed and were rejected (by `prop_assume!`), and fails on the
/// first counter-example (shrunk by proptest).
fn check(
    name: &str,
    uv: std::ops::Range<f64>,
    test: impl Fn(f64, f64, f64, f64) -> Result<(), TestCaseError>,
) {
    use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
    let (passed, rejected) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let mut runner = TestRunner::new(ProptestConfig {
        cases: CASES,
        failure_persistence: None,
        ..ProptestConfig::default()
    });
    let result = runner.run(
        &(uv.clone(), uv, 0.0..1.0f64, 0.0..1.0f64),
        |(u, v, a, b)| {
            let r = test(u, v, a, b);
            match &r {
                Ok(()) => passed.fetch_add(1, Relaxed),
                Err(TestCaseError::Reject(_)) => rejected.fetch_add(1, Relaxed),
                Err(TestCaseError::Fail(_)) => 0,
            };
            r
        },
    );
    println!(
        "[{name}] {} cases passed, {} rejected by assumptions",
        passed.load(Relaxed),
        rejected.load(Relaxed)
    );
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
    assert!(
        passed.load(Relaxed) >= CASES as usize,
        "{name}: too few cases ran"
    );
}

#[test]
fn lathe_hits_lie_on_the_surface_with_perpendicular_normals() {
    check("lathe", 0.0..1.0, |u, v, a, b| {
        let l = vase();
        let size = l.size();
        let (p, n) = l.sample(DVec2::new(u, v)).unwrap();
        prop_assume!(p.x.hypot(p.z) > 1e-3 * size);
        let o = p + toward_outside(n, a, b) * 1e-3 * size;
        let h = l.intersect(o, p - o, 1e-9, f64::INFINITY, Solver::Robust);
        prop_assert!(h.is_some(), "no hit from {o} toward {p}");
        let h = h.unwrap();
        prop_assert!(
            (h.p - p).length() < 1e-6 * size,
            "hit {} vs target {p}",
            h.p
        );
        prop_assert!((h.t - 1.0).abs() < 1e-6);
        if let Part::Side(i) = h.part {
            let q = l.segments()[i].point(h.s);
            let m = DVec2::new(h.p.x.hypot(h.p.z), h.p.y);
            prop_assert!((m - q).length() < 1e-6 * size);
            // Tangents: along the profile (dpdu) and around the axis.
            let around = DVec3::new(-h.p.z, 0.0, h.p.x).normalize();
            prop_assert!(h.n.dot(h.dpdu.normalize()).abs() < 1e-9);
            prop_assert!(h.n.dot(around).abs() < 1e-9);
            prop_assert!((h.n.length() - 1.0).abs() < 1e-12);
            // Outward: the sampled normal and the hit's agree.
            prop_assert!(h.n.dot(n) > 0.999);
        }
        Ok(())
    });
}

#[test]
fn patch_hits_lie_on_the_surface_with_perpendicular_normals() {
    check("patch", 0.001..0.999, |u, v, a, b| {
        let p = wavy();
        let size = p.size();
        let (q, _, _) = p.eval(u, v);
        let n = p.normal(u, v);
        let o = q + toward_outside(n, a, b) * 1e-3 * size;
        let h = p.intersect(o, q - o, 1e-9, f64::INFINITY, PatchSolver::Robust);
        prop_assert!(h.is_some(), "no hit from {o} toward {q}");
        let h = h.unwrap();
        prop_assert!(
            (h.p - q).length() < 1e-6 * size,
            "hit {} vs target {q}",
            h.p
        );
        let (s, pu, pv) = p.eval(h.uv.x, h.uv.y);
        prop_assert!((s - h.p).length() < 1e-6 * size);
        prop_assert!(h.n.dot(pu.normalize()).abs() < 1e-9);
        prop_assert!(h.n.dot(pv.normalize()).abs() < 1e-9);
        prop_assert!((h.uv - DVec2::new(u, v)).length() < 1e-5);
        Ok(())
    });
}
