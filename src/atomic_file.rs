//! Writing a file so that no reader ever sees half of it: the content goes to a temporary file
//! in the target's folder (same file system), which is then renamed over the target. The file
//! gets the permissions a plain `create` would give (0666 minus the umask), not the owner-only
//! mode of temporary files, so image viewers and web servers can read it.
//!
//! Only a regular file (or nothing) at the target is replaced: a symbolic link, a directory or
//! a device there is refused, so `-o` can never overwrite what a link points at. Temporary
//! files are named `.sppm-<pid>-...`; a process killed mid-write (SIGKILL, power loss) leaves
//! one behind, and the next write into that folder removes those whose process is gone.

use std::fs::File;
use std::path::Path;

/// Writes `path` atomically. `fill` receives the temporary file's path (for writers that open
/// the file themselves) and the open file, and writes the content.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&Path, &mut File) -> Result<(), String>,
) -> Result<(), String> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    check_target(path)?;
    remove_stale(dir);
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
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(|e| format!("cannot create a file in `{}`: {e}", dir.display()))?;
    let tmp_path = tmp.path().to_path_buf();
    fill(&tmp_path, tmp.as_file_mut())?;
    // Checked again just before the rename: the path may have changed while `fill` ran.
    check_target(path)?;
    tmp.persist(path)
        .map_err(|e| format!("cannot write `{}`: {}", path.display(), e.error))?;
    Ok(())
}

const TEMP_PREFIX: &str = ".sppm-";

/// Refuses a target that exists and is not a regular file (not following a symbolic link).
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
        Err(_) => Ok(()),
    }
}

/// Removes `.sppm-<pid>-*` temporary files in `dir` whose process no longer runs (where that
/// can be told: on Linux, by `/proc/<pid>`). Best effort; errors are ignored.
fn remove_stale(dir: &Path) {
    let proc_root = Path::new("/proc/self");
    if !proc_root.exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(TEMP_PREFIX)) else {
            continue;
        };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        let alive = Path::new("/proc").join(pid.to_string()).exists();
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if !alive && is_file {
            let _ = std::fs::remove_file(entry.path());
        }
    }
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
    fn stale_temporary_files_of_dead_processes_are_removed() {
        if !Path::new("/proc/self").exists() {
            eprintln!("skipped: no /proc to tell live processes");
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        // A pid far above the kernel's maximum (4194304) belongs to no process.
        let stale = dir.path().join(".sppm-999999999-abc.png");
        let live = dir
            .path()
            .join(format!(".sppm-{}-def.png", std::process::id()));
        let other = dir.path().join("notes.txt");
        for p in [&stale, &live, &other] {
            std::fs::write(p, "x").unwrap();
        }
        write_atomic(&dir.path().join("out.png"), |_, _| Ok(())).unwrap();
        assert!(!stale.exists(), "a dead process's temporary file is left");
        assert!(live.exists(), "a live process's temporary file was removed");
        assert!(other.exists());
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
