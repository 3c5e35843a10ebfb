//! The pest parser and the conversion of its parse tree into the [`ast`](super::ast).

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::LazyLock;

use pest::Parser;
use pest::iterators::{Pair, Pairs};
use pest::pratt_parser::{Assoc, Op, PrattParser};

use super::ast::*;
use super::errors::check_nesting;
use super::fast::Reader;
use super::recover::all_errors;
use crate::diag::{Diagnostic, SourceResult};
use crate::span::{FileId, Span};

#[derive(pest_derive::Parser)]
#[grammar = "../grammar/scene.pest"]
pub(super) struct SceneParser;

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

/// Parses one file. On failure returns its syntax errors, in order, up to
/// `MAX_SYNTAX_ERRORS` (`recover`).
pub fn parse(file: FileId, text: &str) -> SourceResult<Vec<Item>> {
    let stray = check_nesting(file, text)?;
    // A byte order mark may only open the file: `chunk` does not know where it stands.
    if !text.contains('\u{FEFF}')
        && let Some(items) = parse_by_item(file, text)
    {
        return items;
    }
    parse_whole(file, text, stray)
}

/// The file parsed in one piece with the `file` rule; its errors are every syntax error.
pub(super) fn parse_whole(
    file: FileId,
    text: &str,
    stray: Option<usize>,
) -> SourceResult<Vec<Item>> {
    let mut pairs =
        SceneParser::parse(Rule::file, text).map_err(|e| all_errors(file, text, e, stray))?;
    let file_pair = pairs.next().expect("file rule");
    let items = file_pair.into_inner().next().expect("items");
    let cx = Cx::new(file);
    let items = cx.items(items);
    cx.finish(items)
}

/// The file's items parsed a few top-level items at a time (the `chunk` rule), or `None` at a
/// syntax error (the whole-file parse then finds and reports every error). pest's token list,
/// 80 bytes a token and two tokens a rule matched, then holds a chunk instead of the whole
/// file: that list was most of the peak memory of loading a large scene.
///
/// The common items are read directly ([`super::fast`]); pest parses from the first item that
/// reader leaves to it, a chunk at a time, and the reader takes over again after the chunk.
pub(super) fn parse_by_item(file: FileId, text: &str) -> Option<SourceResult<Vec<Item>>> {
    let cx = Cx::new(file);
    let mut items = Vec::new();
    let mut at = 0;
    loop {
        let mut reader = Reader::new(file, text, at);
        while reader.blanks().is_some() {
            if reader.pos == text.len() {
                items.shrink_to_fit();
                return Some(cx.finish(items));
            }
            at = reader.pos;
            match reader.item() {
                Some(item) => {
                    items.push(item);
                    at = reader.pos;
                }
                None => break,
            }
        }
        let rest = &text[at..];
        let chunk = SceneParser::parse(Rule::chunk, rest).ok()?.next()?;
        cx.base.set(at);
        // The next chunk starts after the last item (with the blanks before its first item).
        let mut end = 0;
        for item in chunk.into_inner() {
            if item.as_rule() == Rule::EOI {
                items.shrink_to_fit();
                return Some(cx.finish(items));
            }
            end = item.as_span().end();
            items.push(cx.item(item));
        }
        if end == 0 {
            return None;
        }
        at += end;
    }
}

struct Cx {
    file: FileId,
    /// Where the text the pairs index into starts in the file (a chunk's offset when the file
    /// is parsed a chunk of top-level items at a time).
    base: Cell<usize>,
    /// Terms (operands and operators) of the expressions being built, summed along the current
    /// path of nested expressions: a bound on the depth of the expression tree there.
    terms: Cell<usize>,
    /// The first expression that went over [`MAX_EXPRESSION_TERMS`].
    too_long: RefCell<Option<Diagnostic>>,
    /// Errors found while building the tree (unknown escapes in strings, a macro parameter
    /// named twice): the text parsed, but it means nothing.
    errors: RefCell<Vec<Diagnostic>>,
}

impl Cx {
    fn new(file: FileId) -> Self {
        Cx {
            file,
            base: Cell::new(0),
            terms: Cell::new(0),
            too_long: RefCell::new(None),
            errors: RefCell::new(Vec::new()),
        }
    }

    /// The items, or the errors found while building them.
    fn finish(self, items: Vec<Item>) -> SourceResult<Vec<Item>> {
        if let Some(d) = self.too_long.into_inner() {
            return Err(vec![d]);
        }
        let errors = self.errors.into_inner();
        if errors.is_empty() {
            Ok(items)
        } else {
            Err(errors)
        }
    }
}

impl Cx {
    fn span(&self, pair: &Pair<Rule>) -> Span {
        let s = pair.as_span();
        let base = self.base.get();
        Span::new(
            self.file,
            (base + s.start()) as u32,
            (base + s.end()) as u32,
        )
    }

    fn name(&self, pair: Pair<Rule>) -> Name {
        Name {
            span: self.span(&pair),
            text: pair.as_str().to_string(),
        }
    }

    fn items(&self, pair: Pair<Rule>) -> Vec<Item> {
        // Sized first: a long body's vector does not double past what it holds (it took the
        // parse of a 16 MiB body of `x,` past 2.7 GB).
        let inner = pair.into_inner();
        let mut items = Vec::with_capacity(inner.len());
        items.extend(inner.map(|p| self.item(p)));
        items
    }

    fn item(&self, pair: Pair<Rule>) -> Item {
        match pair.as_rule() {
            Rule::keyword => Item::Keyword(self.name(pair)),
            Rule::comma => Item::Comma(self.span(&pair)),
            Rule::expr | Rule::iexpr => Item::Expr(self.expr(pair)),
            // POV-Ray's colour-map entry: an array of its parts (`color` words dropped).
            Rule::map_entry => Item::Expr(Expr {
                span: self.span(&pair),
                kind: ExprKind::Array(
                    pair.into_inner()
                        .filter(|p| p.as_rule() != Rule::color_word)
                        .map(|p| self.expr(p))
                        .collect(),
                ),
            }),
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
                let params: Vec<Name> = inner
                    .next()
                    .unwrap()
                    .into_inner()
                    .map(|p| self.name(p))
                    .collect();
                self.distinct(&params, "macro");
                let body = self.items(inner.next().unwrap());
                DirectiveKind::Macro(Rc::new(MacroDef { name, params, body }))
            }
            Rule::include_d => {
                let s = inner.next().unwrap();
                let path_span = self.span(&s);
                DirectiveKind::Include {
                    path: self.unescape(s.into_inner().next().unwrap()),
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
        let n = pair.clone().into_inner().len();
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
        } else if pair
            .clone()
            .into_inner()
            .any(|p| p.as_rule() == Rule::qmark)
        {
            self.conditional(pair.into_inner())
        } else {
            self.pratt(pair.into_inner())
        };
        self.terms.set(terms - n);
        e
    }

    /// A chain `c ? a : d ? b : e` from its terms: the parts between `?` and `:` parsed on
    /// their own, folded from the right.
    fn conditional(&self, pairs: Pairs<Rule>) -> Expr {
        let mut parts = vec![Vec::new()];
        for p in pairs {
            match p.as_rule() {
                Rule::qmark | Rule::colon => parts.push(Vec::new()),
                _ => parts.last_mut().expect("a part").push(p),
            }
        }
        // `cond, then, cond, then, ..., otherwise` (the grammar gives an odd count).
        let mut parts: Vec<Expr> = parts
            .into_iter()
            .map(|ps| self.pratt(ps.into_iter()))
            .collect();
        let mut e = parts.pop().expect("the last part");
        while let (Some(then), Some(cond)) = (parts.pop(), parts.pop()) {
            let span = cond.span.join(e.span);
            e = Expr {
                kind: ExprKind::Conditional(Box::new([cond, then, e])),
                span,
            };
        }
        e
    }

    fn pratt<'a>(&self, pairs: impl Iterator<Item = Pair<'a, Rule>>) -> Expr {
        PRATT
            .map_primary(|p| self.primary(p))
            .map_prefix(|op, rhs| {
                let span = self.span(&op).join(rhs.span);
                let op = match op.as_rule() {
                    Rule::neg => UnOp::Neg,
                    Rule::pos => UnOp::Pos,
                    Rule::not => UnOp::Not,
                    _ => match op.as_str() {
                        "rgbf" => UnOp::Rgbf,
                        "rgbt" => UnOp::Rgbt,
                        "rgbft" => UnOp::Rgbft,
                        _ => UnOp::Rgb,
                    },
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
            Rule::string => ExprKind::Str(self.unescape(pair.into_inner().next().unwrap()).into()),
            Rule::paren => {
                // The span takes in both parentheses: a message quoting `-(1)` quotes all of it.
                let inner = self.expr(pair.into_inner().next().unwrap());
                return Expr { span, ..inner };
            }
            Rule::vector => ExprKind::Vector(pair.into_inner().map(|p| self.expr(p)).collect()),
            Rule::array => ExprKind::Array(pair.into_inner().map(|p| self.expr(p)).collect()),
            Rule::named => {
                // A plain name, a block `name { items }` or a call `name(args)`. A plain name's
                // span is the name's own (`named` also covers the blanks after it).
                let mut i = pair.into_inner();
                let name = i.next().unwrap();
                if name.as_rule() == Rule::fn_kw {
                    return Expr {
                        span,
                        kind: ExprKind::Function(Rc::new(self.function(name, i))),
                    };
                }
                match i.next() {
                    None => {
                        return Expr {
                            span: self.span(&name),
                            kind: ExprKind::Ident(name.as_str().to_string()),
                        };
                    }
                    Some(tail) if matches!(tail.as_rule(), Rule::items | Rule::map_items) => {
                        ExprKind::Block {
                            kind: self.name(name),
                            items: Rc::new(self.items(tail)),
                        }
                    }
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

impl Cx {
    /// Reports a parameter named twice (by name: a macro may have thousands of parameters).
    fn distinct(&self, params: &[Name], what: &str) {
        let mut seen: std::collections::HashMap<&str, &Name> = Default::default();
        for p in params {
            if let Some(first) = seen.get(p.text.as_str()).copied() {
                self.errors.borrow_mut().push(
                    Diagnostic::error(
                        p.span,
                        format!("{what} parameter `{}` is named twice", p.text),
                    )
                    .with_label("second parameter of this name")
                    .with_extra(first.span, "first one")
                    .with_help("give each parameter its own name"),
                );
            } else {
                seen.insert(&p.text, p);
            }
        }
    }

    /// `function (params)? { body }` after its `function` word.
    fn function(&self, keyword: Pair<Rule>, mut rest: Pairs<Rule>) -> FunctionDef {
        let keyword = self.span(&keyword);
        let mut next = rest.next().expect("function body");
        let params = if next.as_rule() == Rule::fn_params {
            let params: Vec<Name> = next
                .into_inner()
                .next()
                .expect("params")
                .into_inner()
                .map(|p| self.name(p))
                .collect();
            self.distinct(&params, "function");
            next = rest.next().expect("function body");
            Some(params)
        } else {
            None
        };
        let grid = if next.as_rule() == Rule::fn_grid {
            let mut sides = next.into_inner().map(|p| self.expr(p));
            let (w, h) = (sides.next().expect("width"), sides.next().expect("height"));
            next = rest.next().expect("function body");
            Some(Box::new((w, h)))
        } else {
            None
        };
        FunctionDef {
            params,
            grid,
            body: self.expr(next),
            keyword,
        }
    }

    /// The text of a string literal's inside (`str_inner`) with its escapes replaced: `\"`,
    /// `\\`, `\n` and `\t`. Any other backslash is an error at it (a Windows path such as
    /// `"C:\textures\wood.png"` would otherwise silently lose its backslashes).
    fn unescape(&self, pair: Pair<Rule>) -> String {
        let s = pair.as_str();
        let base = self.base.get() + pair.as_span().start();
        let mut out = String::with_capacity(s.len());
        let mut chars = s.char_indices();
        while let Some((i, c)) = chars.next() {
            if c != '\\' {
                out.push(c);
                continue;
            }
            match chars.next() {
                Some((_, 'n')) => out.push('\n'),
                Some((_, 't')) => out.push('\t'),
                Some((_, o @ ('"' | '\\'))) => out.push(o),
                other => {
                    let end = other.map_or(s.len(), |(j, o)| j + o.len_utf8());
                    let span = Span::new(self.file, (base + i) as u32, (base + end) as u32);
                    self.errors.borrow_mut().push(
                        Diagnostic::error(
                            span,
                            format!("unknown escape `{}` in a string", &s[i..end]),
                        )
                        .with_label("not an escape")
                        .with_help(
                            "the escapes are `\\\"`, `\\\\`, `\\n` and `\\t`; write `\\\\` for a \
                             backslash (or `/` in a file path)",
                        ),
                    );
                }
            }
        }
        out
    }
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
    fn parenthesised_spans_take_in_both_parentheses() {
        let text = "-(1) + (2 * 3)";
        let items = p(text);
        let Item::Expr(e) = &items[0] else { panic!() };
        let ExprKind::Binary(BinOp::Add, lhs, rhs) = &e.kind else {
            panic!("{e:?}")
        };
        let at = |s: Span| &text[s.start as usize..s.end as usize];
        assert_eq!(at(e.span), text);
        assert_eq!(at(lhs.span), "-(1)");
        assert_eq!(at(rhs.span), "(2 * 3)");
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

    /// Item by item gives the tree of the whole-file parse, spans included: blanks and
    /// comments between items, directives with bodies, strings with escapes, a last item
    /// without a line break after it, and errors found while building the tree.
    #[test]
    fn item_by_item_matches_the_whole_file() {
        let texts = [
            "",
            "  // only a comment\n",
            "#declare M = material { diffuse rgb <0.7, 0.7, 0.7> }\n\
             /* a /* nested */ comment */ sphere { <1, 2, 3>, 0.5 material { M } }\n\
             #if (1 < 2) box { <0,0,0>, <1,1,1> } #else disk { } #end\n\
             #macro R(A, B) #debug concat(\"a\\tb\", str(A, 0, 2)) #end R(1, 2)\n\
             , translate (-<1, 2, 3>.x * 2 ? 1 : 0) #include \"x.inc\"\tx[1]",
            "#debug \"bad \\q escape\" #debug \"\\w\"",
            "#macro M(A, A) #end sphere { }",
        ];
        for text in texts {
            let stray = check_nesting(FileId(3), text).unwrap();
            let whole = format!("{:?}", parse_whole(FileId(3), text, stray));
            let by_item = parse_by_item(FileId(3), text)
                .unwrap_or_else(|| panic!("a syntax error in {text:?}"));
            assert_eq!(format!("{by_item:?}"), whole, "{text}");
        }
        // More items than a chunk holds (16): chunks follow one another without a gap.
        let long: String = (0..53)
            .map(|i| format!("sphere {{ <{i}, 0, 0>, 0.5 }} // {i}\n#declare A{i} = {i} , \t"))
            .collect();
        let stray = check_nesting(FileId(1), &long).unwrap();
        let whole = format!("{:?}", parse_whole(FileId(1), &long, stray));
        let by_item = parse_by_item(FileId(1), &long).expect("no syntax error");
        assert_eq!(format!("{by_item:?}"), whole);
        // A syntax error anywhere leaves the item-by-item parse to the whole-file one, also
        // in a later chunk.
        let late_error = format!("{long} sphere {{ }} }} x");
        for text in [
            "sphere { } }",
            "sphere { ",
            "#end",
            "x /* open",
            &late_error,
        ] {
            assert!(parse_by_item(FileId(0), text).is_none(), "{text}");
        }
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
