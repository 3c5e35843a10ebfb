//! The page's data as JSON: the status, and diagnostics with their source excerpt.

use std::fmt::Write;

use sppm_lang::SourceFile;
use sppm_lang::{Diagnostic, SourceMap};

use super::Status;

/// Lines of source shown before and after the first line of a diagnostic's span.
const CONTEXT_LINES: usize = 2;
/// Longest excerpt line sent (characters); longer lines are cut around the span.
const MAX_LINE: usize = 160;
/// Longest message, label or help sent (characters); the terminal shows them whole.
const MAX_TEXT: usize = 2000;
/// Most bytes of one status message: diagnostics past it are counted, not sent (a scene that
/// prints a thousand long `#debug` lines makes each tab's message no larger).
pub const MAX_STATUS_BYTES: u64 = 256 * 1024;

/// A line of an excerpt: its number, its text, and the highlighted character range in it.
pub type ExcerptLine = (usize, String, Option<(usize, usize)>);

/// One diagnostic as the page shows it.
#[derive(Debug, Clone, Default)]
pub struct DiagnosticView {
    pub error: bool,
    pub message: String,
    pub label: String,
    pub help: Option<String>,
    /// `file:line:column`, empty when the diagnostic has no place in a file.
    pub location: String,
    /// The excerpt: (line number, text, highlighted character range in `text`).
    pub lines: Vec<ExcerptLine>,
}

/// The diagnostics of a load, with their excerpts.
pub fn diagnostics_view(sources: &SourceMap, diagnostics: &[Diagnostic]) -> Vec<DiagnosticView> {
    diagnostics
        .iter()
        .map(|d| {
            let mut v = DiagnosticView {
                error: d.is_error(),
                message: d.message.clone(),
                label: d.label.clone(),
                help: d.help.clone(),
                ..DiagnosticView::default()
            };
            if let Some(file) = sources.get(d.span.file) {
                let (line, col) = sources.line_col(d.span);
                v.location = format!("{}:{line}:{col}", file.name);
                v.lines = excerpt(file, d.span.start as usize, d.span.end as usize);
            }
            v
        })
        .collect()
}

/// The lines around byte range `start..end` of `file`, each with the part of the range it holds.
/// Only the lines shown are read (a file with many diagnostics costs each only its lines).
fn excerpt(file: &SourceFile, start: usize, end: usize) -> Vec<ExcerptLine> {
    let text: &str = &file.text;
    let start = floor_boundary(text, start.min(text.len()));
    let end = floor_boundary(text, end.clamp(start, text.len()));
    let first = file.locate(start).line;
    let from = file.lines_above(start, CONTEXT_LINES);
    let mut out = Vec::new();
    let mut offset = from.line_start;
    for (number, line) in (from.line..).zip(text[from.line_start..].split('\n')) {
        let line_start = offset;
        offset += line.len() + 1;
        let line_end = line_start + line.len();
        if number > first + CONTEXT_LINES && line_start > end {
            break;
        }
        // The highlighted byte range of this line, as character offsets.
        let hl = (start <= line_end && end >= line_start && (start < end || number == first)).then(
            || {
                let a = start.max(line_start) - line_start;
                let b = end.min(line_end) - line_start;
                (line[..a].chars().count(), line[..b].chars().count())
            },
        );
        out.push(cut(number + 1, line, hl));
    }
    out
}

/// A line cut to [`MAX_LINE`] characters around its highlight.
fn cut(number: usize, line: &str, hl: Option<(usize, usize)>) -> ExcerptLine {
    let chars: Vec<char> = line.trim_end_matches('\r').chars().collect();
    if chars.len() <= MAX_LINE {
        return (number, chars.into_iter().collect(), hl);
    }
    let from = hl.map_or(0, |(a, _)| a.saturating_sub(MAX_LINE / 4));
    let to = (from + MAX_LINE).min(chars.len());
    let text: String = chars[from..to].iter().collect();
    let hl = hl.map(|(a, b)| (a - from, b.min(to) - from));
    (number, text, hl)
}

fn floor_boundary(text: &str, mut i: usize) -> usize {
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// The status as one JSON object; `image` is the sequence number of the latest image (0: none).
pub fn status_json(s: &Status, image: u64) -> String {
    let mut o = String::from("{");
    field(&mut o, "scene", &string(&s.scene));
    field(&mut o, "state", &string(s.state));
    field(&mut o, "message", &string(&s.message));
    field(&mut o, "round", &s.round.to_string());
    field(&mut o, "stage", &string(s.stage));
    field(&mut o, "iteration", &s.iteration.to_string());
    field(&mut o, "iterations", &s.iterations.to_string());
    field(&mut o, "elapsed", &number(s.elapsed));
    field(&mut o, "photons_per_second", &number(s.photons_per_second));
    let since = s.saved_at.map(|t| t.elapsed().as_secs_f64());
    field(&mut o, "since_save", &since.map_or("null".into(), number));
    field(&mut o, "exposure", &number(s.exposure));
    field(&mut o, "image", &image.to_string());
    // Diagnostics in order while they fit; the page says how many more there are.
    let mut diags = String::from("[");
    let mut shown = 0;
    for d in &s.diagnostics {
        let json = diagnostic_json(d);
        if (o.len() + diags.len() + json.len() + 64) as u64 > MAX_STATUS_BYTES {
            break;
        }
        if shown > 0 {
            diags.push(',');
        }
        diags.push_str(&json);
        shown += 1;
    }
    diags.push(']');
    field(&mut o, "diagnostics", &diags);
    field(&mut o, "more", &(s.diagnostics.len() - shown).to_string());
    o.pop();
    o.push('}');
    o
}

fn diagnostic_json(d: &DiagnosticView) -> String {
    let mut o = String::from("{");
    field(&mut o, "error", &d.error.to_string());
    field(&mut o, "message", &string(short(&d.message)));
    field(&mut o, "label", &string(short(&d.label)));
    field(
        &mut o,
        "help",
        &d.help
            .as_deref()
            .map_or("null".into(), |h| string(short(h))),
    );
    field(&mut o, "location", &string(&d.location));
    let lines: Vec<String> = d
        .lines
        .iter()
        .map(|(n, text, hl)| {
            let hl = hl.map_or("null".into(), |(a, b)| format!("[{a},{b}]"));
            format!("[{n},{},{hl}]", string(text))
        })
        .collect();
    field(&mut o, "lines", &format!("[{}]", lines.join(",")));
    o.pop();
    o.push('}');
    o
}

/// `text` cut to [`MAX_TEXT`] characters.
fn short(text: &str) -> &str {
    text.char_indices()
        .nth(MAX_TEXT)
        .map_or(text, |(i, _)| &text[..i])
}

fn field(o: &mut String, name: &str, value: &str) {
    let _ = write!(o, "\"{name}\":{value},");
}

/// A finite number (JSON has no NaN or infinity: those are sent as 0).
fn number(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "0".into()
    }
}

/// A JSON string literal.
fn string(s: &str) -> String {
    let mut o = String::with_capacity(s.len() + 2);
    o.push('"');
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            '\n' => o.push_str("\\n"),
            '\r' => o.push_str("\\r"),
            '\t' => o.push_str("\\t"),
            // `<` escaped too, so that no text can close a script element.
            c if (c as u32) < 0x20 || c == '<' || c == '\u{2028}' || c == '\u{2029}' => {
                let _ = write!(o, "\\u{:04x}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`excerpt`] of `text` as a file of its own.
    fn excerpt_of(text: &str, start: usize, end: usize) -> Vec<ExcerptLine> {
        let mut map = SourceMap::new();
        let id = map.add(std::path::Path::new("t.scn"), "t.scn".into(), text);
        excerpt(map.get(id).unwrap(), start, end)
    }

    /// A thousand long diagnostics make a message no larger than the cap, and say how many
    /// were left out.
    #[test]
    fn a_status_message_is_bounded() {
        let d = DiagnosticView {
            message: "\u{2028}".repeat(50_000),
            label: "<".repeat(50_000),
            help: Some("x".repeat(50_000)),
            lines: vec![(1, "y".repeat(MAX_LINE), Some((0, 3))); 5],
            ..DiagnosticView::default()
        };
        let status = Status {
            diagnostics: vec![d; 1000],
            ..Status::default()
        };
        let json = status_json(&status, 7);
        assert!(json.len() as u64 <= MAX_STATUS_BYTES, "{}", json.len());
        let shown = json.matches("\"message\":\"\\u2028").count();
        assert!(shown >= 1, "no diagnostic shown");
        assert!(
            json.ends_with(&format!("\"more\":{}}}", 1000 - shown)),
            "{}",
            &json[json.len() - 40..]
        );
    }

    #[test]
    fn strings_are_escaped() {
        assert_eq!(string("a\"b\\c\nd\u{1}<"), r#""a\"b\\c\nd\u0001\u003c""#);
    }

    #[test]
    fn excerpt_marks_the_span_on_its_line_with_context() {
        let text = "one\ntwo\nthree bad here\nfour\nfive\nsix\n";
        let start = text.find("bad").unwrap();
        let lines = excerpt_of(text, start, start + 3);
        let numbers: Vec<usize> = lines.iter().map(|l| l.0).collect();
        assert_eq!(numbers, [1, 2, 3, 4, 5]);
        assert_eq!(lines[2].1, "three bad here");
        assert_eq!(lines[2].2, Some((6, 9)));
        assert!(lines.iter().filter(|l| l.2.is_some()).count() == 1);
    }

    #[test]
    fn a_huge_line_is_cut_around_the_span() {
        let mut text = "x".repeat(100_000);
        text.push_str("ééé bad");
        let start = text.find("bad").unwrap();
        let lines = excerpt_of(&text, start, start + 3);
        assert_eq!(lines.len(), 1);
        let (_, line, hl) = &lines[0];
        assert!(line.chars().count() <= MAX_LINE);
        let (a, b) = hl.unwrap();
        let marked: String = line.chars().skip(a).take(b - a).collect();
        assert_eq!(marked, "bad");
    }

    #[test]
    fn an_empty_span_at_the_end_of_the_text_is_marked() {
        let text = "sphere {";
        let lines = excerpt_of(text, text.len(), text.len());
        assert_eq!(lines, vec![(1, "sphere {".to_string(), Some((8, 8)))]);
    }
}
