//! Diagnostics: the error and warning type of the language side, and their rendering.
//!
//! Modelled on typst: evaluation returns [`SourceResult`], a list of diagnostics on failure;
//! helpers return a plain [`Error`] (message and help, no position) and the caller attaches the
//! span late with [`At::at`]. Diagnostics are rendered only at the edge (the CLI, tests), with
//! [`to_report`] (a miette report, one snippet of the lines around each span) or
//! [`render_plain`] (a string without colors at a fixed width).

mod render;
mod source;

pub use render::{render_plain, to_report};
pub use source::{Location, SourceFile, SourceMap};

use crate::span::Span;

/// A size for a message: bytes below 1 KiB, then KiB, MiB or GiB with three significant
/// digits at most (rounded, so that the parts of an estimate add up to about its total).
pub fn size_text(bytes: u64) -> String {
    let b = bytes as f64;
    let (value, unit) = match bytes {
        1 => return "1 byte".into(),
        0..1024 => return format!("{bytes} bytes"),
        1024..0x10_0000 => (b / 1024.0, "KiB"),
        0x10_0000..0x4000_0000 => (b / f64::from(1u32 << 20), "MiB"),
        _ => (b / f64::from(1u32 << 30), "GiB"),
    };
    if value < 10.0 {
        format!("{value:.2} {unit}")
    } else if value < 100.0 {
        format!("{value:.1} {unit}")
    } else {
        format!("{value:.0} {unit}")
    }
}

/// A number as a person would write it in a message: shortest round-trip form, rounded to 6
/// significant digits when that form is long (`-0.09999999999999998` is `-0.1`), and in
/// exponent form when very large or small (`1e300`, not 301 digits); zero without a sign
/// (`-0` is `0`).
pub fn short_number(x: f64) -> String {
    // `-0.0 == 0.0`: both are shown as `0`.
    let x = if x == 0.0 { 0.0 } else { x };
    if !x.is_finite() {
        return format!("{x}");
    }
    let shortest = format!("{x}");
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    let a = rounded.abs();
    if a != 0.0 && !(1e-5..1e15).contains(&a) {
        return format!("{rounded:e}");
    }
    if shortest.len() <= 12 {
        shortest
    } else {
        format!("{rounded}")
    }
}

/// Result of a step that may fail with several diagnostics.
pub type SourceResult<T> = Result<T, Vec<Diagnostic>>;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Severity {
    Error,
    Warning,
    /// A message the scene asked for (`#debug`): neither an error nor a warning.
    Note,
}

/// One error or warning, pointing at source text.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    pub severity: Severity,
    pub message: String,
    /// Where the problem is.
    pub span: Span,
    /// The label at `span` (what was found, what is wrong).
    pub label: String,
    /// Further spans with labels (e.g. "first declared here").
    pub labels: Vec<(Span, String)>,
    /// A suggested fix.
    pub help: Option<String>,
    /// Innermost first: where the failing code was reached from ("in macro Branch called here").
    pub trace: Vec<(Span, String)>,
    /// The caller cancelled the work ([`Diagnostic::interrupted`]): not the scene's fault.
    pub interrupted: bool,
}

/// The most bytes a diagnostic keeps of its message, a label or its help: a scene can put a
/// string of megabytes into a message (`#debug S`, an image named by a long string), and a
/// thousand such messages would hold gigabytes and take minutes to print.
pub const MAX_DIAGNOSTIC_TEXT: usize = 8 << 10;

/// `text` cut to at most [`MAX_DIAGNOSTIC_TEXT`] bytes (at a character boundary), ending in a
/// note of how much was left out; copies only what it keeps.
pub fn clip_text(text: &str) -> String {
    if text.len() <= MAX_DIAGNOSTIC_TEXT {
        return text.to_string();
    }
    // Room for the note (at most 40 bytes).
    let mut cut = MAX_DIAGNOSTIC_TEXT - 64;
    while !text.is_char_boundary(cut) {
        cut -= 1;
    }
    format!(
        "{}… ({} more not shown)",
        &text[..cut],
        size_text((text.len() - cut) as u64)
    )
}

fn clip(text: String) -> String {
    if text.len() <= MAX_DIAGNOSTIC_TEXT {
        text
    } else {
        clip_text(&text)
    }
}

impl Diagnostic {
    pub fn error(span: Span, message: impl Into<String>) -> Self {
        Self {
            severity: Severity::Error,
            message: clip(message.into()),
            span,
            label: String::new(),
            labels: Vec::new(),
            help: None,
            trace: Vec::new(),
            interrupted: false,
        }
    }

    /// An error about no place in the source: a setting the file never wrote, an option of
    /// the caller, the machine's limits.
    pub fn unplaced(message: impl Into<String>) -> Self {
        Self::error(Span::detached(), message)
    }

    /// The error of work the caller cancelled: the one word "interrupted".
    pub fn interrupted() -> Self {
        Self {
            interrupted: true,
            ..Self::unplaced("interrupted")
        }
    }

    pub fn warning(span: Span, message: impl Into<String>) -> Self {
        Self {
            severity: Severity::Warning,
            ..Self::error(span, message)
        }
    }

    pub fn note(span: Span, message: impl Into<String>) -> Self {
        Self {
            severity: Severity::Note,
            ..Self::error(span, message)
        }
    }

    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = clip(label.into());
        self
    }

    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(clip(help.into()));
        self
    }

    pub fn with_extra(mut self, span: Span, label: impl Into<String>) -> Self {
        self.labels.push((span, clip(label.into())));
        self
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// The same diagnostic at `span` (a check that knows the value, its caller the place).
    pub fn at(self, span: Span) -> Self {
        Self { span, ..self }
    }

    /// Whether the span points into a source (not [`Span::detached`]).
    pub fn is_placed(&self) -> bool {
        !self.span.is_detached()
    }
}

/// The message alone (a log line, a test's assertion); [`render_plain`] draws the span and help.
impl std::fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Diagnostic {}

/// A stage that fails with one diagnostic passes it on where a list is expected (`?`).
impl From<Diagnostic> for Vec<Diagnostic> {
    fn from(d: Diagnostic) -> Self {
        vec![d]
    }
}

/// A spanless error from a helper; the caller attaches the span.
#[derive(Debug, Clone, PartialEq)]
pub struct Error {
    pub message: String,
    pub label: String,
    pub help: Option<String>,
}

impl Error {
    pub fn new(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            label: String::new(),
            help: None,
        }
    }

    pub fn label(mut self, label: impl Into<String>) -> Self {
        self.label = label.into();
        self
    }

    pub fn help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    pub fn at(self, span: Span) -> Diagnostic {
        Diagnostic {
            label: clip(self.label),
            help: self.help.map(clip),
            ..Diagnostic::error(span, self.message)
        }
    }
}

/// Attach a span to a spanless result.
pub trait At<T> {
    fn at(self, span: Span) -> SourceResult<T>;
}

impl<T> At<T> for Result<T, Error> {
    fn at(self, span: Span) -> SourceResult<T> {
        self.map_err(|e| vec![e.at(span)])
    }
}

impl<T> At<T> for Result<T, String> {
    fn at(self, span: Span) -> SourceResult<T> {
        self.map_err(|e| vec![Diagnostic::error(span, e)])
    }
}

/// Names longer than this get no suggestion (and are suggested for none): a typo is looked for
/// among names a person writes, and the edit distance costs the product of the two lengths.
const MAX_SUGGEST_LEN: usize = 64;
/// The most cells of edit-distance tables one suggestion computes (about 0.1 s): a scope of
/// many thousands of names is searched only in part.
const MAX_SUGGEST_WORK: usize = 20_000_000;

/// The closest candidate to `name` by edit distance, if it is close enough to be a likely typo.
pub fn suggest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    suggest_all(name, candidates, 1).into_iter().next()
}

/// Up to `n` candidates close enough to `name` to be likely typos, closest first (ties by name).
pub fn suggest_all<'a>(
    name: &str,
    candidates: impl IntoIterator<Item = &'a str>,
    n: usize,
) -> Vec<&'a str> {
    let len = name.chars().count();
    if len > MAX_SUGGEST_LEN {
        return Vec::new();
    }
    let limit = (len / 3).max(1);
    let mut work = 0usize;
    let mut close: Vec<(usize, &str)> = candidates
        .into_iter()
        .filter(|c| c.len().abs_diff(name.len()) <= 4 * limit)
        .map(|c| (c, c.chars().count()))
        // The edit distance is at least the difference in length.
        .filter(|&(_, n)| n.abs_diff(len) <= limit && n <= MAX_SUGGEST_LEN)
        .take_while(|&(_, n)| {
            work += (len + 1) * (n + 1);
            work <= MAX_SUGGEST_WORK
        })
        .map(|(c, n)| (edit_distance(name, c), c, n))
        // Replacing every character is no typo (`R` is not a misspelt `x`).
        .filter(|&(d, _, n)| d <= limit && d < len.max(n))
        .map(|(d, c, _)| (d, c))
        .collect();
    close.sort();
    close.dedup();
    close.into_iter().take(n).map(|(_, c)| c).collect()
}

/// Edit distance over chars where swapping two neighbours counts as one edit (`ligth` is one
/// edit from `light`): optimal string alignment, from strsim.
pub fn edit_distance(a: &str, b: &str) -> usize {
    strsim::osa_distance(a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sizes in messages: exact bytes when small, three significant digits otherwise (a
    /// limit of 1 byte was "1 MiB", and parts rounded up each added up past their total).
    #[test]
    fn sizes_are_shown_in_their_unit() {
        assert_eq!(size_text(0), "0 bytes");
        assert_eq!(size_text(1), "1 byte");
        assert_eq!(size_text(1536), "1.50 KiB");
        assert_eq!(size_text(20 << 20), "20.0 MiB");
        assert_eq!(size_text(2047 << 20), "2.00 GiB");
        assert_eq!(size_text(300 << 30), "300 GiB");
    }

    /// A suggestion costs a bounded amount of work: a 100 000-character name is compared with
    /// nothing (its table would have 10^10 cells), and among 50 000 names of 60 characters only
    /// the first few thousand are compared (a typo of the last one is not found; one of the
    /// tenth is). Short names still find their typos.
    #[test]
    fn suggestions_are_bounded_in_work() {
        let long = "a".repeat(100_000);
        assert!(suggest(&format!("b{long}"), [long.as_str()]).is_none());
        // 60 pseudo-random letters each (far apart from one another).
        let mut x = 1u64;
        let names: Vec<String> = (0..50_000)
            .map(|_| {
                (0..60)
                    .map(|_| {
                        x = x
                            .wrapping_mul(6364136223846793005)
                            .wrapping_add(1442695040888963407);
                        char::from(b'a' + ((x >> 33) % 26) as u8)
                    })
                    .collect()
            })
            .collect();
        let typo = |i: usize| format!("{}Z", &names[i][..59]);
        let all = || names.iter().map(|s| s.as_str());
        assert_eq!(suggest(&typo(10), all()), Some(names[10].as_str()));
        assert!(suggest(&typo(49_990), all()).is_none());
        assert_eq!(suggest("ligth", ["light", "sphere"]), Some("light"));
    }

    #[test]
    fn numbers_are_shown_as_written() {
        assert_eq!(short_number(-0.09999999999999998), "-0.1");
        assert_eq!(short_number(0.5), "0.5");
        assert_eq!(short_number(3.0), "3");
        assert_eq!(short_number(1e300), "1e300");
        assert_eq!(short_number(4e38), "4e38");
        assert_eq!(short_number(1.23456789e-7), "1.23457e-7");
        assert_eq!(short_number(123456.789), "123456.789");
        assert_eq!(short_number(f64::NAN), "NaN");
        assert_eq!(short_number(-0.0), "0");
        assert_eq!(short_number(0.1 + 0.2), "0.3");
    }

    #[test]
    fn edit_distance_basics() {
        assert_eq!(edit_distance("sphere", "sphere"), 0);
        assert_eq!(edit_distance("spher", "sphere"), 1);
        assert_eq!(edit_distance("shpere", "sphere"), 1);
        assert_eq!(edit_distance("ligth", "light"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
    }

    #[test]
    fn suggestion_picks_closest_and_rejects_far() {
        let c = ["sphere", "plane", "quad"];
        assert_eq!(suggest("spher", c), Some("sphere"));
        assert_eq!(suggest("xyzzy", c), None);
        assert_eq!(suggest("ligth", ["light", "spotlight"]), Some("light"));
        assert_eq!(suggest("difuse", ["diffuse", "mirror"]), Some("diffuse"));
        // A name with no character in common is no typo, however short.
        assert_eq!(suggest("R", ["x", "y", "z", "pi"]), None);
        assert_eq!(suggest("P", ["pi"]), None);
        assert_eq!(suggest("p", ["pi"]), Some("pi"));
        assert_eq!(suggest("ab", ["ac"]), Some("ac"));
    }
}
