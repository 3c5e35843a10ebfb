//! Command-line arguments and dispatch. Exit status: 0 ok, 1 scene errors, 2 usage errors.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod render;

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

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Parse and evaluate a scene; print diagnostics or a summary.
    Check {
        /// The scene file (.scn).
        scene: PathBuf,
    },
    /// Render a scene with stochastic progressive photon mapping.
    Render(render::RenderArgs),
}

pub fn run(cli: Cli) -> ExitCode {
    match cli.command {
        Command::Check { scene } => {
            eprintln!("check {}: the language is not built yet", scene.display());
            ExitCode::from(EXIT_USAGE)
        }
        Command::Render(args) => render::run(args),
    }
}
