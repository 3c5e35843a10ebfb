//! Command-line arguments and dispatch. Exit status: 0 ok, 1 scene errors (and work
//! interrupted before it had a result), 2 usage errors.

/// `eprintln!` that never panics: a message to a standard error that cannot be written (a full
/// disk, a closed pipe) is lost, and the command goes on to its own exit status.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}
/// `eprint!` that never panics (see [`say!`]).
#[cfg_attr(not(feature = "watch"), allow(unused_macros))]
macro_rules! say_inline {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stderr(), $($arg)*);
    }};
}

#[cfg(feature = "chart")]
mod chart;
mod check;
mod farm;
mod frames;
mod identity;
#[cfg(feature = "watch")]
mod live;
#[cfg(feature = "lsp")]
mod lsp;
mod merge;
mod output;
mod reference;
mod render;
#[cfg(feature = "watch")]
mod watch;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Arg, ArgAction, ArgMatches};
use sppm_lang::EvalOptions;

/// Scene errors (bad scene text, failed render).
pub const EXIT_SCENE_ERROR: u8 = 1;
/// Usage errors (bad arguments, unreadable input file given on the command line).
pub const EXIT_USAGE: u8 = 2;

/// The parsed command line. The parser is clap's builder (the derive macros cost a fresh
/// build's first image more than these lines).
#[derive(Debug)]
pub struct Cli {
    pub command: Command,
}

impl Cli {
    /// The command line's grammar: its commands, flags and help.
    pub fn command() -> clap::Command {
        let cmd = clap::Command::new("sppm-lang")
            .version(env!("CARGO_PKG_VERSION"))
            .about("A scene language and an SPPM renderer")
            .subcommand_required(true)
            .arg_required_else_help(true)
            .subcommand(
                clap::Command::new("check")
                    .about("Parse and evaluate a scene; print diagnostics or a summary")
                    .arg(scene_arg())
                    .args(SizeArgs::args())
                    .args(LimitArgs::args()),
            )
            .subcommand(render::RenderArgs::command(
                clap::Command::new("render")
                    .about("Render a scene with stochastic progressive photon mapping"),
            ));
        #[cfg(feature = "watch")]
        let cmd = cmd.subcommand(watch::WatchArgs::command(
            clap::Command::new("watch")
                .about("Re-render a scene every time it or a file it reads is saved"),
        ));
        #[cfg(feature = "chart")]
        let cmd = cmd.subcommand(chart::ChartArgs::command(
            clap::Command::new("chart").about(
                "Chart error against render time for every integrator against a reference image",
            ),
        ));
        let cmd = cmd
            .subcommand(reference::ReferenceArgs::command(
                clap::Command::new("reference").about(
                    "Render a reference image for `chart` with the path tracer, in two \
                     independent halves whose difference estimates its noise (written beside it)",
                ),
            ))
            .subcommand(merge::MergeArgs::command(clap::Command::new("merge").about(
                "Merge the chains of a still (`render --chain K/N`) into one image, weighted by \
                 their iterations",
            )))
            .subcommand(farm::FarmArgs::command(clap::Command::new("farm").about(
                "Split the frames or chains of a scene over a cluster's batch scheduler (Slurm)",
            )));
        #[cfg(feature = "lsp")]
        let cmd = cmd.subcommand(
            clap::Command::new("lsp")
                .about(
                    "Serve the Language Server Protocol on stdin and stdout, for editors: \
                     diagnostics, completion, hover, go to definition, references and the \
                     outline of scene files",
                )
                .arg(
                    flag("stdio", "stdio")
                        .help("Accepted for editors that pass it: stdio is the only transport"),
                ),
        );
        cmd
    }

    /// Parses the process's arguments; on a usage error (or `--help`, `--version`) prints and
    /// exits as clap does.
    pub fn parse() -> Self {
        let mut matches = Self::command().get_matches();
        Self::from_matches(&mut matches).unwrap_or_else(|e| e.exit())
    }

    fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        let Some((name, mut sub)) = m.remove_subcommand() else {
            return Err(clap::Error::raw(
                clap::error::ErrorKind::MissingSubcommand,
                "a subcommand is required",
            ));
        };
        let sub = &mut sub;
        let command = match name.as_str() {
            "check" => Command::Check {
                scene: required(sub, "scene")?,
                size: SizeArgs::from_matches(sub),
                limits: LimitArgs::from_matches(sub)?,
            },
            "render" => Command::Render(render::RenderArgs::from_matches(sub)?),
            #[cfg(feature = "watch")]
            "watch" => Command::Watch(watch::WatchArgs::from_matches(sub)?),
            #[cfg(feature = "chart")]
            "chart" => Command::Chart(chart::ChartArgs::from_matches(sub)?),
            "reference" => Command::Reference(reference::ReferenceArgs::from_matches(sub)?),
            "merge" => Command::Merge(merge::MergeArgs::from_matches(sub)?),
            "farm" => Command::Farm(farm::FarmArgs::from_matches(sub)?),
            #[cfg(feature = "lsp")]
            "lsp" => Command::Lsp,
            other => {
                return Err(clap::Error::raw(
                    clap::error::ErrorKind::InvalidSubcommand,
                    format!("the subcommand '{other}' wasn't recognized"),
                ));
            }
        };
        Ok(Self { command })
    }
}

/// The positional scene file every command that loads one takes.
fn scene_arg() -> Arg {
    Arg::new("scene")
        .value_name("SCENE")
        .value_parser(clap::value_parser!(PathBuf))
        .required(true)
        .help("The scene file (.scn)")
}

/// `--long VALUE`, taken once (a repeat replaces it).
fn option(id: &'static str, long: &'static str, value_name: &'static str) -> Arg {
    Arg::new(id)
        .long(long)
        .value_name(value_name)
        .action(ArgAction::Set)
}

/// `--long` without a value.
fn flag(id: &'static str, long: &'static str) -> Arg {
    Arg::new(id).long(long).action(ArgAction::SetTrue)
}

/// An argument the parser has made sure of (required, or with a default).
fn required<T: Clone + Send + Sync + 'static>(
    m: &mut ArgMatches,
    id: &str,
) -> Result<T, clap::Error> {
    m.remove_one::<T>(id).ok_or_else(|| {
        clap::Error::raw(
            clap::error::ErrorKind::MissingRequiredArgument,
            format!("the following required argument was not provided: {id}"),
        )
    })
}

/// [`EvalOptions`]' step limit as the default of `--max-steps`.
fn default_max_steps() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| EvalOptions::default().max_steps.to_string())
}

/// Whether a flag made by [`flag`] was given.
fn switch(m: &mut ArgMatches, id: &str) -> bool {
    m.remove_one::<bool>(id).unwrap_or(false)
}

/// The limits of the render options, checked again by the render (the library's callers have
/// no command line).
pub use sppm_lang::internals::prepare::{MAX_ITERATIONS, MAX_PHOTONS, MAX_THREADS};
/// Longest time limit or snapshot interval in seconds (a year).
pub const MAX_SECONDS: f64 = 365.0 * 24.0 * 3600.0;

/// A positive number of seconds, at most [`MAX_SECONDS`].
pub fn parse_seconds(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number of seconds"))?;
    if !(v > 0.0 && v <= MAX_SECONDS) {
        return Err(format!(
            "must be more than 0 and at most {MAX_SECONDS} seconds (a year), got {text}"
        ));
    }
    Ok(v)
}

/// A byte count with an optional binary suffix: `1500000`, `512K`, `512M`, `4G`.
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    // A plain number (`1500000`, `1e9`) is bytes; otherwise digits then a unit.
    let split = if t.parse::<f64>().is_ok() {
        None
    } else {
        t.char_indices().find(|(_, c)| c.is_ascii_alphabetic())
    };
    let (digits, unit) = match split {
        Some((i, _)) => (&t[..i], &t[i..]),
        None => (t, ""),
    };
    let shift = match unit.to_ascii_uppercase().as_str() {
        "" | "B" => 0,
        "K" | "KB" | "KIB" => 10,
        "M" | "MB" | "MIB" => 20,
        "G" | "GB" | "GIB" => 30,
        "T" | "TB" | "TIB" => 40,
        _ => return Err(format!("unknown unit `{unit}`; use K, M, G or T")),
    };
    let n: f64 = digits
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a size such as 512M or 4G"))?;
    let bytes = n * (1u64 << shift) as f64;
    if !(1.0..1.8e19).contains(&bytes) {
        return Err(format!("`{text}` is out of range"));
    }
    Ok(bytes as u64)
}

/// The image a command writes: `-o`, or the scene's name with `.png`; a `.png` or `.exr` that
/// is absent or a regular file (never a link, folder or device), in an existing folder that
/// accepts files, and not the scene itself. Checked before the scene is loaded; the files the
/// load reads are checked with [`check_not_an_input`].
pub fn output_path(
    output: Option<&std::path::Path>,
    scene: &std::path::Path,
) -> Result<PathBuf, String> {
    if output.is_none() && scene.file_stem().is_none_or(|s| s.is_empty() || s == ".") {
        // `render .`: the image's name comes from the scene's, and this one has none.
        return Err(format!(
            "`{}` is not a scene file name (it names no file); give the scene's file, e.g. \
             `scene.scn`",
            scene.display()
        ));
    }
    let output = output.map_or_else(|| scene.with_extension("png"), |o| o.to_path_buf());
    match output.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("exr") => {}
        _ => {
            let name = output.file_name().and_then(|n| n.to_str()).unwrap_or("");
            let dotfile = name.starts_with('.')
                && [".png", ".exr"]
                    .iter()
                    .any(|e| name.eq_ignore_ascii_case(e));
            return Err(if dotfile {
                format!(
                    "output `{}` has no name before its extension; write e.g. `image{name}`",
                    output.display()
                )
            } else {
                format!("output `{}` must end in .png or .exr", output.display())
            });
        }
    }
    sppm_lang::internals::atomic_file::check_output(&output, &[scene])?;
    Ok(output)
}

/// A cancel handle that Ctrl-C and SIGTERM raise, installed before anything long starts (the
/// load included), so that they stop the work at its next check instead of waiting for it. A
/// handler installed earlier in this process is kept (only one can be; the commands install
/// theirs first thing).
pub fn cancel_on_ctrl_c() -> sppm_lang::Cancel {
    let cancel = sppm_lang::Cancel::new();
    let raise = cancel.clone();
    let _ = ctrlc::set_handler(move || raise.cancel());
    cancel
}

/// Refuses `outputs` that are among `inputs` (the files a load read): writing there would
/// destroy a scene, an include or a texture (and `watch` would see its own output as a change).
/// Whether `path` ends in `.exr` (any case).
pub fn is_exr(path: &std::path::Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

pub fn check_not_an_input(outputs: &[&std::path::Path], inputs: &[PathBuf]) -> Result<(), String> {
    for o in outputs {
        sppm_lang::internals::atomic_file::check_output(o, inputs)?;
    }
    Ok(())
}

/// A thread count from 1 to [`MAX_THREADS`].
pub fn parse_threads(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number"))?;
    if !(1..=MAX_THREADS).contains(&n) {
        return Err(format!("must be from 1 to {MAX_THREADS}, got {n}"));
    }
    Ok(n)
}

/// Largest `--scale` factor (the result is range-checked again by the render).
pub const MAX_SCALE: f64 = 64.0;

/// `WxH`, or one side with the other left out (`640x`, `x480`) to keep the scene's aspect ratio.
pub fn parse_resolution(text: &str) -> Result<Resolution, String> {
    let usage = || format!("`{text}` is not a resolution such as 640x480, 640x or x480");
    let (w, h) = text.trim().split_once(['x', 'X']).ok_or_else(usage)?;
    let side = |s: &str| -> Result<Option<u32>, String> {
        if s.is_empty() {
            return Ok(None);
        }
        match s.parse::<u32>() {
            Ok(n) if (1..=sppm_lang::internals::scene::MAX_RESOLUTION_SIDE).contains(&n) => {
                Ok(Some(n))
            }
            Ok(n) => Err(format!(
                "each side must be from 1 to {}, got {n}",
                sppm_lang::internals::scene::MAX_RESOLUTION_SIDE
            )),
            Err(_) => Err(usage()),
        }
    };
    match (side(w)?, side(h)?) {
        (None, None) => Err(usage()),
        (Some(w), Some(h))
            if u64::from(w) * u64::from(h) > sppm_lang::internals::scene::MAX_PIXELS =>
        {
            Err(format!(
                "{w}x{h} is {} pixels, more than the limit of {}",
                u64::from(w) * u64::from(h),
                sppm_lang::internals::scene::MAX_PIXELS
            ))
        }
        (w, h) => Ok(Resolution {
            width: w,
            height: h,
        }),
    }
}

/// A scale factor for the scene's resolution: more than 0, at most [`MAX_SCALE`].
pub fn parse_scale(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if !(v > 0.0 && v <= MAX_SCALE) {
        return Err(format!(
            "must be more than 0 and at most {MAX_SCALE}, got {text}"
        ));
    }
    Ok(v)
}

/// A resolution from the command line; a side left out follows the scene's aspect ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resolution {
    pub width: Option<u32>,
    pub height: Option<u32>,
}

/// The image size, overriding the scene's `settings { resolution }`.
#[derive(Debug, Clone)]
pub struct SizeArgs {
    pub resolution: Option<Resolution>,
    pub scale: Option<f64>,
}

impl SizeArgs {
    pub fn args() -> [Arg; 2] {
        [
            option("resolution", "resolution", "WxH")
                .value_parser(parse_resolution)
                .help(
                    "Image size `WxH` (e.g. 320x240); `320x` or `x240` keeps the scene's aspect \
                     ratio. Settings derived from the pixel size (the default initial radius) \
                     follow it",
                ),
            option("scale", "scale", "F")
                .value_parser(parse_scale)
                .conflicts_with("resolution")
                .help(
                    "Scale the scene's resolution by F (e.g. 0.25 for a quick preview), keeping \
                     its aspect ratio",
                ),
        ]
    }

    pub fn from_matches(m: &mut ArgMatches) -> Self {
        Self {
            resolution: m.remove_one("resolution"),
            scale: m.remove_one("scale"),
        }
    }

    pub fn is_set(&self) -> bool {
        self.resolution.is_some() || self.scale.is_some()
    }

    /// The resolution a scene of `scene_size` renders at with these flags.
    pub fn apply(&self, (w, h): (u32, u32)) -> (u32, u32) {
        let aspect = f64::from(w.max(1)) / f64::from(h.max(1));
        let side = |v: f64| v.round().clamp(1.0, f64::from(u32::MAX)) as u32;
        match (self.resolution, self.scale) {
            (Some(r), _) => match (r.width, r.height) {
                (Some(w), Some(h)) => (w, h),
                (Some(w), None) => (w, side(f64::from(w) / aspect)),
                (None, Some(h)) => (side(f64::from(h) * aspect), h),
                (None, None) => (w, h),
            },
            (None, Some(f)) => (side(f64::from(w) * f), side(f64::from(h) * f)),
            (None, None) => (w, h),
        }
    }

    /// Sets `scene`'s resolution as the flags ask; a size beyond the render's limits is the
    /// flag's fault (a usage error naming it), not the scene's.
    pub fn apply_to(&self, scene: &mut sppm_lang::internals::scene::Scene) -> Result<(), String> {
        scene.settings.resolution = self.resolution_for(scene.settings.resolution)?;
        Ok(())
    }

    /// The resolution a scene of `scene_size` renders at, checked as [`SizeArgs::apply_to`]
    /// checks it.
    pub fn resolution_for(&self, scene_size: (u32, u32)) -> Result<(u32, u32), String> {
        use sppm_lang::internals::scene::{MAX_PIXELS, MAX_RESOLUTION_SIDE};
        let (w, h) = self.apply(scene_size);
        let side = w.max(h);
        if self.is_set() && (side > MAX_RESOLUTION_SIDE || u64::from(w) * u64::from(h) > MAX_PIXELS)
        {
            let flag = if self.scale.is_some() {
                "--scale"
            } else {
                "--resolution"
            };
            return Err(format!(
                "{flag} makes the image {w}x{h}, beyond {MAX_RESOLUTION_SIDE} pixels per side or \
                 {MAX_PIXELS} pixels in all; ask for a smaller size"
            ));
        }
        Ok((w, h))
    }
}

/// Limits of the scene interpreter.
#[derive(Debug, Clone)]
pub struct LimitArgs {
    pub max_iterations: u64,
    pub max_depth: u64,
    pub memory_limit: Option<u64>,
    pub max_steps: u64,
}

impl LimitArgs {
    pub fn args() -> [Arg; 4] {
        [
            option("max_iterations", "max-iterations", "MAX_ITERATIONS")
                .value_parser(clap::value_parser!(u64))
                .default_value("1000000")
                .help("Most iterations a single `#while`/`#for` loop may run"),
            option("max_depth", "max-depth", "MAX_DEPTH")
                .value_parser(clap::value_parser!(u64).range(1..=100_000))
                .default_value("256")
                .help("Deepest macro call nesting (recursion depth)"),
            option("memory_limit", "memory-limit", "BYTES")
                .value_parser(parse_bytes)
                .help(
                    "Most memory a render may need (e.g. `4G`, `512M`; default: 2 GiB or half \
                     the machine's memory, whichever is less). Checked against an estimate \
                     before rendering starts",
                ),
            option("max_steps", "max-steps", "MAX_STEPS")
                .value_parser(clap::value_parser!(u64).range(1..))
                .default_value(default_max_steps())
                .help(
                    "Most evaluation steps in all (statements, loop iterations, macro calls, \
                     operations)",
                ),
        ]
    }

    pub fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            max_iterations: required(m, "max_iterations")?,
            max_depth: required(m, "max_depth")?,
            memory_limit: m.remove_one("memory_limit"),
            max_steps: required(m, "max_steps")?,
        })
    }

    pub fn options(&self) -> EvalOptions {
        EvalOptions {
            max_iterations: self.max_iterations,
            max_depth: self.max_depth as usize,
            max_steps: self.max_steps,
            // Resolved here, so that images are checked against the limit the render will
            // have (the machine's default included) as they are loaded.
            memory_limit: Some(
                self.memory_limit
                    .unwrap_or_else(sppm_lang::internals::prepare::default_memory_limit),
            ),
            ..EvalOptions::default()
        }
    }
}

#[derive(Debug)]
pub enum Command {
    /// Parse and evaluate a scene; print diagnostics or a summary.
    Check {
        scene: PathBuf,
        size: SizeArgs,
        limits: LimitArgs,
    },
    /// Render a scene with stochastic progressive photon mapping.
    Render(render::RenderArgs),
    /// Re-render a scene every time it or a file it reads is saved.
    #[cfg(feature = "watch")]
    Watch(watch::WatchArgs),
    /// Chart error against render time for every integrator against a reference image.
    #[cfg(feature = "chart")]
    Chart(chart::ChartArgs),
    /// Render a reference image for `chart` with the path tracer, in two independent halves
    /// whose difference estimates its noise (written beside it).
    Reference(reference::ReferenceArgs),
    /// Merge the chains of a still (`render --chain K/N`) into one image, weighted by their
    /// iterations.
    Merge(merge::MergeArgs),
    /// Split the frames or chains of a scene over a cluster's batch scheduler (Slurm).
    Farm(farm::FarmArgs),
    /// Serve the Language Server Protocol on stdin and stdout, for editors: diagnostics,
    /// completion, hover, go to definition, references and the outline of scene files.
    #[cfg(feature = "lsp")]
    /// (`--stdio` is accepted for editors that pass it: stdio is the only transport.)
    Lsp,
}

pub fn run(cli: Cli) -> ExitCode {
    match cli.command {
        Command::Check {
            scene,
            size,
            limits,
        } => {
            let render_options = sppm_lang::internals::render::RenderOptions {
                memory_limit: limits.memory_limit,
                ..Default::default()
            };
            check::run(&scene, &limits.options(), &render_options, &size)
        }
        Command::Render(args) => render::run(args),
        #[cfg(feature = "watch")]
        Command::Watch(args) => watch::run(&args),
        #[cfg(feature = "chart")]
        Command::Chart(args) => chart::run(&args),
        Command::Reference(args) => reference::run(&args),
        Command::Merge(args) => merge::run(&args),
        Command::Farm(args) => farm::run(&args),
        #[cfg(feature = "lsp")]
        Command::Lsp => lsp::run(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_side_left_out_keeps_the_aspect_ratio() {
        let size = |r: &str| SizeArgs {
            resolution: Some(parse_resolution(r).unwrap()),
            scale: None,
        };
        assert_eq!(size("320x").apply((640, 480)), (320, 240));
        assert_eq!(size("x100").apply((640, 480)), (133, 100));
        assert_eq!(size("50x50").apply((640, 480)), (50, 50));
        let scale = SizeArgs {
            resolution: None,
            scale: Some(0.25),
        };
        assert_eq!(scale.apply((640, 480)), (160, 120));
        // Never below one pixel.
        assert_eq!(scale.apply((2, 1)), (1, 1));
    }
}
