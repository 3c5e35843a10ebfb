//! Parse + evaluate speed: a generated 100 000-object scene and the macro-heavy fractal tree.
//! The baseline is parsing alone (pest + AST) of the same text, measured in the same run; the
//! ratio evaluate/parse is printed at the end.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group};
use sppm_lang::span::FileId;
use sppm_lang::{EvalOptions, load_source, syntax};

fn big_scene(n: usize) -> String {
    let mut s = String::from("#declare M = material { diffuse rgb <0.7, 0.7, 0.7> }\n");
    for i in 0..n {
        let (x, z) = ((i % 316) as f64 * 0.1, (i / 316) as f64 * 0.1);
        s.push_str(&format!(
            "sphere {{ <{x:.1}, 0.05, {z:.1}>, 0.04 material {{ M }} translate <0, {}, 0> }}\n",
            i % 7
        ));
    }
    s
}

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
    g.sample_size(10);
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

    let parse = median(
        || {
            black_box(syntax::parse(FileId(0), &big).unwrap());
        },
        5,
    );
    let full = median(
        || {
            black_box(load_source("big.scn", &big, &opts));
        },
        5,
    );
    let tree = median(
        || {
            black_box(load_source("tree.scn", TREE, &opts));
        },
        5,
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
