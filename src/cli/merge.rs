//! `sppm-lang merge`: combine the chain files of one still (see `sppm_lang::chains`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use super::{EXIT_SCENE_ERROR, EXIT_USAGE};

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The chain files (EXR written by `render --chain K/N`).
    #[arg(required = true)]
    pub chains: Vec<PathBuf>,
    /// The merged image (.exr, linear).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: &MergeArgs) -> ExitCode {
    if !super::is_exr(&args.output) {
        say!(
            "error: the merge is written as linear EXR: name `{}` with .exr",
            args.output.display()
        );
        return ExitCode::from(EXIT_USAGE);
    }
    if let Err(e) = super::check_not_an_input(&[&args.output], &args.chains) {
        say!("error: {e}");
        return ExitCode::from(EXIT_USAGE);
    }
    let inputs: Vec<&std::path::Path> = args.chains.iter().map(PathBuf::as_path).collect();
    match sppm_lang::internals::chains::merge_files(&inputs, &args.output) {
        Ok(total) => {
            say!(
                "wrote {}: {} chains, {total} iterations in all",
                args.output.display(),
                inputs.len()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            say!("error: {e}");
            ExitCode::from(EXIT_SCENE_ERROR)
        }
    }
}
