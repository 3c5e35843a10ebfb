//! Parse + evaluate speed: a generated 100 000-object scene and the macro-heavy fractal tree.
//! Baselines measured in the same run: reading the text (counting its lines), parsing alone
//! (pest + AST), and, when `povray` is installed, POV-Ray 3.7 parsing the same scene written in
//! its language (`big_scene_pov`; its own "Parse Time"), run alternately with the library load.
//! The ratios are printed at the end. Run with `cargo bench --bench parse`.
//!
//! With `SPPM_PARSE_ONCE=N` it parses a generated scene of N objects once and exits (a fixed
//! workload for `valgrind --tool=callgrind`). With `SPPM_BIG_SCENE_DIR=dir` set it only writes `dir/big.scn` and `dir/big.pov` and exits
//! (used by `benches/povray_parse.sh`, which compares the `sppm-lang check` command); with
//! `SPPM_POVRAY_ONLY=1` it runs only the comparison with POV-Ray.

use std::hint::black_box;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group};
use sppm_lang::EvalOptions;
use sppm_lang::FileId;
use sppm_lang::internals::eval::load_source;
use sppm_lang::internals::syntax;

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

/// CPU seconds of this process (all threads) and of its waited-for children, from
/// `/proc/self/stat` (Linux; clock ticks from `getconf CLK_TCK`, 100 if unknown).
fn cpu_seconds() -> Option<(f64, f64)> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at the state, field 3.
    let rest = stat.rsplit_once(')')?.1;
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(4)
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    let tick = Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .ok()
        .and_then(|o| {
            String::from_utf8_lossy(&o.stdout)
                .trim()
                .parse::<f64>()
                .ok()
        })
        .unwrap_or(100.0);
    (f.len() == 4).then(|| ((f[0] + f[1]) / tick, (f[2] + f[3]) / tick))
}

/// The library load of the 100k scene against POV-Ray 3.7 on the same scene, alternated run by
/// run (medians of 3): CPU time of the load (all threads) against the CPU time of the whole
/// `povray` process (parse, bounding and a 1x1 render: an upper bound of its parse), and wall
/// time of the load against POV-Ray's own "Parse Time" (wall, so it moves with the machine's
/// load).
fn compare_with_povray(big: &str, opts: &EvalOptions) {
    let dir = std::env::temp_dir().join(format!("sppm-parse-bench-{}", std::process::id()));
    let pov = dir.join("big.pov");
    if std::fs::create_dir_all(&dir).is_err()
        || std::fs::write(&pov, big_scene_pov(100_000)).is_err()
    {
        println!("POV-Ray comparison skipped: cannot write {}", pov.display());
        return;
    }
    let (mut wall, mut cpu, mut pov_parse, mut pov_cpu) = (vec![], vec![], vec![], vec![]);
    for _ in 0..3 {
        let c0 = cpu_seconds();
        let Some(p) = povray_parse_seconds(&pov) else {
            println!(
                "POV-Ray comparison skipped: `povray` is not installed (apt-get install povray)"
            );
            let _ = std::fs::remove_dir_all(&dir);
            return;
        };
        let c1 = cpu_seconds();
        pov_parse.push(p);
        let s = Instant::now();
        black_box(load_source("big.scn", big, opts));
        wall.push(s.elapsed().as_secs_f64());
        let c2 = cpu_seconds();
        if let (Some(c0), Some(c1), Some(c2)) = (c0, c1, c2) {
            pov_cpu.push(c1.1 - c0.1);
            cpu.push(c2.0 - c1.0);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    let med = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let (w, c, pp, pc) = (med(wall), med(cpu), med(pov_parse), med(pov_cpu));
    println!(
        "100k objects against POV-Ray 3.7 (same scene in its language, alternated, medians of \
         3): CPU: load {c:.2} s, whole povray process {pc:.2} s: ratio {:.2} x POV-Ray; wall: \
         load {w:.2} s, POV-Ray's Parse Time {pp:.2} s: ratio {:.2} x POV-Ray",
        c / pc,
        w / pp
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
    // Only the comparison with POV-Ray (no criterion runs).
    if std::env::var_os("SPPM_POVRAY_ONLY").is_some() {
        compare_with_povray(&big_scene(100_000), &EvalOptions::default());
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
