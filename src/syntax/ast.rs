//! The syntax tree. Every node carries the [`Span`] of the text it came from.

use std::rc::Rc;

use crate::span::Span;

/// A name with its span.
#[derive(Debug, Clone, PartialEq)]
pub struct Name {
    pub text: String,
    pub span: Span,
}

/// One item of a file or of a block body.
#[derive(Debug, Clone)]
pub enum Item {
    Directive(Box<Directive>),
    /// A property keyword such as `translate`; its arguments are the items that follow.
    Keyword(Name),
    Comma(Span),
    Expr(Expr),
}

impl Item {
    pub fn span(&self) -> Span {
        match self {
            Item::Directive(d) => d.span,
            Item::Keyword(n) => n.span,
            Item::Comma(s) => *s,
            Item::Expr(e) => e.span,
        }
    }
}

#[derive(Debug, Clone)]
pub struct Directive {
    pub kind: DirectiveKind,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub enum DirectiveKind {
    /// `#declare` (global) or `#local` (current macro or file scope).
    Bind {
        name: Name,
        value: Expr,
        local: bool,
    },
    If {
        branches: Vec<(Expr, Vec<Item>)>,
        otherwise: Option<Vec<Item>>,
    },
    While {
        cond: Expr,
        body: Vec<Item>,
    },
    For {
        var: Name,
        from: Expr,
        to: Expr,
        step: Option<Expr>,
        body: Vec<Item>,
    },
    Macro(Rc<MacroDef>),
    Include {
        path: String,
        path_span: Span,
    },
    /// `#ifdef (Name)` (or `#ifndef` when `negate`).
    IfDef {
        name: Name,
        negate: bool,
        body: Vec<Item>,
        otherwise: Option<Vec<Item>>,
    },
    /// `#undef Name`.
    Undef(Name),
    /// `#switch (value) #case ... #range ... [#else ...] #end`.
    Switch {
        value: Expr,
        clauses: Vec<Clause>,
        otherwise: Option<Vec<Item>>,
    },
    /// `#break`: leaves the innermost `#switch`, `#while` or `#for`.
    Break,
    /// `#debug`, `#warning` or `#error` with its message.
    Message {
        kind: MessageKind,
        value: Expr,
    },
}

/// One `#case (v)` or `#range (lo, hi)` clause of a `#switch`.
#[derive(Debug, Clone)]
pub struct Clause {
    pub test: ClauseTest,
    pub body: Vec<Item>,
}

#[derive(Debug, Clone)]
pub enum ClauseTest {
    Case(Expr),
    Range(Expr, Expr),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageKind {
    Debug,
    Warning,
    Error,
}

#[derive(Debug)]
pub struct MacroDef {
    pub name: Name,
    pub params: Vec<Name>,
    pub body: Vec<Item>,
}

#[derive(Debug, Clone)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnOp {
    Neg,
    Pos,
    Not,
    Rgb,
    /// POV-Ray's colours with filter and transmit (`rgbf <r, g, b, f>`, `rgbt <r, g, b, t>`,
    /// `rgbft <r, g, b, f, t>`): a material's colour only.
    Rgbf,
    Rgbt,
    Rgbft,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
}

impl BinOp {
    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::And => "&&",
            BinOp::Or => "||",
        }
    }
}

#[derive(Debug, Clone)]
pub enum ExprKind {
    Number(f64),
    Str(Rc<str>),
    Bool(bool),
    Ident(String),
    Vector(Vec<Expr>),
    Array(Vec<Expr>),
    /// `kind { items }`: an object, material, texture, settings, ... block.
    Block {
        kind: Name,
        items: Rc<Vec<Item>>,
    },
    Call {
        name: Name,
        args: Vec<Expr>,
    },
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `condition ? then : otherwise`.
    Conditional(Box<[Expr; 3]>),
    Index(Box<Expr>, Box<Expr>),
    Field(Box<Expr>, Name),
    /// `function(a, b) { body }` (POV-Ray's user function).
    Function(Rc<FunctionDef>),
}

/// A user function as written: its parameters (`None`: POV-Ray's implicit `x, y, z`) and body.
#[derive(Debug)]
pub struct FunctionDef {
    pub params: Option<Vec<Name>>,
    /// POV-Ray's height field form `function W, H { ... }`: the grid it is sampled on.
    pub grid: Option<Box<(Expr, Expr)>>,
    pub body: Expr,
    /// The `function` word.
    pub keyword: Span,
}
