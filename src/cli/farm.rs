//! `sppm-lang farm slurm`: the frames or chains of a scene as a Slurm job array (and the
//! chains' merge as a job that waits for it); the planning is `sppm_lang::farm`'s.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use clap::{Arg, ArgAction, ArgGroup, ArgMatches};
use sppm_lang::internals::farm::{Farm, Task, Work, chain_tasks, parse_job_id};

use super::frames::{self, FramePattern};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, flag, option};

/// Most tasks in one array (Slurm's own limit, `MaxArraySize`, is usually lower).
const MAX_TASKS: u32 = 100_000;

#[derive(Debug)]
pub struct FarmArgs {
    pub scheduler: Scheduler,
}

#[derive(Debug)]
pub enum Scheduler {
    /// Write (and with --submit, submit) a Slurm job array of the frames or chains still to
    /// render; a rerun skips the finished ones, so it also retries the failed.
    Slurm(SlurmArgs),
}

#[derive(Debug)]
pub struct SlurmArgs {
    pub scene: PathBuf,
    pub frames: Option<(u32, u32)>,
    pub chains: Option<u32>,
    pub output: Option<PathBuf>,
    pub partition: Option<String>,
    pub time: Option<String>,
    pub cpus_per_task: u32,
    pub dir: Option<PathBuf>,
    pub submit: bool,
    pub render_args: Vec<String>,
}

impl FarmArgs {
    /// `farm`'s schedulers on `cmd`.
    pub fn command(cmd: clap::Command) -> clap::Command {
        cmd.subcommand_required(true)
            .arg_required_else_help(true)
            .subcommand(SlurmArgs::command(clap::Command::new("slurm").about(
                "Write (and with --submit, submit) a Slurm job array of the frames or chains \
                 still to render; a rerun skips the finished ones, so it also retries the failed",
            )))
    }

    pub fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        match m.remove_subcommand() {
            Some((name, mut sub)) if name == "slurm" => Ok(Self {
                scheduler: Scheduler::Slurm(SlurmArgs::from_matches(&mut sub)?),
            }),
            _ => Err(clap::Error::raw(
                clap::error::ErrorKind::MissingSubcommand,
                "a scheduler is required",
            )),
        }
    }
}

impl SlurmArgs {
    fn command(cmd: clap::Command) -> clap::Command {
        cmd.group(
            ArgGroup::new("work")
                .required(true)
                .args(["frames", "chains"]),
        )
        .arg(super::scene_arg().help("The scene file (.scn), on a file system every node sees"))
        .arg(
            option("frames", "frames", "A..B")
                .value_parser(frames::parse_frames)
                .help(
                    "Render frames A to B of an animation, a task per frame (`render \
                         --frames A..B --frame K`)",
                ),
        )
        .arg(
            option("chains", "chains", "N")
                .value_parser(clap::value_parser!(u32).range(1..=MAX_TASKS as i64))
                .help(
                    "Render the still as N chains, a task per chain, and merge them when all \
                         succeeded",
                ),
        )
        .arg(super::output_arg("OUTPUT").help(
            "Frames: the name pattern (default `<scene>_%04d.png`). Chains: the \
                         merged image (.exr, default `<scene>.exr`); chain K is written beside it \
                         as `<name>.chainK.exr`",
        ))
        .arg(
            option("partition", "partition", "PARTITION")
                .value_parser(clap::value_parser!(String))
                .help("The Slurm partition (default: the cluster's)"),
        )
        .arg(
            option("time", "time", "TIME")
                .value_parser(clap::value_parser!(String))
                .help("Each task's time limit, in Slurm's form (`30`, `2:00:00`, `1-0`)"),
        )
        .arg(
            option("cpus_per_task", "cpus-per-task", "CPUS_PER_TASK")
                .value_parser(clap::value_parser!(u32).range(1..=4096))
                .default_value("1")
                .help("CPUs per task; each render runs that many threads"),
        )
        .arg(
            option("dir", "dir", "DIR")
                .value_parser(clap::value_parser!(PathBuf))
                .help(
                    "Folder of the batch scripts and logs (default: `<job name>.slurm` \
                         beside the output)",
                ),
        )
        .arg(flag("submit", "submit").help(
            "Submit with `sbatch`; without it the scripts are written and the commands printed",
        ))
        .arg(
            Arg::new("render_args")
                .value_name("RENDER FLAGS")
                .value_parser(clap::value_parser!(String))
                .action(ArgAction::Append)
                .last(true)
                .help(
                    "Flags given to every render, after `--` (e.g. `-- --iterations 64 \
                         --seed 3`)",
                ),
        )
    }

    fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            scene: super::required(m, "scene")?,
            frames: m.remove_one("frames"),
            chains: m.remove_one("chains"),
            output: m.remove_one("output"),
            partition: m.remove_one("partition"),
            time: m.remove_one("time"),
            cpus_per_task: super::required(m, "cpus_per_task")?,
            dir: m.remove_one("dir"),
            submit: super::switch(m, "submit"),
            render_args: m
                .remove_many("render_args")
                .map(Iterator::collect)
                .unwrap_or_default(),
        })
    }
}

pub fn run(args: &FarmArgs) -> ExitCode {
    match &args.scheduler {
        Scheduler::Slurm(a) => slurm(a),
    }
}

fn slurm(args: &SlurmArgs) -> ExitCode {
    let usage = |e: String| {
        say!("error: {e}");
        ExitCode::from(EXIT_USAGE)
    };
    let farm = match plan(args) {
        Ok(f) => f,
        Err(e) => return usage(e),
    };
    let remaining = farm.remaining();
    let what = match farm.work {
        Work::Frames { .. } => "frame",
        Work::Chains { .. } => "chain",
    };
    say!(
        "{} of {} {what}s finished; {} to render{}",
        farm.tasks.len() - remaining.len(),
        farm.tasks.len(),
        remaining.len(),
        if remaining.is_empty() {
            String::new()
        } else {
            format!(
                " ({})",
                sppm_lang::internals::farm::array_spec(&indices(&remaining))
            )
        }
    );
    let merge =
        matches!(farm.work, Work::Chains { .. }) && (farm.merge_needed() || !remaining.is_empty());
    if remaining.is_empty() && !merge {
        say!("nothing to submit");
        return ExitCode::SUCCESS;
    }
    let array_path = farm.dir.join("tasks.sbatch");
    let merge_path = farm.dir.join("merge.sbatch");
    let written = std::fs::create_dir_all(&farm.dir)
        .map_err(|e| format!("cannot make `{}`: {e}", farm.dir.display()))
        .and_then(|()| {
            if !remaining.is_empty() {
                write_script(&array_path, &farm.array_script(&remaining))?;
            }
            match farm.merge_script() {
                Some(text) if merge => write_script(&merge_path, &text),
                _ => Ok(()),
            }
        });
    if let Err(e) = written {
        say!("error: {e}");
        return ExitCode::from(EXIT_SCENE_ERROR);
    }
    if !args.submit {
        if !remaining.is_empty() {
            say!("wrote {}; submit it with", array_path.display());
            say!("  sbatch --parsable {}", array_path.display());
        }
        if merge {
            say!(
                "wrote {}; submit it after the array with",
                merge_path.display()
            );
            say!(
                "  sbatch --dependency=afterok:<array job id> {}",
                merge_path.display()
            );
        }
        return ExitCode::SUCCESS;
    }
    let queued = queued_jobs(&farm.name);
    if !queued.is_empty() {
        say!(
            "error: jobs of `{}` are still queued or running ({}): wait for them to end, or \
             `scancel` them, then run this again to resubmit what they did not finish",
            farm.name,
            queued.join(", ")
        );
        return ExitCode::from(EXIT_SCENE_ERROR);
    }
    let mut array_id = None;
    if !remaining.is_empty() {
        match sbatch(&[], &array_path) {
            Ok(id) => {
                say!("submitted job array {id}");
                println!("array {id}");
                array_id = Some(id);
            }
            Err(e) => {
                say!("error: {e}");
                return ExitCode::from(EXIT_SCENE_ERROR);
            }
        }
    }
    if merge {
        let dependency = array_id.map(|id| format!("--dependency=afterok:{id}"));
        match sbatch(dependency.as_slice(), &merge_path) {
            Ok(id) => {
                say!("submitted merge job {id}");
                println!("merge {id}");
            }
            Err(e) => {
                say!("error: {e}");
                return ExitCode::from(EXIT_SCENE_ERROR);
            }
        }
    }
    ExitCode::SUCCESS
}

fn indices(tasks: &[&Task]) -> Vec<u32> {
    tasks.iter().map(|t| t.index).collect()
}

/// The farm `args` describe, with absolute paths.
fn plan(args: &SlurmArgs) -> Result<Farm, String> {
    let cwd = std::env::current_dir().map_err(|e| format!("no working folder: {e}"))?;
    if !args.scene.is_file() {
        return Err(format!("`{}` is not a scene file", args.scene.display()));
    }
    let scene = std::fs::canonicalize(&args.scene)
        .map_err(|e| format!("cannot read `{}`: {e}", args.scene.display()))?;
    let absolute = |p: &Path| cwd.join(p);
    let (work, tasks, output) = match (args.frames, args.chains) {
        (Some((first, last)), _) => {
            if last - first >= MAX_TASKS {
                return Err(format!(
                    "{}..{} is more than {MAX_TASKS} frames; split the range",
                    first, last
                ));
            }
            let given = args.output.clone().map_or_else(
                || FramePattern::for_scene(&scene).map(|p| p.path_text()),
                Some,
            );
            let given = given.ok_or_else(|| "give the frames' names with -o".to_string())?;
            let pattern = FramePattern::parse(&absolute(&given))?.ok_or_else(|| {
                format!(
                    "output `{}` has no place for the frame number: put `%04d` in its name, \
                     e.g. `frame_%04d.png`",
                    given.display()
                )
            })?;
            super::output_path(Some(&pattern.path(first)), &scene)?;
            let tasks = (first..=last)
                .map(|k| Task {
                    index: k,
                    output: pattern.path(k),
                })
                .collect();
            (Work::Frames { first, last }, tasks, absolute(&given))
        }
        (None, Some(count)) => {
            let merged = absolute(
                &args
                    .output
                    .clone()
                    .unwrap_or_else(|| scene.with_extension("exr")),
            );
            if !super::is_exr(&merged) {
                return Err(format!(
                    "the merged chains are written as linear EXR: name `{}` with .exr",
                    merged.display()
                ));
            }
            super::output_path(Some(&merged), &scene)?;
            let tasks = chain_tasks(&merged, count);
            (
                Work::Chains {
                    count,
                    merged: merged.clone(),
                },
                tasks,
                merged,
            )
        }
        (None, None) => return Err("give --frames A..B or --chains N".into()),
    };
    let stem: String = scene
        .file_stem()
        .unwrap_or_default()
        .to_string_lossy()
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let name = format!("sppm-{stem}");
    let dir = args.dir.as_deref().map_or_else(
        || {
            output
                .parent()
                .unwrap_or(&cwd)
                .join(format!("{name}.slurm"))
        },
        absolute,
    );
    let binary =
        std::env::current_exe().map_err(|e| format!("cannot find this program's file: {e}"))?;
    let farm = Farm {
        work,
        tasks,
        binary,
        scene,
        output,
        render_args: args.render_args.clone(),
        workdir: cwd,
        dir,
        name,
        partition: args.partition.clone(),
        time: args.time.clone(),
        cpus_per_task: args.cpus_per_task,
    };
    farm.check()?;
    Ok(farm)
}

fn write_script(path: &Path, text: &str) -> Result<(), String> {
    sppm_lang::internals::atomic_file::write_atomic(path, |_, file| {
        use std::io::Write as _;
        file.write_all(text.as_bytes())
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))
    })
}

/// `sbatch --parsable [flags] script`: the job id.
fn sbatch(flags: &[String], script: &Path) -> Result<u64, String> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .args(flags)
        .arg(script)
        .output()
        .map_err(|e| format!("cannot run `sbatch` ({e}): is Slurm's client installed?"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!(
            "sbatch {} failed: {}",
            script.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    parse_job_id(&stdout).ok_or_else(|| format!("sbatch printed no job id: `{}`", stdout.trim()))
}

/// The ids of this farm's jobs in the queue (pending or running); none when `squeue` cannot
/// tell (then `sbatch` reports what is wrong).
fn queued_jobs(name: &str) -> Vec<String> {
    Command::new("squeue")
        .args(["--noheader", "--format=%i", "--name"])
        .arg(format!("{name},{name}-merge"))
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| {
            String::from_utf8_lossy(&o.stdout)
                .split_whitespace()
                .map(str::to_string)
                .collect()
        })
        .unwrap_or_default()
}
