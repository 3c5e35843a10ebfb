//! `sppm-lang chart` through the real binary on the inputs that used to hang it or lose its
//! work: extreme values in `--from-csv` (subnormal, huge, equal), values a chart cannot draw,
//! a method variant the render refuses, and an interruption after some methods finished.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use crate::running;
use running::{Running, sppm_within};

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The CSV header `chart` writes and reads.
const HEADER: &str = "method,iterations,seconds,rmse,rel_mse,window_rmse,window_rel_mse\n";

/// `chart --from-csv <csv> -o <png>`, which must end within a minute (a generous bound: it
/// draws eight charts in well under ten seconds).
fn from_csv(csv: &Path, png: &Path) -> Output {
    let args = [
        "chart",
        "--from-csv",
        csv.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ];
    sppm_within(&args, 60).unwrap_or_else(|| panic!("chart --from-csv {csv:?} did not end"))
}

/// Values at the ends of `f64` (the smallest subnormal, subnormals, 1e-300 with 1e300, the
/// largest `f64`), a single row, and all values equal are charted: the command ends, writes
/// every chart, and its CSV redraws.
#[test]
fn extreme_values_in_a_csv_are_charted_in_bounded_time() {
    let dir = tempfile::tempdir().unwrap();
    let tables = [
        (
            "subnormal",
            "sppm,1,5e-324,1e-310,5e-324,,\nsppm,2,1e-310,1e-320,1e-309,,\n",
        ),
        (
            "decades",
            "sppm,1,1e-300,1e300,1e-300,,\npath,1,1e300,1e-300,1e300,,\n\
             path,2,1.7976931348623157e308,5e-324,1,,\n",
        ),
        ("single", "path,1,0.5,0.25,0.125,,\n"),
        (
            "equal",
            "sppm,1,3,3,3,3,3\nsppm,2,3,3,3,3,3\npath,1,3,3,3,3,3\n",
        ),
    ];
    for (name, rows) in tables {
        let csv = dir.path().join(format!("{name}_in.csv"));
        std::fs::write(&csv, format!("{HEADER}{rows}")).unwrap();
        let png = dir.path().join(format!("{name}.png"));
        let start = Instant::now();
        let out = from_csv(&csv, &png);
        let took = start.elapsed().as_secs_f64();
        println!("{name}: {took:.2} s");
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        let img = image::open(&png).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(img.width() > 0);
        for written in ["svg", "csv"] {
            assert!(
                png.with_extension(written).is_file(),
                "{name}: no {written}"
            );
        }
        assert!(dir.path().join(format!("{name}_relmse.png")).is_file());
        // The CSV the chart wrote reads back.
        let again = dir.path().join(format!("{name}_again.png"));
        let out = from_csv(&png.with_extension("csv"), &again);
        assert_eq!(out.status.code(), Some(0), "{name} again: {}", stderr(&out));
    }
}

/// A value a chart cannot draw (NaN, infinite, a negative error, a time of 0 or less) or an
/// iteration count that is not a whole number is a usage error naming the file, its line and
/// the column, and nothing is written.
#[test]
fn values_a_chart_cannot_draw_are_refused_naming_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("path,1,0.5,NaN,0.1,,", "(rmse)", "NaN"),
        ("path,1,-0.5,0.2,0.1,,", "(seconds)", "-0.5"),
        ("path,1,0,0.2,0.1,,", "(seconds)", "`0`"),
        ("path,1,0.5,0.2,-1e-3,,", "(rel_mse)", "-1e-3"),
        ("path,1,0.5,0.2,0.1,inf,0.1", "(window_rmse)", "inf"),
        ("path,1,0.5,0.2,0.1,0.3,1e400", "(window_rel_mse)", "1e400"),
        ("path,-1,0.5,0.2,0.1,,", "(iterations)", "-1"),
    ];
    let png = dir.path().join("c.png");
    for (row, column, value) in cases {
        let csv = dir.path().join("bad.csv");
        std::fs::write(&csv, format!("{HEADER}path,1,0.25,0.5,0.2,,\n{row}\n")).unwrap();
        let out = from_csv(&csv, &png);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{row}: {err}");
        assert!(!err.contains("panicked"), "{row}: {err}");
        assert!(err.contains("bad.csv:3:"), "{row}: no line: {err}");
        assert!(err.contains(column), "{row}: no column {column}: {err}");
        assert!(err.contains(value), "{row}: no value {value}: {err}");
        assert!(
            err.contains("cannot draw") || err.contains("not a whole number"),
            "{row}: {err}"
        );
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, ["bad.csv"], "{row}: files written");
    }
}

/// A tiny scene (8x8) in `dir`, with `settings` added, and a reference for it: its path and
/// the reference's.
fn scene_and_reference(dir: &Path, settings: &str) -> (PathBuf, PathBuf) {
    let scene = dir.join("scene.scn");
    std::fs::write(
        &scene,
        format!(
            "settings {{ resolution <8, 8> iterations 2 seed 1 {settings} }}\n\
             camera {{ location <0, 0, -5> look_at <0, 0, 0> fov 30 }}\n\
             light {{ <0, 5, -5> intensity 10 }}\n\
             sphere {{ <0, 0, 0>, 1 }}\n"
        ),
    )
    .unwrap();
    let reference = dir.join("ref.exr");
    let out = sppm_within(
        &[
            "render",
            scene.to_str().unwrap(),
            "--photons",
            "500",
            "-o",
            reference.to_str().unwrap(),
        ],
        60,
    )
    .expect("the reference renders");
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    (scene, reference)
}

/// The scene asks for the most photons per iteration there may be, so `sppm-photons4x` asks
/// for four times too many: refused before any method renders (the first, `sppm`, has a
/// 20 s budget and the refusal comes well before it would end), at the scene's settings,
/// naming the method; nothing is written. Every refused method is named at once.
#[test]
fn a_variant_past_the_photon_limit_is_refused_before_any_render() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, reference) = scene_and_reference(dir.path(), "photons 100000000000");
    let png = dir.path().join("c.png");
    let start = Instant::now();
    let out = sppm_within(
        &[
            "chart",
            scene.to_str().unwrap(),
            "--reference",
            reference.to_str().unwrap(),
            "--budget",
            "20",
            "--methods",
            "sppm,sppm-photons4x",
            "-o",
            png.to_str().unwrap(),
        ],
        60,
    )
    .expect("chart ends");
    let took = start.elapsed().as_secs_f64();
    let err = stderr(&out);
    println!("refused in {took:.2} s: {err}");
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(took < 15.0, "took {took} s: a method rendered first");
    assert!(err.contains("method `sppm-photons4x`"), "{err}");
    assert!(
        err.contains("photons per iteration must be at most"),
        "{err}"
    );
    assert!(err.contains("scene.scn:1:"), "not at the settings: {err}");
    assert!(!err.contains("chart: sppm ("), "a method started: {err}");
    // All methods: each refused one is reported (photon mapping would store too many
    // photons), none rendered.
    let out = sppm_within(
        &[
            "chart",
            scene.to_str().unwrap(),
            "--reference",
            reference.to_str().unwrap(),
            "--budget",
            "20",
            "-o",
            png.to_str().unwrap(),
        ],
        60,
    )
    .expect("chart ends");
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("method `photon_map`"), "{err}");
    assert!(err.contains("method `sppm-photons4x`"), "{err}");
    assert!(!err.contains("chart: sppm ("), "a method started: {err}");
    for name in ["c.png", "c.svg", "c.csv"] {
        assert!(!dir.path().join(name).exists(), "{name} written");
    }
}

/// SIGTERM while the second method renders: the chart stops at once, writes the first
/// method's rows (CSV and charts) and says which method it stopped in; the stopped method
/// has no rows.
#[cfg(unix)]
#[test]
fn an_interrupted_later_method_leaves_the_earlier_rows_written() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, reference) = scene_and_reference(dir.path(), "photons 500");
    let png = dir.path().join("c.png");
    let mut command = Command::new(env!("CARGO_BIN_EXE_sppm-lang"));
    command.args([
        "chart",
        scene.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
        "--budget",
        "1",
        "--methods",
        "sppm,path",
        "-o",
        png.to_str().unwrap(),
    ]);
    let mut run = Running::spawn(command);
    run.expect("chart: path (", Duration::from_secs(60));
    let pid = run.child.id().to_string();
    let sent = Command::new("kill").args(["-TERM", &pid]).status().unwrap();
    assert!(sent.success());
    let start = Instant::now();
    let status = loop {
        if let Some(status) = run.child.try_wait().unwrap() {
            break status;
        }
        assert!(start.elapsed().as_secs() < 30, "chart did not stop");
        std::thread::sleep(Duration::from_millis(20));
    };
    run.drain(Duration::from_millis(200));
    let err = run.log.join("\n");
    assert_eq!(status.code(), Some(0), "{err}");
    assert!(err.contains("interrupted during method `path`"), "{err}");
    assert!(err.contains("finished (sppm) were written"), "{err}");
    let csv = std::fs::read_to_string(dir.path().join("c.csv")).unwrap();
    assert!(csv.lines().any(|l| l.starts_with("sppm,")), "{csv}");
    assert!(!csv.lines().any(|l| l.starts_with("path,")), "{csv}");
    for chart in ["c.png", "c.svg", "c_relmse.png", "c_relmse.svg"] {
        assert!(dir.path().join(chart).is_file(), "{chart} missing");
    }
}
