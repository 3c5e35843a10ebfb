//! The table of source files a load read, indexed by [`FileId`].

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::span::{FileId, Span};

/// Bytes between two checkpoints of a file's line index: locating an offset reads at most this
/// many bytes, whatever the file's size.
const BLOCK: usize = 4096;

/// Where the byte at a multiple of [`BLOCK`] sits: its line (0-based), where that line starts,
/// and its column in characters (0-based).
#[derive(Debug, Clone, Copy)]
struct Checkpoint {
    line: usize,
    line_start: usize,
    column: usize,
}

/// A position in a file: 0-based line, the line's first byte, 0-based column in characters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    pub line: usize,
    pub line_start: usize,
    pub column: usize,
}

/// One source file: its path (as given or resolved), a display name, and its text.
#[derive(Debug, Clone)]
pub struct SourceFile {
    pub path: PathBuf,
    pub name: String,
    pub text: Arc<str>,
    /// One checkpoint per [`BLOCK`] bytes, so that a diagnostic finds its line without
    /// counting every line before it (thousands of diagnostics in a large file stay linear).
    index: Arc<[Checkpoint]>,
}

fn is_char_start(b: u8) -> bool {
    b & 0xc0 != 0x80
}

impl SourceFile {
    fn new(path: &Path, name: String, text: Arc<str>) -> Self {
        let bytes = text.as_bytes();
        let mut index = Vec::with_capacity(bytes.len() / BLOCK + 1);
        let mut at = Checkpoint {
            line: 0,
            line_start: 0,
            column: 0,
        };
        for (block, chunk) in bytes.chunks(BLOCK).enumerate() {
            index.push(at);
            for (i, &b) in chunk.iter().enumerate() {
                if b == b'\n' {
                    at.line += 1;
                    at.line_start = block * BLOCK + i + 1;
                    at.column = 0;
                } else if is_char_start(b) {
                    at.column += 1;
                }
            }
        }
        index.push(at);
        Self {
            path: path.to_path_buf(),
            name,
            text,
            index: index.into(),
        }
    }

    /// The start of the line `n` lines above the one holding byte `offset` (or of the first
    /// line), with [`SourceFile::locate`]'s cost per line.
    pub fn lines_above(&self, offset: usize, n: usize) -> Location {
        let mut at = self.locate(offset);
        for _ in 0..n {
            if at.line_start == 0 {
                break;
            }
            at = self.locate(at.line_start - 1);
        }
        at
    }

    /// The line, line start and column of byte `offset` (clamped to the text), reading at most
    /// `BLOCK` bytes.
    pub fn locate(&self, offset: usize) -> Location {
        let bytes = self.text.as_bytes();
        let offset = offset.min(bytes.len());
        let base = offset / BLOCK * BLOCK;
        let cp = self.index[offset / BLOCK];
        let before = &bytes[base..offset];
        match before.iter().rposition(|&b| b == b'\n') {
            Some(i) => Location {
                line: cp.line + before.iter().filter(|&&b| b == b'\n').count(),
                line_start: base + i + 1,
                column: before[i + 1..]
                    .iter()
                    .filter(|&&b| is_char_start(b))
                    .count(),
            },
            None => Location {
                line: cp.line,
                line_start: cp.line_start,
                column: cp.column + before.iter().filter(|&&b| is_char_start(b)).count(),
            },
        }
    }
}

/// Every source file of one load, so that diagnostics can show their snippets.
#[derive(Debug, Clone, Default)]
pub struct SourceMap {
    files: Vec<SourceFile>,
}

impl SourceMap {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn add(&mut self, path: &Path, name: String, text: impl Into<Arc<str>>) -> FileId {
        self.files.push(SourceFile::new(path, name, text.into()));
        FileId((self.files.len() - 1) as u32)
    }

    pub fn get(&self, id: FileId) -> Option<&SourceFile> {
        self.files.get(id.0 as usize)
    }

    pub fn files(&self) -> &[SourceFile] {
        &self.files
    }

    /// The source text a span covers (empty for detached or out-of-range spans).
    pub fn snippet(&self, span: Span) -> &str {
        self.get(span.file)
            .and_then(|f| f.text.get(span.start as usize..span.end as usize))
            .unwrap_or("")
    }

    /// 1-based line and column of a span's start.
    pub fn line_col(&self, span: Span) -> (usize, usize) {
        let Some(file) = self.get(span.file) else {
            return (0, 0);
        };
        let at = file.locate(span.start as usize);
        (at.line + 1, at.column + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `locate` against counting from the start, at every offset of a text with long and
    /// short lines, multi-byte characters and lines crossing block boundaries.
    #[test]
    fn locate_agrees_with_counting_from_the_start() {
        let mut text = String::new();
        for i in 0..300 {
            text.push_str(&"é€x".repeat(i * 7 % 1500));
            text.push('\n');
            if i % 17 == 0 {
                text.push('\n');
            }
        }
        let mut map = SourceMap::new();
        let id = map.add(Path::new("t.scn"), "t.scn".into(), text.clone());
        let file = map.get(id).unwrap();
        let (mut line, mut line_start, mut column) = (0, 0, 0);
        for (offset, b) in text.bytes().enumerate() {
            if text.is_char_boundary(offset) {
                let want = Location {
                    line,
                    line_start,
                    column,
                };
                assert_eq!(file.locate(offset), want, "offset {offset}");
            }
            if b == b'\n' {
                (line, line_start, column) = (line + 1, offset + 1, 0);
            } else if is_char_start(b) {
                column += 1;
            }
        }
        assert_eq!(file.locate(text.len()).line, line);
        assert_eq!(file.locate(usize::MAX).line, line);
    }
}
