//! The memory one load holds, in one running total against its limit
//! ([`super::EvalOptions::memory_limit`], or [`super::DEFAULT_PARSE_MEMORY`]): the text it
//! parses (every file, includes too, with what parsing it takes), the strings it builds and
//! the images it decodes. Each file, string or image is checked against what the others left,
//! so that many of them, each within the limit alone, cannot together pass it.
//!
//! What is counted is never given back: a syntax tree may live on in the macros it defines, and
//! a string in any variable or array; so the total bounds what the load can hold at once.

use super::Evaluator;
use crate::diag::{Error, SourceResult, size_text};
use crate::span::Span;

/// What a load holds so far, by kind (bytes).
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct Held {
    /// What parsing the scene text takes (the scene file and every include, each time it is
    /// read: [`crate::syntax::parse_memory`], an upper bound that covers the text too).
    pub text: u64,
    /// Strings the evaluation joins (`+`, the one way to build a long one); literals are part
    /// of the text.
    pub strings: u64,
    /// Decoded images ([`crate::scene::IMAGE_BYTES_PER_PIXEL`] a pixel).
    pub images: u64,
    /// Height fields' heights (4 bytes a sample).
    pub height_fields: u64,
}

impl Held {
    pub fn total(&self) -> u64 {
        self.text
            .saturating_add(self.strings)
            .saturating_add(self.images)
            .saturating_add(self.height_fields)
    }

    /// "parsed text 1.20 GiB, strings 640 MiB": the kinds held, for a message.
    pub fn parts(&self) -> String {
        let parts: Vec<String> = [
            ("parsed text", self.text),
            ("strings", self.strings),
            ("images", self.images),
            ("height fields", self.height_fields),
        ]
        .into_iter()
        .filter(|(_, b)| *b > 0)
        .map(|(what, b)| format!("{what} {}", size_text(b)))
        .collect();
        if parts.is_empty() {
            "nothing".into()
        } else {
            parts.join(", ")
        }
    }
}

impl Evaluator {
    /// The load's memory limit (bytes).
    pub(super) fn memory_limit(&self) -> u64 {
        self.options
            .memory_limit
            .unwrap_or(super::DEFAULT_PARSE_MEMORY)
    }

    /// Bytes the load may still hold.
    pub(super) fn memory_left(&self) -> u64 {
        self.memory_limit().saturating_sub(self.held.total())
    }

    /// Counts a string of `bytes` the evaluation built at `span`, or refuses it when it would
    /// take the load past its memory limit.
    pub(super) fn hold_string(&mut self, bytes: u64, span: Span) -> SourceResult<()> {
        if bytes > self.memory_left() {
            return Err(vec![
                Error::new(format!(
                    "this string of {} would take the load past its memory limit of {}: it \
                     holds {} already ({})",
                    size_text(bytes),
                    size_text(self.memory_limit()),
                    size_text(self.held.total()),
                    self.held.parts()
                ))
                .label("one string too many")
                .help(
                    "is a long string copied in a loop? build only what the scene needs, or \
                     raise the limit with `--memory-limit` (e.g. `--memory-limit 4G`)",
                )
                .at(span),
            ]);
        }
        self.held.strings += bytes;
        Ok(())
    }
}
