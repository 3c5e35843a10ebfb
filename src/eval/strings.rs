//! POV-Ray's string functions: `concat`, `str`, `vstr`, `substr`, `strlen`, `chr`, `asc`,
//! `strupr`, `strlwr` and `val`. Positions and lengths count characters (a string here is
//! UTF-8, POV-Ray's is bytes); every string made stays within [`MAX_STRING_BYTES`].

use std::rc::Rc;

use super::MAX_STRING_BYTES;
use super::value::Value;
use crate::diag::{Error, short_number};

/// Digits after the point when POV-Ray's precision is negative (C's `%f`).
const DEFAULT_PRECISION: usize = 6;

type CallResult = Result<Value, (usize, Error)>;

/// Calls string function `name`; `None` when `name` is none of them. Argument errors carry the
/// index of the offending argument (`usize::MAX` for the call as a whole), as in `builtins`.
pub fn call(name: &str, args: &[Value]) -> Option<CallResult> {
    let arity: &[usize] = match name {
        "concat" => &[],
        "str" => &[1, 3],
        "vstr" => &[5],
        "substr" => &[3],
        "strlen" | "chr" | "asc" | "strupr" | "strlwr" | "val" => &[1],
        _ => return None,
    };
    if name == "concat" && args.is_empty() {
        return Some(Err((
            usize::MAX,
            Error::new("`concat` needs at least one argument")
                .help("call it with strings, e.g. `concat(\"a\", str(N), \"b\")`"),
        )));
    }
    if !arity.is_empty() && !arity.contains(&args.len()) {
        let takes = match arity {
            [1, 3] => "1 or 3 arguments".to_string(),
            [1] => "1 argument".to_string(),
            [n] => format!("{n} arguments"),
            _ => unreachable!("arity of {name}"),
        };
        return Some(Err((
            usize::MAX,
            Error::new(format!("`{name}` takes {takes}, found {}", args.len()))
                .help(format!("call it as {}", signature(name))),
        )));
    }
    Some(dispatch(name, args))
}

fn signature(name: &str) -> &'static str {
    match name {
        "str" => {
            "`str(x)` (as `#debug` writes it) or `str(x, width, decimals)`: a negative width \
             pads with zeros, negative decimals give 6"
        }
        "vstr" => {
            "`vstr(n, V, separator, width, decimals)`: the first n (2 to 5) components of V, \
             each as `str(c, width, decimals)`"
        }
        "substr" => "`substr(s, position, length)`, positions counting from 1",
        "strlen" => "`strlen(s)`",
        "chr" => "`chr(code)`",
        "asc" => "`asc(s)`",
        "strupr" => "`strupr(s)`",
        "strlwr" => "`strlwr(s)`",
        _ => "`val(s)`",
    }
}

fn string(args: &[Value], i: usize, name: &str) -> Result<Rc<str>, (usize, Error)> {
    match &args[i] {
        Value::Str(s) => Ok(s.clone()),
        o => Err((
            i,
            Error::new(format!("`{name}` needs a string, found {}", o.type_name())).help(
                match name {
                    "concat" => "every argument of `concat` is a string: write a number as \
                                 `str(x)`"
                        .to_string(),
                    _ => format!("call it as {}", signature(name)),
                },
            ),
        )),
    }
}

/// A number argument as POV-Ray reads a count: truncated towards zero.
fn whole(args: &[Value], i: usize) -> Result<i64, (usize, Error)> {
    args[i].num().map(|x| x.trunc() as i64).map_err(|e| (i, e))
}

fn too_long(bytes: usize) -> Error {
    Error::new(format!(
        "the string would be {bytes} bytes, more than the limit of {MAX_STRING_BYTES} bytes"
    ))
    .help("is a string built in a loop, or a width too large? build only what the scene needs")
}

fn text(s: String) -> CallResult {
    Ok(Value::Str(Rc::from(s)))
}

fn dispatch(name: &str, args: &[Value]) -> CallResult {
    match name {
        "concat" => {
            let mut parts = Vec::with_capacity(args.len());
            for i in 0..args.len() {
                parts.push(string(args, i, name)?);
            }
            let bytes: usize = parts.iter().map(|p| p.len()).sum();
            if bytes > MAX_STRING_BYTES {
                return Err((usize::MAX, too_long(bytes)));
            }
            text(parts.concat())
        }
        "str" if args.len() == 1 => match &args[0] {
            // As `#debug` shows it: `str(0.1 + 0.2)` is "0.3", `str(-0.0)` is "0".
            Value::Num(x) => text(short_number(*x)),
            Value::Str(s) => Ok(Value::Str(s.clone())),
            o => Err((
                0,
                Error::new(format!("`str` needs a number, found {}", o.type_name())).help(
                    "`str(x)` writes a number as a string; `vstr(3, V, \", \", 0, 2)` writes \
                     a vector (`#debug V` shows a whole vector)",
                ),
            )),
        },
        "str" => {
            let x = args[0].num().map_err(|e| (0, e))?;
            format_number(x, whole(args, 1)?, whole(args, 2)?)
                .map(Value::Str)
                .map_err(|e| (usize::MAX, e))
        }
        "vstr" => vstr(args),
        "substr" => {
            let s = string(args, 0, name)?;
            let (pos, len) = (whole(args, 1)?, whole(args, 2)?);
            let count = s.chars().count() as i64;
            if pos < 1 || len < 0 || pos.saturating_add(len) - 1 > count {
                return Err((
                    usize::MAX,
                    Error::new(format!(
                        "`substr` from position {pos}, {len} characters, is outside the string \
                         ({count} characters)"
                    ))
                    .label("illegal parameters in substr")
                    .help(
                        "`substr(s, position, length)` counts positions from 1; the range must \
                         lie within the string: test `strlen(s)` first",
                    ),
                ));
            }
            text(
                s.chars()
                    .skip(pos as usize - 1)
                    .take(len as usize)
                    .collect(),
            )
        }
        "strlen" => Ok(Value::Num(string(args, 0, name)?.chars().count() as f64)),
        "chr" => {
            let code = whole(args, 0)?;
            match u32::try_from(code)
                .ok()
                .filter(|&c| c > 0)
                .and_then(char::from_u32)
            {
                Some(c) => text(c.to_string()),
                None => Err((
                    0,
                    Error::new(format!("value {code} cannot be used in `chr`"))
                        .label("not a character code")
                        .help(
                            "`chr(code)` takes a Unicode code point from 1 to 1114111, other \
                             than 55296 to 57343 (surrogates); `chr(65)` is \"A\"",
                        ),
                )),
            }
        }
        "asc" => {
            // POV-Ray's `asc("")` is 0.
            let s = string(args, 0, name)?;
            Ok(Value::Num(
                s.chars().next().map_or(0.0, |c| f64::from(c as u32)),
            ))
        }
        "strupr" => text(string(args, 0, name)?.to_uppercase()).and_then(bounded),
        "strlwr" => text(string(args, 0, name)?.to_lowercase()).and_then(bounded),
        "val" => Ok(Value::Num(leading_number(&string(args, 0, name)?))),
        _ => unreachable!("string function {name}"),
    }
}

/// Upper- and lower-casing may lengthen a string (`ß` is `SS`).
fn bounded(v: Value) -> CallResult {
    match &v {
        Value::Str(s) if s.len() > MAX_STRING_BYTES => Err((usize::MAX, too_long(s.len()))),
        _ => Ok(v),
    }
}

/// `vstr(N, V, S, L, P)`: the first `N` components of `V` (missing ones are 0, as in
/// POV-Ray), each written as `str(c, L, P)`, joined by `S`.
fn vstr(args: &[Value]) -> CallResult {
    let n = whole(args, 0)?;
    if !(2..=5).contains(&n) {
        return Err((
            0,
            Error::new(format!("`vstr` writes 2 to 5 components, found {n}"))
                .help("the first argument is the number of components: 2 to 5"),
        ));
    }
    let comps: Vec<f64> = match &args[1] {
        Value::Vec2(v) => v.to_array().to_vec(),
        Value::Vec3(v) | Value::Color(v) => v.to_array().to_vec(),
        Value::Array(xs) if xs.len() <= 5 && xs.iter().all(|x| matches!(x, Value::Num(_))) => {
            xs.iter().filter_map(|x| x.num().ok()).collect()
        }
        o => {
            return Err((
                1,
                Error::new(format!("`vstr` needs a vector, found {}", o.type_name()))
                    .help("call it as `vstr(3, <x, y, z>, \", \", 0, 2)`; a number is `str(x)`"),
            ));
        }
    };
    let sep = string(args, 2, "vstr")?;
    let (width, precision) = (whole(args, 3)?, whole(args, 4)?);
    let mut out = String::new();
    for i in 0..n as usize {
        if i > 0 {
            out.push_str(&sep);
        }
        let part = format_number(comps.get(i).copied().unwrap_or(0.0), width, precision)
            .map_err(|e| (usize::MAX, e))?;
        if out.len() + part.len() > MAX_STRING_BYTES {
            return Err((usize::MAX, too_long(out.len() + part.len())));
        }
        out.push_str(&part);
    }
    text(out)
}

/// `x` as C's `%*.*f` writes it, which POV-Ray's `str(x, width, precision)` is: at least
/// `|width|` characters, padded with spaces on the left, or with zeros after the sign when
/// `width` is negative; `precision` digits after the point (6 when negative).
pub(crate) fn format_number(x: f64, width: i64, precision: i64) -> Result<Rc<str>, Error> {
    let zeros = width < 0;
    let width = usize::try_from(width.unsigned_abs()).unwrap_or(usize::MAX);
    let digits = if precision < 0 {
        DEFAULT_PRECISION
    } else {
        usize::try_from(precision).unwrap_or(usize::MAX)
    };
    // The digits before the point (at most 309 for a finite f64), a sign and the point.
    let whole_part = format!("{:.0}", x.abs().trunc()).len() + usize::from(x < 0.0) + 1;
    let least = width.max(digits.saturating_add(whole_part));
    if least > MAX_STRING_BYTES {
        return Err(Error::new(format!(
            "this number would be written in at least {least} bytes, more than the string \
             limit of {MAX_STRING_BYTES} bytes"
        ))
        .help("`str(x, width, decimals)`: choose a width and a number of decimals that fit"));
    }
    // Padded by hand: Rust's formatting takes widths and precisions below 65536 only. A
    // binary fraction has at most 1074 digits after the point, so more are zeros.
    let exact = digits.min(EXACT_DIGITS);
    let mut s = format!("{x:.exact$}");
    s.extend(std::iter::repeat_n('0', digits - exact));
    let pad = width.saturating_sub(s.len());
    if pad > 0 {
        // As C's `0` flag: zeros go after the sign, `-0042`.
        let at = if zeros {
            usize::from(s.starts_with('-'))
        } else {
            0
        };
        let fill = if zeros { '0' } else { ' ' };
        s.insert_str(at, &fill.to_string().repeat(pad));
    }
    Ok(Rc::from(s))
}

/// Digits after the point that can differ from 0 in an `f64` (its smallest step is 2^-1074).
const EXACT_DIGITS: usize = 1074;

/// The number at the start of `s` (after blanks), as C's `atof` reads it, which POV-Ray's
/// `val` is: `val("12abc")` is 12, `val("abc")` is 0.
fn leading_number(s: &str) -> f64 {
    let t = s.trim_start();
    let b = t.as_bytes();
    let mut i = 0;
    let digits = |i: &mut usize| {
        let start = *i;
        while *i < b.len() && b[*i].is_ascii_digit() {
            *i += 1;
        }
        *i - start
    };
    if i < b.len() && matches!(b[i], b'+' | b'-') {
        i += 1;
    }
    let mut mantissa = digits(&mut i);
    if i < b.len() && b[i] == b'.' {
        i += 1;
        mantissa += digits(&mut i);
    }
    if mantissa == 0 {
        return 0.0;
    }
    let end = i;
    if i < b.len() && matches!(b[i], b'e' | b'E') {
        let mut j = i + 1;
        if j < b.len() && matches!(b[j], b'+' | b'-') {
            j += 1;
        }
        if digits(&mut j) > 0 {
            return t[..j].parse().unwrap_or(0.0);
        }
    }
    t[..end].parse().unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(text: &str) -> Value {
        Value::Str(Rc::from(text))
    }

    /// The `%*.*f` forms POV-Ray 3.7 prints, including ties (to even, as C rounds the exact
    /// binary value) and precisions past what Rust's formatting takes.
    #[test]
    fn numbers_are_written_as_c_writes_them() {
        let f = |x, w, p| format_number(x, w, p).unwrap().to_string();
        assert_eq!(f(2.5, 0, 0), "2");
        assert_eq!(f(3.5, 0, 0), "4");
        assert_eq!(f(0.125, 0, 2), "0.12");
        assert_eq!(f(-1.5, -7, 1), "-0001.5");
        assert_eq!(f(-1.5, 7, 1), "   -1.5");
        assert_eq!(f(1e20, 0, -1), "100000000000000000000.000000");
        assert_eq!(f(1.0, 3, 1), "1.0");
        let long = f(0.5, 0, 70_000);
        assert_eq!(long.len(), 70_002);
        assert!(long.starts_with("0.5") && long[3..].bytes().all(|b| b == b'0'));
        let wide = f(7.0, 70_000, 0);
        assert_eq!(wide.len(), 70_000);
        assert!(wide.ends_with(" 7"));
    }

    #[test]
    fn widths_and_joins_past_the_string_limit_are_errors() {
        assert!(format_number(1.0, MAX_STRING_BYTES as i64 + 1, 0).is_err());
        assert!(format_number(1.0, 0, MAX_STRING_BYTES as i64).is_err());
        assert!(format_number(1.0, i64::MIN, i64::MAX).is_err());
        let half = s(&"a".repeat(MAX_STRING_BYTES / 2 + 1));
        let Some(Err((_, e))) = call("concat", &[half.clone(), half]) else {
            panic!("concat past the limit was accepted")
        };
        assert!(e.message.contains("more than the limit"), "{}", e.message);
    }

    #[test]
    fn val_reads_the_leading_number_as_atof() {
        for (text, want) in [
            ("3.5e2", 350.0),
            ("  12abc", 12.0),
            ("-.5x", -0.5),
            ("+7.", 7.0),
            ("1e", 1.0),
            ("1e+", 1.0),
            ("2E-1z", 0.2),
            (".", 0.0),
            ("-", 0.0),
            ("abc", 0.0),
            ("", 0.0),
        ] {
            assert_eq!(leading_number(text), want, "{text:?}");
        }
    }

    #[test]
    fn substr_and_chr_bounds() {
        let hello = s("hello");
        let sub = |p: f64, l: f64| call("substr", &[hello.clone(), Value::Num(p), Value::Num(l)]);
        assert!(matches!(sub(1.0, 5.0), Some(Ok(Value::Str(t))) if &*t == "hello"));
        assert!(matches!(sub(6.0, 0.0), Some(Ok(Value::Str(t))) if t.is_empty()));
        for (p, l) in [
            (0.0, 1.0),
            (5.0, 2.0),
            (2.0, -1.0),
            (1e300, 1.0),
            (1.0, 1e300),
        ] {
            assert!(matches!(sub(p, l), Some(Err(_))), "substr({p}, {l})");
        }
        for code in [0.0, -1.0, 55296.0, 1_114_112.0, 1e300] {
            assert!(
                matches!(call("chr", &[Value::Num(code)]), Some(Err((0, _)))),
                "chr({code})"
            );
        }
    }
}
