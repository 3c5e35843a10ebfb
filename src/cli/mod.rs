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

mod animate;
mod args;
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

pub use args::*;

use clap::ArgMatches;

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
                clap::Command::new("render").about(
                    "Render a scene with the scene's integrator, `--integrator`'s, or the \
                         default (docs/integrators.md)",
                ),
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

/// Whether `path` ends in `.exr` (any case).
pub fn is_exr(path: &std::path::Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// Refuses `outputs` that are among `inputs` (the files a load read): writing there would
/// destroy a scene, an include or a texture (and `watch` would see its own output as a change).
pub fn check_not_an_input(outputs: &[&std::path::Path], inputs: &[PathBuf]) -> Result<(), String> {
    for o in outputs {
        sppm_lang::internals::atomic_file::check_output(o, inputs)?;
    }
    Ok(())
}

#[derive(Debug)]
pub enum Command {
    /// Parse and evaluate a scene; print diagnostics or a summary.
    Check {
        scene: PathBuf,
        size: SizeArgs,
        limits: LimitArgs,
    },
    /// Render a scene (with its `integrator`, else the default rule's method).
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

    /// Every argument of every command, given by itself (beside what the command requires)
    /// with a value its parser accepts, reaches the command's options: clap's builder reads
    /// each argument by its id, and a type that does not match the parser's would panic only
    /// when a user gives that argument.
    #[test]
    fn every_argument_reads_back() {
        Cli::command().debug_assert();
        let bases: &[(&[&str], &[&str])] = &[
            (&["check"], &["s.scn"]),
            (&["render"], &["s.scn"]),
            (&["watch"], &["s.scn"]),
            (&["chart"], &["s.scn", "--reference", "r.exr"]),
            (
                &["reference"],
                &["s.scn", "--time", "1", "--output", "r.exr"],
            ),
            (&["merge"], &["a.exr", "--output", "m.exr"]),
            (
                &["farm", "slurm"],
                &["s.scn", "--output", "f_%02d.png", "--frames", "1..2"],
            ),
            (&["lsp"], &[]),
        ];
        let values = [
            "4",
            "0.5",
            "x.png",
            "64x48",
            "1/2",
            "1..2",
            "1G",
            "sppm",
            "path,sppm",
            "1:00:00",
            "0,0,8,8",
        ];
        let root = Cli::command();
        let mut checked = 0;
        for (path, base) in bases {
            let Some(cmd) = path
                .iter()
                .try_fold(&root, |c, name| c.find_subcommand(name))
            else {
                continue; // a command whose feature is off
            };
            for arg in cmd.get_arguments() {
                let Some(long) = arg.get_long() else { continue };
                if ["help", "version"].contains(&long) {
                    continue;
                }
                let tries: Vec<Vec<String>> = if arg.get_action().takes_values() {
                    values
                        .iter()
                        .map(|v| vec![format!("--{long}"), v.to_string()])
                        .collect()
                } else {
                    vec![vec![format!("--{long}")]]
                };
                // An argument that requires another (`--port` needs `--serve`, watch's `--frames`
                // needs `--frame`) is tried with each of the command's other arguments beside
                // it (those that take a value with `1`).
                let flags: Vec<Vec<String>> = std::iter::once(vec![])
                    .chain(cmd.get_arguments().filter_map(|a| {
                        let l = format!("--{}", a.get_long()?);
                        Some(if a.get_action().takes_values() {
                            vec![l, "1".to_string()]
                        } else {
                            vec![l]
                        })
                    }))
                    .collect();
                let tries: Vec<Vec<String>> = flags
                    .iter()
                    .flat_map(|f| {
                        tries
                            .iter()
                            .map(move |t| f.iter().cloned().chain(t.iter().cloned()).collect())
                    })
                    .collect();
                // The base as it is; without its own value of this argument (given twice
                // would be refused) or of the farm's `--frames` (`--chains` replaces it in a
                // required group); or no base (`chart --from-csv` conflicts with a scene).
                let without = |drop: &str| -> Vec<&str> {
                    let mut b = base.to_vec();
                    if let Some(at) = b.iter().position(|a| *a == drop) {
                        b.drain(at..at + 2);
                    }
                    b
                };
                let own = format!("--{long}");
                let variants = [base.to_vec(), without(&own), without("--frames"), vec![]];
                let parsed = variants.iter().find_map(|base| {
                    tries.iter().find_map(|extra| {
                        let argv = ["sppm-lang"]
                            .iter()
                            .chain(path.iter())
                            .chain(base.iter())
                            .map(|s| s.to_string())
                            .chain(extra.iter().cloned());
                        Cli::command().try_get_matches_from(argv).ok()
                    })
                });
                let Some(mut m) = parsed else {
                    panic!("no test value parses for `{}` --{long}", path.join(" "));
                };
                if let Err(e) = Cli::from_matches(&mut m) {
                    panic!("`{}` --{long}: {e}", path.join(" "));
                }
                checked += 1;
            }
        }
        assert!(checked > 40, "only {checked} arguments checked");
    }
}
