//! Parse + evaluate speed: a generated 100 000-object scene and the macro-heavy fractal tree.
//! Baselines measured in the same run: reading the text (counting its lines) and parsing alone
//! (pest + AST); the ratios are printed at the end. Run with `cargo bench --bench parse`.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group};
use sppm_lang::span::FileId;
use sppm_lang::{EvalOptions, load_source, syntax};

#[path = "support/big_scene.rs"]
mod big_scene;
use big_scene::big_scene;

const TREE: &str = "
#declare Glass = material { glass ior 1.5 }
#macro Branch(P, Dir, Len, Depth)
  cylinder { P, P + Dir*Len, Len*0.08  material { Glass } }
  #if (Depth > 0)
    Branch(P + Dir*Len, vrotate(Dir, <0, 0,  25>), Len*0.618, Depth - 1)
    Branch(P + Dir*Len, vrotate(Dir, <0, 0, -25>), Len*0.618, Depth - 1)
  #end
#end
Branch(<0, 0, 0>, <0, 1, 0>, 0.5, 13)
";

fn median(mut f: impl FnMut(), runs: usize) -> Duration {
    let mut t: Vec<Duration> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed()
        })
        .collect();
    t.sort();
    t[runs / 2]
}

fn benches(c: &mut Criterion) {
    let big = big_scene(100_000);
    let opts = EvalOptions::default();
    let mut g = c.benchmark_group("parse");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    g.bench_function("read_text_100k", |b| {
        b.iter(|| black_box(&big).lines().count())
    });
    g.bench_function("parse_only_100k", |b| {
        b.iter(|| syntax::parse(FileId(0), black_box(&big)).unwrap().len())
    });
    g.bench_function("parse_eval_100k", |b| {
        b.iter(|| {
            load_source("big.scn", black_box(&big), &opts)
                .scene
                .unwrap()
                .objects
                .len()
        })
    });
    g.bench_function("parse_eval_tree_depth13", |b| {
        b.iter(|| {
            load_source("tree.scn", black_box(TREE), &opts)
                .scene
                .unwrap()
                .objects
                .len()
        })
    });
    g.finish();

    let read = median(
        || {
            black_box(black_box(&big).lines().count());
        },
        3,
    );
    let parse = median(
        || {
            black_box(syntax::parse(FileId(0), &big).unwrap());
        },
        3,
    );
    let full = median(
        || {
            black_box(load_source("big.scn", &big, &opts));
        },
        3,
    );
    let tree = median(
        || {
            black_box(load_source("tree.scn", TREE, &opts));
        },
        3,
    );
    println!(
        "reading the 100k text (line count): {:.2} ms; pest parse + AST is {:.0} x that",
        read.as_secs_f64() * 1e3,
        parse.as_secs_f64() / read.as_secs_f64(),
    );
    println!(
        "100k objects: parse {:.1} ms, parse+evaluate {:.1} ms (ratio {:.2} x parse alone); tree (16383 cylinders): {:.1} ms ({:.2} x the 100k parse)",
        parse.as_secs_f64() * 1e3,
        full.as_secs_f64() * 1e3,
        full.as_secs_f64() / parse.as_secs_f64(),
        tree.as_secs_f64() * 1e3,
        tree.as_secs_f64() / parse.as_secs_f64(),
    );
}

criterion_group!(group, benches);

fn main() {
    group();
    Criterion::default().configure_from_args().final_summary();
}
