//! Rays per second for the revolve and the patch, robust against Newton, on a fixed ray set.
//! Criterion reports time per batch of `RAYS` rays; rays/s = RAYS / time.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use sppm_lang::internals::bezier::lathe::Lathe;
use sppm_lang::internals::bezier::patch::Patch;
use sppm_lang::internals::bezier::{Solver, Solver as PatchSolver};
use sppm_measure::bezier::{vase_profile, wavy_points};

const RAYS: usize = 4096;

fn rays(lo: DVec3, hi: DVec3) -> Vec<(DVec3, DVec3)> {
    let mut k = 0x1234_5678u64;
    let mut f = move || {
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (k >> 11) as f64 / (1u64 << 53) as f64
    };
    let c = 0.5 * (lo + hi);
    let size = (hi - lo).max_element();
    (0..RAYS)
        .map(|_| {
            let o = c + DVec3::new(f() - 0.5, f() - 0.5, f() - 0.5).normalize() * 3.0 * size;
            let t = lo + (hi - lo) * DVec3::new(f(), f(), f());
            (o, t - o)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let vase = Lathe::new(&vase_profile().segments, None).unwrap();
    let patch = Patch::new(&wavy_points()).unwrap();

    let mut g = c.benchmark_group("revolve");
    g.throughput(Throughput::Elements(RAYS as u64));
    let (lo, hi) = vase.bounds();
    let rs = rays(lo, hi);
    for (name, solver) in [
        ("robust", Solver::Robust),
        (
            "newton_8x4",
            Solver::Newton {
                iterations: 8,
                starts: 4,
            },
        ),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                rs.iter()
                    .filter(|(o, d)| {
                        vase.intersect(*o, *d, 1e-9, f64::INFINITY, solver)
                            .is_some()
                    })
                    .count()
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group("patch");
    g.throughput(Throughput::Elements(RAYS as u64));
    let (lo, hi) = patch.bounds();
    let rs = rays(lo, hi);
    for (name, solver) in [
        ("robust", PatchSolver::Robust),
        (
            "newton_16x9",
            PatchSolver::Newton {
                iterations: 16,
                starts: 9,
            },
        ),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                rs.iter()
                    .filter(|(o, d)| {
                        patch
                            .intersect(*o, *d, 1e-9, f64::INFINITY, solver)
                            .is_some()
                    })
                    .count()
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
