//! Syntax: source files, the pest grammar, and the AST with spans.

pub mod ast;
mod parser;
mod source;

pub use parser::{MAX_NESTING, parse};
pub use source::{SourceFile, SourceMap};
