//! The files a document includes, found from its text (also when it does not parse), read
//! through the load's [`World`] so that an editor's unsaved buffers count: where the names in
//! scope come from, and where go-to-definition leads.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::outline::Outline;
use crate::world::World;

/// The deepest chain of includes followed, and the most files read for one request.
const MAX_DEPTH: usize = 8;
const MAX_FILES: usize = 32;
/// Larger included files are left out of completion and navigation (not of diagnostics).
pub const MAX_ANALYSED_BYTES: u64 = 4 << 20;

/// An included file: its path (for a standard file, its `std/...` name), text and outline.
pub struct Included {
    pub path: PathBuf,
    /// A standard file, built into the binary (no file on disk).
    pub builtin: bool,
    pub text: Arc<str>,
    pub outline: Outline,
}

/// Where `#include "name"` in the file `from` leads: a standard file's name as it is, else
/// relative to the including file's folder (as the evaluator resolves it).
pub fn resolve(from: &Path, name: &str) -> (PathBuf, bool) {
    if builtin(name).is_some() {
        return (PathBuf::from(name), true);
    }
    let p = Path::new(name);
    if p.is_absolute() {
        return (p.to_path_buf(), false);
    }
    let dir = from.parent().unwrap_or(Path::new(""));
    (crate::world::normalize(&dir.join(p)), false)
}

/// The text of a standard file (`std/colors.scn`).
pub fn builtin(name: &str) -> Option<&'static str> {
    crate::eval::STD_FILES
        .iter()
        .find(|(p, _)| *p == name)
        .map(|(_, t)| *t)
}

/// The files `path` (whose outline is `outline`) includes, directly or through others, each
/// once, in the order first met.
pub fn included(world: &dyn World, path: &Path, outline: &Outline) -> Vec<Included> {
    let mut out: Vec<Included> = Vec::new();
    let mut seen = vec![crate::world::normalize(path)];
    let mut todo: Vec<(PathBuf, String, usize)> = outline
        .includes
        .iter()
        .rev()
        .map(|i| (path.to_path_buf(), i.path.clone(), 1))
        .collect();
    while let Some((from, name, depth)) = todo.pop() {
        if out.len() >= MAX_FILES {
            break;
        }
        let (p, is_builtin) = resolve(&from, &name);
        if seen.contains(&p) {
            continue;
        }
        seen.push(p.clone());
        let text: Arc<str> = match builtin(&name) {
            Some(t) => t.into(),
            None => match crate::world::read_text(world, &p, MAX_ANALYSED_BYTES) {
                Ok(t) => t.into(),
                Err(_) => continue,
            },
        };
        let outline = Outline::new(&text);
        if depth < MAX_DEPTH {
            for i in outline.includes.iter().rev() {
                todo.push((p.clone(), i.path.clone(), depth + 1));
            }
        }
        out.push(Included {
            path: p,
            builtin: is_builtin,
            text,
            outline,
        });
    }
    out
}
