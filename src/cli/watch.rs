//! `sppm-lang watch`: re-render a scene every time it (or anything it reads) is saved.
//!
//! Each round: load the scene, watch exactly the files the load read, render (a quick preview
//! first, then the full settings) on a worker thread that writes progressive snapshots
//! atomically, and wait for the next change. A change cancels the render in flight. A scene
//! with errors prints its diagnostics and leaves the last good image untouched.
//!
//! Status lines go to stderr. When stderr is not a terminal they are plain lines starting with
//! `[watch]`, one per event, which the integration tests read.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use clap::Args;
use sppm_lang::render::{self, RenderOptions};
use sppm_lang::scene::Scene;
use sppm_lang::watch::DependencyWatcher;
use sppm_lang::{EvalOptions, SourceMap};

use super::check::{print_diagnostics, print_render_error};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, LimitArgs};

#[derive(Debug, Clone, Args)]
pub struct WatchArgs {
    /// The scene file (.scn).
    pub scene: PathBuf,
    /// Output image (.png or .exr); default: the scene's name with `.png`.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Render a quick low-resolution preview before the full render (the default).
    #[arg(long, overrides_with = "no_preview")]
    pub preview: bool,
    /// Go straight to the full render.
    #[arg(long)]
    pub no_preview: bool,
    /// Clear the terminal before each render (the default on a terminal).
    #[arg(long, overrides_with = "no_clear")]
    pub clear: bool,
    /// Never clear the terminal.
    #[arg(long)]
    pub no_clear: bool,
    /// Write a snapshot at most this often (seconds); the first iteration of each render and
    /// the final image are always written.
    #[arg(long, default_value_t = 1.0, value_parser = parse_interval)]
    pub snapshot_every: f64,
    /// Worker threads for rendering (default: all cores).
    #[arg(long, value_parser = super::parse_threads)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub limits: LimitArgs,
}

/// How a render round ended.
enum Outcome {
    Finished,
    Cancelled,
}

struct Job {
    cancel: Arc<AtomicBool>,
    /// Set before cancelling when the image of the cancelled render is to be written (Ctrl-C);
    /// a change of the scene cancels without writing, the next render replaces the image.
    keep: Arc<AtomicBool>,
    handle: JoinHandle<Outcome>,
}

impl Job {
    fn stop(self, keep_image: bool) -> Outcome {
        self.keep.store(keep_image, Ordering::SeqCst);
        self.cancel.store(true, Ordering::SeqCst);
        self.handle.join().unwrap_or(Outcome::Cancelled)
    }
}

pub fn run(args: &WatchArgs) -> ExitCode {
    if !args.scene.is_file() {
        eprintln!(
            "error: scene file `{}` does not exist (watch needs an existing scene to start)",
            args.scene.display()
        );
        return ExitCode::from(EXIT_USAGE);
    }
    let output = match super::output_path(args.output.as_deref(), &args.scene) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_USAGE);
        }
    };
    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst)) {
            eprintln!("error: cannot install the Ctrl-C handler: {e}");
            return ExitCode::from(EXIT_USAGE);
        }
    }
    let mut watcher = match DependencyWatcher::new() {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
    };
    let terminal = std::io::stderr().is_terminal();
    let clear = terminal && !args.no_clear;
    let preview = !args.no_preview;
    let options = args.limits.options();
    let mut job: Option<Job> = None;
    let mut round = 0u32;
    let mut changed_at = Instant::now();
    loop {
        if clear {
            eprint!("\x1b[2J\x1b[H");
        }
        let loaded = load(&args.scene, &options);
        if let Err(e) = watcher.set_dependencies(&loaded.dependencies) {
            status(&format!("cannot watch the scene's files: {e}"));
        }
        match loaded.scene {
            Some(scene) => {
                round += 1;
                status(&format!(
                    "render #{round} started ({})",
                    args.scene.display()
                ));
                job = Some(start(
                    round,
                    scene,
                    output.clone(),
                    preview,
                    args,
                    changed_at,
                    loaded.sources,
                ));
            }
            None if loaded.empty => {}
            None => status("the scene has errors; the last image is kept"),
        }
        status("waiting for changes");
        let stop = || interrupted.load(Ordering::SeqCst);
        let changes = watcher.wait_batch(None, &stop);
        if let Some(j) = job.take() {
            let outcome = j.stop(changes.is_none());
            if matches!(outcome, Outcome::Cancelled) && changes.is_some() {
                status(&format!("render #{round} cancelled"));
            }
        }
        match changes {
            Some(batch) => {
                changed_at = batch.first_event;
                let names: Vec<String> = batch
                    .files
                    .iter()
                    .map(|f| f.display().to_string())
                    .collect();
                status(&format!("changed: {}", names.join(", ")));
            }
            None => {
                // A render in flight has written its finished iterations (see `start`).
                status("interrupted");
                return ExitCode::SUCCESS;
            }
        }
    }
}

/// What one load gives the watch loop.
struct Load {
    /// The file was empty (already reported).
    empty: bool,
    scene: Option<Scene>,
    dependencies: Vec<PathBuf>,
    sources: SourceMap,
}

/// A number of seconds from 0 to [`super::MAX_SECONDS`] (0: write every iteration).
fn parse_interval(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(0.0) => Ok(0.0),
        _ => super::parse_seconds(text),
    }
}

fn load(path: &Path, options: &EvalOptions) -> Load {
    // Editors truncate a file before writing it: an empty scene is a save in progress (or a
    // mistake), never a scene to render over the last image.
    if std::fs::metadata(path).is_ok_and(|m| m.is_file() && m.len() == 0) {
        status(&format!(
            "`{}` is empty; the last image is kept (waiting for the next save)",
            path.display()
        ));
        return Load {
            empty: true,
            scene: None,
            dependencies: vec![path.to_path_buf()],
            sources: SourceMap::default(),
        };
    }
    match sppm_lang::load_file(path, options) {
        Ok(loaded) => {
            print_diagnostics(&loaded);
            let scene = if loaded.has_errors() {
                None
            } else {
                loaded.scene
            };
            Load {
                empty: false,
                scene,
                dependencies: loaded.dependencies,
                sources: loaded.sources,
            }
        }
        Err(e) => {
            // Deleted between saves (delete-and-recreate): keep watching the path.
            status(&format!("cannot read `{}`: {e}", path.display()));
            Load {
                empty: false,
                scene: None,
                dependencies: vec![path.to_path_buf()],
                sources: SourceMap::default(),
            }
        }
    }
}

/// Starts a render round on a worker thread: an optional preview, then the full render.
fn start(
    round: u32,
    scene: Scene,
    output: PathBuf,
    preview: bool,
    args: &WatchArgs,
    changed_at: Instant,
    sources: SourceMap,
) -> Job {
    let cancel = Arc::new(AtomicBool::new(false));
    let keep = Arc::new(AtomicBool::new(false));
    let (flag, keep_image) = (cancel.clone(), keep.clone());
    let snapshot_every = Duration::from_secs_f64(args.snapshot_every);
    let threads = args.threads;
    let memory_limit = args.limits.memory_limit;
    let handle = std::thread::spawn(move || {
        let mut stages = Vec::new();
        if preview {
            stages.push(("preview", preview_of(&scene)));
        }
        stages.push(("full", scene));
        let mut first_snapshot = true;
        for (stage, scene) in stages {
            let options = RenderOptions {
                threads,
                memory_limit,
                ..RenderOptions::default()
            };
            let exposure = scene.settings.exposure;
            let mut last_write: Option<Instant> = None;
            let mut written = 0u32;
            let mut on_progress = |p: &render::Progress| {
                let due = last_write.is_none_or(|t| t.elapsed() >= snapshot_every)
                    || p.iteration == p.iterations;
                if !due {
                    return;
                }
                match p.image().write(&output, exposure) {
                    Ok(()) => {
                        last_write = Some(Instant::now());
                        written = p.iteration;
                        let latency = if first_snapshot {
                            first_snapshot = false;
                            format!(
                                ", {:.3} s after the change",
                                changed_at.elapsed().as_secs_f64()
                            )
                        } else {
                            String::new()
                        };
                        let rate = p.stats.photons as f64 / p.elapsed.as_secs_f64().max(1e-9);
                        status(&format!(
                            "render #{round} {stage} iteration {}/{} written to {}{latency} ({:.2} Mphotons/s)",
                            p.iteration,
                            p.iterations,
                            output.display(),
                            rate / 1e6
                        ));
                    }
                    Err(e) => status(&format!("cannot write the image: {e}")),
                }
            };
            match render::render(&scene, &options, &flag, &mut on_progress) {
                Ok(out) if out.cancelled => {
                    if keep_image.load(Ordering::SeqCst) && out.iterations_done > 0 {
                        match out.image.write(&output, exposure) {
                            Ok(()) => status(&format!(
                                "render #{round} {stage} stopped after {} iterations, written to {}",
                                out.iterations_done,
                                output.display()
                            )),
                            Err(e) => status(&format!("cannot write the image: {e}")),
                        }
                    }
                    return Outcome::Cancelled;
                }
                Ok(out) => {
                    // Stopped early by a time limit: the last iterations may not be on disk yet.
                    if out.iterations_done > written
                        && let Err(e) = out.image.write(&output, exposure)
                    {
                        status(&format!("cannot write the image: {e}"));
                    }
                    status(&format!(
                        "render #{round} {stage} finished: {} iterations in {:.2} s",
                        out.iterations_done,
                        out.elapsed.as_secs_f64()
                    ));
                }
                Err(e) => {
                    print_render_error(&sources, &e);
                    status(&format!("render #{round} failed"));
                    return Outcome::Finished;
                }
            }
        }
        Outcome::Finished
    });
    Job {
        cancel,
        keep,
        handle,
    }
}

/// The quick first picture: a quarter of the resolution (at least 32 pixels on the short
/// side), a tenth of the photons, at most 4 iterations.
pub fn preview_of(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let (w, h) = s.settings.resolution;
    let short = w.min(h).max(1);
    let factor = (short / 32).clamp(1, 4);
    s.settings.resolution = ((w / factor).max(1), (h / factor).max(1));
    s.settings.photons = (s.settings.photons / 10).max(1000);
    s.settings.iterations = s.settings.iterations.min(4);
    s.settings.time_limit = None;
    s
}

fn status(message: &str) {
    let mut err = std::io::stderr().lock();
    let _ = writeln!(err, "[watch] {message}");
}
