//! `sppm-lang chart`: render a scene with every integrator and chosen SPPM variations under a
//! growing time budget, measure the error against a reference (whole image and an optional
//! window), and draw error against time (log-log, PNG + SVG) with a CSV table.
//!
//! Each method renders once with the full budget as its time limit; the image is measured at
//! geometric checkpoints (budget / 32, / 16, ..., budget) from the progress callback. The time
//! a checkpoint spends computing errors is subtracted from the render time it reports.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use clap::Args;
use sppm_lang::chart::{ChartSpec, Series, draw};
use sppm_lang::compare::{ErrorStats, ImageView, Window, error};
use sppm_lang::film::Image;
use sppm_lang::render::{InitialRadius, RenderOptions, effective_settings, render};
use sppm_lang::scene::{ColorSpace, Integrator, Scene, load_image};

use super::check::print_diagnostics;
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, LimitArgs};

#[derive(Debug, Args)]
pub struct ChartArgs {
    /// The scene file (.scn).
    #[arg(required_unless_present = "from_csv")]
    pub scene: Option<PathBuf>,
    /// Reference image (linear EXR) of the same resolution.
    #[arg(long, required_unless_present = "from_csv")]
    pub reference: Option<PathBuf>,
    /// Redraw the charts from a CSV this command wrote earlier, without rendering.
    #[arg(long, value_name = "CSV", conflicts_with_all = ["scene", "reference", "window", "methods"])]
    pub from_csv: Option<PathBuf>,
    /// Largest time budget per method, in seconds (`60` or `60s`).
    #[arg(long, default_value = "60")]
    pub budget: String,
    /// Pixel window x0,y0,x1,y1 (columns then rows, half-open) also measured on its own.
    #[arg(long)]
    pub window: Option<String>,
    /// Output chart (.png); an .svg and a .csv with the same stem are written beside it.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Only these methods (comma-separated labels, see the CSV); default: all.
    #[arg(long)]
    pub methods: Option<String>,
    #[command(flatten)]
    pub limits: LimitArgs,
}

/// A method on the chart: an integrator and its parameter changes.
struct Method {
    label: String,
    integrator: Integrator,
    alpha: Option<f64>,
    radius_factor: f64,
    photon_factor: f64,
    /// The earlier default radius: one pixel footprint at the look-at distance for every pixel.
    look_at_radius: bool,
}

fn methods() -> Vec<Method> {
    let m = |label: &str, integrator, alpha, radius_factor, photon_factor| Method {
        label: label.into(),
        integrator,
        alpha,
        radius_factor,
        photon_factor,
        look_at_radius: false,
    };
    vec![
        m("sppm", Integrator::Sppm, None, 1.0, 1.0),
        Method {
            look_at_radius: true,
            ..m("sppm-lookat", Integrator::Sppm, None, 1.0, 1.0)
        },
        m("sppm-alpha0.5", Integrator::Sppm, Some(0.5), 1.0, 1.0),
        m("sppm-alpha0.7", Integrator::Sppm, Some(0.7), 1.0, 1.0),
        m("sppm-alpha0.9", Integrator::Sppm, Some(0.9), 1.0, 1.0),
        m("sppm-radius0.5x", Integrator::Sppm, None, 0.5, 1.0),
        m("sppm-radius2x", Integrator::Sppm, None, 2.0, 1.0),
        m("sppm-radius4x", Integrator::Sppm, None, 4.0, 1.0),
        m("sppm-photons0.25x", Integrator::Sppm, None, 1.0, 0.25),
        m("sppm-photons4x", Integrator::Sppm, None, 1.0, 4.0),
        m("ppm", Integrator::Ppm, None, 1.0, 1.0),
        m("photon_map", Integrator::PhotonMap, None, 1.0, 1.0),
        m("path", Integrator::Path, None, 1.0, 1.0),
        m("whitted", Integrator::Whitted, None, 1.0, 1.0),
    ]
}

/// One measurement.
struct Row {
    method: String,
    iterations: u32,
    seconds: f64,
    whole: Errors,
    window: Option<Errors>,
}

/// The two errors the chart draws.
#[derive(Clone, Copy)]
struct Errors {
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

/// Reads the rows of a CSV written by [`write_outputs`].
fn read_csv(path: &Path) -> Result<(Vec<Row>, bool), String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let mut rows = Vec::new();
    let mut has_window = false;
    for (n, line) in text.lines().enumerate().skip(1) {
        let bad = || format!("{}:{}: not a chart row: `{line}`", path.display(), n + 1);
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 7 {
            return Err(bad());
        }
        let num = |s: &str| s.parse::<f64>().map_err(|_| bad());
        let window = if f[5].is_empty() {
            None
        } else {
            has_window = true;
            Some(Errors {
                rmse: num(f[5])?,
                rel_mse: num(f[6])?,
            })
        };
        rows.push(Row {
            method: f[0].to_string(),
            iterations: f[1].parse().map_err(|_| bad())?,
            seconds: num(f[2])?,
            whole: Errors {
                rmse: num(f[3])?,
                rel_mse: num(f[4])?,
            },
            window,
        });
    }
    if rows.is_empty() {
        return Err(format!("`{}` has no rows", path.display()));
    }
    Ok((rows, has_window))
}

fn parse_budget(text: &str) -> Result<f64, String> {
    let t = text.trim().trim_end_matches('s');
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "--budget `{text}`: expected a positive number of seconds"
        )),
    }
}

fn to_f32(img: &Image) -> Vec<[f32; 3]> {
    img.pixels.iter().map(|p| p.map(|v| v as f32)).collect()
}

pub fn run(args: &ChartArgs) -> ExitCode {
    match chart(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_USAGE)
        }
    }
}

fn chart(args: &ChartArgs) -> Result<ExitCode, String> {
    let budget = parse_budget(&args.budget)?;
    let window = args.window.as_deref().map(Window::parse).transpose()?;
    let ext = args.output.extension().and_then(|e| e.to_str());
    if !ext.is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        return Err(format!(
            "output `{}` must end in .png",
            args.output.display()
        ));
    }
    if let Some(csv) = &args.from_csv {
        let (rows, has_window) = read_csv(csv)?;
        write_outputs(args, &rows, has_window)?;
        return Ok(ExitCode::SUCCESS);
    }
    let (Some(scene_path), Some(reference_path)) = (&args.scene, &args.reference) else {
        return Err("give a scene and --reference (or --from-csv)".into());
    };
    let reference = load_image(reference_path, ColorSpace::Linear)?;
    let loaded = sppm_lang::load_file(scene_path, &args.limits.options())
        .map_err(|e| format!("cannot read `{}`: {e}", scene_path.display()))?;
    print_diagnostics(&loaded);
    let scene = match &loaded.scene {
        Some(s) if !loaded.has_errors() => s.clone(),
        _ => return Ok(ExitCode::from(EXIT_SCENE_ERROR)),
    };
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
    // The earlier default initial radius, one pixel footprint at the look-at distance, for the
    // `sppm-lookat` method.
    let look_at_radius = {
        let settings =
            effective_settings(&scene, &RenderOptions::default()).map_err(|e| e.message)?;
        match settings.initial_radius(&scene.camera) {
            InitialRadius::Fixed(r) => r,
            InitialRadius::Footprint { per_distance } => {
                per_distance * (scene.camera.look_at - scene.camera.location).length()
            }
        }
    };
    let wanted: Option<Vec<String>> = args
        .methods
        .as_deref()
        .map(|m| m.split(',').map(|s| s.trim().to_string()).collect());
    let mut rows = Vec::new();
    for m in methods() {
        if wanted.as_ref().is_some_and(|w| !w.contains(&m.label)) {
            continue;
        }
        eprintln!("chart: {} ({budget} s)", m.label);
        let mut s: Scene = scene.clone();
        s.settings.integrator = m.integrator;
        if let Some(a) = m.alpha {
            s.settings.alpha = a;
        }
        if m.look_at_radius {
            s.settings.radius = Some(look_at_radius);
        }
        s.settings.radius_scale = m.radius_factor;
        s.settings.photons = ((s.settings.photons as f64 * m.photon_factor) as u64).max(1);
        let opts = RenderOptions {
            iterations: Some(u32::MAX),
            time_limit: Some(budget),
            ..Default::default()
        };
        let checkpoints: Vec<f64> = (0..6).rev().map(|k| budget / f64::from(1 << k)).collect();
        let mut next = 0usize;
        let mut overhead = 0.0f64;
        let mut measured = Vec::new();
        let mut failure = None;
        let mut on_progress = |p: &sppm_lang::render::Progress| {
            let t = p.elapsed.as_secs_f64() - overhead;
            if next < checkpoints.len() && t >= checkpoints[next] {
                let t0 = Instant::now();
                while next < checkpoints.len() && t >= checkpoints[next] {
                    next += 1;
                }
                let img = p.image();
                let pix = to_f32(&img);
                let measure = ImageView::new(img.width, img.height, &pix).and_then(|v| {
                    Ok((
                        error(v, ref_view, None)?,
                        window
                            .map(|win| error(v, ref_view, Some(win)))
                            .transpose()?,
                    ))
                });
                match measure {
                    Ok((whole, win)) => {
                        measured.push((p.iteration, t, Errors::from(whole), win.map(Errors::from)))
                    }
                    Err(e) => failure = Some(e),
                }
                overhead += t0.elapsed().as_secs_f64();
            }
        };
        let out = render(&s, &opts, &AtomicBool::new(false), &mut on_progress)
            .map_err(|e| format!("{}: {}", m.label, e.message))?;
        if let Some(e) = failure {
            return Err(e);
        }
        // The last iteration is always measured (the render may stop between checkpoints).
        let last_t = out.elapsed.as_secs_f64() - overhead;
        if measured.last().is_none_or(|r| r.0 != out.iterations_done) && out.iterations_done > 0 {
            let pix = to_f32(&out.image);
            let v = ImageView::new(out.image.width, out.image.height, &pix)?;
            let whole = error(v, ref_view, None)?;
            let win = window
                .map(|win| error(v, ref_view, Some(win)))
                .transpose()?;
            measured.push((
                out.iterations_done,
                last_t,
                Errors::from(whole),
                win.map(Errors::from),
            ));
        }
        for (iterations, seconds, whole, window) in measured {
            eprintln!(
                "  {iterations:>6} it {seconds:>8.2} s  rmse {:.5}  relmse {:.5}{}",
                whole.rmse,
                whole.rel_mse,
                window.map_or(String::new(), |w| format!(
                    "  window rmse {:.5} relmse {:.5}",
                    w.rmse, w.rel_mse
                ))
            );
            rows.push(Row {
                method: m.label.clone(),
                iterations,
                seconds,
                whole,
                window,
            });
        }
    }
    write_outputs(args, &rows, window.is_some())?;
    Ok(ExitCode::SUCCESS)
}

fn sibling(path: &Path, suffix: &str, ext: &str) -> PathBuf {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("chart");
    path.with_file_name(format!("{stem}{suffix}.{ext}"))
}

fn write_outputs(args: &ChartArgs, rows: &[Row], has_window: bool) -> Result<(), String> {
    let mut csv =
        String::from("method,iterations,seconds,rmse,rel_mse,window_rmse,window_rel_mse\n");
    for r in rows {
        let (wr, wm) = r.window.map_or((String::new(), String::new()), |w| {
            (format!("{:.6e}", w.rmse), format!("{:.6e}", w.rel_mse))
        });
        let _ = writeln!(
            csv,
            "{},{},{:.3},{:.6e},{:.6e},{wr},{wm}",
            r.method, r.iterations, r.seconds, r.whole.rmse, r.whole.rel_mse
        );
    }
    let csv_path = args.output.with_extension("csv");
    write_atomic(&csv_path, &csv)?;
    type Pick = fn(&Row) -> Option<f64>;
    let mut charts: Vec<(&str, &str, &str, Pick)> = vec![
        ("", "RMSE (whole image)", "RMSE", |r| Some(r.whole.rmse)),
        (
            "_relmse",
            "relative MSE (whole image)",
            "relative MSE",
            |r| Some(r.whole.rel_mse),
        ),
    ];
    if has_window {
        charts.push(("_window", "RMSE (window)", "RMSE", |r| {
            r.window.map(|w| w.rmse)
        }));
        charts.push((
            "_window_relmse",
            "relative MSE (window)",
            "relative MSE",
            |r| r.window.map(|w| w.rel_mse),
        ));
    }
    let mut labels: Vec<&str> = Vec::new();
    for r in rows {
        if !labels.contains(&r.method.as_str()) {
            labels.push(&r.method);
        }
    }
    for (suffix, title, y_label, pick) in charts {
        let series: Vec<Series> = labels
            .iter()
            .map(|l| Series {
                label: (*l).to_string(),
                points: rows
                    .iter()
                    .filter(|r| r.method == *l)
                    .filter_map(|r| pick(r).map(|v| (r.seconds, v)))
                    .filter(|(t, v)| *t > 0.0 && *v > 0.0)
                    .collect(),
            })
            .filter(|s| !s.points.is_empty())
            .collect();
        let spec = ChartSpec {
            title: format!("{title} against render time"),
            x_label: "seconds".into(),
            y_label: y_label.into(),
            log_x: true,
            log_y: true,
        };
        for ext in ["png", "svg"] {
            draw(&spec, &series, &sibling(&args.output, suffix, ext))?;
        }
    }
    Ok(())
}

fn write_atomic(path: &Path, text: &str) -> Result<(), String> {
    sppm_lang::atomic_file::write_atomic(path, |_, f| {
        f.write_all(text.as_bytes())
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))
    })
}
