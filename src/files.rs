//! Reading the files a scene names (the scene itself, includes, OBJ meshes, images) within
//! limits: only regular files are read (a directory, device, FIFO or socket is refused before
//! it is opened, so `/dev/zero` or a pipe cannot stall or flood a load), and never more than a
//! given number of bytes, checked both against the size the file system reports and while
//! reading (a file that grows meanwhile is cut off and refused).
//!
//! A [`FileError`] keeps the operating system's error (a caller acts on its kind: a missing
//! file is watched for until it appears); it becomes a diagnostic at the place that named the
//! file, or with [`FileError::to_diagnostic`] when no source names it.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::diag::Diagnostic;

/// Largest scene or include file read: 256 MiB (a generated scene of 100 000 objects is 7 MB).
pub const MAX_SOURCE_BYTES: u64 = 256 << 20;
/// Largest OBJ mesh or image file read: 1 GiB.
pub const MAX_ASSET_BYTES: u64 = 1 << 30;

/// Why a file was not read.
#[derive(Debug)]
pub enum FileError {
    /// The operating system's error (missing file, no permission, ...).
    Io(std::io::Error),
    /// The file was refused (not a regular file, too large, not text); the message says why.
    Refused(String),
}

impl std::fmt::Display for FileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FileError::Io(e) => write!(f, "{e}"),
            FileError::Refused(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for FileError {}

impl FileError {
    /// The message with the path: `cannot read `p`: ...` for an OS error, the refusal as it is.
    pub fn with_path(&self, path: &Path) -> String {
        match self {
            FileError::Io(e) => format!("cannot read `{}`: {e}", path.display()),
            FileError::Refused(m) => m.clone(),
        }
    }

    /// The error about `path` as a diagnostic at no place in the sources (the scene file a
    /// command line or a library call names).
    pub fn to_diagnostic(&self, path: &Path) -> Diagnostic {
        Diagnostic::unplaced(self.with_path(path))
    }
}

/// What kind of file `path` is, in words, when it is not a regular file.
fn not_regular(meta: &std::fs::Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a named pipe (FIFO)");
        }
        if t.is_socket() {
            return Some("a socket");
        }
        if t.is_char_device() || t.is_block_device() {
            return Some("a device");
        }
    }
    Some("not a regular file")
}

/// Opens `path` for reading if it is a regular file of at most `max_bytes` bytes.
pub fn open_regular(path: &Path, max_bytes: u64) -> Result<File, FileError> {
    let shown = path.display();
    let refuse = |kind: &str| {
        FileError::Refused(format!("`{shown}` is {kind}, not a file that can be read"))
    };
    let meta = std::fs::metadata(path).map_err(FileError::Io)?;
    if let Some(kind) = not_regular(&meta) {
        return Err(refuse(kind));
    }
    if meta.len() > max_bytes {
        return Err(FileError::Refused(format!(
            "`{shown}` is {} bytes, more than the limit of {max_bytes} bytes",
            meta.len()
        )));
    }
    let file = File::open(path).map_err(FileError::Io)?;
    // The path may have been replaced between the two looks: check what was opened (a FIFO
    // swapped in at that moment would block the open itself; that race is not closed here).
    let meta = file.metadata().map_err(FileError::Io)?;
    if let Some(kind) = not_regular(&meta) {
        return Err(refuse(kind));
    }
    Ok(file)
}

/// The bytes of the regular file `path`, at most `max_bytes` of them.
pub fn read_bytes(path: &Path, max_bytes: u64) -> Result<Vec<u8>, FileError> {
    let file = open_regular(path, max_bytes)?;
    let hint = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut bytes = Vec::with_capacity(hint.min(max_bytes) as usize);
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(FileError::Io)?;
    if bytes.len() as u64 > max_bytes {
        return Err(FileError::Refused(format!(
            "`{}` grew past the limit of {max_bytes} bytes while it was read",
            path.display()
        )));
    }
    Ok(bytes)
}

/// [`read_bytes`], a large file in pieces read in parallel: the copies from the page cache and
/// the first touches of the buffer's pages happen on every core. A file whose size changes
/// while it is read is read again by [`read_bytes`] (which refuses one that grew too large).
pub fn read_bytes_parallel(path: &Path, max_bytes: u64) -> Result<Vec<u8>, FileError> {
    #[cfg(unix)]
    {
        use rayon::prelude::*;
        use std::os::unix::fs::FileExt;
        /// Bytes per piece; files under four pieces are read in one.
        const PIECE: usize = 1 << 20;
        let file = open_regular(path, max_bytes)?;
        let len = file.metadata().map_err(FileError::Io)?.len();
        if len >= 4 * PIECE as u64 {
            let mut bytes = vec![0u8; len as usize];
            // Whether every piece was read whole (a short read: the file shrank).
            let whole = bytes
                .par_chunks_mut(PIECE)
                .enumerate()
                .map(|(k, piece)| {
                    let mut at = 0;
                    while at < piece.len() {
                        match file.read_at(&mut piece[at..], (k * PIECE + at) as u64) {
                            Ok(0) => return Ok(false),
                            Ok(n) => at += n,
                            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                            Err(e) => return Err(e),
                        }
                    }
                    Ok(true)
                })
                .try_reduce(|| true, |a, b| Ok(a && b))
                .map_err(FileError::Io)?;
            if whole && file.read_at(&mut [0], len).map_err(FileError::Io)? == 0 {
                return Ok(bytes);
            }
        }
    }
    read_bytes(path, max_bytes)
}

/// The text of the regular file `path` (UTF-8), at most `max_bytes` bytes.
pub fn read_text(path: &Path, max_bytes: u64) -> Result<String, FileError> {
    let bytes = read_bytes(path, max_bytes)?;
    String::from_utf8(bytes).map_err(|e| {
        FileError::Refused(format!(
            "`{}` is not UTF-8 text (invalid byte at offset {})",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_files_are_read_whole() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.scn");
        std::fs::write(&p, "sphere {}").unwrap();
        assert_eq!(read_text(&p, 100).unwrap(), "sphere {}");
    }

    /// Files of a few sizes around the piece size read in parallel byte for byte as the plain
    /// read gives them; the limit and special files are refused as by [`read_bytes`].
    #[test]
    fn large_files_read_in_parallel_whole_and_in_order() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.obj");
        for len in [10, (4 << 20) - 1, 4 << 20, (5 << 20) + 12_345] {
            let bytes: Vec<u8> = (0..len as u32)
                .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8)
                .collect();
            std::fs::write(&p, &bytes).unwrap();
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(3)
                .build()
                .unwrap();
            let got = pool.install(|| read_bytes_parallel(&p, 1 << 30)).unwrap();
            assert!(got == bytes, "{len} bytes");
            let e = read_bytes_parallel(&p, len as u64 - 1)
                .unwrap_err()
                .to_string();
            assert!(e.contains("more than the limit"), "{e}");
        }
        let e = read_bytes_parallel(dir.path(), 100)
            .unwrap_err()
            .to_string();
        assert!(e.contains("a directory"), "{e}");
    }

    #[test]
    fn special_files_and_large_files_are_refused_without_reading() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_bytes(dir.path(), 100).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        #[cfg(unix)]
        {
            // Reading /dev/zero would never end; it must be refused at once.
            let e = read_bytes(Path::new("/dev/zero"), 100)
                .unwrap_err()
                .to_string();
            assert!(e.contains("a device"), "{e}");
        }
        let p = dir.path().join("big.obj");
        std::fs::write(&p, vec![b'v'; 1000]).unwrap();
        let e = read_bytes(&p, 999).unwrap_err().to_string();
        assert!(e.contains("more than the limit"), "{e}");
        assert_eq!(read_bytes(&p, 1000).unwrap().len(), 1000);
        std::fs::write(&p, [0xff, 0xfe, b'x']).unwrap();
        let e = read_text(&p, 1000).unwrap_err().to_string();
        assert!(e.contains("not UTF-8"), "{e}");
        let missing = dir.path().join("missing");
        let e = read_text(&missing, 10).unwrap_err().with_path(&missing);
        assert!(e.starts_with("cannot read `"), "{e}");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("pipe.scn");
        let ok = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .map(|s| s.success())
            .unwrap_or(false);
        if !ok {
            eprintln!("skipped: mkfifo is not available");
            return;
        }
        // Opening a FIFO for reading blocks until a writer comes; the check comes first.
        let e = read_text(&p, 100).unwrap_err().to_string();
        assert!(e.contains("named pipe"), "{e}");
    }
}
