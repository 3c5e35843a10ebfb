//! User functions: `function(a, b) { expr }` compiled once into a [`Function`] program, and
//! their calls.
//!
//! Compiling walks the body once: a parameter becomes a slot load, a name of a declared number
//! its value (captured when the function is defined, as in POV-Ray), a part without parameters
//! is folded into a constant, a call of another user function copies that function's program
//! in (its arguments stored into fresh slots), and the function language's maths become
//! operations. A call then runs the program; nothing is re-read from the syntax tree.

use std::rc::Rc;
use std::sync::Arc;

use super::Evaluator;
use super::value::{FunctionValue, Value};
use crate::diag::{At, Diagnostic, Error, SourceResult, suggest};
use crate::scene::function::{BINARY_NAMES, Binary, MAX_OPS, UNARY_NAMES, Unary, unary};
use crate::scene::{Function, FunctionError, Op};
use crate::span::Span;
use crate::syntax::ast::*;

/// A compiled part of a body: a constant (folded) or code that pushes one value.
pub(super) enum Piece {
    Const(f64),
    Code(Vec<Op>),
}

impl Piece {
    fn into_code(self) -> Vec<Op> {
        match self {
            Piece::Const(c) => vec![Op::Const(c)],
            Piece::Code(c) => c,
        }
    }
}

/// The state of one function's compilation.
pub(super) struct Compiler {
    pub(super) params: Vec<String>,
    /// Slots in use: the parameters, then the arguments of inlined calls.
    slots: usize,
    /// Operations emitted so far (inlined copies included), against [`MAX_OPS`].
    ops: usize,
}

/// The names a function body can call besides user functions.
fn language_names() -> String {
    let mut names: Vec<&str> = UNARY_NAMES.iter().map(|(n, _)| *n).collect();
    names.extend(BINARY_NAMES.iter().map(|(n, _)| *n));
    names.extend(["min", "max", "select"]);
    names.join(" ")
}

impl Evaluator {
    /// Compiles `def` into a function value.
    pub(super) fn define_function(&mut self, def: &FunctionDef, span: Span) -> SourceResult<Value> {
        let params: Vec<String> = match &def.params {
            Some(ps) => ps.iter().map(|p| p.text.clone()).collect(),
            None => ["x", "y", "z"].map(String::from).to_vec(),
        };
        let mut c = Compiler {
            slots: params.len(),
            params,
            ops: 0,
        };
        let grid = match &def.grid {
            None => None,
            Some(sides) => {
                let (w, h) = (&sides.0, &sides.1);
                let side = |ev: &mut Self, e: &Expr| -> SourceResult<f64> {
                    ev.eval(e)?
                        .num()
                        .map_err(|e| {
                            e.help("the grid's sides are numbers: `function 256, 256 { x * y }`")
                        })
                        .at(e.span)
                };
                Some((side(self, w)?, side(self, h)?, w.span.join(h.span)))
            }
        };
        let code = self.compile(&mut c, &def.body)?.into_code();
        let func = Function::new(c.params.len(), c.slots, code).map_err(|e| match e {
            FunctionError::TooLarge(n) => vec![too_large(n, def.body.span)],
            FunctionError::Malformed(m) => vec![
                Error::new(format!("internal error compiling this function: {m}"))
                    .help("please report this scene")
                    .at(def.keyword),
            ],
        })?;
        Ok(Value::Function(Rc::new(FunctionValue {
            code: Arc::new(func),
            params: c.params,
            span,
            grid,
        })))
    }

    /// Calls user function `f` (bound to `name`) with numbers.
    pub(super) fn call_function(
        &mut self,
        f: &FunctionValue,
        name: &Name,
        args: &[Expr],
        span: Span,
    ) -> SourceResult<Value> {
        check_arity(f, name, args.len(), span)?;
        let mut xs = Vec::with_capacity(args.len());
        for a in args {
            xs.push(self.eval(a)?.num().at(a.span)?);
        }
        self.charge(f.code.code().len() as u64, span)?;
        Ok(Value::Num(f.code.eval(&xs)))
    }

    pub(super) fn compile(&mut self, c: &mut Compiler, e: &Expr) -> SourceResult<Piece> {
        self.tick(e.span)?;
        let piece = match &e.kind {
            ExprKind::Number(n) => Piece::Const(*n),
            ExprKind::Bool(b) => Piece::Const(f64::from(u8::from(*b))),
            ExprKind::Ident(name) => self.compile_name(c, name, e.span)?,
            ExprKind::Unary(op, inner) => {
                let op = match op {
                    UnOp::Pos => return self.compile(c, inner),
                    UnOp::Neg => Unary::Neg,
                    UnOp::Not => Unary::Not,
                    UnOp::Rgb | UnOp::Rgbf | UnOp::Rgbt | UnOp::Rgbft => {
                        return Err(vec![not_a_number(e.span, "a color")]);
                    }
                };
                match self.compile(c, inner)? {
                    Piece::Const(x) => Piece::Const(unary(op, x)),
                    Piece::Code(mut code) => {
                        code.push(Op::Unary(op));
                        Piece::Code(code)
                    }
                }
            }
            ExprKind::Binary(op, a, b) => {
                let op = match op {
                    BinOp::Add => Binary::Add,
                    BinOp::Sub => Binary::Sub,
                    BinOp::Mul => Binary::Mul,
                    BinOp::Div => Binary::Div,
                    BinOp::Lt => Binary::Lt,
                    BinOp::Le => Binary::Le,
                    BinOp::Gt => Binary::Gt,
                    BinOp::Ge => Binary::Ge,
                    BinOp::Eq => Binary::Eq,
                    BinOp::Ne => Binary::Ne,
                    BinOp::And => Binary::And,
                    BinOp::Or => Binary::Or,
                };
                let pa = self.compile(c, a)?;
                let pb = self.compile(c, b)?;
                self.combine(c, vec![pa, pb], Op::Binary(op), e.span)?
            }
            ExprKind::Conditional(parts) => {
                // `c ? a : b` is `select(-(c == 0), b, a)`: `b` where the condition is 0.
                let [cond, then, otherwise] = &**parts;
                let pc = self.compile(c, cond)?;
                let pt = self.compile(c, then)?;
                let po = self.compile(c, otherwise)?;
                match pc {
                    Piece::Const(x) => {
                        if x != 0.0 {
                            pt
                        } else {
                            po
                        }
                    }
                    Piece::Code(mut code) => {
                        code.extend([Op::Unary(Unary::Not), Op::Unary(Unary::Neg)]);
                        self.combine(c, vec![Piece::Code(code), po, pt], Op::Select3, e.span)?
                    }
                }
            }
            ExprKind::Call { name, args } => self.compile_call(c, name, args, e.span)?,
            ExprKind::Block { kind, items } if kind.text == "pattern" => {
                self.compile_pattern(c, items, e.span)?
            }
            ExprKind::Function(_) => {
                return Err(vec![
                    Error::new("a function cannot be defined inside a function")
                        .label("a function inside a function's body")
                        .help(
                            "declare it before: `#declare G = function(a) { ... };`, then call \
                             `G(...)` in this body",
                        )
                        .at(e.span),
                ]);
            }
            // Vectors, components, strings, other blocks: constants only.
            _ => {
                if let Some(p) = first_param(e, &c.params) {
                    return Err(vec![
                        Error::new(format!(
                            "a function computes with numbers: parameter `{}` cannot be used \
                             here",
                            p.0
                        ))
                        .label("a parameter inside a vector, component or block")
                        .help(
                            "write the computation with numbers, e.g. `sqrt(x*x + y*y + z*z)` \
                             for a length",
                        )
                        .at(p.1),
                    ]);
                }
                self.constant_value(e)?
            }
        };
        if let Piece::Code(code) = &piece {
            c.ops = c.ops.max(code.len());
            if c.ops > MAX_OPS {
                return Err(vec![too_large(c.ops, e.span)]);
            }
        }
        Ok(piece)
    }

    /// Pieces followed by `op`: folded when all are constants.
    fn combine(
        &mut self,
        c: &mut Compiler,
        pieces: Vec<Piece>,
        op: Op,
        span: Span,
    ) -> SourceResult<Piece> {
        let n = pieces.len();
        let consts: Vec<f64> = pieces
            .iter()
            .filter_map(|p| match p {
                Piece::Const(x) => Some(*x),
                Piece::Code(_) => None,
            })
            .collect();
        if consts.len() == n && !matches!(op, Op::Pattern(_)) {
            let mut code: Vec<Op> = consts.into_iter().map(Op::Const).collect();
            code.push(op);
            let f = Function::new(0, 0, code).map_err(|_| vec![too_large(MAX_OPS, span)])?;
            return Ok(Piece::Const(f.eval(&[])));
        }
        let mut code = Vec::new();
        for p in pieces {
            code.extend(p.into_code());
        }
        code.push(op);
        if code.len() > MAX_OPS {
            return Err(vec![too_large(code.len(), span)]);
        }
        c.ops = c.ops.max(code.len());
        Ok(Piece::Code(code))
    }

    fn compile_name(&mut self, c: &mut Compiler, name: &str, span: Span) -> SourceResult<Piece> {
        if let Some(i) = c.params.iter().position(|p| p == name) {
            return Ok(Piece::Code(vec![Op::Load(i as u32)]));
        }
        if self.defining.as_deref() == Some(name) {
            return Err(vec![self_reference(name, span)]);
        }
        match self.lookup_quiet(name) {
            Some(Value::Num(x)) => Ok(Piece::Const(x)),
            Some(Value::Bool(b)) => Ok(Piece::Const(f64::from(u8::from(b)))),
            Some(Value::Function(f)) => Err(vec![
                Error::new(format!("function `{name}` used as a value"))
                    .label("a function, not a number")
                    .help(format!("call it: `{}`", f.signature(name)))
                    .at(span),
            ]),
            Some(v) if ["x", "y", "z"].contains(&name) && !matches!(v, Value::Num(_)) => {
                Err(vec![unknown_param(name, c, span, false)])
            }
            Some(v) => Err(vec![not_a_number(span, v.type_name())]),
            None if self.poisoned.contains(name) => Err(super::silent()),
            None => Err(vec![unknown_param(name, c, span, true)]),
        }
    }

    fn compile_call(
        &mut self,
        c: &mut Compiler,
        name: &Name,
        args: &[Expr],
        span: Span,
    ) -> SourceResult<Piece> {
        let text = name.text.as_str();
        if self.defining.as_deref() == Some(text) {
            return Err(vec![self_reference(text, name.span)]);
        }
        match self.lookup_quiet(text) {
            Some(Value::Function(f)) => {
                check_arity(&f, name, args.len(), span)?;
                let mut pieces = Vec::with_capacity(args.len());
                for a in args {
                    pieces.push(self.compile(c, a)?);
                }
                return self.inline(c, &f, pieces, span);
            }
            // A declaration that failed (its error is reported): not again at each call.
            None if self.poisoned.contains(text) => return Err(super::silent()),
            Some(Value::Macro(_)) | None => {}
            Some(v) => {
                return Err(vec![
                    Error::new(format!("`{text}` is {}, not a function", v.type_name()))
                        .label("called here")
                        .help(format!(
                            "only functions are called with `(...)`; a function is declared \
                             with `#declare {text} = function(x, y, z) {{ ... }};`"
                        ))
                        .at(name.span),
                ]);
            }
        }
        let op = if let Some((_, u)) = UNARY_NAMES.iter().find(|(n, _)| *n == text) {
            Some((Op::Unary(*u), 1..=1))
        } else if let Some((_, b)) = BINARY_NAMES.iter().find(|(n, _)| *n == text) {
            Some((Op::Binary(*b), 2..=2))
        } else {
            match text {
                "min" => Some((Op::Min(args.len() as u32), 1..=usize::MAX)),
                "max" => Some((Op::Max(args.len() as u32), 1..=usize::MAX)),
                "select" => Some((
                    if args.len() == 4 {
                        Op::Select4
                    } else {
                        Op::Select3
                    },
                    3..=4,
                )),
                _ => None,
            }
        };
        let Some((op, arity)) = op else {
            // Anything else (a macro, a string or vector function) is run when the function is
            // defined, on constants only.
            if let Some(p) = args.iter().find_map(|a| first_param(a, &c.params)) {
                return Err(vec![
                    Error::new(format!(
                        "`{text}` cannot be called with a function's parameters"
                    ))
                    .label(format!("parameter `{}` passed on", p.0))
                    .help(format!(
                        "a function body calls user functions and the maths {}; other \
                             calls take constants only (they are computed once, when the \
                             function is defined)",
                        language_names()
                    ))
                    .at(p.1)
                    .with_extra(name.span, "this call"),
                ]);
            }
            return self.constant_value(&Expr {
                kind: ExprKind::Call {
                    name: name.clone(),
                    args: args.to_vec(),
                },
                span,
            });
        };
        if !arity.contains(&args.len()) {
            let want = match text {
                "min" | "max" => "one or more arguments".to_string(),
                "select" => "3 or 4 arguments".to_string(),
                _ if *arity.start() == 1 => "1 argument".to_string(),
                _ => format!("{} arguments", arity.start()),
            };
            return Err(vec![
                Error::new(format!("`{text}` takes {want}, found {}", args.len()))
                    .label("wrong number of arguments")
                    .help(match text {
                        "select" => {
                            "`select(a, b, c)` is b if a < 0, else c; `select(a, b, c, d)` \
                                 is b if a < 0, c if a = 0, else d"
                                .to_string()
                        }
                        "atan2" => "call it as `atan2(y, x)`".to_string(),
                        "pow" => "call it as `pow(base, exponent)`".to_string(),
                        "mod" | "div" => format!("call it as `{text}(a, b)`"),
                        _ => format!("call it as `{text}(x)`"),
                    })
                    .at(span),
            ]);
        }
        let mut pieces = Vec::with_capacity(args.len());
        for a in args {
            pieces.push(self.compile(c, a)?);
        }
        self.combine(c, pieces, op, span)
    }

    /// A call of user function `f`: its arguments stored into fresh slots, then a copy of its
    /// program reading them there. Constant arguments fold the call.
    fn inline(
        &mut self,
        c: &mut Compiler,
        f: &FunctionValue,
        pieces: Vec<Piece>,
        span: Span,
    ) -> SourceResult<Piece> {
        if pieces.iter().all(|p| matches!(p, Piece::Const(_))) {
            let xs: Vec<f64> = pieces
                .into_iter()
                .map(|p| match p {
                    Piece::Const(x) => x,
                    Piece::Code(_) => unreachable!(),
                })
                .collect();
            return Ok(Piece::Const(f.code.eval(&xs)));
        }
        let callee = f.code.code();
        let n = pieces.len();
        let base = c.slots;
        c.slots += f.code.slots();
        let mut code = Vec::new();
        for p in pieces {
            code.extend(p.into_code());
        }
        if code.len() + n + callee.len() > MAX_OPS || c.slots > MAX_OPS {
            return Err(vec![too_large(code.len() + n + callee.len(), span)]);
        }
        self.charge((n + callee.len()) as u64, span)?;
        let slot = |s: u32| (s as usize + base) as u32;
        code.extend((0..n).rev().map(|i| Op::Store(slot(i as u32))));
        code.extend(callee.iter().map(|op| match op {
            Op::Load(s) => Op::Load(slot(*s)),
            Op::Store(s) => Op::Store(slot(*s)),
            op => op.clone(),
        }));
        c.ops = c.ops.max(code.len());
        Ok(Piece::Code(code))
    }

    /// The value of a part without parameters, evaluated as any expression: a number.
    fn constant_value(&mut self, e: &Expr) -> SourceResult<Piece> {
        match self.eval(e)? {
            Value::Num(x) => Ok(Piece::Const(x)),
            Value::Bool(b) => Ok(Piece::Const(f64::from(u8::from(b)))),
            v => Err(vec![not_a_number(e.span, v.type_name())]),
        }
    }
}

/// The first parameter of `params` that `e` names, with its span.
fn first_param<'a>(e: &'a Expr, params: &[String]) -> Option<(&'a str, Span)> {
    let mut stack = vec![e];
    while let Some(e) = stack.pop() {
        match &e.kind {
            ExprKind::Ident(n) if params.contains(n) => return Some((n, e.span)),
            ExprKind::Vector(xs) | ExprKind::Array(xs) => stack.extend(xs),
            ExprKind::Call { args, .. } => stack.extend(args),
            ExprKind::Unary(_, a) | ExprKind::Field(a, _) => stack.push(a),
            ExprKind::Binary(_, a, b) | ExprKind::Index(a, b) => stack.extend([&**a, &**b]),
            ExprKind::Conditional(parts) => stack.extend(parts.iter()),
            _ => {}
        }
    }
    None
}

fn check_arity(f: &FunctionValue, name: &Name, found: usize, span: Span) -> SourceResult<()> {
    let want = f.params.len();
    if found == want {
        return Ok(());
    }
    Err(vec![
        Error::new(format!(
            "`{}` takes {want} argument{}, found {found}",
            name.text,
            if want == 1 { "" } else { "s" }
        ))
        .label("wrong number of arguments")
        .help(format!("call it as `{}`", f.signature(&name.text)))
        .at(span)
        .with_extra(f.span, "the function is defined here"),
    ])
}

fn self_reference(name: &str, span: Span) -> Diagnostic {
    Error::new(format!("function `{name}` refers to itself"))
        .label("the function being defined")
        .help(
            "functions are not recursive (nor in POV-Ray): compute the value without calling \
             it, or write a `#macro` for a recursive computation",
        )
        .at(span)
}

fn not_a_number(span: Span, what: &str) -> Diagnostic {
    Error::new(format!("a function computes with numbers, found {what}"))
        .label(format!("this is {what}"))
        .help("take a number from it (a component `V.x`), or declare a number before the function")
        .at(span)
}

fn unknown_param(name: &str, c: &Compiler, span: Span, undeclared: bool) -> Diagnostic {
    let params = c.params.join(", ");
    let mut e = Error::new(format!(
        "`{name}` is not a parameter of this function{}",
        if undeclared {
            " nor a declared number"
        } else {
            ""
        }
    ))
    .label("unknown in this body");
    e = if let Some(s) = suggest(name, c.params.iter().map(String::as_str)) {
        e.help(format!("did you mean `{s}`? The parameters are ({params})"))
    } else {
        e.help(format!(
            "the parameters are ({params}); a constant is declared before the function \
             (`#declare K = 2;`)"
        ))
    };
    e.at(span)
}

fn too_large(n: usize, span: Span) -> Diagnostic {
    Error::new(format!(
        "this function is too large: {n} operations, more than {MAX_OPS}"
    ))
    .label("too large once the functions it calls are copied in")
    .help(
        "every call of another function copies that function's body: a chain of functions \
         each calling the next twice doubles at every step; compute a shared part once",
    )
    .at(span)
}

/// Stack of the thread [`compile_function`] runs on: a body nests as deep as the parser allows.
const COMPILE_STACK: usize = 256 << 20;

/// Runs scene text `text` and returns the function it declares as `name`, compiled: the way a
/// caller outside the language (a measurement, a test) gets a [`Function`]. The errors of the
/// text, or one saying that `name` is not a function, otherwise.
pub fn compile_function(text: &str, name: &str) -> Result<Arc<Function>, Vec<Diagnostic>> {
    let (text, name) = (text.to_string(), name.to_string());
    let work = move || {
        let mut ev = Evaluator::new(super::EvalOptions::default());
        let file = ev.sources.add(
            std::path::Path::new("function.scn"),
            "function.scn".into(),
            text.clone(),
        );
        let mut items = crate::syntax::parse(file, &text)?;
        ev.run_top(&mut items, &mut super::blocks::TopSink::default());
        if ev.errors.iter().any(Diagnostic::is_error) {
            return Err(ev.errors);
        }
        match ev.lookup_quiet(&name) {
            Some(Value::Function(f)) => Ok(Arc::clone(&f.code)),
            _ => Err(vec![Diagnostic::error(
                Span::detached(),
                format!("`{name}` is not a declared function"),
            )]),
        }
    };
    std::thread::Builder::new()
        .name("sppm-function".into())
        .stack_size(COMPILE_STACK)
        .spawn(work)
        .map_err(|e| {
            vec![Diagnostic::error(
                Span::detached(),
                format!("cannot start: {e}"),
            )]
        })?
        .join()
        .unwrap_or_else(|_| {
            Err(vec![Diagnostic::error(
                Span::detached(),
                "internal error compiling the function",
            )])
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The compiled function `name` after running `text`, or the first error's message.
    fn compiled(text: &str, name: &str) -> Result<Arc<Function>, String> {
        compile_function(text, name).map_err(|e| e[0].message.clone())
    }

    #[test]
    fn constants_fold_and_are_captured_at_definition() {
        let f = compiled(
            "#declare K = 3; #declare V = <1, 2, 3>;
             #declare F = function(a) { a * (K * 2 + V.z + sqrt(16) + pi * 0) };
             #declare K = 100;",
            "F",
        )
        .unwrap();
        // `a`, one folded constant, the product: nothing else survives.
        assert_eq!(
            f.code(),
            [Op::Load(0), Op::Const(13.0), Op::Binary(Binary::Mul)]
        );
        assert_eq!(f.eval(&[2.0]), 26.0);
    }

    #[test]
    fn calls_are_inlined_into_slots_not_linked() {
        let f = compiled(
            "#declare G = function(a, b) { a - b };
             #declare F = function { G(x * 2, y) + G(1, 1) };",
            "F",
        )
        .unwrap();
        // G(1, 1) folds to 0; G(x * 2, y) stores its arguments in slots 3 and 4.
        assert_eq!(f.slots(), 5);
        assert!(f.code().contains(&Op::Store(3)));
        assert!(f.code().contains(&Op::Load(4)));
        assert_eq!(f.eval(&[5.0, 3.0, 0.0]), 7.0);
    }

    #[test]
    fn doubling_inlines_stop_at_the_size_limit() {
        // Each function calls the previous one twice: 2^20 copies of the first.
        let mut text = String::from("#declare F0 = function(a) { a + 1 };\n");
        for i in 1..=20 {
            text += &format!(
                "#declare F{i} = function(a) {{ F{}(a) * F{}(a + 1) }};\n",
                i - 1,
                i - 1
            );
        }
        let err = compiled(&text, "F20").unwrap_err();
        assert!(err.contains("too large"), "{err}");
        // One error: the functions after the one that failed call a poisoned name, silently.
        let all = compile_function(&text, "F20").unwrap_err();
        let errors: Vec<_> = all.iter().filter(|d| d.is_error()).collect();
        assert_eq!(errors.len(), 1, "{errors:?}");
    }

    #[test]
    fn deep_bodies_compile_and_run_without_recursion_at_run_time() {
        // 150 nested additions need a stack of 151 values (on the heap); a chain of 4 000
        // additions two.
        let body = format!("{}x{}", "1 + (".repeat(150), ")".repeat(150));
        let f = compiled(&format!("#declare F = function {{ {body} }};"), "F").unwrap();
        assert_eq!(f.eval(&[1.0, 0.0, 0.0]), 151.0);
        let chain = format!("x{}", " + x".repeat(4_000));
        let f = compiled(&format!("#declare F = function {{ {chain} }};"), "F").unwrap();
        assert_eq!(f.eval(&[0.5, 0.0, 0.0]), 2000.5);
    }

    #[test]
    fn self_reference_and_unknown_names_are_errors() {
        let e = compiled("#declare F = function(n) { F(n - 1) };", "F").unwrap_err();
        assert!(e.contains("refers to itself"), "{e}");
        let e = compiled("#declare F = 1; #declare F = function { F + x };", "F").unwrap_err();
        assert!(e.contains("refers to itself"), "{e}");
        let e = compiled("#declare F = function(a) { a + q };", "F").unwrap_err();
        assert!(e.contains("not a parameter"), "{e}");
        let e = compiled("#declare F = function(a) { a + x };", "F").unwrap_err();
        assert!(e.contains("not a parameter"), "{e}");
        let e = compiled("#declare F = function(a) { vlength(<a, 0, 0>) };", "F").unwrap_err();
        assert!(e.contains("parameters"), "{e}");
    }
}
