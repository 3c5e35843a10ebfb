//! Source spans: the only thing the renderer knows about source text.
//!
//! A [`Span`] names a file by [`FileId`] and a byte range inside it. The language side owns the
//! table that turns a `FileId` back into a path and text (see `diag::SourceMap`); the renderer
//! only carries spans so that its errors can point at the declaration that caused them.

/// Index of a source file in the language side's source map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FileId(pub u32);

/// A byte range `start..end` in one source file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Span {
    pub file: FileId,
    pub start: u32,
    pub end: u32,
}

impl Span {
    pub const fn new(file: FileId, start: u32, end: u32) -> Self {
        Self { file, start, end }
    }

    /// A span for data that did not come from source text (built in Rust, e.g. by a test).
    pub const fn detached() -> Self {
        Self {
            file: FileId(u32::MAX),
            start: 0,
            end: 0,
        }
    }

    pub fn is_detached(&self) -> bool {
        self.file.0 == u32::MAX
    }

    /// The smallest span covering both (they must be in the same file).
    pub fn join(self, other: Span) -> Span {
        if self.file != other.file {
            return self;
        }
        Span {
            file: self.file,
            start: self.start.min(other.start),
            end: self.end.max(other.end),
        }
    }

    pub fn len(&self) -> usize {
        (self.end - self.start) as usize
    }

    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }
}
