//! Expressions: literals, names, operators, indexing, and calls of built-in functions.

use crate::diag::short_number;
use std::rc::Rc;

use glam::{DVec2, DVec3};

use super::Evaluator;
use super::builtins::{self, FUNCTIONS};
use super::random::RANDOM_FUNCTIONS;
use super::value::Value;
use crate::diag::{At, Diagnostic, Error, SourceResult, suggest};
use crate::span::Span;
use crate::syntax::ast::*;

impl Evaluator {
    pub(crate) fn eval(&mut self, e: &Expr) -> SourceResult<Value> {
        let v = self.eval_inner(e)?;
        match &v {
            Value::Num(n) if !n.is_finite() => Err(vec![not_finite(e.span, "number")]),
            Value::Vec3(a) | Value::Color(a) if !a.is_finite() => {
                Err(vec![not_finite(e.span, "vector")])
            }
            Value::Vec2(a) if !a.is_finite() => Err(vec![not_finite(e.span, "vector")]),
            _ => Ok(v),
        }
    }

    fn eval_inner(&mut self, e: &Expr) -> SourceResult<Value> {
        // Every operation is a step (a literal is none): a long expression evaluated in a loop
        // costs its length, so the budget bounds the time it takes.
        if !matches!(
            e.kind,
            ExprKind::Number(_) | ExprKind::Bool(_) | ExprKind::Str(_)
        ) {
            self.tick(e.span)?;
        }
        Ok(match &e.kind {
            ExprKind::Number(n) if !n.is_finite() => {
                return Err(vec![
                    Error::new("this number is too large to be represented")
                        .label("beyond the largest number, about 1.8e308")
                        .help(
                            "numbers are 64-bit floating point: write one of at most about \
                             1.8e308 (use an exponent, e.g. `1e300`)",
                        )
                        .at(e.span),
                ]);
            }
            ExprKind::Number(n) => Value::Num(*n),
            ExprKind::Bool(b) => Value::Bool(*b),
            ExprKind::Str(s) => {
                if s.len() > super::MAX_STRING_BYTES {
                    return Err(vec![
                        Error::new(format!(
                            "this string is {} bytes, more than the limit of {} bytes",
                            s.len(),
                            super::MAX_STRING_BYTES
                        ))
                        .label("too long")
                        .help("keep long data in a file the scene reads (an image, a mesh)")
                        .at(e.span),
                    ]);
                }
                Value::Str(s.clone())
            }
            ExprKind::Ident(name) => self.lookup(name, e.span)?,
            ExprKind::Vector(parts) => {
                if parts.len() > 3 {
                    self.charge(parts.len() as u64 * super::STEPS_PER_ELEMENT, e.span)?;
                }
                let mut xs = Vec::with_capacity(parts.len());
                for p in parts {
                    xs.push(self.eval(p)?.num().at(p.span)?);
                }
                match xs.len() {
                    2 => Value::Vec2(DVec2::new(xs[0], xs[1])),
                    3 => Value::Vec3(DVec3::new(xs[0], xs[1], xs[2])),
                    _ => Value::Array(Rc::new(xs.into_iter().map(Value::Num).collect())),
                }
            }
            ExprKind::Array(parts) => {
                self.charge(parts.len() as u64 * super::STEPS_PER_ELEMENT, e.span)?;
                let mut xs = Vec::with_capacity(parts.len());
                for p in parts {
                    xs.push(self.eval(p)?);
                }
                Value::Array(Rc::new(xs))
            }
            ExprKind::Block { kind, items } => self.eval_block(kind, items, e.span)?,
            ExprKind::Call { name, args } => {
                match self.lookup_quiet(&name.text) {
                    Some(Value::Macro(m)) => return self.call_macro_value(&m, name, args, e.span),
                    Some(Value::Function(f)) => return self.call_function(&f, name, args, e.span),
                    _ => {}
                }
                if let Some(r) = self.call_random(name, args, e.span) {
                    return r;
                }
                let mut vals = Vec::with_capacity(args.len());
                for a in args {
                    vals.push(self.eval(a)?);
                }
                // A string argument is scanned (`len`, `str`); an array is not (`dim`): strings
                // only.
                let work: u64 = vals
                    .iter()
                    .filter(|v| matches!(v, Value::Str(_)))
                    .map(super::work_of)
                    .sum();
                self.charge(work, e.span)?;
                match builtins::call(&name.text, &vals) {
                    Some(Ok(v)) => {
                        // A string made (`str` with a width, `concat`) costs its length.
                        self.charge(super::work_of(&v), e.span)?;
                        v
                    }
                    Some(Err((i, mut err))) => {
                        if err.label.is_empty() {
                            err.label = "invalid argument".into();
                        }
                        let span = args.get(i).map_or(e.span, |a| a.span);
                        return Err(vec![err.at(span)]);
                    }
                    // A macro of an include that failed to parse: its error is reported.
                    None if self.poisoned.contains(&name.text) => return Err(super::silent()),
                    None => {
                        if let Some(v) = self.lookup_quiet(&name.text) {
                            return Err(vec![
                                Error::new(format!(
                                    "`{}` is {}, not a function",
                                    name.text,
                                    v.type_name()
                                ))
                                .label("called here")
                                .help(
                                    if crate::scene::animation_value(&name.text, None).is_some() {
                                        format!(
                                            "`{}` is one of the animation values, read as a number \
                                         (`{} * 2`); only macros and functions are called with \
                                         `(...)`",
                                            name.text, name.text
                                        )
                                    } else {
                                        format!(
                                            "only macros and functions are called with `(...)`; a \
                                         function is declared with `#declare {} = function(x, \
                                         y, z) {{ ... }};`",
                                            name.text
                                        )
                                    },
                                )
                                .at(name.span),
                            ]);
                        }
                        let mut err = Error::new(format!("unknown function `{}`", name.text))
                            .label("no built-in function or macro of this name");
                        let mut cands: Vec<&str> = FUNCTIONS.to_vec();
                        cands.extend(RANDOM_FUNCTIONS.iter().map(|(n, _)| *n));
                        let macros: Vec<String> = if self.may_suggest_name() {
                            self.globals
                                .iter()
                                .filter(|(_, b)| matches!(b.value, Value::Macro(_)))
                                .map(|(n, _)| n.clone())
                                .collect()
                        } else {
                            Vec::new()
                        };
                        cands.extend(macros.iter().map(String::as_str));
                        let random_names: Vec<&str> =
                            RANDOM_FUNCTIONS.iter().map(|(n, _)| *n).collect();
                        if let Some(hint) = crate::syntax::povray_hint(&name.text, "") {
                            err = err.help(hint);
                        } else if let Some(s) = suggest(&name.text, cands) {
                            err = err.help(format!("did you mean `{s}`?"));
                        } else {
                            err = err.help(format!(
                                "the built-in functions are {} {}; a macro is declared with \
                                 `#macro`",
                                FUNCTIONS.join(" "),
                                random_names.join(" ")
                            ));
                        }
                        return Err(vec![err.at(name.span)]);
                    }
                }
            }
            ExprKind::Unary(op, inner) => {
                let v = self.eval(inner)?;
                unary(*op, v).at(e.span)?
            }
            ExprKind::Binary(op, a, b) => {
                let va = self.eval(a)?;
                // Short-circuit logic.
                if matches!(op, BinOp::And | BinOp::Or) {
                    let x = va.truthy().at(a.span)?;
                    if (*op == BinOp::And && !x) || (*op == BinOp::Or && x) {
                        return Ok(Value::Bool(x));
                    }
                    return Ok(Value::Bool(self.eval(b)?.truthy().at(b.span)?));
                }
                let vb = self.eval(b)?;
                // Strings are joined or compared whole: the work of both operands.
                self.charge(super::work_of(&va) + super::work_of(&vb), e.span)?;
                // A joined string counts against the load's memory before it is made.
                if let (BinOp::Add, Value::Str(x), Value::Str(y)) = (op, &va, &vb) {
                    let bytes = x.len() + y.len();
                    if bytes <= super::MAX_STRING_BYTES {
                        self.hold_string(bytes as u64, e.span)?;
                    }
                }
                binary(*op, va, vb).at(e.span)?
            }
            ExprKind::Conditional(parts) => {
                // Only the chosen branch is evaluated (a recursive macro's base case stops it).
                let [cond, then, otherwise] = &**parts;
                if self.eval(cond)?.truthy().at(cond.span)? {
                    self.eval(then)?
                } else {
                    self.eval(otherwise)?
                }
            }
            ExprKind::Index(base, index) => {
                let vb = self.eval(base)?;
                let i = self.eval(index)?.num().at(index.span)?;
                index_value(vb, i).at(index.span)?
            }
            ExprKind::Field(base, field) => {
                let vb = self.eval(base)?;
                field_value(vb, &field.text).at(field.span)?
            }
            ExprKind::Function(def) => self.define_function(def, e.span)?,
        })
    }
}

fn not_finite(span: Span, what: &str) -> Diagnostic {
    Error::new(format!("this {what} is not finite (NaN or infinity)"))
        .label("not a finite value")
        .help("check for a division by a tiny number or an overflowing power")
        .at(span)
}

fn unary(op: UnOp, v: Value) -> Result<Value, Error> {
    Ok(match (op, v) {
        (UnOp::Pos, v @ (Value::Num(_) | Value::Vec2(_) | Value::Vec3(_) | Value::Color(_))) => v,
        (UnOp::Neg, Value::Num(n)) => Value::Num(-n),
        (UnOp::Neg, Value::Vec2(a)) => Value::Vec2(-a),
        (UnOp::Neg, Value::Vec3(a)) => Value::Vec3(-a),
        (UnOp::Neg, Value::Color(a)) => Value::Color(-a),
        (UnOp::Not, v) => Value::Bool(!v.truthy()?),
        (UnOp::Rgb, v) => Value::Color(v.color()?),
        (op @ (UnOp::Rgbf | UnOp::Rgbt | UnOp::Rgbft), v) => filtered(op, v)?,
        (op, v) => {
            return Err(Error::new(format!(
                "cannot apply `{}` to {}",
                match op {
                    UnOp::Neg => "-",
                    UnOp::Pos => "+",
                    UnOp::Not => "!",
                    UnOp::Rgb => "rgb",
                    UnOp::Rgbf => "rgbf",
                    UnOp::Rgbt => "rgbt",
                    UnOp::Rgbft => "rgbft",
                },
                v.type_name()
            ))
            .help("it applies to numbers and vectors (`!` to conditions)"));
        }
    })
}

/// POV-Ray's `rgbf <r, g, b, f>`, `rgbt <r, g, b, t>` and `rgbft <r, g, b, f, t>` (a number
/// stands for every component, as in POV-Ray).
fn filtered(op: UnOp, v: Value) -> Result<Value, Error> {
    let (word, n) = match op {
        UnOp::Rgbf => ("rgbf", 4),
        UnOp::Rgbt => ("rgbt", 4),
        _ => ("rgbft", 5),
    };
    let xs: Vec<f64> = match &v {
        Value::Num(x) => vec![*x; n],
        Value::Array(a) if a.len() == n => a
            .iter()
            .map(|x| match x {
                Value::Num(x) => Some(*x),
                _ => None,
            })
            .collect::<Option<_>>()
            .unwrap_or_default(),
        _ => Vec::new(),
    };
    if xs.len() != n {
        return Err(Error::new(format!(
            "`{word}` takes {n} components, found {}",
            v.type_name()
        ))
        .help(format!(
            "write e.g. `{word} <1, 0.9, 0.9, {}>`",
            if n == 4 { "0.8" } else { "0.5, 0.3" }
        )));
    }
    let c = DVec3::new(xs[0], xs[1], xs[2]);
    Ok(match op {
        UnOp::Rgbf => Value::Filtered(c, xs[3], 0.0),
        UnOp::Rgbt => Value::Filtered(c, 0.0, xs[3]),
        _ => Value::Filtered(c, xs[3], xs[4]),
    })
}

/// How close two numbers are equal for `==`, `!=` and `#case`: as POV-Ray's `=`, `!=` and
/// `#case`, `|a - b| < 1e-10`.
pub(super) const EQUAL_WITHIN: f64 = 1e-10;

fn binary(op: BinOp, a: Value, b: Value) -> Result<Value, Error> {
    use BinOp::*;
    use Value::*;
    let mismatch = |a: &Value, b: &Value| {
        Error::new(format!(
            "cannot apply `{}` to {} and {}",
            op.symbol(),
            a.type_name(),
            b.type_name()
        ))
        .label("type mismatch")
        .help(
            "arithmetic takes numbers and vectors of one size (a number scales a vector); \
             `+` joins two strings, `str(x)` makes a number a string",
        )
    };
    if matches!(op, Div) {
        let zero = match &b {
            Num(x) => *x == 0.0,
            Vec2(v) => v.x == 0.0 || v.y == 0.0,
            Vec3(v) | Color(v) => v.abs().min_element() == 0.0,
            _ => false,
        };
        if zero {
            return Err(Error::new("division by zero")
                .label("this divides by zero")
                .help("check the divisor first, e.g. `#if (N != 0)`"));
        }
    }
    let arith = |x: f64, y: f64| match op {
        Add => x + y,
        Sub => x - y,
        Mul => x * y,
        _ => x / y,
    };
    let arith3 = |x: DVec3, y: DVec3| match op {
        Add => x + y,
        Sub => x - y,
        Mul => x * y,
        _ => x / y,
    };
    let arith2 = |x: DVec2, y: DVec2| match op {
        Add => x + y,
        Sub => x - y,
        Mul => x * y,
        _ => x / y,
    };
    Ok(match op {
        Add | Sub | Mul | Div => match (&a, &b) {
            (Num(x), Num(y)) => Num(arith(*x, *y)),
            (Vec3(x), Vec3(y)) => Vec3(arith3(*x, *y)),
            (Color(x), Color(y) | Vec3(y)) | (Vec3(x), Color(y)) => Color(arith3(*x, *y)),
            (Vec3(x), Num(y)) => Vec3(arith3(*x, DVec3::splat(*y))),
            (Color(x), Num(y)) => Color(arith3(*x, DVec3::splat(*y))),
            (Num(x), Vec3(y)) if matches!(op, Mul | Add) => Vec3(arith3(DVec3::splat(*x), *y)),
            (Num(x), Color(y)) if matches!(op, Mul | Add) => Color(arith3(DVec3::splat(*x), *y)),
            (Vec2(x), Vec2(y)) => Vec2(arith2(*x, *y)),
            (Vec2(x), Num(y)) => Vec2(arith2(*x, DVec2::splat(*y))),
            (Num(x), Vec2(y)) if matches!(op, Mul | Add) => Vec2(arith2(DVec2::splat(*x), *y)),
            (Str(x), Str(y)) if op == Add => {
                if x.len() + y.len() > super::MAX_STRING_BYTES {
                    return Err(Error::new(format!(
                        "the joined string would be {} bytes, more than the limit of {} bytes",
                        x.len() + y.len(),
                        super::MAX_STRING_BYTES
                    ))
                    .help("is a string doubled in a loop? build only what the scene needs"));
                }
                Str(Rc::from(format!("{x}{y}")))
            }
            _ => return Err(mismatch(&a, &b)),
        },
        Lt | Le | Gt | Ge => match (&a, &b) {
            (Num(x), Num(y)) => Bool(match op {
                Lt => x < y,
                Le => x <= y,
                Gt => x > y,
                _ => x >= y,
            }),
            _ => return Err(mismatch(&a, &b).help("only numbers can be ordered")),
        },
        Eq | Ne => {
            // Numbers (and components) within EQUAL_WITHIN are equal, as in POV-Ray: a sum of
            // tenths equals the number it adds up to.
            let eq = match (&a, &b) {
                (Num(x), Num(y)) => (x - y).abs() < EQUAL_WITHIN,
                (Bool(x), Bool(y)) => x == y,
                (Str(x), Str(y)) => x == y,
                (Vec2(x), Vec2(y)) => (*x - *y).abs().max_element() < EQUAL_WITHIN,
                (Vec3(x) | Color(x), Vec3(y) | Color(y)) => {
                    (*x - *y).abs().max_element() < EQUAL_WITHIN
                }
                _ => return Err(mismatch(&a, &b)),
            };
            Bool(eq == (op == Eq))
        }
        And | Or => unreachable!("short-circuited"),
    })
}

fn index_value(v: Value, i: f64) -> Result<Value, Error> {
    let len = match &v {
        Value::Array(a) => a.len(),
        Value::Vec2(_) => 2,
        Value::Vec3(_) | Value::Color(_) => 3,
        o => {
            return Err(Error::new(format!("cannot index {}", o.type_name()))
                .label("not an array, vector or colour")
                .help(
                    "`[i]` takes an element of an array (`[1, 2, 3][0]`) or a component of a \
                     vector or colour (`<1, 2, 3>[0]`); a string's characters are not indexed",
                ));
        }
    };
    if len == 0 {
        return Err(
            Error::new(format!("index {} of an empty array", exact_number(i)))
                .label("the array is empty")
                .help("an empty array has no elements to take: test `len(A) > 0` first"),
        );
    }
    if i.fract() != 0.0 {
        return Err(Error::new(format!(
            "index {} is not a whole number",
            exact_number(i)
        ))
        .label("not a whole number")
        .help(format!(
            "indices are whole numbers from 0 to {}: round it with `floor(...)` or `round(...)`",
            len - 1
        )));
    }
    if i < 0.0 || i >= len as f64 {
        return Err(Error::new(format!(
            "index {} out of range (length {len})",
            short_number(i)
        ))
        .label("out of range")
        .help(format!("indices run from 0 to {}", len - 1)));
    }
    let i = i as usize;
    Ok(match v {
        Value::Array(a) => a[i].clone(),
        Value::Vec2(a) => Value::Num(a[i]),
        Value::Vec3(a) | Value::Color(a) => Value::Num(a[i]),
        _ => unreachable!(),
    })
}

/// A number as short as it reads, unless that form would hide its fraction
/// (`0.9999999999999999` is not shown as `1`).
pub(super) fn exact_number(x: f64) -> String {
    let short = short_number(x);
    if x.fract() != 0.0 && short.parse::<f64>().is_ok_and(|s| s.fract() == 0.0) {
        format!("{x}")
    } else {
        short
    }
}

fn field_value(v: Value, f: &str) -> Result<Value, Error> {
    let i = match f {
        "x" | "u" | "r" | "red" => 0,
        "y" | "v" | "g" | "green" => 1,
        "z" | "b" | "blue" => 2,
        _ => {
            return Err(Error::new(format!("unknown component `.{f}`"))
                .help("components are `.x`, `.y`, `.z` (or `.r`, `.g`, `.b`)"));
        }
    };
    let what = v.type_name();
    index_value(v, i as f64).map_err(|_| {
        Error::new(format!("{what} has no component `.{f}`"))
            .label("no such component")
            .help(
                "`.x` `.y` `.z` (`.r` `.g` `.b`) read a vector's or colour's components; a 2D \
                 vector has `.x` and `.y` (`.u` `.v`) only",
            )
    })
}
