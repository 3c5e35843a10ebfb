//! Recovery after a syntax error: every syntax error of a file, not just the first.
//!
//! The rule (docs/language.md, "Syntax errors"): a file is cut at *sync points*, the starts of
//! lines that begin a top-level item: outside every `{ }`, `( )`, `[ ]` and block directive
//! (`#if ... #end`, ...), starting with `#` or a name, after a line that ended an item (not
//! after `=`, `,` or an operator). After an error, the text from the last sync point before it
//! (whose text before parses on its own) to the next sync point after it is blanked out, with
//! its line breaks kept so that spans stay valid, and the file is parsed again. An error before
//! the end of the blanked text follows from the blanking and is not reported: the blanked part
//! grows back to an earlier sync point instead. The good path never comes here.

use pest::Parser;

use super::errors::{after_comment_or_string, check_nesting, error_pos, syntax_error};
use super::parser::{Rule, SceneParser};
use crate::diag::Diagnostic;
use crate::span::{FileId, Span};

/// The most syntax errors reported for one file.
pub const MAX_SYNTAX_ERRORS: usize = 20;

/// The most parses one recovery may run (reported errors, and unreported widenings of a
/// blanked part): keeps a pathological file from costing a parse per line.
const MAX_PARSES: usize = 3 * MAX_SYNTAX_ERRORS;

/// Every syntax error of `text` (up to [`MAX_SYNTAX_ERRORS`], then a note), in order, given the
/// first (`first`, from a parse of the whole text) and where the first character outside ASCII
/// stands (`stray`).
pub(super) fn all_errors(
    file: FileId,
    text: &str,
    first: pest::error::Error<Rule>,
    stray: Option<usize>,
) -> Vec<Diagnostic> {
    let syncs = sync_points(text);
    let mut errors = vec![syntax_error(file, text, first.clone(), stray)];
    let mut masked = text.as_bytes().to_vec();
    let mut parses = 0;
    let Some((mut start, mut frontier)) =
        blank_around(&mut masked, &syncs, error_pos(&first), &mut parses)
    else {
        return errors;
    };
    while parses < MAX_PARSES {
        parses += 1;
        let m = as_text(&masked);
        let Err(e) = SceneParser::parse(Rule::file, m) else {
            break;
        };
        let pos = error_pos(&e);
        if pos < frontier {
            // The blanking left something before it incomplete: blank from an earlier point.
            let Some(&earlier) = syncs.iter().rev().find(|&&s| s < start.min(pos)) else {
                blank(&mut masked, 0, frontier);
                start = 0;
                continue;
            };
            blank(&mut masked, earlier, frontier);
            start = earlier;
            continue;
        }
        if errors.len() == MAX_SYNTAX_ERRORS {
            let at = pos.min(text.len());
            errors.push(Diagnostic::note(
                Span::new(file, at as u32, at as u32),
                format!(
                    "more syntax errors may follow; only the first {MAX_SYNTAX_ERRORS} are \
                     reported"
                ),
            ));
            break;
        }
        let stray = check_nesting(file, m).ok().flatten();
        errors.push(syntax_error(file, m, e, stray));
        match blank_around(&mut masked, &syncs, pos, &mut parses) {
            Some((s, end)) => {
                start = s;
                frontier = frontier.max(end);
            }
            None => break,
        }
    }
    errors
}

/// Blanks the part around an error at `pos`: from the last sync point at or before it whose
/// text before parses (else the start of the file) to the first sync point after it (else the
/// end). Returns the part, or `None` when it reaches the end of the file (nothing is left).
fn blank_around(
    masked: &mut [u8],
    syncs: &[usize],
    pos: usize,
    parses: &mut usize,
) -> Option<(usize, usize)> {
    let end = syncs
        .iter()
        .copied()
        .find(|&s| s > pos)
        .unwrap_or(masked.len());
    let mut start = 0;
    for &s in syncs.iter().rev().filter(|&&s| s <= pos) {
        if *parses >= MAX_PARSES {
            break;
        }
        *parses += 1;
        if SceneParser::parse(Rule::file, as_text(&masked[..s])).is_ok() {
            start = s;
            break;
        }
    }
    blank(masked, start, end);
    (end < masked.len()).then_some((start, end))
}

/// Sync points only stand at line starts (ASCII) and the blanked bytes become spaces, so the
/// text stays UTF-8: a character is blanked whole or not at all.
fn as_text(bytes: &[u8]) -> &str {
    std::str::from_utf8(bytes).unwrap_or("")
}

/// Replaces `bytes[from..to]` with spaces, line breaks kept.
fn blank(bytes: &mut [u8], from: usize, to: usize) {
    let to = to.min(bytes.len());
    for b in &mut bytes[from..to] {
        if *b != b'\n' {
            *b = b' ';
        }
    }
}

/// The sync points of `text`, in order (see the module doc).
fn sync_points(text: &str) -> Vec<usize> {
    let bytes = text.as_bytes();
    let mut syncs = Vec::new();
    // The brackets and block directives open here.
    let mut stack: Vec<u8> = Vec::new();
    // The last character outside comments and blanks: whether the item before has ended.
    let mut last = b'\n';
    let mut line_start = true;
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c == b'\n' {
            line_start = true;
            i += 1;
            continue;
        }
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        let starts_line = std::mem::replace(&mut line_start, false);
        if c == b'/' && matches!(bytes.get(i + 1), Some(b'/' | b'*')) {
            i = after_comment_or_string(bytes, i).unwrap_or(i + 1);
            // A comment ends nothing: what follows it on its line may still start an item.
            line_start = starts_line;
            continue;
        }
        if starts_line
            && stack.is_empty()
            && (c == b'#' || c.is_ascii_alphabetic() || c == b'_')
            && !continues_item(last)
            && !continues_directive(&text[i..])
        {
            syncs.push(i);
        }
        if c == b'"' {
            i = after_comment_or_string(bytes, i).unwrap_or(i + 1);
            last = b'"';
            continue;
        }
        // A closer ends the innermost opener of its kind and whatever was left open inside it
        // (`( }` closes the brace); one with no opener is ignored.
        let mut close = |open: u8| {
            if let Some(k) = stack.iter().rposition(|&o| o == open) {
                stack.truncate(k);
            }
        };
        match c {
            b'{' | b'(' | b'[' => stack.push(c),
            b'}' => close(b'{'),
            b')' => close(b'('),
            b']' => close(b'['),
            b'#' => {
                let word = directive_word(&text[i..]);
                if matches!(
                    word,
                    "if" | "ifdef" | "ifndef" | "switch" | "while" | "for" | "macro"
                ) {
                    stack.push(b'#');
                } else if word == "end" {
                    close(b'#');
                }
                i += 1 + word.len();
                last = if word.is_empty() { b'#' } else { b'a' };
                continue;
            }
            _ => {}
        }
        last = c;
        i += 1;
    }
    syncs
}

/// Whether an item whose last character is `c` goes on on the next line.
fn continues_item(c: u8) -> bool {
    matches!(
        c,
        b'=' | b','
            | b'+'
            | b'-'
            | b'*'
            | b'/'
            | b'<'
            | b'?'
            | b':'
            | b'&'
            | b'|'
            | b'!'
            | b'.'
            | b'#'
    )
}

/// Whether `rest` starts with a directive that belongs to the construct around it.
fn continues_directive(rest: &str) -> bool {
    matches!(
        directive_word(rest),
        "end" | "else" | "elif" | "case" | "range" | "break"
    ) && rest.starts_with('#')
}

/// The word after `#` at the start of `rest` (empty when `rest` starts otherwise).
fn directive_word(rest: &str) -> &str {
    let Some(after) = rest.strip_prefix('#') else {
        return "";
    };
    let end = after
        .find(|c: char| !c.is_ascii_alphanumeric() && c != '_')
        .unwrap_or(after.len());
    &after[..end]
}

/// The names a file declares globally (`#declare Name`, `#macro Name`), wherever they stand
/// (outside comments and strings): what an include whose parse failed would have defined.
pub fn declared_names(text: &str) -> Vec<String> {
    let bytes = text.as_bytes();
    let mut names = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if let Some(next) = after_comment_or_string(bytes, i) {
            i = next.max(i + 1);
            continue;
        }
        let rest = &text[i..];
        let word = directive_word(rest);
        if matches!(word, "declare" | "macro") {
            let after = rest[1 + word.len()..].trim_start();
            let name: String = after
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() && !name.starts_with(|c: char| c.is_ascii_digit()) {
                names.push(name);
            }
            i += 1 + word.len();
            continue;
        }
        i += 1;
    }
    names.sort();
    names.dedup();
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(text: &str) -> Vec<Diagnostic> {
        super::super::parse(FileId(0), text).expect_err("a syntax error")
    }

    #[test]
    fn sync_points_start_top_level_items() {
        let text =
            "#declare A =\n  sphere { <0,0,0>, 1 }\nbox {\n  <0,0,0>\n}\n#if (1)\n a\n#end\n";
        let at: Vec<&str> = sync_points(text).iter().map(|&s| &text[s..s + 3]).collect();
        // Not `sphere` (after `=`), not `a` (inside `#if`), not `#end`.
        assert_eq!(at, ["#de", "box", "#if"]);
    }

    #[test]
    fn each_broken_item_is_one_error_in_order() {
        let text = "sphere { <0,0,0>, 1 ) }\nbox { <0,0,0>, <1,1,1> }\nsphere { <0,0,0>, (1 }\n\
                    #declare = 3;\nbox { <0,0,0>, <1,1,1> ] }\n";
        let e = errors(text);
        assert_eq!(e.len(), 4, "{e:#?}");
        let starts: Vec<u32> = e.iter().map(|d| d.span.start).collect();
        assert!(starts.windows(2).all(|w| w[0] < w[1]), "{starts:?}");
    }

    #[test]
    fn a_blanked_declaration_does_not_leave_its_head_behind() {
        // The error is in the value, which starts a line of its own.
        let text = "#declare A =\n  sphere { <0,0,0>, 1) }\n#declare B = 2;\n";
        assert_eq!(errors(text).len(), 1);
    }

    #[test]
    fn many_errors_stop_at_the_cap_with_a_note() {
        let text = "sphere { ) }\n".repeat(30);
        let e = errors(&text);
        assert_eq!(e.len(), MAX_SYNTAX_ERRORS + 1);
        assert!(!e[MAX_SYNTAX_ERRORS].is_error());
    }

    #[test]
    fn declared_names_skip_comments_and_strings() {
        let text = "#declare A = 1;\n// #declare B = 2;\n#debug \"#macro C()\"\n#macro D(x) x #end\n#local E = 1;\n";
        assert_eq!(declared_names(text), ["A", "D"]);
    }
}
