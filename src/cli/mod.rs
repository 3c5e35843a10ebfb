//! Command-line arguments and dispatch. Exit status: 0 ok, 1 scene errors, 2 usage errors.

mod chart;
mod check;
mod output;
mod render;
mod watch;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use sppm_lang::EvalOptions;

/// Scene errors (bad scene text, failed render).
pub const EXIT_SCENE_ERROR: u8 = 1;
/// Usage errors (bad arguments, unreadable input file given on the command line).
pub const EXIT_USAGE: u8 = 2;

#[derive(Debug, Parser)]
#[command(
    name = "sppm-lang",
    version,
    about = "A scene language and an SPPM renderer"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// Most iterations a render may be asked for on the command line.
pub const MAX_ITERATIONS: u32 = 100_000_000;
/// Most photons per iteration on the command line (memory is checked again by the render).
pub const MAX_PHOTONS: u64 = 100_000_000_000;
/// Most worker threads.
pub const MAX_THREADS: usize = 1024;
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

/// Limits of the scene interpreter.
#[derive(Debug, Clone, Args)]
pub struct LimitArgs {
    /// Most iterations a single `#while`/`#for` loop may run.
    #[arg(long, default_value_t = 1_000_000)]
    pub max_iterations: u64,
    /// Deepest macro call nesting (recursion depth).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    pub max_depth: u64,
    /// Most evaluation steps in all (statements, loop iterations, macro calls).
    #[arg(long, default_value_t = EvalOptions::default().max_steps, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_steps: u64,
}

impl LimitArgs {
    pub fn options(&self) -> EvalOptions {
        EvalOptions {
            max_iterations: self.max_iterations,
            max_depth: self.max_depth as usize,
            max_steps: self.max_steps,
            ..EvalOptions::default()
        }
    }
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Parse and evaluate a scene; print diagnostics or a summary.
    Check {
        /// The scene file (.scn).
        scene: PathBuf,
        #[command(flatten)]
        limits: LimitArgs,
    },
    /// Render a scene with stochastic progressive photon mapping.
    Render(render::RenderArgs),
    /// Re-render a scene every time it or a file it reads is saved.
    Watch(watch::WatchArgs),
    /// Chart error against render time for every integrator against a reference image.
    Chart(chart::ChartArgs),
}

pub fn run(cli: Cli) -> ExitCode {
    match cli.command {
        Command::Check { scene, limits } => check::run(&scene, &limits.options()),
        Command::Render(args) => render::run(args),
        Command::Watch(args) => watch::run(&args),
        Command::Chart(args) => chart::run(&args),
    }
}
