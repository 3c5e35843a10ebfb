//! Syntax errors: what the pest parser's failures and over-deep nesting are reported as (the
//! expected tokens named as a reader calls them, unclosed brackets pointed at where they open).

use pest::Parser;

use super::parser::{MAX_NESTING, Rule, SceneParser};
use crate::diag::{Diagnostic, SourceResult};
use crate::span::{FileId, Span};

/// What a grammar rule is called in messages.
fn describe(rule: Rule) -> &'static str {
    match rule {
        Rule::EOI => "end of file",
        Rule::items | Rule::item | Rule::map_items => "a statement",
        Rule::map_entry => "a colour-map entry `[pos, color]`",
        Rule::color_word | Rule::map_word => "a name",
        Rule::comma => "`,`",
        Rule::declare => "`#declare`",
        Rule::local => "`#local`",
        Rule::if_d => "`#if`",
        Rule::elif_d => "`#elif`",
        Rule::else_d => "`#else`",
        Rule::while_d => "`#while`",
        Rule::for_d => "`#for`",
        Rule::macro_d => "`#macro`",
        Rule::include_d => "`#include`",
        Rule::ifdef_d => "`#ifdef`",
        Rule::ifndef_d => "`#ifndef`",
        Rule::undef_d => "`#undef`",
        Rule::switch_d => "`#switch`",
        Rule::case_d => "`#case`",
        Rule::range_d => "`#range`",
        Rule::break_d => "`#break`",
        Rule::debug_d => "`#debug`",
        Rule::warning_d => "`#warning`",
        Rule::error_d => "`#error`",
        Rule::dword => "a directive",
        Rule::params => "parameter names",
        Rule::keyword => "a property keyword",
        Rule::expr | Rule::vexpr | Rule::iexpr => "an expression",
        Rule::add | Rule::sub | Rule::mul | Rule::div => "an operator",
        Rule::le | Rule::ge | Rule::eq | Rule::ne | Rule::lt | Rule::gt => "an operator",
        Rule::and | Rule::or => "an operator",
        Rule::qmark => "`?`",
        Rule::colon => "`:`",
        Rule::neg | Rule::pos | Rule::not => "an operator",
        Rule::rgb => "`rgb`",
        Rule::index => "`[`",
        Rule::field => "`.`",
        Rule::paren => "`(`",
        Rule::vector => "a vector `<x, y, z>`",
        Rule::array => "an array `[a, b]`",
        Rule::named => "a name",
        Rule::args => "`(`",
        Rule::number => "a number",
        Rule::boolean => "`true` or `false`",
        Rule::string | Rule::str_inner => "a string",
        Rule::ident | Rule::ident_raw | Rule::fn_word => "a name",
        _ => "something else",
    }
}

/// The syntax error of a failed parse; `stray` is the first character outside ASCII that
/// stands outside strings and comments ([`check_nesting`]).
pub(super) fn syntax_error(
    file: FileId,
    text: &str,
    e: pest::error::Error<Rule>,
    stray: Option<usize>,
) -> Diagnostic {
    let pos = error_pos(&e);
    if let Some(at) = stray.filter(|&at| at >= pos && caused_by(text, at, pos)) {
        return not_ascii(file, text, at);
    }
    let found = found_at(text, pos);
    let len = if pos >= text.len() {
        0
    } else {
        found_len(text, pos)
    };
    let span = Span::new(file, pos as u32, (pos + len) as u32);
    let (rules, after_operand) = match &e.variant {
        pest::error::ErrorVariant::ParsingError { positives, .. } => expected_rules(positives),
        pest::error::ErrorVariant::CustomError { .. } => (Vec::new(), false),
    };
    let mut expected: Vec<&str> = rules.into_iter().map(describe).collect();
    // Say "a directive" once instead of listing every one, and leave out the tokens that could
    // merely continue an expression when there are other choices.
    if expected.iter().filter(|e| e.starts_with("`#")).count() > 2 {
        expected.retain(|e| {
            !e.starts_with("`#") || matches!(*e, "`#elif`" | "`#else`" | "`#case`" | "`#range`")
        });
        expected.push("a directive");
    }
    if expected.len() > 3 || after_operand {
        expected.retain(|e| !matches!(*e, "`.`" | "`[`" | "an operator"));
    }
    expected.sort();
    expected.dedup();
    let expected_text = match expected.len() {
        0 => "something else".to_string(),
        1 => expected[0].to_string(),
        n => format!("{} or {}", expected[..n - 1].join(", "), expected[n - 1]),
    };
    let mut d = if expected.is_empty() {
        Diagnostic::error(span, format!("syntax error: unexpected {found}"))
            .with_label("not expected here")
    } else {
        Diagnostic::error(
            span,
            format!("syntax error: expected {expected_text}, found {found}"),
        )
        .with_label(format!("expected {expected_text}"))
    };
    let rest = &text[pos.min(text.len())..];
    if rest.starts_with('#') {
        let word: String = rest
            .strip_prefix('#')
            .unwrap_or(rest)
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        let known = [
            "declare", "local", "if", "elif", "else", "end", "while", "for", "macro", "include",
            "ifdef", "ifndef", "undef", "switch", "case", "range", "break", "debug", "warning",
            "error",
        ];
        if let Some(hint) = super::povray_hint(&format!("#{word}"), "") {
            // What could stand here instead matters less than the spelling to write.
            d = d.with_help(hint);
            d.message = format!("syntax error: unexpected {found}");
            d.label = "a POV-Ray directive".into();
        } else if matches!(word.as_str(), "end" | "else" | "elif") {
            d = d.with_help(format!(
                "`#{word}` without a matching `#if`, `#ifdef`, `#switch`, `#while`, `#for` or \
                 `#macro`"
            ));
        } else if matches!(word.as_str(), "case" | "range") {
            d = d.with_help(format!(
                "`#{word}` stands only directly inside `#switch (value) ... #end`"
            ));
        } else if let Some(form) = directive_form(&word) {
            // A directive of the language whose head does not parse: how it is written.
            d.message = format!("syntax error: malformed `#{word}`");
            d.label = "not the form of this directive".into();
            d = d.with_help(format!("write it as {form}"));
        } else if let Some(head) = known
            .iter()
            .filter(|k| word.len() > k.len() && word.starts_with(*k))
            .max_by_key(|k| k.len())
        {
            // `#elsebox`, `#declareX`: a directive's word ends where its name does.
            d = d.with_help(format!(
                "a directive's word stands alone: write `#{head} {}`",
                &word[head.len()..]
            ));
        } else if let Some(s) = crate::diag::suggest(&word, known) {
            d = d.with_help(format!("did you mean `#{s}`?"));
        }
    } else if expected_text.contains("a name") && is_keyword(&text[pos..pos + len]) {
        d = d.with_help(format!(
            "`{}` is a reserved word (a property keyword); choose another name",
            &text[pos..pos + len]
        ));
    } else if rest.starts_with('?') {
        d = d.with_help(
            "a conditional `c ? a : b` stands here only in parentheses: `(c ? a : b)` (in a \
             block's body, inside `< >`, and as the middle part of another conditional)",
        );
    } else if pos >= text.len() && expected_text.contains("`}`") {
        d = d.with_help("a block is not closed: add `}`");
    } else if rest.starts_with('{') {
        match super::povray_hint(word_before(text, pos), "") {
            Some(hint) => d = d.with_help(hint),
            None => d = d.with_help("a block needs a name before `{`, e.g. `sphere { ... }`"),
        }
    } else if rest.starts_with('}') && !open_blocks(&text[..pos]).iter().any(|o| o.1 == 1) {
        d.message = "syntax error: unmatched `}`".into();
        d.label = "no block is open here".into();
        d = d.with_help(
            "remove this `}`, or look above for a block closed twice (`{` and `}` must pair up)",
        );
    } else if let Some(hint) = super::povray_hint(&text[pos..pos + len], "") {
        d = d.with_help(hint);
    } else if rest.starts_with('=') && !rest.starts_with("==") {
        d = d.with_help(
            "POV-Ray's comparison `=` is `==` here (`=` stands only in `#declare Name = value`)",
        );
    }
    // The parser stops at the comment's `/` or just after it.
    let comment_at = if rest.starts_with("/*") {
        Some(pos)
    } else if rest.starts_with('*') && text[..pos].ends_with('/') {
        Some(pos - 1)
    } else {
        None
    };
    if let Some(at) = comment_at
        && !block_comment(text.as_bytes(), at).closed
    {
        return Diagnostic::error(
            Span::new(file, at as u32, at as u32 + 2),
            "syntax error: a `/* ... */` comment is never closed",
        )
        .with_label("this `/*` is never closed")
        .with_extra(last_char(file, text), "the file ends here, inside it")
        .with_help("close it with `*/`");
    }
    if rest.starts_with('"') && !string_closed(&rest[1..]) {
        return Diagnostic::error(
            Span::new(file, pos as u32, pos as u32 + 1),
            "syntax error: a string is never closed",
        )
        .with_label("this `\"` has no closing `\"` on its line")
        .with_help(
            "close the string with `\"` before the end of the line (a string cannot span lines; \
             write `\\n` for a line break in it)",
        );
    }
    if pos >= text.len()
        && let Some(open) = unclosed(text)
    {
        return never_closed(file, text, open);
    }
    if pos >= text.len() && (text.matches("#end").count() < count_openers(text)) {
        d = d.with_help("a directive is not closed: add `#end`");
    }
    if let Some(format) = other_renderer(text) {
        d = d.with_help(format!(
            "this looks like {format}: sppm-lang reads its own POV-Ray-like language \
             (docs/language.md), e.g. `sphere {{ <0, 0, 0>, 1 }}`; write the scene in it"
        ));
    }
    if d.help.is_none() && rest.starts_with('>') && joined_vector(&text[..pos]) {
        d = d.with_help(
            "without commas, `-` and `+` join the components on their two sides (`<1 -2 3>` is \
             `<1 - 2, 3>`, as in POV-Ray), and a vector needs two or more: separate the \
             components with commas, e.g. `<-1, -2, -3>`",
        );
    }
    if d.help.is_none()
        && pos < text.len()
        && innermost_bracket(&text[..pos]) == Some(b'[')
        && text[..pos].trim_end().ends_with(|c: char| {
            c.is_ascii_alphanumeric() || matches!(c, '_' | ')' | ']' | '>' | '"')
        })
    {
        // `[0 Red]`: POV-Ray's colour-map entries are written without a comma.
        d = d.with_help(format!(
            "the items of `[...]` are separated by commas: add `,` before {found} (e.g. \
             `[0, Red]`)"
        ));
    }
    if d.help.is_none() {
        // No better guess: what would fit, or where the cause usually is.
        d = d.with_help(if pos >= text.len() {
            format!("the file ends too early: add {expected_text}")
        } else if expected.is_empty() {
            format!("remove {found}, or look before it for something left open (`<`, `(`, `{{`)")
        } else {
            format!("write {expected_text} here, or remove {found}")
        });
    }
    d
}

/// How the head of directive `#word` is written (`None` for a word that is no directive, and
/// for those handled on their own: `#end`, `#else`, `#elif`, `#case`, `#range`).
fn directive_form(word: &str) -> Option<&'static str> {
    Some(match word {
        "declare" => "`#declare Name = value;`",
        "local" => "`#local Name = value;`",
        "if" => "`#if (condition) ... #end`, the condition in parentheses",
        "while" => "`#while (condition) ... #end`, the condition in parentheses",
        "for" => "`#for (I, from, to) ... #end` (or `#for (I, from, to, step)`)",
        "macro" => "`#macro Name(A, B) ... #end`, the parameters in parentheses",
        "include" => "`#include \"file.scn\"`, the file name in quotes",
        "ifdef" => "`#ifdef (Name) ... #end`, the name in parentheses",
        "ifndef" => "`#ifndef (Name) ... #end`, the name in parentheses",
        "undef" => "`#undef Name`",
        "switch" => "`#switch (value) #case (v) ... #end`, the value in parentheses",
        "debug" => "`#debug \"text\"` (a string, or a value to show)",
        "warning" => "`#warning \"text\"` (a string, or a value to show)",
        "error" => "`#error \"text\"` (a string, or a value to show)",
        _ => return None,
    })
}

/// The scene format of another renderer that `text` is written in, if it looks like one: a
/// Mitsuba XML file or a pbrt file (both fail to parse early, on their first line).
fn other_renderer(text: &str) -> Option<&'static str> {
    let body = text.trim_start_matches('\u{feff}').trim_start();
    if body.starts_with("<?xml") || body.starts_with("<scene") {
        return Some("a Mitsuba XML scene");
    }
    let pbrt = [
        "WorldBegin",
        "LookAt ",
        "Camera \"",
        "Film \"",
        "Sampler \"",
        "Integrator \"",
        "Shape \"",
        "LightSource \"",
        "AttributeBegin",
    ];
    text.lines()
        .any(|l| pbrt.iter().any(|w| l.trim_start().starts_with(w)))
        .then_some("a pbrt scene")
}

pub(super) fn error_pos(e: &pest::error::Error<Rule>) -> usize {
    match e.location {
        pest::error::InputLocation::Pos(p) => p,
        pest::error::InputLocation::Span((s, _)) => s,
    }
}

/// Whether the parse that failed at `pos` failed because of the character at `at`: with it
/// and the rest of its word written as `_` (a name's character), the text parses, or fails
/// further on. (The parser backtracks: `#declare Größe = 1` fails at `#declare`, not at `ö`.)
fn caused_by(text: &str, at: usize, pos: usize) -> bool {
    let mut end = at;
    let mut word = String::new();
    for c in text[at..].chars() {
        if end > at && !(c.is_alphanumeric() || c == '_') {
            break;
        }
        word.extend(std::iter::repeat_n(
            if c.is_ascii() { c } else { '_' },
            c.len_utf8(),
        ));
        end += c.len_utf8();
    }
    let patched = format!("{}{word}{}", &text[..at], &text[end..]);
    SceneParser::parse(Rule::file, &patched).map_or_else(|e| error_pos(&e) > pos, |_| true)
}

/// A character outside ASCII where the grammar takes none: in a name, or pasted from a
/// document (typographic quotes, a non-breaking space).
fn not_ascii(file: FileId, text: &str, at: usize) -> Diagnostic {
    let c = text[at..].chars().next().unwrap_or(' ');
    let span = Span::new(file, at as u32, (at + c.len_utf8()) as u32);
    let help = match c {
        '\u{201c}' | '\u{201d}' | '\u{201e}' | '\u{ab}' | '\u{bb}' => {
            "a string is written with straight double quotes: `\"file.png\"`".to_string()
        }
        '\u{2018}' | '\u{2019}' => "strings take straight double quotes: `\"...\"`".to_string(),
        '\u{2212}' | '\u{2013}' | '\u{2014}' => "write the minus sign as `-`".to_string(),
        c if c.is_whitespace() => "replace it with a plain space".to_string(),
        _ => "names are ASCII letters, digits and `_` (other characters may stand in strings \
              and comments): e.g. `Grosse` for `Größe`"
            .to_string(),
    };
    Diagnostic::error(
        span,
        format!(
            "syntax error: `{c}` (U+{:04X}) is not part of the language",
            c as u32
        ),
    )
    .with_label("not an ASCII character")
    .with_help(help)
}

/// The name before position `pos`, skipping blanks and one `[...]` (`array[3] {`): what a
/// misplaced `{` was probably meant to open.
fn word_before(text: &str, pos: usize) -> &str {
    let mut head = text[..pos.min(text.len())].trim_end();
    if head.ends_with(']')
        && let Some(open) = head.rfind('[')
    {
        head = head[..open].trim_end();
    }
    // After the last character that is not part of a name (it may take several bytes).
    let start = head
        .char_indices()
        .rev()
        .find(|&(_, c)| !(c.is_ascii_alphanumeric() || c == '_'))
        .map_or(0, |(i, c)| i + c.len_utf8());
    &head[start..]
}

/// The innermost `{` or block directive (`#if`, `#switch`, `#while`, ...: what `#end` closes)
/// still open at the end of the text, as its start and length (comments and strings skipped).
fn unclosed(text: &str) -> Option<(usize, usize)> {
    open_blocks(text).pop()
}

/// Every `{` and block directive still open at the end of the text, outermost first, as in
/// [`unclosed`].
fn open_blocks(text: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut open: Vec<(usize, usize)> = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if let Some(next) = after_comment_or_string(bytes, i) {
            i = next;
            continue;
        }
        match bytes[i] {
            b'{' => open.push((i, 1)),
            b'}' => {
                if let Some(k) = open.iter().rposition(|o| o.1 == 1) {
                    open.truncate(k);
                }
            }
            b'#' => {
                let word = text[i + 1..]
                    .split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
                    .next()
                    .unwrap_or("");
                match word {
                    "if" | "ifdef" | "ifndef" | "switch" | "while" | "for" | "macro" => {
                        open.push((i, word.len() + 1));
                    }
                    "end" => {
                        if let Some(k) = open.iter().rposition(|o| o.1 > 1) {
                            open.truncate(k);
                        }
                    }
                    _ => {}
                }
            }
            _ => {}
        }
        i += 1;
    }
    open
}

/// Whether a string whose text starts at `rest` (after its opening quote) is closed on its
/// line: a `"` before the line's end, a backslash escaping the character after it.
fn string_closed(rest: &str) -> bool {
    let mut chars = rest.chars();
    while let Some(c) = chars.next() {
        match c {
            '"' => return true,
            '\n' => return false,
            '\\' => {
                chars.next();
            }
            _ => {}
        }
    }
    false
}

/// "this `{` is never closed" (or `#if`, ...), at the opener, with the end of the file as a
/// second label.
fn never_closed(file: FileId, text: &str, (open, len): (usize, usize)) -> Diagnostic {
    let opener = &text[open..open + len];
    let (what, help) = if opener == "{" {
        let name = word_before(text, open);
        let block = if name.is_empty() {
            "a block".to_string()
        } else {
            format!("`{name} {{ ... }}`")
        };
        (block, "add `}` where the block ends")
    } else {
        (format!("`{opener}`"), "add `#end` where it ends")
    };
    Diagnostic::error(
        Span::new(file, open as u32, (open + len) as u32),
        format!("syntax error: {what} is never closed"),
    )
    .with_label(format!("this `{opener}` is never closed"))
    .with_extra(last_char(file, text), "the file ends here, inside it")
    .with_help(help)
}

/// The last character of the text that is not blank.
fn last_char(file: FileId, text: &str) -> Span {
    let end = text.trim_end().len();
    let last = text[..end].chars().next_back().map_or(0, char::len_utf8);
    Span::new(file, (end - last) as u32, end as u32)
}

/// The rules a syntax error expected, from the ones pest recorded at the error position.
///
/// The grammar tries some rules only where the next character allows them (see the speed notes
/// in `grammar/scene.pest`); one rule of each place is always tried and stands for the others:
/// `comma` for an item, `rgb` for an operand, `index` for what may follow an operand (postfix
/// and infix operators). This puts back the rules that a place allows, so that the message lists
/// everything that could stand there. The second value says that the position follows an
/// operand: the message then leaves out the tokens that could merely continue the expression.
fn expected_rules(positives: &[Rule]) -> (Vec<Rule>, bool) {
    // A failure at the file's first item is reported as the whole file failing there: what could
    // stand there is any item, as after a comma.
    let positives: &[Rule] = if positives == [Rule::file] {
        &[Rule::comma, Rule::dword]
    } else {
        positives
    };
    let mut rules: Vec<Rule> = positives
        .iter()
        .copied()
        .filter(|r| *r != Rule::args)
        .collect();
    if positives.contains(&Rule::comma) {
        rules.extend([
            Rule::keyword,
            Rule::iexpr,
            Rule::declare,
            Rule::local,
            Rule::if_d,
            Rule::while_d,
            Rule::for_d,
            Rule::macro_d,
            Rule::include_d,
            Rule::ifdef_d,
            Rule::ifndef_d,
            Rule::switch_d,
            Rule::break_d,
            Rule::undef_d,
            Rule::debug_d,
            Rule::warning_d,
            Rule::error_d,
        ]);
    }
    if positives.contains(&Rule::rgb) {
        rules.extend([
            Rule::neg,
            Rule::not,
            Rule::pos,
            Rule::number,
            Rule::ident,
            Rule::vector,
            Rule::string,
            Rule::boolean,
            Rule::array,
            Rule::paren,
        ]);
    }
    (rules, positives.contains(&Rule::index))
}

fn is_keyword(word: &str) -> bool {
    SceneParser::parse(Rule::keyword, word).is_ok_and(|p| p.as_str() == word)
        || matches!(word, "rgb" | "rgbf" | "rgbt" | "rgbft" | "true" | "false")
}

fn count_openers(text: &str) -> usize {
    ["#if", "#switch", "#while", "#for", "#macro"]
        .iter()
        .map(|k| text.matches(k).count())
        .sum()
}

fn found_len(text: &str, pos: usize) -> usize {
    let rest = &text[pos..];
    let word = rest
        .char_indices()
        .take_while(|(_, c)| c.is_ascii_alphanumeric() || *c == '_' || *c == '#')
        .last()
        .map(|(i, c)| i + c.len_utf8());
    word.unwrap_or_else(|| rest.chars().next().map_or(0, char::len_utf8))
}

fn found_at(text: &str, pos: usize) -> String {
    if pos >= text.len() {
        return "end of file".into();
    }
    let len = found_len(text, pos);
    format!("`{}`", &text[pos..pos + len])
}

/// Rejects input nested deeper than [`MAX_NESTING`] before the recursive parser sees it.
/// Otherwise returns where the first character outside ASCII stands outside strings and
/// comments (after a byte order mark), for [`syntax_error`]: the grammar accepts none there.
pub(super) fn check_nesting(file: FileId, text: &str) -> SourceResult<Option<usize>> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    let mut prefix_run = 0usize;
    let mut stray = None;
    let mut i = if text.starts_with('\u{feff}') { 3 } else { 0 };
    while i < bytes.len() {
        let c = bytes[i];
        // `rgb` (and `rgbf`, `rgbt`, `rgbft`) is a prefix operator too: a chain of them nests
        // like `- - - 1`.
        let ident_byte =
            |b: Option<&u8>| b.is_some_and(|b| b.is_ascii_alphanumeric() || *b == b'_');
        if c == b'r'
            && let Some(n) = [&b"rgbft"[..], b"rgbf", b"rgbt", b"rgb"]
                .iter()
                .find(|w| bytes[i..].starts_with(w) && !ident_byte(bytes.get(i + w.len())))
                .map(|w| w.len())
            && !(i > 0 && ident_byte(bytes.get(i - 1)))
        {
            prefix_run += 1;
            if prefix_run > MAX_NESTING {
                return Err(vec![too_deep(Span::new(file, i as u32, (i + n) as u32))]);
            }
            i += n;
            continue;
        }
        match c {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                let c = block_comment(bytes, i);
                if let Some(at) = c.too_deep {
                    return Err(vec![too_deep(Span::new(file, at as u32, (at + 2) as u32))]);
                }
                i = c.end;
                continue;
            }
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
            }
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            b'#' => {
                let rest = &text[i..];
                if ["#if", "#switch", "#while", "#for", "#macro"]
                    .iter()
                    .any(|k| rest.starts_with(k))
                {
                    depth += 1;
                } else if rest.starts_with("#end") {
                    depth = depth.saturating_sub(1);
                }
            }
            128.. if stray.is_none() => stray = Some(i),
            _ => {}
        }
        if matches!(c, b'-' | b'+' | b'!') {
            prefix_run += 1;
        } else if !c.is_ascii_whitespace() {
            prefix_run = 0;
        }
        if depth > MAX_NESTING || prefix_run > MAX_NESTING {
            return Err(vec![too_deep(Span::new(file, i as u32, (i + 1) as u32))]);
        }
        i += 1;
    }
    Ok(stray)
}

/// The innermost of `(`, `[` and `{` still open at the end of `text` (outside strings and
/// comments).
/// Whether `before` (the text up to a `>` that does not close a vector) ends in a vector
/// opened on its line without commas whose components a blank-separated sign joined
/// (`<-1 -2 -3`).
fn joined_vector(before: &str) -> bool {
    let line = &before[before.rfind('\n').map_or(0, |i| i + 1)..];
    line.rfind('<').is_some_and(|open| {
        let inside = &line[open + 1..];
        !inside.contains([',', '>', '(', '[']) && (inside.contains(" -") || inside.contains(" +"))
    })
}

fn innermost_bracket(text: &str) -> Option<u8> {
    let bytes = text.as_bytes();
    let mut open = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if let Some(next) = after_comment_or_string(bytes, i) {
            i = next;
            continue;
        }
        match bytes[i] {
            c @ (b'(' | b'[' | b'{') => open.push(c),
            b')' | b']' | b'}' => {
                open.pop();
            }
            _ => {}
        }
        i += 1;
    }
    open.pop()
}

/// Where the comment or string starting at `i` ends (just past it; at the end of its line for
/// a line comment and an unclosed string), or `None` when none starts there.
pub(super) fn after_comment_or_string(bytes: &[u8], mut i: usize) -> Option<usize> {
    match (bytes[i], bytes.get(i + 1)) {
        (b'/', Some(b'/')) => {
            while i < bytes.len() && bytes[i] != b'\n' {
                i += 1;
            }
            Some(i)
        }
        (b'/', Some(b'*')) => Some(block_comment(bytes, i).end),
        (b'"', _) => {
            i += 1;
            while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                i += if bytes[i] == b'\\' { 2 } else { 1 };
            }
            Some((i + 1).min(bytes.len()))
        }
        _ => None,
    }
}

/// A `/* ... */` comment starting at `start`, where comments nest as in POV-Ray (`/* a /* b */
/// c */` is one comment).
struct BlockComment {
    /// Just past its closing `*/`, or the end of the text.
    end: usize,
    closed: bool,
    /// Where an opening `/*` nests deeper than [`MAX_NESTING`] (the parser would recurse).
    too_deep: Option<usize>,
}

fn block_comment(bytes: &[u8], start: usize) -> BlockComment {
    let (mut depth, mut i, mut too_deep) = (0usize, start, None);
    while i + 1 < bytes.len() {
        match (bytes[i], bytes[i + 1]) {
            (b'/', b'*') => {
                depth += 1;
                if depth > MAX_NESTING && too_deep.is_none() {
                    too_deep = Some(i);
                }
                i += 2;
            }
            (b'*', b'/') => {
                depth -= 1;
                i += 2;
                if depth == 0 {
                    return BlockComment {
                        end: i,
                        closed: true,
                        too_deep,
                    };
                }
            }
            _ => i += 1,
        }
    }
    BlockComment {
        end: bytes.len(),
        closed: false,
        too_deep,
    }
}

fn too_deep(span: Span) -> Diagnostic {
    Diagnostic::error(span, format!("nesting deeper than {MAX_NESTING} levels"))
        .with_label("too deeply nested")
        .with_help("split the expression or block into declared parts")
}
