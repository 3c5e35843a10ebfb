//! Writing a file so that no reader ever sees half of it: the content goes to a temporary file
//! in the target's folder (same file system), which is then renamed over the target. The file
//! gets the permissions a plain `create` would give (0666 minus the umask), not the owner-only
//! mode of temporary files, so image viewers and web servers can read it.
//!
//! Only a regular file (or nothing) at the target is replaced: a symbolic link, a directory or
//! a device there is refused, so `-o` can never overwrite what a link points at. Temporary
//! files are named `.sppm-tmp-<pid>-<6 random letters or digits>.<ext>`; a process killed
//! mid-write (SIGKILL, power loss) leaves one behind, and a later write into that folder
//! removes those of exactly that form whose process is gone (on Linux, no `/proc/<pid>`) and
//! that were last written more than [`STALE_AFTER`] ago (a process in another pid namespace,
//! sharing the folder, is invisible in `/proc` but writes its file within seconds). No other
//! file is touched.

use std::fs::File;
use std::path::Path;

/// Writes `path` atomically. `fill` receives the temporary file's path (for writers that open
/// the file themselves) and the open file, and writes the content.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&Path, &mut File) -> Result<(), String>,
) -> Result<(), String> {
    write_atomic_group(vec![(path, Box::new(fill))])
}

/// How [`write_atomic_group`] fills one file (as `write_atomic`'s `fill`).
pub type Fill<'a> = Box<dyn FnOnce(&Path, &mut File) -> Result<(), String> + 'a>;

/// Writes several files all or none: each is filled into its own temporary file first, and
/// only when every one is complete are they renamed over their targets. A failure while
/// filling (a full disk) leaves every target as it was and no temporary behind. (A rename
/// failing after others succeeded, which a full disk cannot cause, would leave the earlier
/// targets replaced.)
pub fn write_atomic_group(files: Vec<(&Path, Fill<'_>)>) -> Result<(), String> {
    let mut done = Vec::with_capacity(files.len());
    for (path, fill) in files {
        let dir = folder_of(path);
        check_target(path)?;
        remove_stale(dir);
        let mut tmp = temp_in(dir, path)?;
        let tmp_path = tmp.path().to_path_buf();
        fill(&tmp_path, tmp.as_file_mut())?;
        done.push((path, tmp));
    }
    for (path, tmp) in done {
        // Checked again just before the rename: the path may have changed while `fill` ran.
        check_target(path)?;
        tmp.persist(path)
            .map_err(|e| format!("cannot write `{}`: {}", path.display(), e.error))?;
    }
    Ok(())
}

/// A new temporary file in `dir` for the target `path` (its extension kept, readable by all).
fn temp_in(dir: &Path, path: &Path) -> Result<tempfile::NamedTempFile, String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("tmp");
    let suffix = format!(".{ext}");
    let prefix = format!("{TEMP_PREFIX}{}-", std::process::id());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(&suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder
        .tempfile_in(dir)
        .map_err(|e| cannot_create_in(dir, &e))
}

const TEMP_PREFIX: &str = ".sppm-tmp-";
/// Length of the random part of a temporary file's name (`tempfile`'s default).
const RANDOM_LEN: usize = 6;
/// Age after which a temporary file of a process that is not running is removed.
pub const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(600);

/// "cannot create a file in `dir`: <the OS's reason>" (tempfile's error names the temporary
/// file, a name the user never chose; only the OS's reason is kept).
fn cannot_create_in(dir: &Path, e: &std::io::Error) -> String {
    let text = e.to_string();
    let reason = text.split(" at path ").next().unwrap_or(&text);
    format!("cannot create a file in `{}`: {reason}", dir.display())
}

/// The folder `path` is written in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Checks, before any work is done, that [`write_atomic`] can write `path` later: the target
/// is absent or a regular file ([`check_target`]), its folder exists and accepts a new file
/// (a temporary file is created there and removed: this also catches a read-only file
/// system, which binds even the superuser), and it is none of `inputs`, the files the job
/// reads (the scene, its includes, images, meshes): writing there would destroy one. An
/// input is the target when both name the same directory entry after symbolic links are
/// resolved (a hard link to an input is another entry: replacing it leaves the input whole).
pub fn check_output<P: AsRef<Path>>(path: &Path, inputs: &[P]) -> Result<(), String> {
    // `out.png/` or `out.png/.` names a folder: the final rename would fail.
    let named = path.file_name().is_some_and(|n| {
        path.as_os_str()
            .as_encoded_bytes()
            .ends_with(n.as_encoded_bytes())
    });
    if !named {
        return Err(format!(
            "output `{}` does not end in a file name",
            path.display()
        ));
    }
    check_target(path)?;
    let dir = folder_of(path);
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(format!(
                "the folder `{}` of output `{}` is not a directory",
                dir.display(),
                path.display()
            ));
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(format!(
                "the folder `{}` of output `{}` does not exist (create it first)",
                dir.display(),
                path.display()
            ));
        }
        Err(e) => {
            return Err(format!(
                "the folder `{}` of output `{}` cannot be used: {e}",
                dir.display(),
                path.display()
            ));
        }
    }
    tempfile::Builder::new()
        .prefix(&format!("{TEMP_PREFIX}{}-", std::process::id()))
        .tempfile_in(dir)
        .map_err(|e| cannot_create_in(dir, &e))?;
    let target = path
        .file_name()
        .and_then(|name| Some(dir.canonicalize().ok()?.join(name)));
    if let Some(target) = target {
        for input in inputs {
            if input.as_ref().canonicalize().is_ok_and(|i| i == target) {
                return Err(format!(
                    "output `{}` is `{}`, which this command reads; writing there would \
                     destroy it (choose another output path)",
                    path.display(),
                    input.as_ref().display()
                ));
            }
        }
    }
    Ok(())
}

/// Refuses a target that exists and is not a regular file (not following a symbolic link),
/// and a path the system cannot use (a name too long, a file where a folder should be).
pub fn check_target(path: &Path) -> Result<(), String> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_file() => Ok(()),
        Ok(m) => {
            let what = if m.file_type().is_symlink() {
                "a symbolic link"
            } else if m.is_dir() {
                "a directory"
            } else {
                "not a regular file"
            };
            Err(format!(
                "output `{}` is {what}; only a regular file is replaced (remove it or choose \
                 another path)",
                path.display()
            ))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(format!("output `{}` cannot be used: {e}", path.display())),
    }
}

/// Removes the temporary files in `dir` that a process which no longer runs left behind (see
/// the module's docs). Best effort; errors are ignored.
fn remove_stale(dir: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_file_pid) else {
            continue;
        };
        let alive = Path::new("/proc").join(pid.to_string()).exists();
        let old = entry
            .metadata()
            .ok()
            .filter(|m| m.file_type().is_file())
            .and_then(|m| m.modified().ok())
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > STALE_AFTER);
        if !alive && old {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// The process id in a temporary file's name, for names of exactly the form this module
/// gives them: `.sppm-tmp-<pid>-<RANDOM_LEN letters or digits>.<letters or digits>`.
fn temp_file_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(TEMP_PREFIX)?;
    let (pid, rest) = rest.split_once('-')?;
    let (random, ext) = rest.split_once('.')?;
    let form = !pid.is_empty()
        && pid.bytes().all(|b| b.is_ascii_digit())
        && random.len() == RANDOM_LEN
        && random.bytes().all(|b| b.is_ascii_alphanumeric())
        && !ext.is_empty()
        && ext.bytes().all(|b| b.is_ascii_alphanumeric());
    if form { pid.parse().ok() } else { None }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn links_and_special_files_at_the_target_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.png");
        std::fs::write(&real, "keep").unwrap();
        let link = dir.path().join("link.png");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let write = |p: &Path| {
            write_atomic(p, |_, f| {
                use std::io::Write;
                f.write_all(b"new").map_err(|e| e.to_string())
            })
        };
        let e = write(&link).unwrap_err();
        assert!(e.contains("symbolic link"), "{e}");
        assert_eq!(std::fs::read_to_string(&real).unwrap(), "keep");
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        let e = write(dir.path()).unwrap_err();
        assert!(e.contains("directory") || e.contains("cannot"), "{e}");
        let e = write(Path::new("/dev/null")).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
    }

    #[test]
    fn an_output_is_checked_before_any_work() {
        let dir = tempfile::tempdir().unwrap();
        let none: &[&Path] = &[];
        let fine = dir.path().join("out.png");
        check_output(&fine, none).unwrap();
        // The probe leaves nothing behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        let e = check_output(&dir.path().join("missing/out.png"), none).unwrap_err();
        assert!(e.contains("does not exist"), "{e}");
        let file = dir.path().join("scene.scn");
        std::fs::write(&file, "sphere {}").unwrap();
        let e = check_output(&file.join("out.png"), none).unwrap_err();
        assert!(e.contains("cannot be used"), "{e}");
        for folder_like in ["out.png/", "out.png/.", "..", "/"] {
            let e = check_output(&dir.path().join(folder_like), none).unwrap_err();
            assert!(e.contains("does not end in a file name"), "{e}");
        }
        let long = dir.path().join(format!("{}.png", "a".repeat(5000)));
        let e = check_output(&long, none).unwrap_err();
        assert!(e.contains("cannot be used"), "{e}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn an_output_that_is_an_input_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("scene.png");
        std::fs::write(&scene, "sphere {}").unwrap();
        let e = check_output(&scene, &[&scene]).unwrap_err();
        assert!(e.contains("which this command reads"), "{e}");
        // The same file by another spelling of its path.
        let other = dir.path().join(".").join("scene.png");
        assert!(check_output(&other, &[&scene]).is_err());
        // An input that is a link to the output: writing would replace what it reads.
        #[cfg(unix)]
        {
            let link = dir.path().join("link.scn");
            std::os::unix::fs::symlink(&scene, &link).unwrap();
            assert!(check_output(&scene, &[&link]).is_err());
            // A hard link is another directory entry: replacing it leaves the input whole.
            let hard = dir.path().join("hard.png");
            std::fs::hard_link(&scene, &hard).unwrap();
            check_output(&hard, &[&scene]).unwrap();
        }
        // Inputs that are not the output, or do not exist, are no obstacle.
        let missing = dir.path().join("missing.png");
        check_output(&dir.path().join("out.png"), &[&scene, &missing]).unwrap();
    }

    /// Only files of exactly the temporary form, of a process that is gone, and older than
    /// [`STALE_AFTER`] are removed: a user's file that merely starts like one (a scene named
    /// `.sppm-99999-myscene.scn`, notes `.sppm-4000000-notes.txt`) is never touched, nor is
    /// a fresh temporary file of a process this one cannot see.
    #[test]
    fn stale_temporary_files_of_dead_processes_are_removed() {
        if !Path::new("/proc/self").exists() {
            eprintln!("skipped: no /proc to tell live processes");
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let long_ago = std::time::SystemTime::now() - STALE_AFTER * 2;
        let file = |name: &str, old: bool| {
            let p = dir.path().join(name);
            std::fs::write(&p, "x").unwrap();
            if old {
                let f = std::fs::File::options().write(true).open(&p).unwrap();
                f.set_modified(long_ago).unwrap();
            }
            p
        };
        // A pid far above the kernel's maximum (4194304) belongs to no process.
        let stale = file(".sppm-tmp-999999999-aB3xY9.png", true);
        let fresh = file(".sppm-tmp-999999999-aB3xY8.png", false);
        let live = file(
            &format!(".sppm-tmp-{}-def123.png", std::process::id()),
            true,
        );
        let kept = [
            file("notes.txt", true),
            file(".sppm-4000000-notes.txt", true),
            file(".sppm-99999-myscene.scn", true),
            file(".sppm-tmp-999999999-toolong1.png", true),
            file(".sppm-tmp-999999999-aB3xY9.png.bak", true),
            file(".sppm-tmp-999999999-aB3xY9.p-g", true),
            file(".sppm-tmp-x99-aB3xY9.png", true),
        ];
        write_atomic(&dir.path().join("out.png"), |_, _| Ok(())).unwrap();
        assert!(
            !stale.exists(),
            "a dead process's old temporary file is left"
        );
        assert!(fresh.exists(), "a fresh temporary file was removed");
        assert!(live.exists(), "a live process's temporary file was removed");
        for p in &kept {
            assert!(p.exists(), "{} was removed", p.display());
        }
        // The names this module gives are of the form it removes.
        let t = temp_in(dir.path(), &dir.path().join("a.exr")).unwrap();
        let name = t.path().file_name().unwrap().to_str().unwrap().to_string();
        assert_eq!(temp_file_pid(&name), Some(std::process::id()), "{name}");
    }

    /// A group whose second file fails leaves both targets as they were (the first one not
    /// replaced by its new, complete content) and no temporary file; a group that succeeds
    /// replaces both.
    #[test]
    fn a_group_is_written_all_or_none() {
        use std::io::Write;
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.json"));
        std::fs::write(&a, "old a").unwrap();
        std::fs::write(&b, "old b").unwrap();
        let put = |text: &'static str| -> Fill<'static> {
            Box::new(move |_, f| f.write_all(text.as_bytes()).map_err(|e| e.to_string()))
        };
        let fail: Fill<'static> = Box::new(|_, f| {
            f.write_all(b"half").unwrap();
            Err("no space left".to_string())
        });
        assert!(
            write_atomic_group(vec![(a.as_path(), put("new a")), (b.as_path(), fail)]).is_err()
        );
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "old b");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
        write_atomic_group(vec![
            (a.as_path(), put("new a")),
            (b.as_path(), put("new b")),
        ])
        .unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn writes_whole_files_and_leaves_nothing_on_failure() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.txt");
        write_atomic(&target, |_, f| {
            use std::io::Write;
            f.write_all(b"first").map_err(|e| e.to_string())
        })
        .unwrap();
        // A failing writer leaves the previous content and no temporary file.
        let err = write_atomic(&target, |_, f| {
            use std::io::Write;
            f.write_all(b"half").unwrap();
            Err("encoder failed".to_string())
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "first");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&target).unwrap().permissions().mode();
            // Readable by others unless the umask forbids it (the usual 022 does not).
            assert_eq!(mode & 0o600, 0o600, "{mode:o}");
            assert_ne!(
                mode & 0o777,
                0o600,
                "owner-only like a temporary file: {mode:o}"
            );
        }
    }
}
