//! `sppm-lang chart`: render a scene with every integrator and chosen SPPM variations under a
//! growing time budget, measure the error against a reference (whole image and an optional
//! window), and draw error against time (log-log, PNG + SVG) with a CSV table.
//!
//! Each method renders once; the image is measured at geometric checkpoints (budget / 32,
//! / 16, ..., budget) from the progress callback, and the render is stopped at the first
//! iteration that ends past the budget: a method renders past its budget by less than one
//! iteration. The time a checkpoint spends computing errors is subtracted from the render time
//! it reports.
//!
//! The reference's own noise bounds the error a method can show: a method at least as good
//! as the reference measures the reference's noise. When the reference comes from
//! `sppm-lang reference`, its noise image beside it gives that floor (for the whole image and
//! the window); the chart draws it and warns of methods that reach it.

mod methods;
mod outputs;
mod run;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::ArgMatches;
use sppm_lang::SourceMap;
use sppm_lang::internals::compare::{ErrorStats, ImageView, Window, error};
use sppm_lang::internals::render::{InitialRadius, RenderOptions, effective_settings};
use sppm_lang::internals::scene::{ColorSpace, Scene, load_image};

use super::check::print_diagnostics;
use super::reference::{floor_in, noise_paths};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, LimitArgs, SizeArgs, option};
use methods::{Method, methods, parse_methods, rank_of, style_of};
use outputs::{Floors, output_files, read_csv, write_outputs};
use run::{Failure, Stop, measure, run_methods};

/// A method whose error ends within this factor of the reference's noise is "at the floor":
/// its own error is at most about the reference's (sqrt(1.5^2 - 1) = 1.1 times it).
const AT_FLOOR: f64 = 1.5;

#[derive(Debug)]
pub struct ChartArgs {
    pub scene: Option<PathBuf>,
    pub reference: Option<PathBuf>,
    pub from_csv: Option<PathBuf>,
    pub budget: f64,
    pub window: Option<String>,
    pub output: PathBuf,
    pub methods: Option<String>,
    pub size: SizeArgs,
    pub limits: LimitArgs,
}

impl ChartArgs {
    /// `chart`'s flags on `cmd`.
    pub fn command(cmd: clap::Command) -> clap::Command {
        cmd.override_usage(
            "sppm-lang chart <SCENE> --reference <REF.exr> -o <CHART.png> [OPTIONS]\n       \
             sppm-lang chart --from-csv <CSV> -o <CHART.png>",
        )
        .arg(
            super::scene_arg()
                .required(false)
                .required_unless_present("from_csv"),
        )
        .arg(
            option("reference", "reference", "REF.exr")
                .value_parser(clap::value_parser!(PathBuf))
                .required_unless_present("from_csv")
                .help_heading("Required")
                .help(
                    "Reference image (linear EXR) of the same resolution, e.g. made by \
                     `sppm-lang reference` (whose noise estimate beside it marks the error \
                     floor). Required unless --from-csv",
                ),
        )
        .arg(
            option("from_csv", "from-csv", "CSV")
                .value_parser(clap::value_parser!(PathBuf))
                .conflicts_with_all(["scene", "reference", "window", "methods"])
                .help("Redraw the charts from a CSV this command wrote earlier, without rendering"),
        )
        .arg(
            option("budget", "budget", "BUDGET")
                .value_parser(parse_budget)
                .default_value("60")
                .help("Largest time budget per method, in seconds (`60` or `60s`; at most a year)"),
        )
        .arg(
            option("window", "window", "WINDOW")
                .value_parser(clap::value_parser!(String))
                .help(
                    "Pixel window x0,y0,x1,y1 (columns then rows, half-open) also measured on \
                     its own",
                ),
        )
        .arg(
            super::output_arg("CHART.png")
                .required(true)
                .help_heading("Required")
                .help(
                    "Output chart (.png); an .svg and a .csv with the same stem are written \
                     beside it",
                ),
        )
        .arg(
            option("methods", "methods", "METHODS")
                .value_parser(clap::value_parser!(String))
                .help("Only these methods (comma-separated labels, see the CSV); default: all"),
        )
        .args(SizeArgs::args())
        .args(LimitArgs::args())
    }

    pub fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            scene: m.remove_one("scene"),
            reference: m.remove_one("reference"),
            from_csv: m.remove_one("from_csv"),
            budget: super::required(m, "budget")?,
            window: m.remove_one("window"),
            output: super::required(m, "output")?,
            methods: m.remove_one("methods"),
            size: SizeArgs::from_matches(m),
            limits: LimitArgs::from_matches(m)?,
        })
    }
}

/// One measurement.
pub struct Row {
    method: String,
    iterations: u32,
    seconds: f64,
    whole: Errors,
    window: Option<Errors>,
}

/// The two errors the chart draws.
#[derive(Clone, Copy)]
pub struct Errors {
    rmse: f64,
    rel_mse: f64,
}

impl From<ErrorStats> for Errors {
    fn from(e: ErrorStats) -> Self {
        Self {
            rmse: e.rmse,
            rel_mse: e.rel_mse,
        }
    }
}

/// A number of seconds as [`super::parse_seconds`] takes it, with an optional `s`.
fn parse_budget(text: &str) -> Result<f64, String> {
    super::parse_seconds(text.trim().trim_end_matches('s'))
}

pub fn run(args: &ChartArgs) -> ExitCode {
    match chart(args) {
        Ok(code) => code,
        Err(e) => {
            say!("error: {e}");
            ExitCode::from(EXIT_USAGE)
        }
    }
}

fn chart(args: &ChartArgs) -> Result<ExitCode, String> {
    let budget = args.budget;
    let wanted = args.methods.as_deref().map(parse_methods).transpose()?;
    let window = args.window.as_deref().map(Window::parse).transpose()?;
    let ext = args.output.extension().and_then(|e| e.to_str());
    if !ext.is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        return Err(format!(
            "output `{}` must end in .png",
            args.output.display()
        ));
    }
    // Every file the chart writes, checked before anything is rendered against the files named
    // on the command line, and against the scene's files once it is loaded. (The CSV of
    // `--from-csv` may be the one written: redrawing writes back the table it read.)
    let outputs = output_files(&args.output, window.is_some() || args.from_csv.is_some());
    let outputs: Vec<&std::path::Path> = outputs.iter().map(PathBuf::as_path).collect();
    let named: Vec<PathBuf> = [&args.scene, &args.reference]
        .into_iter()
        .flatten()
        .cloned()
        .chain(args.reference.as_deref().map(|r| noise_paths(r).0))
        .collect();
    super::check_not_an_input(&outputs, &named)?;
    if let Some(csv) = &args.from_csv {
        let table = read_csv(csv)?;
        write_outputs(&args.output, &table)?;
        return Ok(ExitCode::SUCCESS);
    }
    let (Some(scene_path), Some(reference_path)) = (&args.scene, &args.reference) else {
        return Err("give a scene and --reference (or --from-csv)".into());
    };
    // The curves compare radiance: an 8-bit image holds tone-mapped sRGB codes, not that.
    let is_float = reference_path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr") || e.eq_ignore_ascii_case("hdr"));
    if !is_float {
        return Err(format!(
            "the reference `{}` is not an EXR or HDR image: the error curves compare linear \
             radiance, which an 8-bit image does not hold (make one with `sppm-lang reference \
             SCENE -o reference.exr`)",
            reference_path.display()
        ));
    }
    let reference = load_image(reference_path, ColorSpace::Linear)?;
    let loaded = sppm_lang::internals::eval::load_file(scene_path, &args.limits.options())
        .map_err(|e| e.with_path(scene_path))?;
    print_diagnostics(&loaded.sources, &loaded.diagnostics);
    let mut scene = match &loaded.scene {
        Some(s) if !loaded.has_errors() => s.clone(),
        _ => return Ok(ExitCode::from(super::check::failure_code(&loaded))),
    };
    super::check_not_an_input(&outputs, &loaded.dependencies)?;
    args.size.apply_to(&mut scene)?;
    let (w, h) = scene.settings.resolution;
    if (w, h) != (reference.width, reference.height) {
        return Err(format!(
            "the scene renders {w}x{h} but the reference is {}x{}",
            reference.width, reference.height
        ));
    }
    let ref_view = ImageView::new(reference.width, reference.height, &reference.pixels)?;
    if let Some(win) = window {
        // Validate the window once, before rendering anything.
        error(ref_view, ref_view, Some(win))?;
    }
    let floors = reference_floors(reference_path, ref_view, window)?;
    // Stopped by the budget or an interruption.
    let options = RenderOptions {
        iterations: Some(crate::cli::MAX_ITERATIONS),
        memory_limit: args.limits.memory_limit,
        ..Default::default()
    };
    // The earlier default initial radius, one pixel footprint at the look-at distance, for the
    // `sppm-lookat` method.
    let look_at_radius = match effective_settings(&scene, &options) {
        Ok(settings) => match settings.initial_radius(&scene.camera) {
            InitialRadius::Fixed(r) | InitialRadius::Orthographic(r) => r,
            InitialRadius::Footprint { per_distance } => {
                per_distance * (scene.camera.look_at - scene.camera.location).length()
            }
        },
        Err(e) => {
            print_diagnostics(&loaded.sources, &[e.at(scene.settings.span)]);
            return Ok(ExitCode::from(EXIT_SCENE_ERROR));
        }
    };
    let chosen: Vec<(Method, Scene)> = methods()
        .into_iter()
        .filter(|m| wanted.as_ref().is_none_or(|w| w.contains(&m.label)))
        .map(|m| {
            let s = m.scene(&scene, look_at_radius);
            (m, s)
        })
        .collect();
    let refused = methods::validate(&chosen, &options);
    if !refused.is_empty() {
        print_diagnostics(&loaded.sources, &refused);
        return Ok(ExitCode::from(EXIT_SCENE_ERROR));
    }
    let stop = Stop::on_interrupt();
    let name = |p: &std::path::Path| {
        p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    };
    let mut table = outputs::Table {
        scene: name(scene_path),
        reference: name(reference_path),
        rows: Vec::new(),
        floors,
        has_window: window.is_some(),
    };
    let failure = run_methods(&chosen, budget, &mut table.rows, |s| {
        measure(s, &options, budget, &stop, ref_view, window)
    });
    finish(&args.output, &table, failure, &loaded.sources)
}

/// Writes the table and its charts, then reports the method that did not finish, if one did
/// not. The rows of the methods that finished before it are written (a failure or an
/// interruption late in a long chart keeps them); with none, nothing is written, so the files
/// of an earlier run stay. An interruption with rows written exits 0, as `render` does.
fn finish(
    output: &std::path::Path,
    table: &outputs::Table,
    failure: Option<(String, Failure)>,
    sources: &SourceMap,
) -> Result<ExitCode, String> {
    let finished: Vec<&str> = table.rows.iter().fold(Vec::new(), |mut seen, r| {
        if !seen.contains(&r.method.as_str()) {
            seen.push(&r.method);
        }
        seen
    });
    let Some((label, failure)) = failure else {
        warn_at_floor(&table.rows, &table.floors);
        write_outputs(output, table)?;
        return Ok(ExitCode::SUCCESS);
    };
    let kept = if finished.is_empty() {
        "no method had finished before it, so nothing was written".to_string()
    } else {
        warn_at_floor(&table.rows, &table.floors);
        write_outputs(output, table).map_err(|e| {
            format!("chart: method `{label}` did not finish, and writing the others failed: {e}")
        })?;
        format!(
            "the rows of the methods that finished ({}) were written to `{}` and its charts",
            finished.join(", "),
            output.with_extension("csv").display()
        )
    };
    match failure {
        Failure::Interrupted => {
            say!("chart: interrupted during method `{label}`; {kept}");
            Ok(if finished.is_empty() {
                ExitCode::from(EXIT_SCENE_ERROR)
            } else {
                ExitCode::SUCCESS
            })
        }
        Failure::Render(e) => {
            let e = sppm_lang::Diagnostic {
                message: format!("the chart's method `{label}` failed: {}", e.message),
                ..e
            };
            print_diagnostics(sources, &[e]);
            say!("chart: {kept}");
            Ok(ExitCode::from(EXIT_SCENE_ERROR))
        }
        Failure::Other(e) => Err(format!("chart: method `{label}` failed: {e}; {kept}")),
    }
}

/// The reference's noise floors (whole image, window) from the noise image beside it.
fn reference_floors(
    reference_path: &std::path::Path,
    ref_view: ImageView<'_>,
    window: Option<Window>,
) -> Result<Floors, String> {
    let (noise_path, _) = noise_paths(reference_path);
    if !noise_path.is_file() {
        say!(
            "warning: chart: no noise estimate `{}` beside the reference, so the chart cannot \
             mark the error floor and a method better than the reference cannot be told from \
             it; make the reference with `sppm-lang reference`",
            noise_path.display()
        );
        return Ok(Floors::default());
    }
    let noise = load_image(&noise_path, ColorSpace::Linear)?;
    let noise_view = ImageView::new(noise.width, noise.height, &noise.pixels)?;
    let whole = floor_in(ref_view, noise_view, None)?;
    let win = window
        .map(|w| floor_in(ref_view, noise_view, Some(w)))
        .transpose()?;
    say!(
        "chart: the reference's noise: RMSE {:.3e}, relative MSE {:.3e}{}",
        whole.rmse,
        whole.rel_mse,
        win.map_or(String::new(), |w| format!(
            "; in the window RMSE {:.3e}, relative MSE {:.3e}",
            w.rmse, w.rel_mse
        ))
    );
    Ok(Floors {
        whole: Some(whole.into()),
        window: win.map(Errors::from),
    })
}

/// Warns of each method whose last error is at the reference's noise floor.
fn warn_at_floor(rows: &[Row], floors: &Floors) {
    for w in at_floor(rows, floors) {
        say!("warning: chart: {w}");
    }
}

/// The methods whose last error is at the reference's noise floor: the chart cannot rank
/// them, however good they are.
fn at_floor(rows: &[Row], floors: &Floors) -> Vec<String> {
    let mut out = Vec::new();
    let mut seen: Vec<&str> = Vec::new();
    for r in rows.iter().rev() {
        if seen.contains(&r.method.as_str()) {
            continue;
        }
        seen.push(&r.method);
        let checks = [
            ("whole image", Some(r.whole), floors.whole),
            ("window", r.window, floors.window),
        ];
        for (what, e, floor) in checks {
            if let (Some(e), Some(f)) = (e, floor)
                && e.rmse < AT_FLOOR * f.rmse
            {
                out.push(format!(
                    "{}'s error on the {what} (RMSE {:.3e}) is at the reference's noise floor \
                     ({:.3e}): the reference cannot rank it; render a longer reference",
                    r.method, e.rmse, f.rmse
                ));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, seconds: f64, rmse: f64) -> Row {
        let e = Errors { rmse, rel_mse: 0.0 };
        Row {
            method: method.into(),
            iterations: 1,
            seconds,
            whole: e,
            window: None,
        }
    }

    #[test]
    fn only_a_last_error_near_the_floor_is_reported() {
        let floors = Floors {
            whole: Some(Errors {
                rmse: 0.01,
                rel_mse: 0.0,
            }),
            window: None,
        };
        let rows = [
            row("a", 1.0, 0.012),
            row("a", 2.0, 0.05),
            row("b", 1.0, 0.05),
            row("b", 2.0, 0.014),
        ];
        let got = at_floor(&rows, &floors);
        assert_eq!(got.len(), 1, "{got:?}");
        assert!(
            got[0].starts_with("b's error on the whole image"),
            "{got:?}"
        );
        assert!(at_floor(&rows, &Floors::default()).is_empty());
    }

    /// Three methods whose second fails: the third is not run, the first one's rows are
    /// written (CSV and charts) and the error names the failed method and the written one.
    /// An interruption of the first method writes nothing, and leaves the files there.
    #[test]
    fn a_later_method_that_fails_leaves_the_earlier_rows_written() {
        let src = "settings { resolution <4, 4> }\nlight { <0, 5, -5> intensity 10 }\n";
        let scene = sppm_lang::internals::eval::load_source("t.scn", src, &Default::default())
            .scene
            .expect("the scene loads");
        let chosen: Vec<(Method, Scene)> = methods()
            .into_iter()
            .filter(|m| ["sppm", "path", "whitted"].contains(&m.label.as_str()))
            .map(|m| (m, scene.clone()))
            .collect();
        let e = Errors {
            rmse: 0.1,
            rel_mse: 0.01,
        };
        let mut calls = 0;
        let mut rows = Vec::new();
        let failure = run_methods(&chosen, 1.0, &mut rows, |_| {
            calls += 1;
            if calls == 2 {
                Err(Failure::Other("the disk is on fire".into()))
            } else {
                Ok(vec![(1, 0.5, e, None), (2, 1.0, e, None)])
            }
        });
        assert_eq!(calls, 2, "the method after the failed one ran");
        let failure = failure.expect("a failure");
        assert_eq!(failure.0, "path");
        let dir = tempfile::tempdir().unwrap();
        let output = dir.path().join("c.png");
        let table = outputs::Table {
            scene: "t.scn".into(),
            reference: "r.exr".into(),
            rows,
            floors: Floors::default(),
            has_window: false,
        };
        let err = finish(&output, &table, Some(failure), &SourceMap::default()).unwrap_err();
        assert!(
            err.contains("method `path` failed: the disk is on fire"),
            "{err}"
        );
        assert!(err.contains("finished (sppm) were written"), "{err}");
        let csv = std::fs::read_to_string(dir.path().join("c.csv")).unwrap();
        assert_eq!(csv.lines().filter(|l| l.starts_with("sppm,")).count(), 2);
        assert!(!csv.contains("path,") && !csv.contains("whitted,"), "{csv}");
        for chart in ["c.png", "c.svg", "c_relmse.png", "c_relmse.svg"] {
            assert!(dir.path().join(chart).is_file(), "{chart} missing");
        }
        let before = std::fs::read(dir.path().join("c.csv")).unwrap();
        let empty = outputs::Table {
            rows: Vec::new(),
            ..table
        };
        let code = finish(
            &output,
            &empty,
            Some(("sppm".into(), Failure::Interrupted)),
            &SourceMap::default(),
        )
        .unwrap();
        assert_eq!(code, ExitCode::from(EXIT_SCENE_ERROR));
        assert_eq!(std::fs::read(dir.path().join("c.csv")).unwrap(), before);
    }
}
