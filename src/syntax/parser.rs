//! The pest parser and the conversion of its parse tree into the [`ast`](super::ast).

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::LazyLock;

use pest::Parser;
use pest::iterators::{Pair, Pairs};
use pest::pratt_parser::{Assoc, Op, PrattParser};

use super::ast::*;
use crate::diag::{Diagnostic, SourceResult};
use crate::span::{FileId, Span};

#[derive(pest_derive::Parser)]
#[grammar = "../grammar/scene.pest"]
struct SceneParser;

/// Deepest nesting of brackets, blocks and directives a file may have. Guards the recursive
/// parser and evaluator against stack exhaustion on absurd input.
pub const MAX_NESTING: usize = 200;

/// Most terms (operands, operators) one expression may have, counting the expressions it sits
/// in: a chain `1 + 1 + ...` builds a tree as deep as it is long, and evaluating it recurses that
/// deep. 100 000 terms overflowed the evaluator's 80 MB stack; 10 000 leave a wide margin.
pub const MAX_EXPRESSION_TERMS: usize = 10_000;

static PRATT: LazyLock<PrattParser<Rule>> = LazyLock::new(|| {
    PrattParser::new()
        .op(Op::infix(Rule::or, Assoc::Left))
        .op(Op::infix(Rule::and, Assoc::Left))
        .op(Op::infix(Rule::eq, Assoc::Left) | Op::infix(Rule::ne, Assoc::Left))
        .op(Op::infix(Rule::lt, Assoc::Left)
            | Op::infix(Rule::le, Assoc::Left)
            | Op::infix(Rule::gt, Assoc::Left)
            | Op::infix(Rule::ge, Assoc::Left))
        .op(Op::infix(Rule::add, Assoc::Left) | Op::infix(Rule::sub, Assoc::Left))
        .op(Op::infix(Rule::mul, Assoc::Left) | Op::infix(Rule::div, Assoc::Left))
        .op(Op::prefix(Rule::neg)
            | Op::prefix(Rule::pos)
            | Op::prefix(Rule::not)
            | Op::prefix(Rule::rgb))
        .op(Op::postfix(Rule::index) | Op::postfix(Rule::field))
});

/// What a grammar rule is called in messages.
fn describe(rule: Rule) -> &'static str {
    match rule {
        Rule::EOI => "end of file",
        Rule::items | Rule::item => "a statement",
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
        Rule::params => "parameter names",
        Rule::keyword => "a property keyword",
        Rule::expr | Rule::vexpr | Rule::iexpr => "an expression",
        Rule::add | Rule::sub | Rule::mul | Rule::div => "an operator",
        Rule::le | Rule::ge | Rule::eq | Rule::ne | Rule::lt | Rule::gt => "an operator",
        Rule::and | Rule::or => "an operator",
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
        Rule::ident | Rule::ident_raw => "a name",
        _ => "something else",
    }
}

/// Parses one file. On failure returns one syntax error.
pub fn parse(file: FileId, text: &str) -> SourceResult<Vec<Item>> {
    check_nesting(file, text)?;
    let mut pairs =
        SceneParser::parse(Rule::file, text).map_err(|e| vec![syntax_error(file, text, e)])?;
    let file_pair = pairs.next().expect("file rule");
    let items = file_pair.into_inner().next().expect("items");
    let cx = Cx {
        file,
        terms: Cell::new(0),
        too_long: RefCell::new(None),
    };
    let items = cx.items(items);
    match cx.too_long.into_inner() {
        Some(d) => Err(vec![d]),
        None => Ok(items),
    }
}

fn syntax_error(file: FileId, text: &str, e: pest::error::Error<Rule>) -> Diagnostic {
    let pos = match e.location {
        pest::error::InputLocation::Pos(p) => p,
        pest::error::InputLocation::Span((s, _)) => s,
    };
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
            d = d.with_help(hint);
            if expected_text == "something else" {
                d.message = format!("syntax error: unexpected {found}");
                d.label = "a POV-Ray directive".into();
            }
        } else if matches!(word.as_str(), "end" | "else" | "elif") {
            d = d.with_help(format!(
                "`#{word}` without a matching `#if`, `#ifdef`, `#switch`, `#while`, `#for` or \
                 `#macro`"
            ));
        } else if matches!(word.as_str(), "case" | "range") {
            d = d.with_help(format!(
                "`#{word}` stands only directly inside `#switch (value) ... #end`"
            ));
        } else if let Some(s) = crate::diag::suggest(&word, known) {
            d = d.with_help(format!("did you mean `#{s}`?"));
        }
    } else if expected_text.contains("a name") && is_keyword(&text[pos..pos + len]) {
        d = d.with_help(format!(
            "`{}` is a reserved word (a property keyword); choose another name",
            &text[pos..pos + len]
        ));
    } else if pos >= text.len() && expected_text.contains("`}`") {
        d = d.with_help("a block is not closed: add `}`");
    } else if rest.starts_with('{') {
        match super::povray_hint(word_before(text, pos), "") {
            Some(hint) => d = d.with_help(hint),
            None => d = d.with_help("a block needs a name before `{`, e.g. `sphere { ... }`"),
        }
    } else if rest.starts_with('=') && !rest.starts_with("==") {
        d = d.with_help(
            "POV-Ray's comparison `=` is `==` here (`=` stands only in `#declare Name = value`)",
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
    d
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
    let start = head
        .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .map_or(0, |i| i + 1);
    &head[start..]
}

/// The innermost `{` or block directive (`#if`, `#switch`, `#while`, ...: what `#end` closes)
/// still open at the end of the text, as its start and length (comments and strings skipped).
fn unclosed(text: &str) -> Option<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut open: Vec<(usize, usize)> = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i + 1 < bytes.len() && !(bytes[i] == b'*' && bytes[i + 1] == b'/') {
                    i += 1;
                }
                i += 1;
            }
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
            }
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
    open.pop()
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
    let end = text.trim_end().len();
    let last = text[..end].chars().next_back().map_or(0, char::len_utf8);
    Diagnostic::error(
        Span::new(file, open as u32, (open + len) as u32),
        format!("syntax error: {what} is never closed"),
    )
    .with_label(format!("this `{opener}` is never closed"))
    .with_extra(
        Span::new(file, (end - last) as u32, end as u32),
        "the file ends here, inside it",
    )
    .with_help(help)
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
        || matches!(word, "rgb" | "true" | "false")
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
fn check_nesting(file: FileId, text: &str) -> SourceResult<()> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    let mut prefix_run = 0usize;
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        // `rgb` is a prefix operator too: a chain of them nests like `- - - 1`.
        let ident_byte =
            |b: Option<&u8>| b.is_some_and(|b| b.is_ascii_alphanumeric() || *b == b'_');
        if c == b'r'
            && bytes[i..].starts_with(b"rgb")
            && !(i > 0 && ident_byte(bytes.get(i - 1)))
            && !ident_byte(bytes.get(i + 3))
        {
            prefix_run += 1;
            if prefix_run > MAX_NESTING {
                return Err(vec![too_deep(Span::new(file, i as u32, (i + 3) as u32))]);
            }
            i += 3;
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
                i += 2;
                while i + 1 < bytes.len() && !(bytes[i] == b'*' && bytes[i + 1] == b'/') {
                    i += 1;
                }
                i += 2;
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
    Ok(())
}

fn too_deep(span: Span) -> Diagnostic {
    Diagnostic::error(span, format!("nesting deeper than {MAX_NESTING} levels"))
        .with_label("too deeply nested")
        .with_help("split the expression or block into declared parts")
}

struct Cx {
    file: FileId,
    /// Terms (operands and operators) of the expressions being built, summed along the current
    /// path of nested expressions: a bound on the depth of the expression tree there.
    terms: Cell<usize>,
    /// The first expression that went over [`MAX_EXPRESSION_TERMS`].
    too_long: RefCell<Option<Diagnostic>>,
}

impl Cx {
    fn span(&self, pair: &Pair<Rule>) -> Span {
        let s = pair.as_span();
        Span::new(self.file, s.start() as u32, s.end() as u32)
    }

    fn name(&self, pair: Pair<Rule>) -> Name {
        Name {
            span: self.span(&pair),
            text: pair.as_str().to_string(),
        }
    }

    fn items(&self, pair: Pair<Rule>) -> Vec<Item> {
        pair.into_inner().map(|p| self.item(p)).collect()
    }

    fn item(&self, pair: Pair<Rule>) -> Item {
        match pair.as_rule() {
            Rule::keyword => Item::Keyword(self.name(pair)),
            Rule::comma => Item::Comma(self.span(&pair)),
            Rule::expr | Rule::iexpr => Item::Expr(self.expr(pair)),
            _ => Item::Directive(Box::new(self.directive(pair))),
        }
    }

    fn directive(&self, pair: Pair<Rule>) -> Directive {
        let span = self.span(&pair);
        let rule = pair.as_rule();
        let mut inner = pair.into_inner();
        let kind = match rule {
            Rule::declare | Rule::local => {
                let name = self.name(inner.next().unwrap());
                let value = self.expr(inner.next().unwrap());
                DirectiveKind::Bind {
                    name,
                    value,
                    local: rule == Rule::local,
                }
            }
            Rule::if_d => {
                let cond = self.expr(inner.next().unwrap());
                let body = self.items(inner.next().unwrap());
                let mut branches = vec![(cond, body)];
                let mut otherwise = None;
                for p in inner {
                    match p.as_rule() {
                        Rule::elif_d => {
                            let mut i = p.into_inner();
                            let c = self.expr(i.next().unwrap());
                            let b = self.items(i.next().unwrap());
                            branches.push((c, b));
                        }
                        _ => otherwise = Some(self.items(p.into_inner().next().unwrap())),
                    }
                }
                DirectiveKind::If {
                    branches,
                    otherwise,
                }
            }
            Rule::while_d => DirectiveKind::While {
                cond: self.expr(inner.next().unwrap()),
                body: self.items(inner.next().unwrap()),
            },
            Rule::for_d => {
                let var = self.name(inner.next().unwrap());
                let from = self.expr(inner.next().unwrap());
                let to = self.expr(inner.next().unwrap());
                let rest: Vec<Pair<Rule>> = inner.collect();
                let (step, body) = if rest.len() == 2 {
                    (
                        Some(self.expr(rest[0].clone())),
                        self.items(rest[1].clone()),
                    )
                } else {
                    (None, self.items(rest[0].clone()))
                };
                DirectiveKind::For {
                    var,
                    from,
                    to,
                    step,
                    body,
                }
            }
            Rule::macro_d => {
                let name = self.name(inner.next().unwrap());
                let params = inner
                    .next()
                    .unwrap()
                    .into_inner()
                    .map(|p| self.name(p))
                    .collect();
                let body = self.items(inner.next().unwrap());
                DirectiveKind::Macro(Rc::new(MacroDef { name, params, body }))
            }
            Rule::include_d => {
                let s = inner.next().unwrap();
                let path_span = self.span(&s);
                DirectiveKind::Include {
                    path: unescape(s.into_inner().next().unwrap().as_str()),
                    path_span,
                }
            }
            Rule::ifdef_d | Rule::ifndef_d => {
                let name = self.name(inner.next().unwrap());
                let body = self.items(inner.next().unwrap());
                let otherwise = inner
                    .next()
                    .map(|p| self.items(p.into_inner().next().unwrap()));
                DirectiveKind::IfDef {
                    name,
                    negate: rule == Rule::ifndef_d,
                    body,
                    otherwise,
                }
            }
            Rule::undef_d => DirectiveKind::Undef(self.name(inner.next().unwrap())),
            Rule::switch_d => {
                let value = self.expr(inner.next().unwrap());
                let mut clauses = Vec::new();
                let mut otherwise = None;
                for p in inner {
                    let r = p.as_rule();
                    let mut i = p.into_inner();
                    match r {
                        Rule::case_d => {
                            let test = ClauseTest::Case(self.expr(i.next().unwrap()));
                            let body = self.items(i.next().unwrap());
                            clauses.push(Clause { test, body });
                        }
                        Rule::range_d => {
                            let lo = self.expr(i.next().unwrap());
                            let hi = self.expr(i.next().unwrap());
                            let body = self.items(i.next().unwrap());
                            clauses.push(Clause {
                                test: ClauseTest::Range(lo, hi),
                                body,
                            });
                        }
                        _ => otherwise = Some(self.items(i.next().unwrap())),
                    }
                }
                DirectiveKind::Switch {
                    value,
                    clauses,
                    otherwise,
                }
            }
            Rule::break_d => DirectiveKind::Break,
            Rule::debug_d | Rule::warning_d | Rule::error_d => DirectiveKind::Message {
                kind: match rule {
                    Rule::debug_d => MessageKind::Debug,
                    Rule::warning_d => MessageKind::Warning,
                    _ => MessageKind::Error,
                },
                value: self.expr(inner.next().unwrap()),
            },
            r => unreachable!("directive rule {r:?}"),
        };
        // A message's span ends with its text (not the blanks that the optional `;` skipped).
        let span = match &kind {
            DirectiveKind::Message { value, .. } => {
                Span::new(self.file, span.start, value.span.end)
            }
            _ => span,
        };
        Directive { kind, span }
    }

    fn expr(&self, pair: Pair<Rule>) -> Expr {
        // A chain of n terms makes a tree up to n deep, and evaluating (and dropping) it recurses
        // that deep: refuse it before building it, as the nesting check refuses deep brackets.
        let n = pair.clone().into_inner().count();
        let terms = self.terms.get() + n;
        if terms > MAX_EXPRESSION_TERMS {
            let first = pair.clone().into_inner().next();
            let span = first
                .as_ref()
                .map_or_else(|| self.span(&pair), |p| self.span(p));
            self.too_long.borrow_mut().get_or_insert_with(|| {
                Diagnostic::error(
                    span,
                    format!("expression too long: more than {MAX_EXPRESSION_TERMS} terms"),
                )
                .with_label("this expression (with the expressions around it)")
                .with_help("split it into declared parts: `#declare A = ...` and use `A`")
            });
            return Expr {
                kind: ExprKind::Number(f64::NAN),
                span: self.span(&pair),
            };
        }
        self.terms.set(terms);
        // One term is a lone primary (prefix and postfix operators and infix operators are
        // terms of their own): no Pratt parser needed, which halves the AST building time of a
        // generated scene (most expressions are single numbers and names).
        let e = if n == 1 {
            self.primary(pair.into_inner().next().expect("one term"))
        } else {
            self.pratt(pair.into_inner())
        };
        self.terms.set(terms - n);
        e
    }

    fn pratt(&self, pairs: Pairs<Rule>) -> Expr {
        PRATT
            .map_primary(|p| self.primary(p))
            .map_prefix(|op, rhs| {
                let span = self.span(&op).join(rhs.span);
                let op = match op.as_rule() {
                    Rule::neg => UnOp::Neg,
                    Rule::pos => UnOp::Pos,
                    Rule::not => UnOp::Not,
                    _ => UnOp::Rgb,
                };
                Expr {
                    kind: ExprKind::Unary(op, Box::new(rhs)),
                    span,
                }
            })
            .map_postfix(|lhs, op| {
                let span = lhs.span.join(self.span(&op));
                let kind = match op.as_rule() {
                    Rule::index => ExprKind::Index(
                        Box::new(lhs),
                        Box::new(self.expr(op.into_inner().next().unwrap())),
                    ),
                    _ => ExprKind::Field(Box::new(lhs), self.name(op.into_inner().next().unwrap())),
                };
                Expr { kind, span }
            })
            .map_infix(|lhs, op, rhs| {
                let span = lhs.span.join(rhs.span);
                let op = match op.as_rule() {
                    Rule::add => BinOp::Add,
                    Rule::sub => BinOp::Sub,
                    Rule::mul => BinOp::Mul,
                    Rule::div => BinOp::Div,
                    Rule::lt => BinOp::Lt,
                    Rule::le => BinOp::Le,
                    Rule::gt => BinOp::Gt,
                    Rule::ge => BinOp::Ge,
                    Rule::eq => BinOp::Eq,
                    Rule::ne => BinOp::Ne,
                    Rule::and => BinOp::And,
                    _ => BinOp::Or,
                };
                Expr {
                    kind: ExprKind::Binary(op, Box::new(lhs), Box::new(rhs)),
                    span,
                }
            })
            .parse(pairs)
    }

    fn primary(&self, pair: Pair<Rule>) -> Expr {
        let span = self.span(&pair);
        let kind = match pair.as_rule() {
            Rule::number => ExprKind::Number(pair.as_str().parse().unwrap_or(f64::NAN)),
            Rule::boolean => ExprKind::Bool(pair.as_str() == "true"),
            Rule::string => {
                ExprKind::Str(unescape(pair.into_inner().next().unwrap().as_str()).into())
            }
            Rule::paren => return self.expr(pair.into_inner().next().unwrap()),
            Rule::vector => ExprKind::Vector(pair.into_inner().map(|p| self.expr(p)).collect()),
            Rule::array => ExprKind::Array(pair.into_inner().map(|p| self.expr(p)).collect()),
            Rule::named => {
                // A plain name, a block `name { items }` or a call `name(args)`. A plain name's
                // span is the name's own (`named` also covers the blanks after it).
                let mut i = pair.into_inner();
                let name = i.next().unwrap();
                match i.next() {
                    None => {
                        return Expr {
                            span: self.span(&name),
                            kind: ExprKind::Ident(name.as_str().to_string()),
                        };
                    }
                    Some(tail) if tail.as_rule() == Rule::items => ExprKind::Block {
                        kind: self.name(name),
                        items: Rc::new(self.items(tail)),
                    },
                    Some(tail) => ExprKind::Call {
                        name: self.name(name),
                        args: tail.into_inner().map(|p| self.expr(p)).collect(),
                    },
                }
            }
            r => unreachable!("primary rule {r:?}"),
        };
        Expr { kind, span }
    }
}

fn unescape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some('t') => out.push('\t'),
                Some(o) => out.push(o),
                None => {}
            }
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(text: &str) -> Vec<Item> {
        parse(FileId(0), text).unwrap_or_else(|e| panic!("{e:?}"))
    }

    #[test]
    fn precedence_mul_over_add() {
        let items = p("1 + 2 * 3");
        let Item::Expr(e) = &items[0] else { panic!() };
        let ExprKind::Binary(BinOp::Add, _, rhs) = &e.kind else {
            panic!("{e:?}")
        };
        assert!(matches!(rhs.kind, ExprKind::Binary(BinOp::Mul, _, _)));
    }

    #[test]
    fn vector_then_keyword() {
        let items = p("sphere { <0, 1, 2>, 0.5 translate <1, 0, 0> }");
        assert_eq!(items.len(), 1);
        let Item::Expr(Expr {
            kind: ExprKind::Block { items, .. },
            ..
        }) = &items[0]
        else {
            panic!()
        };
        assert_eq!(items.len(), 5, "{items:?}");
        assert!(matches!(&items[3], Item::Keyword(n) if n.text == "translate"));
    }

    #[test]
    fn deep_nesting_is_an_error() {
        let text = format!("{}1{}", "(".repeat(1000), ")".repeat(1000));
        assert!(parse(FileId(0), &text).is_err());
    }

    /// Long chains of binary and postfix operators build deep trees: an error, not an abort.
    #[test]
    fn long_operator_chains_are_errors_not_stack_overflows() {
        for (head, link) in [("1", "+1"), ("1", " - 1"), ("A", "[0]"), ("<1,2,3>", ".x")] {
            let text = format!("#declare X = {head}{}", link.repeat(300_000));
            let err = parse(FileId(0), &text).expect_err(link);
            assert!(
                err[0].message.contains("expression too long"),
                "{link}: {:?}",
                err[0].message
            );
        }
        // Along nested expressions the terms add up; side by side they do not.
        // (`1+` is two terms: `inner` has 3 001.)
        let inner = format!("({}1)", "1+".repeat(1_500));
        let nested = format!("#declare X = ({}{inner})", "1+".repeat(1_500));
        assert!(parse(FileId(0), &nested).is_ok());
        let deeper = format!("#declare X = ({}{inner})", "1+".repeat(3_500));
        assert!(parse(FileId(0), &deeper).is_err());
        let side_by_side = format!("#declare X = {}", [inner.as_str(); 3].join(" + "));
        assert!(parse(FileId(0), &side_by_side).is_ok());
        // A long chain below the limit parses.
        let text = format!(
            "#declare X = 1{}",
            "+1".repeat(MAX_EXPRESSION_TERMS / 2 - 1)
        );
        assert!(parse(FileId(0), &text).is_ok());
    }

    /// Chains of prefix operators nest too, `rgb` among them: 300 000 of them overflowed the
    /// parse thread's stack (an abort, not a diagnostic) before `rgb` was counted.
    #[test]
    fn long_prefix_chains_are_errors_not_stack_overflows() {
        for chain in ["rgb ", "-", "-rgb ", "! rgb + "] {
            let text = format!("#declare X = {}1", chain.repeat(300_000));
            let err = parse(FileId(0), &text).expect_err(chain);
            assert!(
                err[0].message.contains("nesting deeper"),
                "{chain}: {:?}",
                err[0].message
            );
        }
        // Up to the limit a chain parses, and a name merely containing `rgb` is no prefix.
        let ok = format!("#declare X = {}1", "rgb ".repeat(MAX_NESTING));
        assert!(parse(FileId(0), &ok).is_ok());
        let names = format!(
            "#declare rgbx = 1 {}",
            "#declare Y = rgbx + argb_ ".repeat(1000)
        );
        assert!(check_nesting(FileId(0), &names).is_ok());
    }
}
