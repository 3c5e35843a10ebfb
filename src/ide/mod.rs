//! Editor support, independent of any editor or protocol: diagnostics, completion, hover,
//! go to definition, references and the outline of a scene file, for a language server
//! (`sppm-lang lsp`) or any other front end.
//!
//! Diagnostics come from the real pipeline ([`check()`]: the load and the prepare stage that
//! `sppm-lang check` runs, on the editor's unsaved buffers through a [`crate::world::Overlay`]).
//! The rest reads the text with a forgiving tokenizer ([`lex`]) and the structure it shows
//! ([`outline`]), so that it works on a file being typed, which seldom parses; the lists it
//! offers (block kinds, each block's properties, built-in functions, the standard library)
//! are the evaluator's own.
//!
//! Positions are byte offsets into the text; [`text::LineIndex`] converts them to the lines and
//! UTF-16 columns editors count in.

mod check;
mod complete;
pub mod docs;
pub mod files;
mod hover;
pub mod lex;
mod navigate;
pub mod outline;
pub mod text;

pub use check::{CheckLimits, FileDiagnostic, check};
pub use complete::{Completion, CompletionKind, Completions, complete};
pub use hover::{Hover, hover};
pub use navigate::{Location, definition, references};
pub use outline::{Outline, Symbol, SymbolKind, symbols};
pub use text::{LineIndex, Position};
