//! Syntax: source files, the pest grammar, and the AST with spans.

pub mod ast;
mod parser;
mod source;

pub use parser::{MAX_EXPRESSION_TERMS, MAX_NESTING, parse};
pub use source::{SourceFile, SourceMap};
