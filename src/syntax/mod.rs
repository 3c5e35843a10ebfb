//! Syntax: source files, the pest grammar, and the AST with spans.

pub mod ast;
mod errors;
mod fast;
mod parser;
pub mod povray;
mod recover;

pub use crate::diag::{SourceFile, SourceMap};
pub use parser::{MAX_EXPRESSION_TERMS, MAX_NESTING, parse};
pub use recover::{MAX_SYNTAX_ERRORS, declared_names};

/// Memory the parser may take per lexeme of scene text (a name or number, or one punctuation
/// character: `0.5` counts as three), its token list and syntax tree alive together. Measured
/// (peak resident memory over lexemes, 2 MiB files): at most 259 bytes, for a body of `x,`
/// repeated; `x.5,` 190, `<1,2>,` 178, `"",` 173, `,` alone 163, `1.5,` 103.
pub const PARSE_BYTES_PER_LEXEME: u64 = 320;

/// The most memory parsing `text` may take: its lexemes (runs of letters, digits and `_`,
/// and every other character but white space, also inside comments and strings, which makes
/// it an upper bound) times [`PARSE_BYTES_PER_LEXEME`]. One pass over the bytes.
pub fn parse_memory(text: &str) -> u64 {
    let mut lexemes = 0u64;
    let mut in_word = false;
    for &b in text.as_bytes() {
        let word = b.is_ascii_alphanumeric() || b == b'_';
        if word {
            lexemes += u64::from(!in_word);
        } else if !b.is_ascii_whitespace() {
            lexemes += 1;
        }
        in_word = word;
    }
    lexemes.saturating_mul(PARSE_BYTES_PER_LEXEME)
}
pub use povray::povray_hint;
