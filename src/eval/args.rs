//! Property arguments and their readers: each checks one argument (a number, a vector, a
//! color, a word, a count) and reports a wrong type or an out-of-range value at its span.

use glam::DVec3;

use super::value::{ColorDef, Value};
use crate::diag::{At, Diagnostic, Error, SourceResult, suggest};
use crate::scene::{Color, MAX_COLOR};
use crate::span::Span;

/// One argument of a property: its value and where it was written.
pub(crate) struct Arg {
    pub value: Value,
    pub span: Span,
}

pub(super) fn num(a: &Arg) -> SourceResult<f64> {
    a.value.num().at(a.span)
}

pub(super) fn vec3(a: &Arg) -> SourceResult<DVec3> {
    a.value.vec3().at(a.span)
}

pub(super) fn color(a: &Arg) -> SourceResult<Color> {
    let c = a.value.color().at(a.span)?;
    check_magnitude(c, a.span)?;
    Ok(c)
}

fn check_magnitude(c: Color, span: Span) -> SourceResult<()> {
    if c.abs().max_element() > MAX_COLOR || !c.is_finite() {
        return Err(range_error(
            span,
            format!(
                "color component {} is out of range",
                crate::diag::short_number(c.abs().max_element())
            ),
            "use components of at most 1e9 (scale the light or the exposure instead)",
        ));
    }
    Ok(())
}

/// A colour a surface reflects, a texture shows or the background emits: within range and not
/// negative.
pub(super) fn surface_color(a: &Arg) -> SourceResult<Color> {
    let c = color(a)?;
    check_surface(c, a.span)?;
    Ok(c)
}

fn check_surface(c: Color, span: Span) -> SourceResult<()> {
    if c.min_element() < 0.0 {
        return Err(range_error(
            span,
            format!(
                "a color must not be negative, found {}",
                crate::diag::short_number(c.min_element())
            ),
            "use components >= 0",
        ));
    }
    Ok(())
}

pub(super) fn word(a: &Arg, choices: &[&str]) -> SourceResult<String> {
    let s = match &a.value {
        Value::Str(s) => s.to_string(),
        v => {
            return Err(vec![
                Error::new(format!(
                    "expected one of {}, found {}",
                    choices.join(", "),
                    v.type_name()
                ))
                .label("not a word")
                .help(format!("write one of the words, e.g. `{}`", choices[0]))
                .at(a.span),
            ]);
        }
    };
    if choices.contains(&s.as_str()) {
        return Ok(s);
    }
    let mut e =
        Error::new(format!("`{s}` is not one of {}", choices.join(", "))).label("unknown choice");
    e = match suggest(&s, choices.iter().copied()) {
        Some(c) => e.help(format!("did you mean `{c}`?")),
        None => e.help(format!("write one of them, e.g. `{}`", choices[0])),
    };
    Err(vec![e.at(a.span)])
}

/// A file name (a string) as written; `Evaluator::resolve_path` makes it a path.
pub(crate) fn file_name(a: &Arg) -> SourceResult<&str> {
    match &a.value {
        Value::Str(s) => Ok(s),
        v => Err(vec![
            Error::new(format!(
                "expected a file name string, found {}",
                v.type_name()
            ))
            .label("not a string")
            .help("write the file name in double quotes, e.g. `\"model.obj\"`")
            .at(a.span),
        ]),
    }
}

pub(super) fn range_error(span: Span, msg: String, help: &str) -> Vec<Diagnostic> {
    vec![
        Error::new(msg)
            .label("out of range")
            .help(help.to_string())
            .at(span),
    ]
}

pub(super) fn positive(a: &Arg, what: &str) -> SourceResult<f64> {
    let x = num(a)?;
    if x <= 0.0 {
        return Err(range_error(
            a.span,
            format!(
                "{what} must be positive, found {}",
                crate::diag::short_number(x)
            ),
            "use a number greater than 0",
        ));
    }
    Ok(x)
}

pub(super) fn count(a: &Arg, what: &str, max: f64) -> SourceResult<f64> {
    let x = num(a)?;
    if x < 1.0 || x.fract() != 0.0 || x > max {
        return Err(range_error(
            a.span,
            format!(
                "{what} must be a whole number from 1 to {}, found {}",
                crate::diag::short_number(max),
                super::expr::exact_number(x)
            ),
            "use a whole number in range",
        ));
    }
    Ok(x)
}

pub(super) fn color_def(a: &Arg) -> SourceResult<ColorDef> {
    match &a.value {
        Value::Texture(t) => Ok(ColorDef::Tex(t.clone())),
        v => {
            let c = v
                .color()
                .map_err(|e| {
                    e.help("give a color `rgb <r, g, b>`, a number or a `texture { ... }`")
                })
                .at(a.span)?;
            check_magnitude(c, a.span)?;
            check_surface(c, a.span)?;
            Ok(ColorDef::Const(c))
        }
    }
}
