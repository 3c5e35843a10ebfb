//! Turning [`Diagnostic`]s into miette reports and plain text.

use std::fmt;

use miette::{
    Diagnostic as MietteDiagnostic, GraphicalReportHandler, GraphicalTheme, LabeledSpan,
    MietteError, MietteSpanContents, SourceCode, SourceSpan, SpanContents,
};

use super::SourceMap;
use super::{Diagnostic, Severity};
use crate::span::Span;

/// One diagnostic in miette's shape: a snippet of the file around its spans, labels, help, and related
/// reports (trace entries in other files, further errors).
#[derive(Debug)]
struct Rendered {
    message: String,
    severity: miette::Severity,
    source: Option<Snippet>,
    labels: Vec<LabeledSpan>,
    help: Option<String>,
    related: Vec<Rendered>,
}

impl fmt::Display for Rendered {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Rendered {}

impl MietteDiagnostic for Rendered {
    fn severity(&self) -> Option<miette::Severity> {
        Some(self.severity)
    }

    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.help
            .as_ref()
            .map(|h| Box::new(h) as Box<dyn fmt::Display>)
    }

    fn source_code(&self) -> Option<&dyn SourceCode> {
        self.source.as_ref().map(|s| s as &dyn SourceCode)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        if self.labels.is_empty() {
            None
        } else {
            Some(Box::new(self.labels.iter().cloned()))
        }
    }

    fn related<'a>(&'a self) -> Option<Box<dyn Iterator<Item = &'a dyn MietteDiagnostic> + 'a>> {
        if self.related.is_empty() {
            None
        } else {
            Some(Box::new(
                self.related.iter().map(|r| r as &dyn MietteDiagnostic),
            ))
        }
    }
}

/// Lines longer than this are cut around the spans on them before miette sees them: miette
/// cannot draw a label past column 65 535 (it panics), and a snippet of a megabyte-long line
/// helps nobody.
const MAX_LINE: usize = 1024;
/// Characters kept on either side of the spans of a cut line.
const CONTEXT: usize = 60;

/// Whole lines copied before the first span's line and after the last span's line: miette
/// shows one line of context on each side.
const WINDOW_LINES: usize = 2;

/// The part of a file miette is shown for one diagnostic: a window of whole lines around its
/// spans, whose first line is line `first_line` (0-based) of the file, so that miette numbers
/// the lines as in the file. Reading only the window keeps the cost of a diagnostic independent
/// of the file's size.
#[derive(Debug)]
struct Snippet {
    name: String,
    text: String,
    first_line: usize,
}

impl SourceCode for Snippet {
    fn read_span<'a>(
        &'a self,
        span: &SourceSpan,
        context_lines_before: usize,
        context_lines_after: usize,
    ) -> Result<Box<dyn SpanContents<'a> + 'a>, MietteError> {
        let inner = self
            .text
            .read_span(span, context_lines_before, context_lines_after)?;
        Ok(Box::new(
            MietteSpanContents::new_named(
                self.name.clone(),
                inner.data(),
                *inner.span(),
                inner.line() + self.first_line,
                inner.column(),
                inner.line_count(),
            )
            .with_language("scn"),
        ))
    }
}

/// The text miette is shown for one diagnostic's file, with offsets into the original text
/// mapped onto it.
struct Excerpt {
    source: Snippet,
    /// `(original start, original end, start in the excerpt)` of every copied piece, in order.
    pieces: Vec<(usize, usize, usize)>,
}

impl Excerpt {
    fn span(&self, span: Span) -> SourceSpan {
        let (a, b) = (self.map(span.start as usize), self.map(span.end as usize));
        SourceSpan::new(a.into(), b.saturating_sub(a))
    }

    fn map(&self, offset: usize) -> usize {
        let mut last = 0;
        for &(lo, hi, at) in &self.pieces {
            if offset < lo {
                return at;
            }
            if offset <= hi {
                return at + (offset - lo);
            }
            last = at + (hi - lo);
        }
        last
    }
}

fn floor_char(text: &str, mut i: usize) -> usize {
    i = i.min(text.len());
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// Whether `c` is shown escaped: a control character other than tab, newline and the
/// carriage return of a CRLF line end (`crlf`: a newline follows it). Printed raw, an escape
/// sequence in a hostile scene (ESC, NUL, a lone CR, C1 controls) would drive the terminal that
/// shows the diagnostic: recolour it, hide lines, retitle the window.
fn hidden(c: char, crlf: bool) -> bool {
    c.is_control() && c != '\n' && c != '\t' && !(c == '\r' && crlf)
}

/// `c` as Rust writes it in a string: `\u{1b}`.
fn escaped(c: char) -> String {
    format!("\\u{{{:x}}}", u32::from(c))
}

/// `text` with its [`hidden`] characters escaped.
fn visible(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for (i, c) in text.char_indices() {
        if hidden(c, text[i + c.len_utf8()..].starts_with('\n')) {
            out.push_str(&escaped(c));
        } else {
            out.push(c);
        }
    }
    out
}

/// Copies `text[lo..hi]` to the end of `out` with its [`hidden`] characters escaped, recording
/// the copied pieces (`(original start, original end, start in out)`) so that offsets still
/// map: a span over a hidden character covers its escape.
fn push_visible(
    out: &mut String,
    pieces: &mut Vec<(usize, usize, usize)>,
    text: &str,
    lo: usize,
    hi: usize,
) {
    let mut start = lo;
    for (i, c) in text[lo..hi].char_indices() {
        let at = lo + i;
        let next = at + c.len_utf8();
        if hidden(c, text[next..].starts_with('\n')) {
            pieces.push((start, at, out.len()));
            out.push_str(&text[start..at]);
            out.push_str(&escaped(c));
            start = next;
        }
    }
    pieces.push((start, hi, out.len()));
    out.push_str(&text[start..hi]);
}

/// The lines of the file around the spans ([`WINDOW_LINES`] more on each side), except that
/// every line longer than [`MAX_LINE`] is cut to a window around the spans on it (or to its
/// start), marked with `…`. Line numbers stay the same; the name says where the first span
/// really is when its line was cut.
fn excerpt(map: &SourceMap, span: Span, others: &[Span]) -> Option<Excerpt> {
    let file = map.get(span.file)?;
    let text: &str = &file.text;
    let spans: Vec<Span> = std::iter::once(span)
        .chain(others.iter().copied().filter(|s| s.file == span.file))
        .collect();
    // The window: whole lines from WINDOW_LINES before the first span's line to WINDOW_LINES
    // after the last span's line.
    let lo = spans.iter().map(|s| s.start as usize).min().unwrap_or(0);
    let hi = spans.iter().map(|s| s.end as usize).max().unwrap_or(0);
    let lo = floor_char(text, lo);
    let hi = floor_char(text, hi.max(lo));
    let first = file.lines_above(lo, WINDOW_LINES);
    let window_start = first.line_start;
    let mut window_end = hi;
    for _ in 0..=WINDOW_LINES {
        match text[window_end..].find('\n') {
            Some(i) => window_end += i + 1,
            None => {
                window_end = text.len();
                break;
            }
        }
    }
    let window = &text[window_start..window_end];
    let mut out = String::new();
    let mut pieces = Vec::new();
    if window.split('\n').all(|l| l.len() <= MAX_LINE) {
        push_visible(&mut out, &mut pieces, text, window_start, window_end);
        return Some(Excerpt {
            source: Snippet {
                name: visible(&file.name),
                text: out,
                first_line: first.line,
            },
            pieces,
        });
    }
    let mut cut_primary = false;
    let mut start = window_start;
    while start < window_end {
        let end = text[start..window_end]
            .find('\n')
            .map_or(window_end, |i| start + i + 1);
        let body_end = if text[..end].ends_with('\n') {
            end - 1
        } else {
            end
        };
        if body_end - start <= MAX_LINE {
            push_visible(&mut out, &mut pieces, text, start, end);
        } else {
            let on_line: Vec<&Span> = spans
                .iter()
                .filter(|s| (s.start as usize) <= body_end && (s.end as usize) >= start)
                .collect();
            let (lo, hi) = match on_line.first() {
                Some(first) => {
                    let a = (first.start as usize).max(start);
                    let b = on_line
                        .iter()
                        .map(|s| (s.end as usize).min(body_end))
                        .max()
                        .unwrap_or(a)
                        .min(a + MAX_LINE);
                    (
                        a.saturating_sub(CONTEXT).max(start),
                        (b + CONTEXT).min(body_end),
                    )
                }
                None => (start, start + CONTEXT.min(body_end - start)),
            };
            let (lo, hi) = (floor_char(text, lo), floor_char(text, hi));
            if on_line.iter().any(|s| **s == span) {
                cut_primary = true;
            }
            if lo > start {
                out.push('…');
            }
            push_visible(&mut out, &mut pieces, text, lo, hi);
            if hi < body_end {
                out.push('…');
            }
            if end > body_end {
                out.push('\n');
            }
        }
        start = end;
    }
    let name = if cut_primary {
        let (line, col) = map.line_col(span);
        format!(
            "{} (line {line} cut around column {col})",
            visible(&file.name)
        )
    } else {
        visible(&file.name)
    };
    Some(Excerpt {
        source: Snippet {
            name,
            text: out,
            first_line: first.line,
        },
        pieces,
    })
}

fn convert(map: &SourceMap, d: &Diagnostic) -> Rendered {
    let others: Vec<Span> = d.labels.iter().map(|(s, _)| *s).collect();
    let excerpt = excerpt(map, d.span, &others);
    let mut labels = Vec::new();
    let mut related = Vec::new();
    if let Some(ex) = &excerpt {
        let text = (!d.label.is_empty()).then(|| visible(&d.label));
        labels.push(LabeledSpan::new_primary_with_span(text, ex.span(d.span)));
    }
    for (span, label) in &d.labels {
        match &excerpt {
            Some(ex) if span.file == d.span.file => {
                labels.push(LabeledSpan::new_with_span(
                    Some(visible(label)),
                    ex.span(*span),
                ));
            }
            _ => related.push(note(map, *span, label)),
        }
    }
    for (span, label) in &d.trace {
        related.push(note(map, *span, label));
    }
    Rendered {
        message: visible(&d.message),
        severity: match d.severity {
            Severity::Error => miette::Severity::Error,
            Severity::Warning => miette::Severity::Warning,
            Severity::Note => miette::Severity::Advice,
        },
        source: excerpt.map(|e| e.source),
        labels,
        help: d.help.as_deref().map(visible),
        related,
    }
}

fn note(map: &SourceMap, span: Span, label: &str) -> Rendered {
    let excerpt = excerpt(map, span, &[]);
    let labels = match &excerpt {
        Some(ex) => vec![LabeledSpan::new_primary_with_span(
            Some("here".into()),
            ex.span(span),
        )],
        None => Vec::new(),
    };
    Rendered {
        message: visible(label),
        severity: miette::Severity::Advice,
        source: excerpt.map(|e| e.source),
        labels,
        help: None,
        related: Vec::new(),
    }
}

/// A miette report holding all `diags`: one of them directly, several as related reports
/// under a summary line.
pub fn to_report(map: &SourceMap, diags: &[Diagnostic]) -> miette::Report {
    if diags.len() == 1 {
        return miette::Report::new(convert(map, &diags[0]));
    }
    let count = |s: Severity| diags.iter().filter(|d| d.severity == s).count();
    let (errors, warnings, notes) = (
        count(Severity::Error),
        count(Severity::Warning),
        count(Severity::Note),
    );
    let message = [(errors, "error"), (warnings, "warning"), (notes, "message")]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{n} {what}{}", plural(*n)))
        .collect::<Vec<_>>()
        .join(", ");
    miette::Report::new(Rendered {
        message,
        severity: if errors > 0 {
            miette::Severity::Error
        } else if warnings > 0 {
            miette::Severity::Warning
        } else {
            miette::Severity::Advice
        },
        source: None,
        labels: Vec::new(),
        help: None,
        related: diags.iter().map(|d| convert(map, d)).collect(),
    })
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Renders each diagnostic as miette's graphical output without colors, `width` columns wide,
/// one after the other. Deterministic: for snapshot tests and non-terminal output.
pub fn render_plain(map: &SourceMap, diags: &[Diagnostic], width: usize) -> String {
    let handler = GraphicalReportHandler::new_themed(GraphicalTheme::unicode_nocolor())
        .with_width(width)
        .with_links(false);
    let mut out = String::new();
    for d in diags {
        let r = convert(map, d);
        if handler.render_report(&mut out, &r).is_err() {
            out.push_str(&d.message);
            out.push('\n');
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn one_line_map(len: usize) -> (SourceMap, crate::span::FileId) {
        let mut text = "x".repeat(len);
        text.push_str(" oops\nsphere {}\n");
        let mut map = SourceMap::new();
        let id = map.add(Path::new("long.scn"), "long.scn".into(), text);
        (map, id)
    }

    #[test]
    fn a_span_at_column_a_million_renders_cut_around_it() {
        let (map, id) = one_line_map(1_000_000);
        let span = Span::new(id, 1_000_001, 1_000_005);
        let mut d = Diagnostic::error(span, "unknown identifier `oops`");
        d.label = "not declared".into();
        d.labels
            .push((Span::new(id, 1_000_007, 1_000_013), "next".into()));
        d.trace.push((Span::new(id, 10, 11), "called here".into()));
        let text = render_plain(&map, std::slice::from_ref(&d), 100);
        assert!(text.contains("oops"), "{text}");
        assert!(text.contains("not declared"), "{text}");
        assert!(text.contains("line 1 cut around column 1000002"), "{text}");
        assert!(
            text.len() < 4_000,
            "the snippet is not cut: {} bytes",
            text.len()
        );
        // The terminal path (miette's own handler) must not panic either.
        let report = to_report(&map, &[d.clone(), d]);
        let shown = format!("{report:?}");
        assert!(shown.contains("oops"), "{shown}");
    }

    #[test]
    fn short_lines_are_shown_unchanged() {
        let mut map = SourceMap::new();
        let id = map.add(Path::new("a.scn"), "a.scn".into(), "sphere { oops }\n");
        let d = Diagnostic::error(Span::new(id, 9, 13), "unknown identifier `oops`");
        let text = render_plain(&map, &[d], 80);
        assert!(text.contains("[a.scn:1:10]"), "{text}");
        assert!(text.contains("sphere { oops }"), "{text}");
    }

    /// Control characters from the scene (ESC, BEL, NUL, DEL, a lone CR, a C1 CSI) reach the
    /// output escaped, in the excerpt, the message and the labels; the label still sits under
    /// the right text, and a CRLF line end is kept as a line end.
    #[test]
    fn control_characters_are_shown_escaped() {
        let mut map = SourceMap::new();
        let text = "a\r\nb \x1b[31m\x07\0\x7f\u{9b} oops\rx\r\n";
        let id = map.add(Path::new("c.scn"), "c\x1b.scn".into(), text);
        let at = text.find("oops").unwrap() as u32;
        let mut d = Diagnostic::error(Span::new(id, at, at + 4), "found `\x1b`");
        d.label = "bad\x07".into();
        d.help = Some("help\0".into());
        d.labels.push((Span::new(id, 4, 5), "escape\x1b".into()));
        let shown = render_plain(&map, std::slice::from_ref(&d), 200);
        let raw: Vec<char> = shown
            .chars()
            .filter(|c| c.is_control() && *c != '\n')
            .collect();
        assert!(raw.is_empty(), "raw {raw:?} in:\n{shown}");
        for want in [
            "b \\u{1b}[31m\\u{7}\\u{0}\\u{7f}\\u{9b} oops\\u{d}x",
            "found `\\u{1b}`",
            "bad\\u{7}",
            "help\\u{0}",
            "escape\\u{1b}",
            "c\\u{1b}.scn",
        ] {
            assert!(shown.contains(want), "no {want} in:\n{shown}");
        }
        // The CRLF after `a` stays a line break: `b ...` is line 2.
        assert!(shown.contains(" 2 │ b "), "{shown}");
        // The label's underline starts under `oops` in the escaped line.
        let line = shown.lines().find(|l| l.contains("oops")).unwrap();
        let under = shown
            .lines()
            .skip_while(|l| !l.contains("oops"))
            .nth(1)
            .unwrap();
        let col = |s: &str, p: usize| s[..p].chars().count();
        assert_eq!(
            col(under, under.find('─').unwrap()),
            col(line, line.find("oops").unwrap()),
            "{shown}"
        );
        // The same through miette's own handler (the terminal path).
        let report = format!("{:?}", to_report(&map, &[d]));
        assert!(!report.contains('\x1b') || report.contains("\\u{1b}[31m"));
        assert!(
            !report.contains('\x07') && !report.contains('\0'),
            "{report}"
        );
    }

    #[test]
    fn offsets_map_into_the_excerpt() {
        let (map, id) = one_line_map(5_000);
        let ex = excerpt(&map, Span::new(id, 5_001, 5_005), &[]).unwrap();
        let src = &ex.source.text;
        let at = ex.span(Span::new(id, 5_001, 5_005));
        assert_eq!(&src[at.offset()..at.offset() + at.len()], "oops");
        // The next line is kept whole and maps exactly.
        let next = ex.span(Span::new(id, 5_006, 5_012));
        assert_eq!(&src[next.offset()..next.offset() + next.len()], "sphere");
    }
}
