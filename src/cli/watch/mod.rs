//! `sppm-lang watch`: re-render a scene every time it (or anything it reads) is saved.
//!
//! Each round: load the scene, watch exactly the files the load read, render (a quick preview
//! first, then the full settings) on a worker thread that writes progressive snapshots
//! atomically, and wait for the next change. A scene with errors prints its diagnostics and
//! leaves the last good image untouched.
//!
//! No save is lost and no work is thrown away for nothing: the files of the previous load stay
//! watched while the next one runs (the scene itself from the start), and a save during a load
//! starts another round. The render in flight goes on during the load; it is cancelled only
//! when the new load gives another scene ([`SceneId`]) or errors. A save that leaves
//! the scene as it was keeps the render going (or finished). A render never replaces a more
//! converged image of the same scene ([`kept`]).
//!
//! With `--serve`, the same events also go to a local web page (see `super::live`).
//!
//! Status lines go to stderr. When stderr is not a terminal they are plain lines starting with
//! `[watch]`, one per event, which the integration tests read.

mod kept;
mod load;
mod round;
mod watcher;

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Instant, SystemTime};

use clap::ArgMatches;
use sppm_lang::FileError;
use sppm_lang::{Diagnostic, EvalOptions};

use super::identity::SceneId;
use super::live::{self, Hub};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, LimitArgs, SizeArgs, flag, option};
use kept::OnDisk;
use load::load;
use round::{Round, start};
use watcher::DependencyWatcher;

#[derive(Debug, Clone)]
pub struct WatchArgs {
    pub scene: PathBuf,
    pub output: Option<PathBuf>,
    /// `--no-preview` (a later `--preview` overrides it).
    pub no_preview: bool,
    /// `--no-clear` (a later `--clear` overrides it).
    pub no_clear: bool,
    pub snapshot_every: f64,
    pub threads: Option<usize>,
    pub serve: bool,
    pub port: u16,
    pub no_token: bool,
    pub frame: Option<u32>,
    pub frames: Option<(u32, u32)>,
    pub clock: Option<(f64, f64)>,
    pub size: SizeArgs,
    pub limits: LimitArgs,
}

impl WatchArgs {
    /// `watch`'s flags on `cmd`.
    pub fn command(cmd: clap::Command) -> clap::Command {
        cmd.arg(super::scene_arg())
            .arg(
                super::output_arg("OUTPUT")
                    .help("Output image (.png or .exr); default: the scene's name with `.png`"),
            )
            .arg(flag("preview", "preview").overrides_with("no_preview").help(
                "Render a quick low-resolution preview before the full render (the default)",
            ))
            .arg(flag("no_preview", "no-preview").help("Go straight to the full render"))
            .arg(
                flag("clear", "clear")
                    .overrides_with("no_clear")
                    .help("Clear the terminal before each render (the default on a terminal)"),
            )
            .arg(flag("no_clear", "no-clear").help("Never clear the terminal"))
            .arg(
                option("snapshot_every", "snapshot-every", "SNAPSHOT_EVERY")
                    .value_parser(parse_interval)
                    .default_value("1")
                    .help(
                        "Write a snapshot at most this often (seconds); the first iteration of \
                         each render and the final image are always written",
                    ),
            )
            .arg(
                super::threads_arg()
                    .help("Worker threads for rendering (default: all cores)"),
            )
            .arg(flag("serve", "serve").help(
                "Also show the render on a local web page (http://127.0.0.1:PORT/, printed at \
                 start), updated at every snapshot",
            ))
            .arg(
                option("port", "port", "PORT")
                    .value_parser(clap::value_parser!(u16))
                    .default_value(default_port())
                    .requires("serve")
                    .help("The page's port (0: any free port)"),
            )
            .arg(flag("no_token", "no-token").requires("serve").help(
                "Answer any local client without the page's access token (then every user of \
                 this machine, and any program, can read the scene and its image)",
            ))
            .arg(
                option("frame", "frame", "K")
                    .value_parser(super::frames::parse_frame)
                    .help(
                        "Show frame K of the scene's animation (its `settings { frames ... }`, or \
                         `--frames`)",
                    ),
            )
            .arg(
                option("frames", "frames", "A..B")
                    .value_parser(super::frames::parse_frames)
                    .requires("frame")
                    .help("The animation's frames, over the scene's (with `--frame`)"),
            )
            .arg(
                option("clock", "clock", "A..B")
                    .value_parser(super::frames::parse_clock)
                    .requires("frame")
                    .allow_hyphen_values(true)
                    .help("The clock at the first and the last frame (with `--frame`)"),
            )
            .args(SizeArgs::args())
            .args(LimitArgs::args())
    }

    pub fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            scene: super::required(m, "scene")?,
            output: m.remove_one("output"),
            no_preview: super::switch(m, "no_preview"),
            no_clear: super::switch(m, "no_clear"),
            snapshot_every: super::required(m, "snapshot_every")?,
            threads: m.remove_one("threads"),
            serve: super::switch(m, "serve"),
            port: super::required(m, "port")?,
            no_token: super::switch(m, "no_token"),
            frame: m.remove_one("frame"),
            frames: m.remove_one("frames"),
            clock: m.remove_one("clock"),
            size: SizeArgs::from_matches(m),
            limits: LimitArgs::from_matches(m)?,
        })
    }
}

/// [`DEFAULT_PORT`] as the default of `--port`.
fn default_port() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| DEFAULT_PORT.to_string())
}

/// The port `--serve` listens on unless told otherwise.
pub const DEFAULT_PORT: u16 = 8421;

/// How a render round ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    Finished,
    Cancelled,
    /// The renderer refused the scene or failed (a save of the same scene tries again).
    Failed,
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
        self.handle.join().unwrap_or(Outcome::Failed)
    }
}

/// The latest round that rendered: its scene and how it is going.
struct Current {
    number: u32,
    scene: SceneId,
    /// `None` once the render ended and `outcome` says how.
    job: Option<Job>,
    outcome: Option<Outcome>,
}

impl Current {
    /// Whether a load that gave `scene` can leave this round as it is: the same scene, still
    /// rendering or finished.
    fn serves(&mut self, scene: SceneId) -> bool {
        if self.job.as_ref().is_some_and(|j| j.handle.is_finished()) {
            self.stop(false);
        }
        self.scene == scene && (self.job.is_some() || self.outcome == Some(Outcome::Finished))
    }

    /// Stops the render if it is still going; `keep_image` writes its finished iterations
    /// (Ctrl-C), otherwise a cancellation is said.
    fn stop(&mut self, keep_image: bool) {
        if let Some(job) = self.job.take() {
            let outcome = job.stop(keep_image);
            if outcome == Outcome::Cancelled && !keep_image {
                status(&format!("render #{} cancelled", self.number));
            }
            self.outcome = Some(outcome);
        }
    }
}

pub fn run(args: &WatchArgs) -> ExitCode {
    // Read as a load reads it: a folder, FIFO or device is named as such.
    if let Err(e) = sppm_lang::internals::files::open_regular(
        &args.scene,
        sppm_lang::internals::files::MAX_SOURCE_BYTES,
    ) {
        let why = match &e {
            FileError::Io(io) if io.kind() == std::io::ErrorKind::NotFound => {
                format!("scene file `{}` does not exist", args.scene.display())
            }
            _ => e.with_path(&args.scene),
        };
        say!("error: {why} (watch needs an existing scene to start)");
        return ExitCode::from(EXIT_USAGE);
    }
    // A name with a frame number (`-o out_%04d.png`) names the frame shown.
    let framed = match args
        .output
        .as_deref()
        .map(super::frames::FramePattern::parse)
    {
        Some(Ok(Some(p))) => match args.frame {
            Some(k) => Some(p.path(k)),
            None => {
                say!("error: an output name with a frame number needs `--frame K`");
                return ExitCode::from(EXIT_USAGE);
            }
        },
        Some(Err(e)) => {
            say!("error: {e}");
            return ExitCode::from(EXIT_USAGE);
        }
        _ => None,
    };
    let output = match super::output_path(framed.as_deref().or(args.output.as_deref()), &args.scene)
    {
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
    let options = EvalOptions {
        cancel: interrupted.clone().into(),
        ..args.limits.options()
    };
    let on_disk = OnDisk::default();
    let mut current: Option<Current> = None;
    let mut round = 0u32;
    let mut changed_at = Instant::now();
    // The first round follows no save.
    let mut saved_at = None;
    // Watched from before the first load, so that a save during it starts the next round.
    if let Err(e) = watcher.set_dependencies([&args.scene]) {
        status(&format!("cannot watch the scene's files: {e}"));
    }
    loop {
        if clear {
            say_inline!("\x1b[2J\x1b[H");
        }
        // The previous files stay watched (and the render in flight goes on) during the load.
        let load_started = SystemTime::now();
        let over = sppm_lang::internals::eval::RangeOverride {
            frames: args.frames,
            clock: args.clock,
        };
        let loaded = load(&args.scene, &options, args.frame.map(|k| (&over, k)));
        if interrupted.load(Ordering::SeqCst) {
            // The render that went on during the load writes its finished iterations.
            if let Some(c) = &mut current {
                c.stop(true);
            }
            status("interrupted");
            return ExitCode::SUCCESS;
        }
        let watched = loaded.dependencies.iter().chain([&args.scene]);
        if let Err(e) = watcher.set_dependencies_after(watched, load_started) {
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
                let d = Diagnostic::error(sppm_lang::Span::detached(), e);
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
                let d = Diagnostic::error(sppm_lang::Span::detached(), e);
                diagnostics.extend(live::diagnostics_view(&loaded.sources, &[d]));
                None
            }
        });
        let scene = scene.map(|s| (SceneId::of(&s), s));
        let unchanged = match (&scene, current.as_mut()) {
            // A finished image deleted by hand is rendered again.
            (Some((id, _)), Some(c)) => (c.serves(*id) && (c.job.is_some() || output.exists()))
                .then_some((c.number, c.job.is_some())),
            _ => None,
        };
        match (unchanged, scene) {
            (Some((number, true)), _) => {
                status(&format!(
                    "unchanged: the scene is as before; render #{number} goes on"
                ));
            }
            (Some((number, false)), _) => {
                status(&format!(
                    "unchanged: the scene is as before; the image of render #{number} stays"
                ));
                // A save with errors may have come in between: the page shows the finished
                // render again.
                if let Some(hub) = &hub {
                    hub.update(|s| {
                        s.state = "finished";
                        s.message = format!("render #{number} finished; the scene is unchanged");
                        s.saved_at = saved_at;
                        s.diagnostics = diagnostics;
                    });
                }
                status("waiting for changes");
            }
            (None, Some((id, scene))) => {
                if let Some(c) = &mut current {
                    c.stop(false);
                }
                round += 1;
                // The method and why, as the render's prepare chooses it (watch takes no
                // `--integrator`).
                let method = sppm_lang::internals::render::method_choice(&scene, None);
                status(&format!(
                    "render #{round} started ({}) with {method}",
                    args.scene.display()
                ));
                if let Some(hub) = &hub {
                    hub.update(|s| {
                        s.state = "rendering";
                        s.message = format!("render #{round} started with {method}");
                        s.round = round;
                        s.stage = "";
                        (s.iteration, s.iterations, s.elapsed) = (0, 0, 0.0);
                        s.photons_per_second = 0.0;
                        s.saved_at = saved_at;
                        s.exposure = scene.settings.exposure;
                        s.diagnostics = diagnostics;
                    });
                }
                let job = start(Round {
                    number: round,
                    scene,
                    identity: id,
                    on_disk: on_disk.clone(),
                    output: output.clone(),
                    preview,
                    snapshot_every: args.snapshot_every,
                    threads: args.threads,
                    memory_limit: args.limits.memory_limit,
                    changed_at,
                    sources: loaded.sources,
                    hub: hub.clone(),
                });
                current = Some(Current {
                    number: round,
                    scene: id,
                    job: Some(job),
                    outcome: None,
                });
            }
            (None, None) => {
                if let Some(c) = &mut current {
                    c.stop(false);
                }
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
        match watcher.wait_batch(None, &stop) {
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
                // A render in flight writes its finished iterations (see `start`).
                if let Some(c) = &mut current {
                    c.stop(true);
                }
                status("interrupted");
                return ExitCode::SUCCESS;
            }
        }
    }
}

/// A number of seconds from 0 to [`super::MAX_SECONDS`] (0: write every iteration).
fn parse_interval(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(0.0) => Ok(0.0),
        _ => super::parse_seconds(text),
    }
}

pub(super) fn status(message: &str) {
    let mut err = std::io::stderr().lock();
    let _ = writeln!(err, "[watch] {message}");
}
