//! A direct reader for the items most of a large scene is made of, beside the pest grammar:
//! property keywords, commas, numbers, names, vectors, blocks, calls, parentheses, prefix,
//! infix and postfix operators, and `#declare`/`#local`. It builds the tree (spans included)
//! that `grammar/scene.pest` and [`super::parser`] build for the same text, several times
//! faster than pest's combinators, and gives up (`None`) on anything else: strings, arrays,
//! the other directives, colour maps, functions, `?:`, characters outside ASCII, and every
//! syntax error. The caller then parses the item with pest, so every diagnostic still comes
//! from the grammar. Where the grammar has a choice, this reader takes the alternative pest's
//! ordered choice takes, or gives up.

use std::rc::Rc;

use super::ast::*;
use super::parser::MAX_EXPRESSION_TERMS;
use crate::span::{FileId, Span};

/// The property keywords of the grammar's `kw_word` rule, sorted (a test checks both).
#[rustfmt::skip]
pub(super) const KEYWORDS: &[&str] = &[
    "absorb", "accuracy", "all_intersections", "alpha", "amount", "angle", "antialias",
    "aperture", "axis", "b_spline", "backdrop", "background", "bezier_spline", "blend", "brick",
    "bump_size", "bumps", "checker", "clock_range", "coated", "conductor", "conic_sweep",
    "corner", "cubic_spline", "cyclic", "degree", "dents", "diffuse", "edge_tint", "eta",
    "exposure", "exr", "extinction", "falloff", "filter", "final_gather", "focus_distance",
    "fov", "frames", "glass", "glossy", "gradient", "handedness", "hierarchy", "image",
    "integrator", "intensity", "interpolate", "inverse", "ior", "iterations", "jpeg", "linear",
    "linear_spline", "linear_sweep", "location", "look_at", "map", "marble", "matrix",
    "max_depth", "max_gradient", "max_trace", "method", "mirror", "mortar", "noise",
    "normal_map", "octaves", "open", "orthographic", "photons", "png", "point_at", "profile",
    "quadratic_spline", "radiance", "radius", "reflectance", "resolution", "right", "ripples",
    "rotate", "roughness", "scale", "seed", "size", "smooth", "specular", "starts", "strength",
    "stripes", "sturm", "thin", "threshold", "time_limit", "tint", "tolerance", "translate",
    "transmit", "ttf", "turbulence", "two_sided", "up", "water_level", "waves", "weight",
    "wood", "wrap", "wrinkles",
];

/// Words that are neither keywords nor names but start an operand.
const RGB: [(&str, UnOp); 4] = [
    ("rgb", UnOp::Rgb),
    ("rgbf", UnOp::Rgbf),
    ("rgbt", UnOp::Rgbt),
    ("rgbft", UnOp::Rgbft),
];

fn is_keyword(word: &str) -> bool {
    KEYWORDS.binary_search(&word).is_ok()
}

fn is_ident_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// The grammar's `operand_start`: where an expression may begin.
fn is_operand_start(b: u8) -> bool {
    b.is_ascii_alphanumeric()
        || matches!(
            b,
            b'<' | b'_' | b'.' | b'-' | b'(' | b'"' | b'[' | b'+' | b'!'
        )
}

/// Which infix operators an expression takes: `expr` all of them, `iexpr` (an item) all but
/// the comparisons `<`, `>`, `<=`, `>=`, `vexpr` (a vector component) the arithmetic ones.
#[derive(Clone, Copy, PartialEq)]
enum Context {
    Full,
    Item,
    Component,
}

/// Binding power of an infix operator, as the Pratt parser of [`super::parser`] orders them.
fn precedence(op: BinOp) -> u8 {
    match op {
        BinOp::Or => 1,
        BinOp::And => 2,
        BinOp::Eq | BinOp::Ne => 3,
        BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => 4,
        BinOp::Add | BinOp::Sub => 5,
        BinOp::Mul | BinOp::Div => 6,
    }
}

pub(super) struct Reader<'a> {
    file: FileId,
    text: &'a str,
    bytes: &'a [u8],
    pub(super) pos: usize,
    /// The most terms along a path of nested expressions inside the expression being read
    /// (the bound [`super::parser`] checks: [`MAX_EXPRESSION_TERMS`]).
    nested: usize,
}

impl<'a> Reader<'a> {
    pub(super) fn new(file: FileId, text: &'a str, pos: usize) -> Self {
        Reader {
            file,
            text,
            bytes: text.as_bytes(),
            pos,
            nested: 0,
        }
    }

    fn peek(&self) -> Option<u8> {
        self.bytes.get(self.pos).copied()
    }

    fn peek_at(&self, ahead: usize) -> Option<u8> {
        self.bytes.get(self.pos + ahead).copied()
    }

    fn span(&self, start: usize, end: usize) -> Span {
        Span::new(self.file, start as u32, end as u32)
    }

    /// Skips blanks and comments (the grammar's `WHITESPACE`). `None` at a block comment left
    /// open: pest reports it.
    pub(super) fn blanks(&mut self) -> Option<()> {
        loop {
            match self.peek() {
                Some(b' ' | b'\t' | b'\n' | 0x0C | b'\r') => self.pos += 1,
                Some(b'/') => match self.peek_at(1) {
                    Some(b'/') => {
                        let rest = &self.bytes[self.pos..];
                        self.pos += rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
                    }
                    Some(b'*') => self.block_comment()?,
                    _ => return Some(()),
                },
                _ => return Some(()),
            }
        }
    }

    /// A block comment from its `/*`; nested comments count (as POV-Ray's do).
    fn block_comment(&mut self) -> Option<()> {
        let mut depth = 0usize;
        let mut i = self.pos;
        let b = self.bytes;
        while i < b.len() {
            if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                depth += 1;
                i += 2;
            } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                depth -= 1;
                i += 2;
                if depth == 0 {
                    self.pos = i;
                    return Some(());
                }
            } else {
                i += 1;
            }
        }
        None
    }

    /// The run of identifier characters at the position (possibly empty).
    fn word(&mut self) -> (usize, &'a str) {
        let start = self.pos;
        while self.peek().is_some_and(is_ident_char) {
            self.pos += 1;
        }
        (start, &self.text[start..self.pos])
    }

    /// A name (not a keyword, `rgb` or a boolean) at the position.
    fn name(&mut self) -> Option<Name> {
        if !self
            .peek()
            .is_some_and(|b| b.is_ascii_alphabetic() || b == b'_')
        {
            return None;
        }
        let (start, w) = self.word();
        if is_reserved(w) {
            return None;
        }
        Some(Name {
            text: w.to_string(),
            span: self.span(start, self.pos),
        })
    }

    /// One item of a file or block body, from its first character.
    pub(super) fn item(&mut self) -> Option<Item> {
        let start = self.pos;
        match self.peek()? {
            b',' => {
                self.pos += 1;
                Some(Item::Comma(self.span(start, self.pos)))
            }
            b'#' => self.declare(),
            b'a'..=b'z' => {
                let (_, w) = self.word();
                if is_keyword(w) {
                    return Some(Item::Keyword(Name {
                        text: w.to_string(),
                        span: self.span(start, self.pos),
                    }));
                }
                self.pos = start;
                Some(Item::Expr(self.expr(Context::Item)?))
            }
            b if is_operand_start(b) => Some(Item::Expr(self.expr(Context::Item)?)),
            _ => None,
        }
    }

    /// `#declare Name = expr ;?` or `#local ...`, the span as the grammar's rule has it: up to
    /// the `;`, or without one up to the next item (blanks included).
    fn declare(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 1;
        let (_, w) = self.word();
        let local = match w {
            "declare" => false,
            "local" => true,
            _ => return None,
        };
        self.blanks()?;
        let name = self.name()?;
        self.blanks()?;
        if self.peek()? != b'=' {
            return None;
        }
        self.pos += 1;
        self.blanks()?;
        let value = self.expr(Context::Full)?;
        self.blanks()?;
        if self.peek() == Some(b';') {
            self.pos += 1;
        }
        Some(Item::Directive(Box::new(Directive {
            kind: DirectiveKind::Bind { name, value, local },
            span: self.span(start, self.pos),
        })))
    }

    /// The items of a block body up to its `}` (consumed).
    fn body(&mut self) -> Option<Vec<Item>> {
        let mut items = Vec::new();
        loop {
            self.blanks()?;
            if self.peek()? == b'}' {
                self.pos += 1;
                return Some(items);
            }
            items.push(self.item()?);
        }
    }

    /// An expression rule (`expr`, `iexpr` or `vexpr`) from its first character; stops after
    /// its last token, before the blanks that follow.
    fn expr(&mut self, cx: Context) -> Option<Expr> {
        let outer = std::mem::take(&mut self.nested);
        let mut terms = 0;
        let e = self.binary(cx, 0, &mut terms)?;
        if cx == Context::Full {
            let end = self.pos;
            self.blanks()?;
            // `c ? a : b`: left to pest.
            if self.peek() == Some(b'?') {
                return None;
            }
            self.pos = end;
        }
        let path = terms + self.nested;
        if path > MAX_EXPRESSION_TERMS {
            return None;
        }
        self.nested = outer.max(path);
        Some(e)
    }

    /// Operands joined by infix operators binding tighter than `min` (left-associative).
    fn binary(&mut self, cx: Context, min: u8, terms: &mut usize) -> Option<Expr> {
        let mut lhs = self.operand(terms)?;
        loop {
            let end = self.pos;
            self.blanks()?;
            let Some((op, len)) = self.infix(cx) else {
                self.pos = end;
                return Some(lhs);
            };
            if precedence(op) <= min {
                self.pos = end;
                return Some(lhs);
            }
            self.pos += len;
            count(terms)?;
            self.blanks()?;
            let rhs = self.binary(cx, precedence(op), terms)?;
            let span = lhs.span.join(rhs.span);
            lhs = Expr {
                kind: ExprKind::Binary(op, Box::new(lhs), Box::new(rhs)),
                span,
            };
        }
    }

    /// The infix operator at the position, as the grammar's ordered choice reads it, with its
    /// length.
    fn infix(&self, cx: Context) -> Option<(BinOp, usize)> {
        let next = self.peek_at(1);
        let op = match self.peek()? {
            b'+' => (BinOp::Add, 1),
            b'-' => (BinOp::Sub, 1),
            b'*' => (BinOp::Mul, 1),
            b'/' => (BinOp::Div, 1),
            _ if cx == Context::Component => return None,
            b'<' if cx == Context::Full => match next {
                Some(b'=') => (BinOp::Le, 2),
                _ => (BinOp::Lt, 1),
            },
            b'>' if cx == Context::Full => match next {
                Some(b'=') => (BinOp::Ge, 2),
                _ => (BinOp::Gt, 1),
            },
            b'=' if next == Some(b'=') => (BinOp::Eq, 2),
            b'!' if next == Some(b'=') => (BinOp::Ne, 2),
            b'&' => (BinOp::And, if next == Some(b'&') { 2 } else { 1 }),
            b'|' => (BinOp::Or, if next == Some(b'|') { 2 } else { 1 }),
            _ => return None,
        };
        Some(op)
    }

    /// Prefix operators, a primary, postfix operators.
    fn operand(&mut self, terms: &mut usize) -> Option<Expr> {
        let start = self.pos;
        count(terms)?;
        let prefix = |this: &mut Self, op: UnOp, terms: &mut usize| {
            let op_span = this.span(start, this.pos);
            this.blanks()?;
            let rhs = this.operand(terms)?;
            Some(Expr {
                span: op_span.join(rhs.span),
                kind: ExprKind::Unary(op, Box::new(rhs)),
            })
        };
        let primary = match self.peek()? {
            b'0'..=b'9' => self.number(),
            b'.' if self.peek_at(1).is_some_and(|b| b.is_ascii_digit()) => self.number(),
            b'<' => self.vector()?,
            b'(' => {
                self.pos += 1;
                self.blanks()?;
                let inner = self.expr(Context::Full)?;
                self.blanks()?;
                if self.peek()? != b')' {
                    return None;
                }
                self.pos += 1;
                Expr {
                    span: self.span(start, self.pos),
                    ..inner
                }
            }
            b'-' | b'+' | b'!' => {
                let op = match self.peek()? {
                    b'-' => UnOp::Neg,
                    b'+' => UnOp::Pos,
                    _ => UnOp::Not,
                };
                self.pos += 1;
                return prefix(self, op, terms);
            }
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => {
                let (_, w) = self.word();
                if let Some(&(_, op)) = RGB.iter().find(|(s, _)| *s == w) {
                    return prefix(self, op, terms);
                }
                match w {
                    "true" | "false" => Expr {
                        kind: ExprKind::Bool(w == "true"),
                        span: self.span(start, self.pos),
                    },
                    // Colour maps and functions have forms of their own; keywords stand
                    // here only as `seed(n)`.
                    "color_map" | "colour_map" | "function" => return None,
                    _ if is_keyword(w) => return None,
                    _ => self.named(start, w)?,
                }
            }
            _ => return None,
        };
        self.postfix(primary, terms)
    }

    /// A number (the grammar's atomic `number` rule) at the position.
    fn number(&mut self) -> Expr {
        let start = self.pos;
        let digits = |this: &mut Self| {
            let from = this.pos;
            while this.peek().is_some_and(|b| b.is_ascii_digit()) {
                this.pos += 1;
            }
            this.pos - from
        };
        if digits(self) > 0 {
            if self.peek() == Some(b'.') {
                self.pos += 1;
                digits(self);
            }
        } else {
            self.pos += 1; // `.`, a digit follows
            digits(self);
        }
        if matches!(self.peek(), Some(b'e' | b'E')) {
            let mark = self.pos;
            self.pos += 1;
            if matches!(self.peek(), Some(b'+' | b'-')) {
                self.pos += 1;
            }
            if digits(self) == 0 {
                self.pos = mark;
            }
        }
        let text = &self.text[start..self.pos];
        Expr {
            kind: ExprKind::Number(text.parse().unwrap_or(f64::NAN)),
            span: self.span(start, self.pos),
        }
    }

    /// `<a, b, ...>`: two components or more, commas between them optional, one after the
    /// last allowed.
    fn vector(&mut self) -> Option<Expr> {
        let start = self.pos;
        self.pos += 1;
        self.blanks()?;
        let mut parts = vec![self.expr(Context::Component)?];
        loop {
            self.blanks()?;
            match self.peek()? {
                b',' => {
                    self.pos += 1;
                    self.blanks()?;
                    if !self.peek().is_some_and(is_operand_start) {
                        break;
                    }
                }
                b'>' => break,
                b if is_operand_start(b) => {}
                _ => return None,
            }
            parts.push(self.expr(Context::Component)?);
        }
        if parts.len() < 2 || self.peek()? != b'>' {
            return None;
        }
        self.pos += 1;
        Some(Expr {
            kind: ExprKind::Vector(parts),
            span: self.span(start, self.pos),
        })
    }

    /// A name `w` (read, starting at `start`), with the block or the arguments after it.
    fn named(&mut self, start: usize, w: &str) -> Option<Expr> {
        let name_end = self.pos;
        let name_span = self.span(start, name_end);
        let name = || Name {
            text: w.to_string(),
            span: name_span,
        };
        self.blanks()?;
        let kind = match self.peek() {
            Some(b'{') => {
                let kind = name();
                self.pos += 1;
                ExprKind::Block {
                    kind,
                    items: Rc::new(self.body()?),
                }
            }
            Some(b'(') => {
                let name = name();
                self.pos += 1;
                ExprKind::Call {
                    name,
                    args: self.args()?,
                }
            }
            _ => {
                self.pos = name_end;
                return Some(Expr {
                    kind: ExprKind::Ident(w.to_string()),
                    span: self.span(start, name_end),
                });
            }
        };
        Some(Expr {
            kind,
            span: self.span(start, self.pos),
        })
    }

    /// A call's arguments after its `(`, up to the `)` (consumed).
    fn args(&mut self) -> Option<Vec<Expr>> {
        let mut args = Vec::new();
        self.blanks()?;
        if self.peek()? == b')' {
            self.pos += 1;
            return Some(args);
        }
        loop {
            args.push(self.expr(Context::Full)?);
            self.blanks()?;
            match self.peek()? {
                b',' => {
                    self.pos += 1;
                    self.blanks()?;
                }
                b')' => {
                    self.pos += 1;
                    return Some(args);
                }
                _ => return None,
            }
        }
    }

    /// `[index]` and `.field` after a primary.
    fn postfix(&mut self, mut lhs: Expr, terms: &mut usize) -> Option<Expr> {
        loop {
            let end = self.pos;
            self.blanks()?;
            let start = self.pos;
            match self.peek() {
                Some(b'[') => {
                    self.pos += 1;
                    self.blanks()?;
                    let index = self.expr(Context::Full)?;
                    self.blanks()?;
                    if self.peek()? != b']' {
                        return None;
                    }
                    self.pos += 1;
                    let span = lhs.span.join(self.span(start, self.pos));
                    lhs = Expr {
                        kind: ExprKind::Index(Box::new(lhs), Box::new(index)),
                        span,
                    };
                }
                Some(b'.') => {
                    self.pos += 1;
                    self.blanks()?;
                    let at = self.pos;
                    if !self
                        .peek()
                        .is_some_and(|b| b.is_ascii_alphabetic() || b == b'_')
                    {
                        // Not a field (`<1 .5>`): the operand ends before the `.`.
                        self.pos = end;
                        return Some(lhs);
                    }
                    let (_, w) = self.word();
                    let field = Name {
                        text: w.to_string(),
                        span: self.span(at, self.pos),
                    };
                    let span = lhs.span.join(self.span(start, self.pos));
                    lhs = Expr {
                        kind: ExprKind::Field(Box::new(lhs), field),
                        span,
                    };
                }
                _ => {
                    self.pos = end;
                    return Some(lhs);
                }
            }
            count(terms)?;
        }
    }
}

/// Counts one more term of an expression; `None` past the bound, before the tree grows deeper
/// (pest's path then reports the expression as too long).
fn count(terms: &mut usize) -> Option<()> {
    *terms += 1;
    (*terms <= MAX_EXPRESSION_TERMS).then_some(())
}

/// Whether `word` (a whole word) is the grammar's `reserved`: not a name.
fn is_reserved(word: &str) -> bool {
    is_keyword(word) || matches!(word, "rgb" | "rgbf" | "rgbt" | "rgbft" | "true" | "false")
}

#[cfg(test)]
mod tests;
