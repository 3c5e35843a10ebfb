//! Syntax: source files, the pest grammar, and the AST with spans.

pub mod ast;
mod errors;
mod parser;
pub mod povray;

pub use crate::diag::{SourceFile, SourceMap};
pub use parser::{MAX_EXPRESSION_TERMS, MAX_NESTING, parse};
pub use povray::povray_hint;
