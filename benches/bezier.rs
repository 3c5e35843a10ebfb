//! Rays per second for the revolve and the patch, robust against Newton, on a fixed ray set.
//! Criterion reports time per batch of `RAYS` rays; rays/s = RAYS / time.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec2, DVec3};
use sppm_lang::bezier::lathe::{Lathe, Solver};
use sppm_lang::bezier::patch::{Patch, PatchSolver};

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
    let seg = |p: &[(f64, f64)]| p.iter().map(|&(r, h)| DVec2::new(r, h)).collect::<Vec<_>>();
    let vase = Lathe::new(
        &[
            seg(&[(0.0, 0.0), (0.5, 0.0), (0.6, 0.05), (0.6, 0.2)]),
            seg(&[(0.6, 0.2), (0.6, 0.6), (1.0, 0.8), (0.7, 1.2)]),
            seg(&[(0.7, 1.2), (0.4, 1.6), (0.3, 1.8), (0.45, 2.0)]),
        ],
        None,
    )
    .unwrap();
    let z = [
        [0.0, 0.8, -0.6, 0.2],
        [0.5, -1.2, 1.4, -0.3],
        [-0.4, 1.5, -1.1, 0.6],
        [0.3, -0.2, 0.7, 0.0],
    ];
    let patch = Patch::new(&std::array::from_fn(|k| {
        DVec3::new((k / 4) as f64, (k % 4) as f64, z[k / 4][k % 4])
    }))
    .unwrap();

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
