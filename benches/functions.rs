//! A compiled user function against the same computation written as a Rust closure:
//! evaluations per second of each over the points of a grid, in one run.
//!
//! `cargo bench --bench functions`

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use sppm_lang::internals::eval::compile_function;

/// A sphere of radius 1 with a ripple, through a helper function and a declared constant: what
/// an isosurface would evaluate.
const SCENE: &str = "
#declare Amp = 0.1;
#declare Ripple = function(a, b) { sin(4 * a) * cos(4 * b) };
#declare F = function { sqrt(x*x + y*y + z*z) - 1 + Amp * Ripple(x, y) };
";

fn points() -> Vec<DVec3> {
    (0..4096)
        .map(|i| {
            let t = i as f64;
            DVec3::new(
                (t * 0.618).fract(),
                (t * 0.414).fract(),
                (t * 0.732).fract(),
            ) * 4.0
                - 2.0
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let f = compile_function(SCENE, "F").expect("the function compiles");
    let closure = |p: DVec3| {
        let amp = black_box(0.1);
        (p.x * p.x + p.y * p.y + p.z * p.z).sqrt() - 1.0
            + amp * ((4.0 * p.x).sin() * (4.0 * p.y).cos())
    };
    let pts = points();
    // Same values first: the measurement compares like with like.
    for p in &pts {
        assert!((f.eval_point(*p) - closure(*p)).abs() < 1e-12);
    }
    let mut g = c.benchmark_group("function");
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.bench_function("compiled", |b| {
        b.iter(|| pts.iter().map(|p| f.eval_point(black_box(*p))).sum::<f64>())
    });
    g.bench_function("closure", |b| {
        b.iter(|| pts.iter().map(|p| closure(black_box(*p))).sum::<f64>())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
