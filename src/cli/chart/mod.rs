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

mod outputs;

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use clap::Args;
use sppm_lang::chart::Dash;
use sppm_lang::compare::{ErrorStats, ImageView, Window, error};
use sppm_lang::film::Image;
use sppm_lang::render::{InitialRadius, RenderOptions, effective_settings, render};
use sppm_lang::scene::{ColorSpace, DEFAULT_PHOTONS, Integrator, Scene, load_image};

use super::check::print_diagnostics;
use super::reference::{floor_in, noise_paths, to_f32};
use super::{EXIT_USAGE, LimitArgs, SizeArgs};
use outputs::{Floors, output_files, read_csv, write_outputs};

/// A method whose error ends within this factor of the reference's noise is "at the floor":
/// its own error is at most about the reference's (sqrt(1.5^2 - 1) = 1.1 times it).
const AT_FLOOR: f64 = 1.5;

#[derive(Debug, Args)]
#[command(
    override_usage = "sppm-lang chart <SCENE> --reference <REF.exr> -o <CHART.png> [OPTIONS]\n       \
                  sppm-lang chart --from-csv <CSV> -o <CHART.png>"
)]
pub struct ChartArgs {
    /// The scene file (.scn).
    #[arg(required_unless_present = "from_csv")]
    pub scene: Option<PathBuf>,
    /// Reference image (linear EXR) of the same resolution, e.g. made by `sppm-lang reference`
    /// (whose noise estimate beside it marks the error floor). Required unless --from-csv.
    #[arg(
        long,
        value_name = "REF.exr",
        required_unless_present = "from_csv",
        help_heading = "Required"
    )]
    pub reference: Option<PathBuf>,
    /// Redraw the charts from a CSV this command wrote earlier, without rendering.
    #[arg(long, value_name = "CSV", conflicts_with_all = ["scene", "reference", "window", "methods"])]
    pub from_csv: Option<PathBuf>,
    /// Largest time budget per method, in seconds (`60` or `60s`; at most a year).
    #[arg(long, default_value = "60", value_parser = parse_budget)]
    pub budget: f64,
    /// Pixel window x0,y0,x1,y1 (columns then rows, half-open) also measured on its own.
    #[arg(long)]
    pub window: Option<String>,
    /// Output chart (.png); an .svg and a .csv with the same stem are written beside it.
    #[arg(short, long, value_name = "CHART.png", help_heading = "Required")]
    pub output: PathBuf,
    /// Only these methods (comma-separated labels, see the CSV); default: all.
    #[arg(long)]
    pub methods: Option<String>,
    #[command(flatten)]
    pub size: SizeArgs,
    #[command(flatten)]
    pub limits: LimitArgs,
}

/// A method on the chart: an integrator and its parameter changes, and how it is drawn.
struct Method {
    label: String,
    integrator: Integrator,
    alpha: Option<f64>,
    radius_factor: f64,
    photon_factor: f64,
    /// Index in the chart's palette.
    colour: usize,
    dash: Dash,
    /// The earlier default radius: one pixel footprint at the look-at distance for every pixel.
    look_at_radius: bool,
}

/// The methods: the integrators as they are (solid lines, one colour each), then SPPM's
/// variations (one line style per parameter; the colour says lower, middle or higher).
fn methods() -> Vec<Method> {
    let m = |label: &str, integrator, alpha, radius_factor, photon_factor, colour, dash| Method {
        label: label.into(),
        integrator,
        alpha,
        radius_factor,
        photon_factor,
        colour,
        dash,
        look_at_radius: false,
    };
    use Dash::{Dashed, Dotted, Solid};
    use Integrator::{Path, PhotonMap, Ppm, Sppm, Whitted};
    // Palette: 0 blue, 1 orange, 2 red, 3 green, 4 teal, 5 purple, 6 brown, 7 gold, 8 pink.
    vec![
        m("sppm", Sppm, None, 1.0, 1.0, 0, Solid),
        Method {
            look_at_radius: true,
            ..m("sppm-lookat", Sppm, None, 1.0, 1.0, 0, Dashed)
        },
        m("ppm", Ppm, None, 1.0, 1.0, 1, Solid),
        m("photon_map", PhotonMap, None, 1.0, 1.0, 2, Solid),
        m("path", Path, None, 1.0, 1.0, 3, Solid),
        m("whitted", Whitted, None, 1.0, 1.0, 6, Solid),
        m("sppm-alpha0.5", Sppm, Some(0.5), 1.0, 1.0, 4, Dashed),
        m("sppm-alpha0.7", Sppm, Some(0.7), 1.0, 1.0, 5, Dashed),
        m("sppm-alpha0.9", Sppm, Some(0.9), 1.0, 1.0, 8, Dashed),
        m("sppm-radius0.5x", Sppm, None, 0.5, 1.0, 4, Dotted),
        m("sppm-radius2x", Sppm, None, 2.0, 1.0, 5, Dotted),
        m("sppm-radius4x", Sppm, None, 4.0, 1.0, 8, Dotted),
        m("sppm-photons0.25x", Sppm, None, 1.0, 0.25, 7, Dashed),
        m("sppm-photons4x", Sppm, None, 1.0, 4.0, 7, Dotted),
    ]
}

/// Where the method labelled `label` comes in [`methods`] (others after them).
fn rank_of(label: &str) -> usize {
    methods()
        .iter()
        .position(|m| m.label == label)
        .unwrap_or(usize::MAX)
}

/// The colour and line style of the method labelled `label` (`None`: not one of ours).
fn style_of(label: &str) -> Option<(usize, Dash)> {
    methods()
        .into_iter()
        .find(|m| m.label == label)
        .map(|m| (m.colour, m.dash))
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

/// The methods `--methods` names (comma-separated labels); an unknown label is an error
/// naming the known ones (it would otherwise be skipped, and the chart end up empty).
fn parse_methods(text: &str) -> Result<Vec<String>, String> {
    let known: Vec<String> = methods().into_iter().map(|m| m.label).collect();
    let wanted: Vec<String> = text.split(',').map(|s| s.trim().to_string()).collect();
    for w in &wanted {
        if !known.contains(w) {
            return Err(format!(
                "--methods: unknown method `{w}`; the methods are {}",
                known.join(", ")
            ));
        }
    }
    Ok(wanted)
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
    let loaded = sppm_lang::load_file(scene_path, &args.limits.options())
        .map_err(|e| e.with_path(scene_path))?;
    print_diagnostics(&loaded);
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
    let mut rows = Vec::new();
    for m in methods() {
        if wanted.as_ref().is_some_and(|w| !w.contains(&m.label)) {
            continue;
        }
        say!("chart: {} ({budget} s)", m.label);
        let mut s: Scene = scene.clone();
        s.settings.integrator = m.integrator;
        if let Some(a) = m.alpha {
            s.settings.alpha = a;
        }
        if m.look_at_radius {
            s.settings.radius = Some(look_at_radius);
        }
        s.settings.radius_scale = m.radius_factor;
        // The photon variants scale the scene's count, or the fixed default where the scene
        // leaves the count to SPPM.
        if m.photon_factor != 1.0 {
            let n = s.settings.photons.unwrap_or(DEFAULT_PHOTONS) as f64 * m.photon_factor;
            s.settings.photons = Some((n as u64).max(1));
        }
        let measured = measure(&s, budget, ref_view, window)?;
        if measured.is_empty() {
            say!("warning: chart: {} finished no iteration", m.label);
        }
        for (iterations, seconds, whole, window) in measured {
            say!(
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
    warn_at_floor(&rows, &floors);
    let name = |p: &std::path::Path| {
        p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    };
    let table = outputs::Table {
        scene: name(scene_path),
        reference: name(reference_path),
        rows,
        floors,
        has_window: window.is_some(),
    };
    write_outputs(&args.output, &table)?;
    Ok(ExitCode::SUCCESS)
}

/// One measurement: iterations, seconds of rendering, errors on the whole image and window.
type Measured = (u32, f64, Errors, Option<Errors>);

/// Renders `scene` until the first iteration that ends past `budget` seconds, measuring the
/// error at the checkpoints and at the last iteration.
fn measure(
    scene: &Scene,
    budget: f64,
    ref_view: ImageView<'_>,
    window: Option<Window>,
) -> Result<Vec<Measured>, String> {
    // Stopped by `stop` once past the budget.
    let opts = RenderOptions {
        iterations: Some(crate::cli::MAX_ITERATIONS),
        ..Default::default()
    };
    let checkpoints: Vec<f64> = (0..6).rev().map(|k| budget / f64::from(1 << k)).collect();
    let errors = |img: &Image| -> Result<(Errors, Option<Errors>), String> {
        let pix = to_f32(img);
        let v = ImageView::new(img.width, img.height, &pix)?;
        let whole = error(v, ref_view, None)?;
        let win = window.map(|w| error(v, ref_view, Some(w))).transpose()?;
        Ok((whole.into(), win.map(Errors::from)))
    };
    let stop = AtomicBool::new(false);
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
            match errors(&p.image()) {
                Ok((whole, win)) => measured.push((p.iteration, t, whole, win)),
                Err(e) => failure = Some(e),
            }
            overhead += t0.elapsed().as_secs_f64();
        }
        if t >= budget {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let out = render(scene, &opts, &stop, &mut on_progress).map_err(|e| e.message)?;
    if let Some(e) = failure {
        return Err(e);
    }
    // The last iteration is always measured (the render may stop between checkpoints).
    if measured.last().is_none_or(|r| r.0 != out.iterations_done) && out.iterations_done > 0 {
        let (whole, win) = errors(&out.image)?;
        let t = out.elapsed.as_secs_f64() - overhead;
        measured.push((out.iterations_done, t, whole, win));
    }
    Ok(measured)
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

    #[test]
    fn every_method_has_its_own_colour_and_style() {
        let all = methods();
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert!(
                    (a.colour, a.dash) != (b.colour, b.dash),
                    "{} and {} look the same",
                    a.label,
                    b.label
                );
            }
        }
    }
}
