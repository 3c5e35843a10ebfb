//! `sppm-lang watch`: re-render a scene every time it (or anything it reads) is saved.
//!
//! Each round: load the scene, watch exactly the files the load read, render (a quick preview
//! first, then the full settings) on a worker thread that writes progressive snapshots
//! atomically, and wait for the next change. A change cancels the render in flight. A scene
//! with errors prints its diagnostics and leaves the last good image untouched.
//!
//! With `--serve`, the same events also go to a local web page (see `super::live`).
//!
//! Status lines go to stderr. When stderr is not a terminal they are plain lines starting with
//! `[watch]`, one per event, which the integration tests read.

mod round;

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Instant;

use clap::Args;
use sppm_lang::files::FileError;
use sppm_lang::scene::{Background, Scene};
use sppm_lang::watch::DependencyWatcher;
use sppm_lang::{Diagnostic, EvalOptions, SourceMap};

use super::check::print_diagnostics;
use super::live::{self, Hub};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, LimitArgs, SizeArgs};
use round::{Round, start};

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
    /// Also show the render on a local web page (http://127.0.0.1:PORT/, printed at start),
    /// updated at every snapshot.
    #[arg(long)]
    pub serve: bool,
    /// The page's port (0: any free port).
    #[arg(long, default_value_t = DEFAULT_PORT, requires = "serve")]
    pub port: u16,
    /// Answer any local client without the page's access token (then every user of this
    /// machine, and any program, can read the scene and its image).
    #[arg(long, requires = "serve")]
    pub no_token: bool,
    #[command(flatten)]
    pub size: SizeArgs,
    #[command(flatten)]
    pub limits: LimitArgs,
}

/// The port `--serve` listens on unless told otherwise.
pub const DEFAULT_PORT: u16 = 8421;

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
    // Read as a load reads it: a folder, FIFO or device is named as such.
    if let Err(e) = sppm_lang::files::open_regular(&args.scene, sppm_lang::files::MAX_SOURCE_BYTES)
    {
        let why = match &e {
            FileError::Io(io) if io.kind() == std::io::ErrorKind::NotFound => {
                format!("scene file `{}` does not exist", args.scene.display())
            }
            _ => e.with_path(&args.scene),
        };
        say!("error: {why} (watch needs an existing scene to start)");
        return ExitCode::from(EXIT_USAGE);
    }
    let output = match super::output_path(args.output.as_deref(), &args.scene) {
        Ok(o) => o,
        Err(e) => {
            say!("error: {e}");
            return ExitCode::from(EXIT_USAGE);
        }
    };
    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst)) {
            say!("error: cannot install the Ctrl-C handler: {e}");
            return ExitCode::from(EXIT_USAGE);
        }
    }
    let mut watcher = match DependencyWatcher::new() {
        Ok(w) => w,
        Err(e) => {
            say!("error: {e}");
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
    };
    let hub = if args.serve {
        let name = args.scene.file_name().map_or_else(
            || args.scene.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        let hub = Hub::new(name);
        match live::Server::start(args.port, !args.no_token, hub.clone()) {
            Ok(server) => status(&format!("serving the live view on {}", server.url)),
            Err(e) => {
                say!("error: {e}");
                return ExitCode::from(EXIT_USAGE);
            }
        }
        Some(hub)
    } else {
        None
    };
    let terminal = std::io::stderr().is_terminal();
    let clear = terminal && !args.no_clear;
    let preview = !args.no_preview;
    let options = args.limits.options();
    let mut job: Option<Job> = None;
    let mut round = 0u32;
    let mut changed_at = Instant::now();
    // The first round follows no save.
    let mut saved_at = None;
    loop {
        if clear {
            say_inline!("\x1b[2J\x1b[H");
        }
        let loaded = load(&args.scene, &options);
        if let Err(e) = watcher.set_dependencies(&loaded.dependencies) {
            status(&format!("cannot watch the scene's files: {e}"));
        }
        let mut diagnostics = live::diagnostics_view(&loaded.sources, &loaded.diagnostics);
        // An output the scene now reads (an image or include of that name) would be destroyed,
        // and each write would start the next round.
        let output_ok = super::check_not_an_input(&[&output], &loaded.dependencies);
        let scene_ok = loaded.scene.is_some();
        let scene = match output_ok.clone() {
            Ok(()) => loaded.scene,
            Err(e) => {
                status(&format!("error: {e}"));
                let d = Diagnostic::error(sppm_lang::span::Span::detached(), e);
                diagnostics.extend(live::diagnostics_view(&loaded.sources, &[d]));
                None
            }
        };
        // A `--scale` or `--resolution` beyond the limits for this scene's size: said like the
        // output's error, and the last image kept.
        let scene = scene.and_then(|mut s| match args.size.apply_to(&mut s) {
            Ok(()) => Some(s),
            Err(e) => {
                status(&format!("error: {e}"));
                let d = Diagnostic::error(sppm_lang::span::Span::detached(), e);
                diagnostics.extend(live::diagnostics_view(&loaded.sources, &[d]));
                None
            }
        });
        match scene {
            Some(scene) => {
                round += 1;
                status(&format!(
                    "render #{round} started ({})",
                    args.scene.display()
                ));
                if let Some(hub) = &hub {
                    hub.update(|s| {
                        s.state = "rendering";
                        s.message = format!("render #{round} started");
                        s.round = round;
                        s.stage = "";
                        (s.iteration, s.iterations, s.elapsed) = (0, 0, 0.0);
                        s.photons_per_second = 0.0;
                        s.saved_at = saved_at;
                        s.exposure = scene.settings.exposure;
                        s.diagnostics = diagnostics;
                    });
                }
                job = Some(start(Round {
                    number: round,
                    scene,
                    output: output.clone(),
                    preview,
                    snapshot_every: args.snapshot_every,
                    threads: args.threads,
                    memory_limit: args.limits.memory_limit,
                    changed_at,
                    sources: loaded.sources,
                    hub: hub.clone(),
                }));
            }
            None => {
                let (state, message) = if loaded.empty {
                    (
                        "empty",
                        "the scene file is empty or declares nothing; the last image is kept",
                    )
                } else if output_ok.is_err() && scene_ok {
                    let m = "the output cannot be written; the last image is kept";
                    status(m);
                    ("errors", m)
                } else {
                    status("the scene has errors; the last image is kept");
                    ("errors", "the scene has errors; the last image is kept")
                };
                if let Some(hub) = &hub {
                    hub.update(|s| {
                        s.state = state;
                        s.message = message.to_string();
                        s.saved_at = saved_at;
                        s.diagnostics = diagnostics;
                    });
                }
                // Nothing renders until the next save.
                status("waiting for changes");
            }
        }
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
                saved_at = Some(batch.first_event);
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
    /// The file was empty or declared nothing: no object, no light, no background (already
    /// reported).
    empty: bool,
    scene: Option<Scene>,
    dependencies: Vec<PathBuf>,
    sources: SourceMap,
    diagnostics: Vec<Diagnostic>,
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
            diagnostics: Vec::new(),
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
            // Only blanks and comments (a save caught half-written, or a file cleared to start
            // again): nothing to render over the last image either. (A background alone, such
            // as an environment map to look at, is something.)
            let bare = scene.as_ref().is_some_and(|s| {
                s.objects.is_empty()
                    && s.lights.is_empty()
                    && matches!(s.background, Background::Color(c) if c == glam::DVec3::ZERO)
                    && s.backdrop.is_none()
            });
            if bare {
                status(&format!(
                    "`{}` declares no object, no light and no background; the last image is \
                     kept (waiting for the next save)",
                    path.display()
                ));
            }
            Load {
                empty: bare,
                scene: scene.filter(|_| !bare),
                dependencies: loaded.dependencies,
                sources: loaded.sources,
                diagnostics: loaded.diagnostics,
            }
        }
        Err(e) => {
            // Deleted between saves (delete-and-recreate): keep watching the path.
            let message = e.with_path(path);
            status(&message);
            Load {
                empty: false,
                scene: None,
                dependencies: vec![path.to_path_buf()],
                sources: SourceMap::default(),
                diagnostics: vec![Diagnostic::error(
                    sppm_lang::span::Span::detached(),
                    message,
                )],
            }
        }
    }
}

pub(super) fn status(message: &str) {
    let mut err = std::io::stderr().lock();
    let _ = writeln!(err, "[watch] {message}");
}
