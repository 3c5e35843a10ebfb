//! Renders split over a batch scheduler (Slurm): which tasks of a job array remain, and the
//! batch scripts that run them. A task is a frame of an animation (`render --frame K`) or a
//! chain of a still (`render --chain K/N`); the chains' merge is a job that depends on the
//! array. Nothing here runs Slurm: the command line submits the scripts.
//!
//! A task is done when its output is a complete file. The renders write atomically, so a file
//! at the output is a finished render; a task that failed or was cancelled leaves none, and the
//! next plan holds it again. That is how failures are found and retried: it needs no
//! accounting database (`sacct`), which many single machines and small clusters lack.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::chains::read_chain;

/// What the array renders.
#[derive(Debug, Clone, PartialEq)]
pub enum Work {
    /// Frames of an animation; `frames` is the range handed to every render (`--frames A..B`).
    Frames { first: u32, last: u32 },
    /// Chains 1 ..= `count` of a still, merged into `merged`.
    Chains { count: u32, merged: PathBuf },
}

/// One array task: its index (`$SLURM_ARRAY_TASK_ID`, the frame or chain number) and the file
/// it writes.
#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    pub index: u32,
    pub output: PathBuf,
}

/// Everything the scripts need; paths are absolute (a job runs wherever the scheduler puts it).
#[derive(Debug, Clone)]
pub struct Farm {
    pub work: Work,
    /// Every task of the work, done or not.
    pub tasks: Vec<Task>,
    /// The sppm-lang binary the tasks run (the same build everywhere: chains compare hashes).
    pub binary: PathBuf,
    pub scene: PathBuf,
    /// The output as given to every render: a frame pattern (`out_%04d.png`) or unused for
    /// chains (each chain's is its task's output).
    pub output: PathBuf,
    /// Flags added to every render (`--iterations 64`, ...).
    pub render_args: Vec<String>,
    /// The folder the jobs start in.
    pub workdir: PathBuf,
    /// The folder of the scripts and the tasks' logs.
    pub dir: PathBuf,
    /// The job's name (its merge job's is this with `-merge`).
    pub name: String,
    pub partition: Option<String>,
    pub time: Option<String>,
    pub cpus_per_task: u32,
}

impl Farm {
    /// Whether the scripts can carry every value as given: the partition a Slurm partition
    /// name, the time limit in Slurm's form ([`check_time`]), the paths, the job's name and
    /// the render flags free of control characters, and none of the render flags `farm`
    /// sets itself. A newline would end an `#SBATCH` line: what follows it would be read as
    /// another directive or, in the script's body, a command. The scripts do not check
    /// again: call this before writing them (the command line writes none for a farm that
    /// fails it).
    pub fn check(&self) -> Result<(), String> {
        if let Some(p) = &self.partition {
            check_partition(p)?;
        }
        if let Some(t) = &self.time {
            check_time(t)?;
        }
        let paths = [
            &self.binary,
            &self.scene,
            &self.output,
            &self.workdir,
            &self.dir,
        ];
        let outputs = self.tasks.iter().map(|t| &t.output);
        let merged = match &self.work {
            Work::Chains { merged, .. } => Some(merged),
            Work::Frames { .. } => None,
        };
        let texts = paths
            .into_iter()
            .chain(outputs)
            .chain(merged)
            .map(|p| p.to_string_lossy())
            .chain(
                std::iter::once(&self.name)
                    .chain(&self.render_args)
                    .map(Into::into),
            );
        for text in texts {
            if text.chars().any(char::is_control) {
                return Err(format!(
                    "{text:?} holds a control character, which a batch script cannot carry"
                ));
            }
        }
        // The flags `farm` sets for each task itself.
        const SET: [&str; 6] = [
            "--threads",
            "--output",
            "--frame",
            "--frames",
            "--chain",
            "-o",
        ];
        for a in &self.render_args {
            let flag = a.split('=').next().unwrap_or(a);
            if SET.contains(&flag) || (a.starts_with("-o") && !a.starts_with("--")) {
                return Err(format!(
                    "the render flag `{a}` is set by `farm` for each task (`--threads` from \
                     `--cpus-per-task`; `-o`, `--frame(s)`, `--chain` per task)"
                ));
            }
        }
        Ok(())
    }

    /// The tasks whose output is not a complete file (see [`is_complete`]).
    pub fn remaining(&self) -> Vec<&Task> {
        self.tasks
            .iter()
            .filter(|t| !is_complete(&self.work, t))
            .collect()
    }

    /// Whether the merge has yet to be written (always false for frames).
    pub fn merge_needed(&self) -> bool {
        match &self.work {
            Work::Frames { .. } => false,
            Work::Chains { merged, .. } => !merged.is_file(),
        }
    }

    /// The array script for `tasks` (its `--array` lists their indices).
    pub fn array_script(&self, tasks: &[&Task]) -> String {
        let indices: Vec<u32> = tasks.iter().map(|t| t.index).collect();
        let mut s = self.header(&self.name, &format!("{}_%A_%a.log", self.name));
        let _ = writeln!(s, "#SBATCH --array={}", array_spec(&indices));
        let _ = writeln!(s, "#SBATCH --cpus-per-task={}", self.cpus_per_task);
        s.push_str("set -eu\nK=\"$SLURM_ARRAY_TASK_ID\"\n");
        let mut command = vec![
            quote(&self.binary.to_string_lossy()),
            "render".into(),
            quote(&self.scene.to_string_lossy()),
        ];
        match &self.work {
            Work::Frames { first, last } => {
                command.push(format!("--frames {first}..{last} --frame \"$K\""));
                command.push(format!("-o {}", quote(&self.output.to_string_lossy())));
            }
            Work::Chains { count, merged } => {
                let (folder, stem) = chain_name_parts(merged);
                command.push(format!("--chain \"$K/{count}\""));
                command.push(format!(
                    "-o {}\"$K\".exr",
                    quote(&folder.join(format!("{stem}.chain")).to_string_lossy())
                ));
            }
        }
        command.push("--threads \"${SLURM_CPUS_PER_TASK:-1}\"".into());
        command.extend(self.render_args.iter().map(|a| quote(a)));
        let _ = writeln!(s, "exec {}", command.join(" "));
        s
    }

    /// The merge script (None for frames): merges every chain into the merged file.
    pub fn merge_script(&self) -> Option<String> {
        let Work::Chains { merged, .. } = &self.work else {
            return None;
        };
        let name = format!("{}-merge", self.name);
        let mut s = self.header(&name, &format!("{name}_%j.log"));
        // A failed chain makes the dependency impossible: the merge leaves the queue rather
        // than waiting there for ever; the rerun that resubmits the chain submits a new merge.
        s.push_str("#SBATCH --kill-on-invalid-dep=yes\n#SBATCH --cpus-per-task=1\nset -eu\n");
        let mut command = vec![quote(&self.binary.to_string_lossy()), "merge".into()];
        command.extend(
            self.tasks
                .iter()
                .map(|t| quote(&t.output.to_string_lossy())),
        );
        command.push(format!("-o {}", quote(&merged.to_string_lossy())));
        let _ = writeln!(s, "exec {}", command.join(" "));
        Some(s)
    }

    fn header(&self, name: &str, log: &str) -> String {
        let mut s = String::from("#!/bin/sh\n");
        let _ = writeln!(s, "#SBATCH --job-name={}", quote(name));
        let _ = writeln!(
            s,
            "#SBATCH --output={}",
            quote(&self.dir.join(log).to_string_lossy())
        );
        let _ = writeln!(
            s,
            "#SBATCH --chdir={}",
            quote(&self.workdir.to_string_lossy())
        );
        if let Some(p) = &self.partition {
            let _ = writeln!(s, "#SBATCH --partition={}", quote(p));
        }
        if let Some(t) = &self.time {
            let _ = writeln!(s, "#SBATCH --time={}", quote(t));
        }
        s
    }
}

/// The folder and stem of a merged file's chains: `out/m.exr` has `out/m.chainK.exr`.
fn chain_name_parts(merged: &Path) -> (PathBuf, String) {
    let folder = merged.parent().map(Path::to_path_buf).unwrap_or_default();
    let stem = merged
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    (folder, stem)
}

/// The chain files of a merged file: chain K of `count` at `<folder>/<stem>.chainK.exr`.
pub fn chain_tasks(merged: &Path, count: u32) -> Vec<Task> {
    let (folder, stem) = chain_name_parts(merged);
    (1..=count)
        .map(|k| Task {
            index: k,
            output: folder.join(format!("{stem}.chain{k}.exr")),
        })
        .collect()
}

/// Whether `task`'s output is finished: a frame whose image header reads, a chain file whose
/// header is this chain's (K of N) with at least one iteration and whose pixels are sound.
pub fn is_complete(work: &Work, task: &Task) -> bool {
    if !task.output.is_file() {
        return false;
    }
    match work {
        // The file's first MiB through the reader the scene's images use (`ImageReader::open`
        // would build every format's decoder a second time, for a file reader): the format by
        // the extension, unless the content says otherwise, as `open` does. Only the header
        // is read, which for our PNG and EXR frames is a few hundred bytes (a foreign frame
        // with a longer header is rendered again, never taken as done).
        Work::Frames { .. } => read_head(&task.output, HEADER_BYTES).is_ok_and(|bytes| {
            let mut r = image::ImageReader::new(std::io::Cursor::new(&bytes[..]));
            if let Ok(format) = image::ImageFormat::from_path(&task.output) {
                r.set_format(format);
            }
            r.with_guessed_format()
                .is_ok_and(|r| r.into_dimensions().is_ok())
        }),
        Work::Chains { count, .. } => read_chain(&task.output).is_ok_and(|c| {
            c.info.chain == task.index && c.info.chains == *count && c.info.iterations > 0
        }),
    }
}

/// How much of a frame [`is_complete`] reads: its header, not a whole 8K image.
const HEADER_BYTES: u64 = 1 << 20;

/// At most `limit` bytes from the start of the file at `path`.
fn read_head(path: &std::path::Path, limit: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(limit)
        .read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// A job array's index list: runs of consecutive numbers as `a-b`, joined by commas
/// (`0-3,7,9-10`).
pub fn array_spec(indices: &[u32]) -> String {
    let mut sorted = indices.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    let mut parts = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let start = sorted[i];
        let mut end = start;
        while i + 1 < sorted.len() && sorted[i + 1] == end + 1 {
            end += 1;
            i += 1;
        }
        parts.push(if start == end {
            start.to_string()
        } else {
            format!("{start}-{end}")
        });
        i += 1;
    }
    parts.join(",")
}

/// `text` as one word of a POSIX shell: in single quotes, a `'` written `'\''`; plain words
/// (letters, digits, `-_./=%:,+`) as they are.
pub fn quote(text: &str) -> String {
    let plain = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=%:,+".contains(c));
    if plain {
        text.to_string()
    } else {
        format!("'{}'", text.replace('\'', "'\\''"))
    }
}

/// A Slurm partition name, or a comma-separated list of them (letters, digits, `_`, `-`,
/// `.`).
pub fn check_partition(p: &str) -> Result<(), String> {
    let name = |n: &str| {
        !n.is_empty()
            && n.chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
    };
    if p.split(',').all(name) {
        Ok(())
    } else {
        Err(format!(
            "`--partition {p:?}` is not a Slurm partition name (letters, digits, `_`, `-`, \
             `.`; several separated by commas)"
        ))
    }
}

/// A time limit in one of Slurm's forms: `minutes`, `minutes:seconds`,
/// `hours:minutes:seconds`, `days-hours`, `days-hours:minutes`, `days-hours:minutes:seconds`,
/// or `UNLIMITED` / `INFINITE`.
pub fn check_time(t: &str) -> Result<(), String> {
    let number = |n: &str| !n.is_empty() && n.len() <= 9 && n.bytes().all(|b| b.is_ascii_digit());
    let fields = |f: &str, most: usize| f.split(':').count() <= most && f.split(':').all(number);
    let ok = t.eq_ignore_ascii_case("unlimited")
        || t.eq_ignore_ascii_case("infinite")
        || match t.split_once('-') {
            Some((days, rest)) => number(days) && fields(rest, 3),
            None => fields(t, 3),
        };
    if ok {
        Ok(())
    } else {
        Err(format!(
            "`--time {t:?}` is not a Slurm time limit (`30`, `30:00`, `2:00:00`, `1-0`, \
             `1-12:00`, `1-12:00:00`, `UNLIMITED`)"
        ))
    }
}

/// The job id in `sbatch --parsable`'s output (`123` or `123;cluster`).
pub fn parse_job_id(stdout: &str) -> Option<u64> {
    let line = stdout.lines().map(str::trim).find(|l| !l.is_empty())?;
    line.split(';').next()?.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chains::{ChainInfo, write_chain};
    use crate::film::Image;

    fn farm(work: Work, tasks: Vec<Task>, dir: &Path) -> Farm {
        Farm {
            work,
            tasks,
            binary: "/opt/sppm lang/sppm-lang".into(),
            scene: "/data/it's.scn".into(),
            output: dir.join("f_%04d.png"),
            render_args: vec!["--iterations".into(), "4".into()],
            workdir: "/data".into(),
            dir: dir.join("farm"),
            name: "sppm-scene".into(),
            partition: Some("gpu".into()),
            time: Some("1:00:00".into()),
            cpus_per_task: 2,
        }
    }

    #[test]
    fn array_specs_join_runs() {
        assert_eq!(array_spec(&[3, 0, 1, 2, 7, 9, 10]), "0-3,7,9-10");
        assert_eq!(array_spec(&[5]), "5");
        assert_eq!(array_spec(&[2, 2, 4]), "2,4");
        assert_eq!(array_spec(&[]), "");
    }

    #[test]
    fn shell_words_are_quoted() {
        assert_eq!(quote("out_%04d.png"), "out_%04d.png");
        assert_eq!(quote("a b"), "'a b'");
        assert_eq!(quote("it's"), "'it'\\''s'");
        assert_eq!(quote("$HOME;rm"), "'$HOME;rm'");
        assert_eq!(quote(""), "''");
    }

    /// The values a batch script carries are checked: a newline in the time limit, the
    /// partition, a path or a render flag would start a directive or a command of its own.
    #[test]
    fn values_the_scripts_cannot_carry_are_refused() {
        for t in [
            "30",
            "30:00",
            "2:00:00",
            "1-0",
            "1-12:30",
            "1-12:30:00",
            "UNLIMITED",
        ] {
            assert_eq!(check_time(t), Ok(()), "{t}");
        }
        for t in [
            "",
            "1\n#SBATCH --wrap=x",
            "1:2:3:4",
            "a",
            "1-2-3",
            "1-",
            "-1",
            ":30",
            "1 h",
        ] {
            assert!(check_time(t).is_err(), "{t:?}");
        }
        for p in ["gpu", "debug,long", "part_1.a-b"] {
            assert_eq!(check_partition(p), Ok(()), "{p}");
        }
        for p in ["", "a\nb", "a b", "gpu,", "a;b"] {
            assert!(check_partition(p).is_err(), "{p:?}");
        }
        let dir = tempfile::tempdir().unwrap();
        let tasks = vec![Task {
            index: 0,
            output: dir.path().join("f_0000.png"),
        }];
        let good = farm(Work::Frames { first: 0, last: 0 }, tasks, dir.path());
        assert_eq!(good.check(), Ok(()));
        let mut f = good.clone();
        f.time = Some("1\necho INJECTED".into());
        assert!(f.check().is_err());
        let mut f = good.clone();
        f.workdir = "/data\n#SBATCH --wrap=x".into();
        assert!(f.check().unwrap_err().contains("control character"));
        let mut f = good.clone();
        f.tasks[0].output = dir.path().join("f\n0000.png");
        assert!(f.check().unwrap_err().contains("control character"));
        let mut f = good.clone();
        f.render_args.push("--seed\r".into());
        assert!(f.check().is_err());
        for set in [
            "--chain",
            "--chain=1/2",
            "-o",
            "-ox.png",
            "--threads",
            "--frames",
        ] {
            let mut f = good.clone();
            f.render_args.push(set.into());
            assert!(f.check().unwrap_err().contains("set by `farm`"), "{set}");
        }
    }

    #[test]
    fn job_ids_are_read_from_parsable_output() {
        assert_eq!(parse_job_id("1234\n"), Some(1234));
        assert_eq!(parse_job_id("77;cluster\n"), Some(77));
        assert_eq!(parse_job_id("Submitted batch job 5"), None);
        assert_eq!(parse_job_id(""), None);
    }

    /// Only frames without a complete image remain, and the array script names exactly them.
    #[test]
    fn finished_frames_are_skipped() {
        let dir = tempfile::tempdir().unwrap();
        let tasks: Vec<Task> = (0..4)
            .map(|k| Task {
                index: k,
                output: dir.path().join(format!("f_{k:04}.png")),
            })
            .collect();
        Image::new(2, 2).write(&tasks[1].output, 1.0).unwrap();
        // A truncated file is not a finished frame.
        std::fs::write(&tasks[2].output, b"\x89PNG").unwrap();
        let f = farm(Work::Frames { first: 0, last: 3 }, tasks, dir.path());
        let left: Vec<u32> = f.remaining().iter().map(|t| t.index).collect();
        assert_eq!(left, [0, 2, 3]);
        let script = f.array_script(&f.remaining());
        assert!(script.contains("#SBATCH --array=0,2-3\n"), "{script}");
        assert!(script.contains("#SBATCH --partition=gpu\n"), "{script}");
        assert!(script.contains("#SBATCH --time=1:00:00\n"), "{script}");
        assert!(script.contains("#SBATCH --cpus-per-task=2\n"), "{script}");
        assert!(
            script.contains(
                "exec '/opt/sppm lang/sppm-lang' render '/data/it'\\''s.scn' --frames 0..3 \
                 --frame \"$K\" -o "
            ),
            "{script}"
        );
        assert!(script.contains("--iterations 4\n"), "{script}");
        assert!(!f.merge_needed());
        assert_eq!(f.merge_script(), None);
    }

    /// EXR frames are read by their header as PNG ones are; a file named `.png` that holds
    /// an EXR is still a finished frame (the content decides), and an EXR cut inside its header
    /// is not.
    #[test]
    fn finished_exr_frames_are_skipped() {
        let dir = tempfile::tempdir().unwrap();
        let names = ["f_0.exr", "f_1.exr", "f_2.png", "f_3.exr", "f_4.exr"];
        let tasks: Vec<Task> = (0..5)
            .map(|k| Task {
                index: k,
                output: dir.path().join(names[k as usize]),
            })
            .collect();
        Image::new(3, 2).write(&tasks[0].output, 1.0).unwrap();
        Image::new(3, 2).write(&tasks[1].output, 1.0).unwrap();
        std::fs::copy(&tasks[1].output, &tasks[2].output).unwrap();
        let whole = std::fs::read(&tasks[1].output).unwrap();
        std::fs::write(&tasks[3].output, &whole[..20]).unwrap();
        // A frame longer than what the check reads: only its head is read, and it is done.
        let mut long = whole.clone();
        long.resize(2 * HEADER_BYTES as usize, 0);
        std::fs::write(&tasks[4].output, &long).unwrap();
        assert_eq!(
            read_head(&tasks[4].output, HEADER_BYTES).unwrap().len() as u64,
            HEADER_BYTES
        );
        let f = farm(Work::Frames { first: 0, last: 4 }, tasks, dir.path());
        let left: Vec<u32> = f.remaining().iter().map(|t| t.index).collect();
        assert_eq!(left, [3]);
    }

    /// A chain is done when its file is that chain's; the merge lists every chain.
    #[test]
    fn finished_chains_are_skipped_and_the_merge_lists_all() {
        let dir = tempfile::tempdir().unwrap();
        let merged = dir.path().join("m.exr");
        let tasks = chain_tasks(&merged, 3);
        assert_eq!(tasks[1].output, dir.path().join("m.chain2.exr"));
        let info = |chain, iterations| ChainInfo {
            iterations,
            photons: 10,
            method: "sppm".into(),
            seed: 1,
            chain,
            chains: 3,
            scene: 5,
        };
        let image = Image::new(2, 2);
        write_chain(&tasks[0].output, &image, &info(1, 2)).unwrap();
        // Chain 3's file holds chain 2: not chain 3's output.
        write_chain(&tasks[2].output, &image, &info(2, 2)).unwrap();
        let f = farm(
            Work::Chains {
                count: 3,
                merged: merged.clone(),
            },
            tasks,
            dir.path(),
        );
        let left: Vec<u32> = f.remaining().iter().map(|t| t.index).collect();
        assert_eq!(left, [2, 3]);
        let script = f.array_script(&f.remaining());
        assert!(script.contains("#SBATCH --array=2-3\n"), "{script}");
        assert!(script.contains("--chain \"$K/3\""), "{script}");
        let chain_out = format!("{}/m.chain", dir.path().display());
        assert!(script.contains(&chain_out), "{script}");
        assert!(f.merge_needed());
        let merge = f.merge_script().unwrap();
        assert!(merge.contains("--kill-on-invalid-dep=yes"), "{merge}");
        assert!(merge.contains("m.chain1.exr"), "{merge}");
        assert!(merge.contains("m.chain3.exr"), "{merge}");
        assert!(
            merge.contains(&format!("-o {}", quote(&merged.to_string_lossy()))),
            "{merge}"
        );
    }
}
