//! Parse + evaluate speed: a generated 100 000-object scene and the macro-heavy fractal tree.
//! Baselines measured in the same run: reading the text (counting its lines), parsing alone
//! (pest + AST), and, when `povray` is installed, POV-Ray 3.7 parsing the same scene written in
//! its language (`big_scene_pov`; its own "Parse Time"), run alternately with the library load.
//! The ratios are printed at the end. Run with `cargo bench --bench parse`.
//!
//! With `SPPM_PARSE_ONCE=N` it parses a generated scene of N objects once and exits (a fixed
//! workload for `valgrind --tool=callgrind`). With `SPPM_BIG_SCENE_DIR=dir` set it only writes `dir/big.scn` and `dir/big.pov` and exits
//! (used by `benches/povray_parse.sh`, which compares the `sppm-lang check` command).

use std::hint::black_box;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group};
use sppm_lang::span::FileId;
use sppm_lang::{EvalOptions, load_source, syntax};

#[path = "support/big_scene.rs"]
mod big_scene;
use big_scene::{big_scene, big_scene_pov};

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
    compare_with_povray(&big, &opts);
}

/// POV-Ray's own "Parse Time" of `pov` in seconds; `None` when `povray` cannot be run.
fn povray_parse_seconds(pov: &Path) -> Option<f64> {
    let out = Command::new("povray")
        .arg("-D")
        .arg(format!("+I{}", pov.display()))
        .args(["+W1", "+H1", "-F", "-GR", "+GS", "+WT1"])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stderr);
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("Parse Time"))?;
    let inner = line.rsplit_once('(')?.1.split_whitespace().next()?;
    inner.parse().ok()
}

/// The library load of the 100k scene against POV-Ray's parse of the same scene, alternated
/// run by run (medians of 3).
fn compare_with_povray(big: &str, opts: &EvalOptions) {
    let dir = std::env::temp_dir().join(format!("sppm-parse-bench-{}", std::process::id()));
    let pov = dir.join("big.pov");
    if std::fs::create_dir_all(&dir).is_err()
        || std::fs::write(&pov, big_scene_pov(100_000)).is_err()
    {
        println!("POV-Ray comparison skipped: cannot write {}", pov.display());
        return;
    }
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        let Some(p) = povray_parse_seconds(&pov) else {
            println!(
                "POV-Ray comparison skipped: `povray` is not installed (apt-get install povray)"
            );
            let _ = std::fs::remove_dir_all(&dir);
            return;
        };
        theirs.push(p);
        let s = Instant::now();
        black_box(load_source("big.scn", big, opts));
        ours.push(s.elapsed().as_secs_f64());
    }
    let _ = std::fs::remove_dir_all(&dir);
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (o, t) = (med(&mut ours), med(&mut theirs));
    println!(
        "100k objects against POV-Ray 3.7 (same scene in its language, its own Parse Time, \
         alternated, medians of 3): load (parse + evaluate) {:.0} ms, POV-Ray parse {:.0} ms: \
         ratio {:.2} x POV-Ray",
        o * 1e3,
        t * 1e3,
        o / t
    );
}

criterion_group!(group, benches);

fn main() {
    // A fixed workload for instruction counts (`valgrind --tool=callgrind`): parse (pest and
    // the AST) a generated scene of N objects once.
    if let Some(n) = std::env::var("SPPM_PARSE_ONCE")
        .ok()
        .and_then(|n| n.parse().ok())
    {
        let text = big_scene(n);
        let items = syntax::parse(FileId(0), &text).expect("parses");
        println!("parsed {} items", items.len());
        return;
    }
    if let Some(dir) = std::env::var_os("SPPM_BIG_SCENE_DIR") {
        let dir = Path::new(&dir);
        std::fs::create_dir_all(dir).expect("create SPPM_BIG_SCENE_DIR");
        std::fs::write(dir.join("big.scn"), big_scene(100_000)).expect("write big.scn");
        std::fs::write(dir.join("big.pov"), big_scene_pov(100_000)).expect("write big.pov");
        return;
    }
    group();
    Criterion::default().configure_from_args().final_summary();
}
