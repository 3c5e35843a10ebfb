//! `sppm-lang render`: load a scene, render it with progress, write the image atomically.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use sppm_lang::render::{Progress, RenderOptions, RenderStats, prepare, render_prepared};
use sppm_lang::scene::{Integrator, Scene};
use sppm_lang::{Cancel, SourceMap};

use super::check::{load_scene, print_render_error, print_render_warning};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, LimitArgs, SizeArgs};

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The scene file (.scn).
    pub scene: PathBuf,
    /// Output image (.png or .exr); default: the scene's name with .png.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// SPPM iterations (overrides the scene's settings).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=super::MAX_ITERATIONS as i64))]
    pub iterations: Option<u32>,
    /// Photons per iteration.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=super::MAX_PHOTONS))]
    pub photons: Option<u64>,
    /// Stop after this many seconds (the finished iterations are written; a render that
    /// finishes no iteration in time writes nothing and fails).
    #[arg(long, value_parser = super::parse_seconds)]
    pub time_limit: Option<f64>,
    /// Worker threads (the image does not depend on it).
    #[arg(long, value_parser = super::parse_threads)]
    pub threads: Option<usize>,
    #[arg(long)]
    pub seed: Option<u64>,
    /// Write the current image every K iterations.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..))]
    pub snapshot_every: Option<u32>,
    /// Rendering method, overriding the scene's `settings { integrator ... }`.
    #[arg(long, value_parser = parse_integrator)]
    pub integrator: Option<Integrator>,
    #[command(flatten)]
    pub size: SizeArgs,
    #[command(flatten)]
    pub limits: LimitArgs,
}

pub fn run(args: RenderArgs) -> ExitCode {
    // First: Ctrl-C stops the load and the prepare stage as it stops the passes.
    let cancel = super::cancel_on_ctrl_c();
    // `--threads` holds for the whole command: reading a large mesh and building its BVH run
    // on rayon's global pool, the passes on the render's own. (If the global pool is already
    // running, as when a test calls this twice, the set-up keeps it.)
    if let Some(n) = args.threads {
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global();
    }
    // The output is checked before the load (which may read a large mesh) and again against
    // the files the load read.
    let output = match super::output_path(args.output.as_deref(), &args.scene) {
        Ok(o) => o,
        Err(e) => {
            say!("error: {e}");
            return ExitCode::from(EXIT_USAGE);
        }
    };
    let eval_options = sppm_lang::EvalOptions {
        cancel: cancel.clone(),
        ..args.limits.options()
    };
    match load_scene(&args.scene, &eval_options) {
        Ok(loaded) => {
            if let Err(e) = super::check_not_an_input(&[&output], &loaded.dependencies) {
                say!("error: {e}");
                return ExitCode::from(EXIT_USAGE);
            }
            let code = render_scene(&loaded.scene, &args, &loaded.sources, &output, &cancel);
            // The image is written and the process ends here: freeing a large scene (a mesh's
            // millions of vertices) is left to the exit.
            std::mem::forget(loaded);
            code
        }
        Err(code) => code,
    }
}

/// Renders an already loaded scene as `args` asks into `output`; `sources` turn render errors
/// that carry a span into diagnostics. `cancel` stops the prepare stage and the passes.
fn render_scene(
    scene: &Scene,
    args: &RenderArgs,
    sources: &SourceMap,
    output: &Path,
    cancel: &Cancel,
) -> ExitCode {
    let mut scene = std::borrow::Cow::Borrowed(scene);
    if let Some(integrator) = args.integrator {
        scene.to_mut().settings.integrator = integrator;
    }
    if args.size.is_set()
        && let Err(e) = args.size.apply_to(scene.to_mut())
    {
        say!("error: {e}");
        return ExitCode::from(EXIT_USAGE);
    }
    let scene = scene.as_ref();
    let options = RenderOptions {
        iterations: args.iterations,
        photons: args.photons,
        seed: args.seed,
        time_limit: args.time_limit,
        threads: args.threads,
        memory_limit: args.limits.memory_limit,
        cancel: cancel.clone(),
        ..RenderOptions::default()
    };
    let exposure = scene.settings.exposure;
    let total = options.iterations.unwrap_or(scene.settings.iterations);
    let bar = std::io::stderr().is_terminal().then(|| {
        let b = ProgressBar::new(total as u64);
        b.set_style(
            ProgressStyle::with_template(
                "{bar:30} {pos}/{len} iterations  {elapsed_precise} (ETA {eta})  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    });
    let mut snapshot_error = None;
    let mut on_progress = |p: &Progress| {
        if let Some(b) = &bar {
            b.set_position(p.iteration as u64);
            let secs = p.elapsed.as_secs_f64().max(1e-9);
            if p.stats.photons > 0 {
                b.set_message(format!(
                    "{:.2} M photons/s",
                    p.stats.photons as f64 / secs / 1e6
                ));
            }
        }
        if let Some(k) = args.snapshot_every
            && p.iteration.is_multiple_of(k)
            && p.iteration < p.iterations
            && let Err(e) = p.image().write(output, exposure)
        {
            snapshot_error = Some(e);
        }
    };
    let on_warning = |w: &sppm_lang::render::RenderError| {
        if let Some(b) = &bar {
            b.suspend(|| print_render_warning(sources, w));
        } else {
            print_render_warning(sources, w);
        }
    };
    let result = prepare(scene, &options).and_then(|(settings, prepared)| {
        for w in prepared.warnings() {
            on_warning(&w);
        }
        let out = render_prepared(
            &prepared,
            &settings,
            &options,
            cancel.flag(),
            &mut on_progress,
        )?;
        Ok((out, prepared))
    });
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    if let Some(e) = snapshot_error {
        say!("warning: snapshot: {e}");
    }
    // Interrupted before any iteration finished (while preparing, or in the first): nothing to
    // show, and nothing wrong with the scene. The image at the output path is kept.
    let interrupted = || {
        say!(
            "interrupted before the first iteration finished; `{}` is left as it was",
            output.display()
        );
        ExitCode::from(EXIT_SCENE_ERROR)
    };
    let (out, prepared) = match result {
        Ok(o) => o,
        Err(e) if e.interrupted => return interrupted(),
        Err(e) => {
            print_render_error(sources, &e);
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
    };
    if out.iterations_done == 0 && out.cancelled {
        return interrupted();
    }
    if out.iterations_done == 0 {
        // Nothing to show: keep whatever image is at the output path.
        let message = format!(
            "no iteration finished within the time limit; `{}` is left as it was",
            output.display()
        );
        let mut e = sppm_lang::render::RenderError::new(message);
        e.help = Some(
            "give more time (`time_limit` in the settings or `--time-limit`), or lower the \
             resolution or photons so that one iteration fits"
                .into(),
        );
        if args.time_limit.is_none() {
            // The limit came from the scene's settings: point at them.
            e = e.at(scene.settings.span);
        }
        print_render_error(sources, &e);
        return ExitCode::from(EXIT_SCENE_ERROR);
    }
    if let Err(e) = out.image.write(output, exposure) {
        say!("error: {e}");
        return ExitCode::from(EXIT_SCENE_ERROR);
    }
    // Written: the process ends after this command, and the exit frees the prepared scene's
    // buffers (BVH, mesh) at once; freeing them one by one first is serial work for nothing.
    std::mem::forget(prepared);
    let secs = out.elapsed.as_secs_f64().max(1e-9);
    say!(
        "{} {}: {} iterations{} in {:.2}s{}",
        if out.cancelled {
            "interrupted,"
        } else {
            "wrote"
        },
        output.display(),
        out.iterations_done,
        if out.cancelled { " (cancelled)" } else { "" },
        secs,
        method_statistics(scene.settings.integrator, &out.stats, secs),
    );
    ExitCode::SUCCESS
}

/// The figures that mean something for `method`: photons and their rate for the photon
/// methods, deposits (photons kept at visible points) for SPPM and PPM; nothing more for the
/// methods without photons.
fn method_statistics(method: Integrator, stats: &RenderStats, secs: f64) -> String {
    let photons = || {
        format!(
            ", {} photons ({:.2} M/s)",
            stats.photons,
            stats.photons as f64 / secs.max(1e-9) / 1e6
        )
    };
    match method {
        Integrator::Sppm => format!(
            "{}, {} deposits, camera/photon casts {:.2}",
            photons(),
            stats.deposits,
            stats.camera_ratio
        ),
        Integrator::Ppm => format!("{}, {} deposits", photons(), stats.deposits),
        Integrator::PhotonMap => photons(),
        Integrator::Path | Integrator::Whitted => String::new(),
    }
}

fn parse_integrator(name: &str) -> Result<Integrator, String> {
    Integrator::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Integrator::ALL.iter().map(|i| i.name()).collect();
        format!(
            "unknown integrator `{name}`; use one of {}",
            names.join(", ")
        )
    })
}
