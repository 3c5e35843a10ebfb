//! Built-in functions and constants.

use crate::diag::short_number;
use std::f64::consts::PI;

use glam::{DAffine3, DVec3};

use super::value::Value;
use crate::diag::Error;

/// Names of the built-in functions (for "did you mean").
pub const FUNCTIONS: &[&str] = &[
    "sin",
    "cos",
    "tan",
    "asin",
    "acos",
    "atan",
    "atan2",
    "sqrt",
    "pow",
    "exp",
    "ln",
    "log",
    "abs",
    "min",
    "max",
    "clamp",
    "floor",
    "ceil",
    "round",
    "mod",
    "radians",
    "degrees",
    "vlength",
    "vnormalize",
    "vdot",
    "vcross",
    "vrotate",
    "concat",
    "vstr",
    "substr",
    "strlen",
    "chr",
    "asc",
    "strupr",
    "strlwr",
    "val",
    "len",
    "str",
];

use crate::scene::scaled_length_f64 as length;
pub(crate) use crate::scene::scaled_unit as unit;

/// Names of the built-in constants.
pub const CONSTANTS: &[&str] = &["pi", "x", "y", "z"];

pub fn constant(name: &str) -> Option<Value> {
    Some(match name {
        "pi" => Value::Num(PI),
        "x" => Value::Vec3(DVec3::X),
        "y" => Value::Vec3(DVec3::Y),
        "z" => Value::Vec3(DVec3::Z),
        _ => return None,
    })
}

/// Rotation by `deg` degrees about x, then y, then z (POV-Ray order).
pub fn rotation(deg: DVec3) -> DAffine3 {
    let r = deg * (PI / 180.0);
    DAffine3::from_rotation_z(r.z) * DAffine3::from_rotation_y(r.y) * DAffine3::from_rotation_x(r.x)
}

/// Calls built-in `name`. `Ok(None)`: no such function. Argument errors carry the index of the
/// offending argument (or `usize::MAX` for the call as a whole).
pub fn call(name: &str, args: &[Value]) -> Option<Result<Value, (usize, Error)>> {
    if let Some(result) = super::strings::call(name, args) {
        return Some(result);
    }
    let arity = match name {
        "atan2" | "pow" | "mod" | "vdot" | "vcross" | "vrotate" => 2,
        "clamp" => 3,
        "min" | "max" => 0,
        n if FUNCTIONS.contains(&n) => 1,
        _ => return None,
    };
    if arity > 0 && args.len() != arity {
        return Some(Err((
            usize::MAX,
            Error::new(format!(
                "`{name}` takes {arity} argument{}, found {}",
                if arity == 1 { "" } else { "s" },
                args.len()
            ))
            .help(format!("call it as `{}`", signature(name))),
        )));
    }
    Some(dispatch(name, args))
}

/// How a built-in function with a fixed number of arguments is called.
fn signature(name: &str) -> String {
    match name {
        "atan2" => "atan2(y, x)".into(),
        "pow" => "pow(base, exponent)".into(),
        "mod" => "mod(a, b)".into(),
        "vdot" | "vcross" => format!("{name}(a, b)"),
        "vrotate" => "vrotate(v, <ax, ay, az>)".into(),
        "clamp" => "clamp(x, lo, hi)".into(),
        "len" => "len(array or string)".into(),
        n if n.starts_with('v') => format!("{n}(v)"),
        n => format!("{n}(x)"),
    }
}

fn n(args: &[Value], i: usize) -> Result<f64, (usize, Error)> {
    args[i].num().map_err(|e| (i, e))
}

fn v(args: &[Value], i: usize) -> Result<DVec3, (usize, Error)> {
    args[i].vec3().map_err(|e| (i, e))
}

fn dispatch(name: &str, args: &[Value]) -> Result<Value, (usize, Error)> {
    let num = |x: f64| Ok(Value::Num(x));
    match name {
        "sin" => num(n(args, 0)?.sin()),
        "cos" => num(n(args, 0)?.cos()),
        "tan" => num(n(args, 0)?.tan()),
        "asin" | "acos" => {
            let x = n(args, 0)?;
            if !(-1.0..=1.0).contains(&x) {
                return Err((
                    0,
                    Error::new(format!(
                        "`{name}` needs an argument in [-1, 1], found {}",
                        short_number(x)
                    ))
                    .help(format!("clamp it first: `{name}(clamp(x, -1, 1))`")),
                ));
            }
            num(if name == "asin" { x.asin() } else { x.acos() })
        }
        "atan" => num(n(args, 0)?.atan()),
        "atan2" => num(n(args, 0)?.atan2(n(args, 1)?)),
        "sqrt" => {
            let x = n(args, 0)?;
            if x < 0.0 {
                return Err((
                    0,
                    Error::new(format!("`sqrt` of a negative number ({})", short_number(x)))
                        .help("check the sign first (`#if (x >= 0)`), or take `sqrt(abs(x))`"),
                ));
            }
            num(x.sqrt())
        }
        "pow" => num(n(args, 0)?.powf(n(args, 1)?)),
        "exp" => num(n(args, 0)?.exp()),
        "ln" | "log" => {
            let x = n(args, 0)?;
            if x <= 0.0 {
                return Err((
                    0,
                    Error::new(format!(
                        "`{name}` needs a positive number, found {}",
                        short_number(x)
                    ))
                    .help("a logarithm is defined above 0 only: check the argument first"),
                ));
            }
            num(if name == "ln" { x.ln() } else { x.log10() })
        }
        "abs" => match &args[0] {
            Value::Vec3(a) => Ok(Value::Vec3(a.abs())),
            _ => num(n(args, 0)?.abs()),
        },
        "min" | "max" => {
            if args.is_empty() {
                return Err((
                    usize::MAX,
                    Error::new(format!("`{name}` needs at least one argument"))
                        .help(format!("call it with numbers, e.g. `{name}(a, b)`")),
                ));
            }
            let mut acc = n(args, 0)?;
            for i in 1..args.len() {
                let x = n(args, i)?;
                acc = if name == "min" {
                    acc.min(x)
                } else {
                    acc.max(x)
                };
            }
            num(acc)
        }
        "clamp" => {
            let (x, lo, hi) = (n(args, 0)?, n(args, 1)?, n(args, 2)?);
            if lo > hi {
                return Err((
                    1,
                    Error::new(format!(
                        "`clamp` bounds are reversed ({} > {})",
                        short_number(lo),
                        short_number(hi)
                    ))
                    .help("write `clamp(x, lo, hi)` with lo ≤ hi"),
                ));
            }
            num(x.clamp(lo, hi))
        }
        "floor" => num(n(args, 0)?.floor()),
        "ceil" => num(n(args, 0)?.ceil()),
        "round" => num(n(args, 0)?.round()),
        "mod" => {
            let b = n(args, 1)?;
            if b == 0.0 {
                return Err((
                    1,
                    Error::new("`mod` by zero")
                        .help("the divisor must not be 0: check it first (`#if (B != 0)`)"),
                ));
            }
            num(n(args, 0)? % b)
        }
        "radians" => num(n(args, 0)?.to_radians()),
        "degrees" => num(n(args, 0)?.to_degrees()),
        "vlength" => match &args[0] {
            Value::Vec2(a) => num(length(a.extend(0.0))),
            _ => num(length(v(args, 0)?)),
        },
        "vnormalize" => {
            let a = v(args, 0)?;
            match unit(a) {
                Some(u) => Ok(Value::Vec3(u)),
                None => Err((
                    0,
                    Error::new("cannot normalize a zero-length vector")
                        .help("a zero vector has no direction: check its length first"),
                )),
            }
        }
        "vdot" => num(v(args, 0)?.dot(v(args, 1)?)),
        "vcross" => Ok(Value::Vec3(v(args, 0)?.cross(v(args, 1)?))),
        "vrotate" => Ok(Value::Vec3(
            rotation(v(args, 1)?).transform_vector3(v(args, 0)?),
        )),
        "len" => match &args[0] {
            Value::Array(a) => num(a.len() as f64),
            Value::Str(s) => num(s.chars().count() as f64),
            o => Err((
                0,
                Error::new(format!(
                    "`len` needs an array or a string, found {}",
                    o.type_name()
                ))
                .help("`len(A)` counts an array's elements or a string's characters"),
            )),
        },
        _ => unreachable!("builtin {name}"),
    }
}
