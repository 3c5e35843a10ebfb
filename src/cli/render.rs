//! `sppm-lang render`: load a scene, render it with progress, write the image atomically.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::ArgMatches;
use indicatif::{ProgressBar, ProgressStyle};
use sppm_lang::internals::chains::{ChainInfo, write_chain};
use sppm_lang::internals::eval::RangeOverride;
use sppm_lang::internals::render::{
    Progress, RenderOptions, RenderStats, method_choice, prepare, render_prepared,
};
use sppm_lang::internals::sampling::chain_seed;
use sppm_lang::internals::scene::{Integrator, Scene};
use sppm_lang::{Cancel, SourceMap};

use super::check::print_diagnostics;
use super::frames::{self, FramePattern};
use super::identity::SceneId;
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, LimitArgs, SizeArgs, option};

#[derive(Debug)]
pub struct RenderArgs {
    pub scene: PathBuf,
    pub output: Option<PathBuf>,
    pub iterations: Option<u32>,
    pub photons: Option<u64>,
    pub time_limit: Option<f64>,
    pub threads: Option<usize>,
    pub seed: Option<u64>,
    pub snapshot_every: Option<u32>,
    pub integrator: Option<Integrator>,
    pub frames: Option<(u32, u32)>,
    pub frame: Option<u32>,
    pub clock: Option<(f64, f64)>,
    pub chain: Option<(u32, u32)>,
    pub size: SizeArgs,
    pub limits: LimitArgs,
}

impl RenderArgs {
    /// `render`'s flags on `cmd`.
    pub fn command(cmd: clap::Command) -> clap::Command {
        cmd.arg(super::scene_arg())
            .arg(
                super::output_arg("OUTPUT")
                    .help("Output image (.png or .exr); default: the scene's name with .png"),
            )
            .arg(
                option("iterations", "iterations", "ITERATIONS")
                    .value_parser(clap::value_parser!(u32).range(1..=super::MAX_ITERATIONS as i64))
                    .help("SPPM iterations (overrides the scene's settings)"),
            )
            .arg(
                option("photons", "photons", "PHOTONS")
                    .value_parser(clap::value_parser!(u64).range(1..=super::MAX_PHOTONS))
                    .help("Photons per iteration"),
            )
            .arg(
                option("time_limit", "time-limit", "TIME_LIMIT")
                    .value_parser(super::parse_seconds)
                    .help(
                        "Stop after this many seconds (the finished iterations are written; a \
                         render that finishes no iteration in time writes nothing and fails)",
                    ),
            )
            .arg(super::threads_arg().help("Worker threads (the image does not depend on it)"))
            .arg(option("seed", "seed", "SEED").value_parser(clap::value_parser!(u64)))
            .arg(
                option("snapshot_every", "snapshot-every", "K")
                    .value_parser(clap::value_parser!(u32).range(1..))
                    .help("Write the current image every K iterations"),
            )
            .arg(
                option("integrator", "integrator", "INTEGRATOR")
                    .value_parser(parse_integrator)
                    .help("Rendering method, overriding the scene's `settings { integrator ... }`"),
            )
            .arg(
                option("frames", "frames", "A..B")
                    .value_parser(frames::parse_frames)
                    .help(
                        "Render frames A to B of an animation (both included), over the scene's \
                         `settings { frames ... }`; the output names a file per frame (`-o \
                         out_%04d.png`)",
                    ),
            )
            .arg(
                option("frame", "frame", "K")
                    .value_parser(frames::parse_frame)
                    .help(
                        "Render frame K of the animation alone (the same image as frame K of the \
                         whole range)",
                    ),
            )
            .arg(
                option("clock", "clock", "A..B")
                    .value_parser(frames::parse_clock)
                    .allow_hyphen_values(true)
                    .help(
                        "The clock at the first and the last frame (default: the scene's \
                         `clock_range`, else 0..1)",
                    ),
            )
            .arg(
                option("chain", "chain", "K/N")
                    .value_parser(parse_chain)
                    .help(
                        "Render chain K of N of a still: its own random streams under the seed, \
                         written as a linear EXR whose header `sppm-lang merge` reads (default \
                         output: `<scene>.chainK.exr`)",
                    ),
            )
            .args(SizeArgs::args())
            .args(LimitArgs::args())
    }

    pub fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            scene: super::required(m, "scene")?,
            output: m.remove_one("output"),
            iterations: m.remove_one("iterations"),
            photons: m.remove_one("photons"),
            time_limit: m.remove_one("time_limit"),
            threads: m.remove_one("threads"),
            seed: m.remove_one("seed"),
            snapshot_every: m.remove_one("snapshot_every"),
            integrator: m.remove_one("integrator"),
            frames: m.remove_one("frames"),
            frame: m.remove_one("frame"),
            clock: m.remove_one("clock"),
            chain: m.remove_one("chain"),
            size: SizeArgs::from_matches(m),
            limits: LimitArgs::from_matches(m)?,
        })
    }
}

/// `K/N` with 1 <= K <= N.
fn parse_chain(text: &str) -> Result<(u32, u32), String> {
    let parsed = text
        .split_once('/')
        .and_then(|(k, n)| Some((k.trim().parse::<u32>().ok()?, n.trim().parse::<u32>().ok()?)));
    match parsed {
        Some((k, n)) if 1 <= k && k <= n => Ok((k, n)),
        _ => Err(format!(
            "`{text}` is not a chain: write K/N with 1 <= K <= N, e.g. 2/8"
        )),
    }
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
    let usage = |e: String| {
        say!("error: {e}");
        ExitCode::from(EXIT_USAGE)
    };
    // The output is checked before the load (which may read a large mesh) and again against
    // the files the load read; a name with a frame number is checked as frame 0's.
    let pattern = match args.output.as_deref().map(FramePattern::parse) {
        Some(Err(e)) => return usage(e),
        Some(Ok(p)) => p,
        None => None,
    };
    let first_output = pattern.as_ref().map(|p| p.path(0));
    let chain_output = match (args.chain, &args.output) {
        (Some((k, _)), None) => {
            let stem = args.scene.file_stem().unwrap_or_default().to_string_lossy();
            Some(args.scene.with_file_name(format!("{stem}.chain{k}.exr")))
        }
        (Some(_), Some(o)) if !super::is_exr(o) => {
            return usage(format!(
                "a chain is written as EXR (its header carries what merging needs): name \
                 `{}` with .exr",
                o.display()
            ));
        }
        _ => None,
    };
    let first_output = first_output.or(chain_output);
    let output = match super::output_path(
        first_output.as_deref().or(args.output.as_deref()),
        &args.scene,
    ) {
        Ok(o) => o,
        Err(e) => return usage(e),
    };
    let eval_options = sppm_lang::EvalOptions {
        cancel: cancel.clone(),
        ..args.limits.options()
    };
    // Read as a still first: that gives the scene's frame range (see `sppm_lang::internals::eval::load_frame`).
    let still = match sppm_lang::internals::eval::load_file(&args.scene, &eval_options) {
        Ok(l) => l,
        Err(e) => return usage(e.with_path(&args.scene)),
    };
    if still.interrupted {
        say!("interrupted");
        return ExitCode::from(EXIT_SCENE_ERROR);
    }
    let over = RangeOverride {
        frames: args.frames,
        clock: args.clock,
    };
    let range = match still.scene.as_ref().filter(|_| !still.has_errors()) {
        Some(s) => sppm_lang::internals::eval::frame_range(&s.settings, &over),
        None => {
            print_diagnostics(&still.sources, &still.diagnostics);
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
    };
    match range {
        Err(e) => {
            print_diagnostics(&still.sources, &still.diagnostics);
            usage(e)
        }
        Ok(Some(_)) if args.chain.is_some() => usage(format!(
            "`--chain` renders a still, and `{}` is an animation: render its frames with \
             `--frame K`",
            args.scene.display()
        )),
        Ok(Some(range)) => {
            super::animate::run(&args, &eval_options, still, pattern, &range, &cancel)
        }
        Ok(None) => {
            let needs = if args.frame.is_some() {
                Some("`--frame`")
            } else if args.clock.is_some() {
                Some("`--clock`")
            } else if pattern.is_some() {
                Some("an output name with a frame number")
            } else {
                None
            };
            if let Some(what) = needs {
                return usage(format!(
                    "{what} needs an animation, and `{}` is a still: give its frames with \
                     `--frames A..B` or `settings {{ frames A, B }}`",
                    args.scene.display()
                ));
            }
            print_diagnostics(&still.sources, &still.diagnostics);
            let Some(scene) = still.scene.as_ref() else {
                return ExitCode::from(EXIT_SCENE_ERROR);
            };
            if let Err(e) = super::check_not_an_input(&[&output], &still.dependencies) {
                return usage(e);
            }
            let code = render_scene(scene, &args, &still.sources, &output, &cancel, true)
                .map_or_else(|c| c, |()| ExitCode::SUCCESS);
            // The image is written and the process ends here: freeing a large scene (a mesh's
            // millions of vertices) is left to the exit.
            std::mem::forget(still);
            code
        }
    }
}

/// Renders an already loaded scene as `args` asks into `output`; `sources` turn render errors
/// that carry a span into diagnostics. `cancel` stops the prepare stage and the passes. `last`:
/// the process ends after this render, which may leave its buffers to the exit.
pub(super) fn render_scene(
    scene: &Scene,
    args: &RenderArgs,
    sources: &SourceMap,
    output: &Path,
    cancel: &Cancel,
    last: bool,
) -> Result<(), ExitCode> {
    // The flags override the scene's settings through the render options; the scene is
    // rendered as loaded.
    let resolution = match args.size.is_set() {
        false => None,
        true => match args.size.resolution_for(scene.settings.resolution) {
            Ok(r) => Some(r),
            Err(e) => {
                say!("error: {e}");
                return Err(ExitCode::from(EXIT_USAGE));
            }
        },
    };
    // The method and why (the flag, the scene's setting or the default rule), as prepare
    // chooses it.
    let method = method_choice(scene, args.integrator);
    let integrator = method.integrator;
    // A chain's header: its iterations are filled in as they finish.
    let base_seed = args.seed.unwrap_or(scene.settings.seed);
    let chain = args.chain.map(|(k, n)| ChainInfo {
        iterations: 0,
        photons: args.photons.or(scene.settings.photons).unwrap_or(0),
        method: integrator.name().to_string(),
        seed: base_seed,
        chain: k,
        chains: n,
        // The identity of what is rendered: the scene with the flags' overrides.
        scene: SceneId::of(&Scene {
            settings: sppm_lang::Settings {
                integrator: Some(integrator),
                resolution: resolution.unwrap_or(scene.settings.resolution),
                ..scene.settings.clone()
            },
            ..scene.clone()
        })
        .value(),
    });
    let write = |image: &sppm_lang::Image, iterations: u32| match &chain {
        Some(info) => write_chain(
            output,
            image,
            &ChainInfo {
                iterations,
                ..info.clone()
            },
        ),
        None => image
            .write(output, scene.settings.exposure)
            .map_err(|d| d.message),
    };
    let options = RenderOptions {
        integrator: args.integrator,
        resolution,
        iterations: args.iterations,
        photons: args.photons,
        seed: match args.chain {
            Some((k, _)) => Some(chain_seed(base_seed, k)),
            None => args.seed,
        },
        time_limit: args.time_limit,
        threads: args.threads,
        memory_limit: args.limits.memory_limit,
        chain: args.chain,
        cancel: cancel.clone(),
        ..RenderOptions::default()
    };
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
            && let Err(e) = write(&p.image(), p.iteration)
        {
            snapshot_error = Some(e);
        }
    };
    let on_warnings = |w: &[sppm_lang::Diagnostic]| {
        if let Some(b) = &bar {
            b.suspend(|| print_diagnostics(sources, w));
        } else {
            print_diagnostics(sources, w);
        }
    };
    let result = prepare(scene, &options).and_then(|(settings, prepared)| {
        on_warnings(&prepared.warnings());
        let out = render_prepared(
            &prepared,
            &settings,
            &options,
            cancel.flag(),
            &mut on_progress,
        )?;
        on_warnings(&prepared.render_warnings());
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
        Err(e) if e.interrupted => return Err(interrupted()),
        Err(e) => {
            print_diagnostics(sources, &[e]);
            return Err(ExitCode::from(EXIT_SCENE_ERROR));
        }
    };
    if out.iterations_done == 0 && out.cancelled {
        return Err(interrupted());
    }
    if out.iterations_done == 0 {
        // Nothing to show: keep whatever image is at the output path.
        let message = format!(
            "no iteration finished within the time limit; `{}` is left as it was",
            output.display()
        );
        let mut e = sppm_lang::Diagnostic::unplaced(message).with_help(
            "give more time (`time_limit` in the settings or `--time-limit`), or lower the \
             resolution or photons so that one iteration fits",
        );
        if args.time_limit.is_none() {
            // The limit came from the scene's settings: point at them.
            e = e.at(scene.settings.span);
        }
        print_diagnostics(sources, &[e]);
        return Err(ExitCode::from(EXIT_SCENE_ERROR));
    }
    if let Err(e) = write(&out.image, out.iterations_done) {
        say!("error: {e}");
        return Err(ExitCode::from(EXIT_SCENE_ERROR));
    }
    // Written: the process ends after this command, and the exit frees the prepared scene's
    // buffers (BVH, mesh) at once; freeing them one by one first is serial work for nothing.
    if last {
        std::mem::forget(prepared);
    }
    let secs = out.elapsed.as_secs_f64().max(1e-9);
    say!(
        "{} {}: {} iterations{} in {:.2}s with {method}{}",
        if out.cancelled {
            "interrupted,"
        } else {
            "wrote"
        },
        output.display(),
        out.iterations_done,
        if out.cancelled { " (cancelled)" } else { "" },
        secs,
        method_statistics(integrator, &out.stats, secs),
    );
    Ok(())
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
        Integrator::Vcm | Integrator::Bpt | Integrator::Lt => {
            format!(", {} light paths", stats.photons)
        }
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
