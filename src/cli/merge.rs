//! `sppm-lang merge`: combine the chain files of one still (see `sppm_lang::chains`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Arg, ArgAction, ArgMatches};

use super::{EXIT_SCENE_ERROR, EXIT_USAGE};

#[derive(Debug)]
pub struct MergeArgs {
    pub chains: Vec<PathBuf>,
    pub output: PathBuf,
}

impl MergeArgs {
    /// `merge`'s arguments on `cmd`.
    pub fn command(cmd: clap::Command) -> clap::Command {
        cmd.arg(
            Arg::new("chains")
                .value_name("CHAINS")
                .value_parser(clap::value_parser!(PathBuf))
                .action(ArgAction::Append)
                .required(true)
                .help("The chain files (EXR written by `render --chain K/N`)"),
        )
        .arg(
            super::output_arg("OUTPUT")
                .required(true)
                .help("The merged image (.exr, linear)"),
        )
    }

    pub fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            chains: m
                .remove_many("chains")
                .map(Iterator::collect)
                .unwrap_or_default(),
            output: super::required(m, "output")?,
        })
    }
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
        Ok((total, method)) => {
            say!(
                "wrote {}: {} chains of {method}, {total} iterations in all",
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
