//! Writing a file so that no reader ever sees half of it: the content goes to a temporary file
//! in the target's folder (same file system), which is then renamed over the target. The file
//! gets the permissions a plain `create` would give (0666 minus the umask), not the owner-only
//! mode of temporary files, so image viewers and web servers can read it.

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
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("tmp");
    let suffix = format!(".{ext}");
    let mut builder = tempfile::Builder::new();
    builder.prefix(".sppm-").suffix(&suffix);
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
    tmp.persist(path)
        .map_err(|e| format!("cannot write `{}`: {}", path.display(), e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
