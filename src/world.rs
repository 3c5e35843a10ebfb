//! Where a load's files come from: the scene file, its includes and the assets it names
//! (images, OBJ meshes). Every read of the evaluation goes through a [`World`], so a program
//! (a test, an embedder, an editor with unsaved buffers) can supply the files from memory
//! ([`MemoryWorld`]) instead of the disk ([`FileSystem`], the default).
//!
//! A world answers for one load at a time and may be read from the evaluation's thread, hence
//! `Send + Sync`. The limits (bytes per file, the whole load's text) are the caller's: each
//! read says how many bytes it accepts, and every world refuses a larger file the same way.

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

use crate::files::FileError;

/// A source of files for a load.
pub trait World: Send + Sync {
    /// The bytes of the regular file at `path`, at most `max_bytes` of them (a larger file is
    /// [`FileError::Refused`]; a missing one an [`FileError::Io`] of kind `NotFound`).
    fn read(&self, path: &Path, max_bytes: u64) -> Result<Vec<u8>, FileError>;

    /// The size in bytes of the regular file at `path`; `None` when there is none.
    fn size(&self, path: &Path) -> Option<u64>;

    /// The one name of the file `path` names (two paths of one file compare equal): includes
    /// compare these to find a cycle.
    fn canonical(&self, path: &Path) -> PathBuf;
}

/// The text of the file at `path` in `world` (UTF-8), at most `max_bytes` bytes.
pub fn read_text(world: &dyn World, path: &Path, max_bytes: u64) -> Result<String, FileError> {
    let bytes = world.read(path, max_bytes)?;
    String::from_utf8(bytes).map_err(|e| {
        FileError::Refused(format!(
            "`{}` is not UTF-8 text (invalid byte at offset {})",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })
}

/// The disk, read within the checks of [`crate::files`]: only regular files (a FIFO or device
/// is refused before it is opened), never more than the limit.
#[derive(Debug, Clone, Copy, Default)]
pub struct FileSystem;

impl World for FileSystem {
    fn read(&self, path: &Path, max_bytes: u64) -> Result<Vec<u8>, FileError> {
        crate::files::read_bytes_parallel(path, max_bytes)
    }

    fn size(&self, path: &Path) -> Option<u64> {
        std::fs::metadata(path)
            .ok()
            .filter(|m| m.is_file())
            .map(|m| m.len())
    }

    fn canonical(&self, path: &Path) -> PathBuf {
        std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
    }
}

/// Files held in memory, by path. Paths are compared after [`normalize`] (`a/./b` and
/// `a/c/../b` are `a/b`); a relative path stays relative (includes resolve against the
/// including file's folder, as on disk).
#[derive(Debug, Clone, Default)]
pub struct MemoryWorld {
    files: HashMap<PathBuf, Arc<[u8]>>,
}

impl MemoryWorld {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds (or replaces) the file `path` with `bytes`.
    pub fn insert(&mut self, path: impl AsRef<Path>, bytes: impl Into<Vec<u8>>) {
        self.files
            .insert(normalize(path.as_ref()), bytes.into().into());
    }

    /// [`MemoryWorld::insert`] without a copy of bytes already shared.
    pub fn insert_shared(&mut self, path: impl AsRef<Path>, bytes: Arc<[u8]>) {
        self.files.insert(normalize(path.as_ref()), bytes);
    }

    /// [`MemoryWorld::insert`], by value (to build a world in one expression).
    pub fn with(mut self, path: impl AsRef<Path>, bytes: impl Into<Vec<u8>>) -> Self {
        self.insert(path, bytes);
        self
    }
}

impl World for MemoryWorld {
    fn read(&self, path: &Path, max_bytes: u64) -> Result<Vec<u8>, FileError> {
        let Some(bytes) = self.files.get(&normalize(path)) else {
            return Err(FileError::Io(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no such file in memory",
            )));
        };
        if bytes.len() as u64 > max_bytes {
            return Err(FileError::Refused(format!(
                "`{}` is {} bytes, more than the limit of {max_bytes} bytes",
                path.display(),
                bytes.len()
            )));
        }
        Ok(bytes.to_vec())
    }

    fn size(&self, path: &Path) -> Option<u64> {
        self.files.get(&normalize(path)).map(|b| b.len() as u64)
    }

    fn canonical(&self, path: &Path) -> PathBuf {
        normalize(path)
    }
}

/// Files held in memory over another world: an editor's unsaved buffers over the disk. A path
/// the overlay holds is read from memory (compared after [`normalize`]); any other from `base`.
#[derive(Debug, Clone, Default)]
pub struct Overlay<W> {
    files: MemoryWorld,
    base: W,
}

impl<W: World> Overlay<W> {
    pub fn new(base: W) -> Self {
        Self {
            files: MemoryWorld::new(),
            base,
        }
    }

    /// Adds (or replaces) the file `path` with `bytes`, over the base's file of that name.
    pub fn insert(&mut self, path: impl AsRef<Path>, bytes: impl Into<Vec<u8>>) {
        self.files.insert(path, bytes);
    }

    /// [`Overlay::insert`] without a copy of bytes already shared.
    pub fn insert_shared(&mut self, path: impl AsRef<Path>, bytes: Arc<[u8]>) {
        self.files.insert_shared(path, bytes);
    }

    fn holds(&self, path: &Path) -> bool {
        self.files.size(path).is_some()
    }
}

impl<W: World> World for Overlay<W> {
    fn read(&self, path: &Path, max_bytes: u64) -> Result<Vec<u8>, FileError> {
        if self.holds(path) {
            self.files.read(path, max_bytes)
        } else {
            self.base.read(path, max_bytes)
        }
    }

    fn size(&self, path: &Path) -> Option<u64> {
        self.files.size(path).or_else(|| self.base.size(path))
    }

    fn canonical(&self, path: &Path) -> PathBuf {
        if self.holds(path) {
            normalize(path)
        } else {
            self.base.canonical(path)
        }
    }
}

/// `path` without `.` components and with each `..` taking off the component before it (a
/// leading `..` of a relative path is kept).
pub fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if matches!(out.components().next_back(), Some(Component::Normal(_))) {
                    out.pop();
                } else if !out.has_root() {
                    out.push("..");
                }
            }
            other => out.push(other),
        }
    }
    out
}

/// A shared [`World`], as the options of a load hold it: the disk unless set. Two handles are
/// equal when they share one world.
#[derive(Clone)]
pub struct SharedWorld(Arc<dyn World>);

impl SharedWorld {
    pub fn new(world: impl World + 'static) -> Self {
        Self(Arc::new(world))
    }
}

impl Default for SharedWorld {
    fn default() -> Self {
        Self::new(FileSystem)
    }
}

impl std::ops::Deref for SharedWorld {
    type Target = dyn World;
    fn deref(&self) -> &Self::Target {
        &*self.0
    }
}

impl From<Arc<dyn World>> for SharedWorld {
    fn from(world: Arc<dyn World>) -> Self {
        Self(world)
    }
}

impl std::fmt::Debug for SharedWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SharedWorld")
    }
}

impl PartialEq for SharedWorld {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_paths_are_normalized_and_limits_hold() {
        let w = MemoryWorld::new().with("dir/a.scn", "sphere {}");
        assert_eq!(
            read_text(&w, Path::new("dir/./sub/../a.scn"), 100).unwrap(),
            "sphere {}"
        );
        assert_eq!(w.size(Path::new("dir/a.scn")), Some(9));
        assert_eq!(
            w.canonical(Path::new("dir/x/../a.scn")),
            Path::new("dir/a.scn")
        );
        let e = w.read(Path::new("dir/a.scn"), 8).unwrap_err().to_string();
        assert!(e.contains("more than the limit"), "{e}");
        match w.read(Path::new("missing.scn"), 100) {
            Err(FileError::Io(e)) => assert_eq!(e.kind(), std::io::ErrorKind::NotFound),
            other => panic!("{other:?}"),
        }
        assert_eq!(normalize(Path::new("../a/../../b")), Path::new("../../b"));
        assert_eq!(normalize(Path::new("/../a")), Path::new("/a"));
    }

    #[test]
    fn an_overlay_reads_its_own_files_first() {
        let base = MemoryWorld::new()
            .with("d/a.scn", "disk a")
            .with("d/b.scn", "disk b");
        let mut w = Overlay::new(base);
        w.insert("d/a.scn", "buffer a");
        assert_eq!(
            read_text(&w, Path::new("d/./a.scn"), 100).unwrap(),
            "buffer a"
        );
        assert_eq!(read_text(&w, Path::new("d/b.scn"), 100).unwrap(), "disk b");
        assert_eq!(w.size(Path::new("d/a.scn")), Some(8));
        assert!(w.read(Path::new("d/a.scn"), 3).is_err());
        assert!(w.read(Path::new("d/c.scn"), 100).is_err());
    }

    #[test]
    fn the_file_system_keeps_the_checks_of_files() {
        let dir = tempfile::tempdir().unwrap();
        let e = FileSystem.read(dir.path(), 100).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        assert_eq!(FileSystem.size(dir.path()), None);
        let p = dir.path().join("a.scn");
        std::fs::write(&p, [0xff, b'x']).unwrap();
        assert_eq!(FileSystem.size(&p), Some(2));
        let e = read_text(&FileSystem, &p, 100).unwrap_err().to_string();
        assert!(e.contains("not UTF-8"), "{e}");
    }
}
