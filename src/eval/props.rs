//! Property specs: how each property keyword takes its arguments, and the transform
//! properties (`translate`, `rotate`, `scale`, `matrix`) that placed blocks share.

use glam::{DAffine3, DVec3};

use super::args::{Arg, num, vec3};
use super::builtins::rotation;
use super::value::Value;
use crate::diag::{At, Error, SourceResult};

/// How a property keyword takes its arguments.
#[derive(Clone, Copy)]
pub(crate) struct PropSpec {
    pub name: &'static str,
    pub min: u8,
    pub max: u8,
    /// The argument is a bare word (`wrap repeat`), not an expression.
    pub word: bool,
    /// What the arguments are, for "needs ..." messages.
    pub hint: &'static str,
    pub example: &'static str,
}

pub(super) const fn p(
    name: &'static str,
    min: u8,
    max: u8,
    hint: &'static str,
    example: &'static str,
) -> PropSpec {
    PropSpec {
        name,
        min,
        max,
        word: false,
        hint,
        example,
    }
}

pub(super) const fn w(name: &'static str, hint: &'static str, example: &'static str) -> PropSpec {
    PropSpec {
        name,
        min: 1,
        max: 1,
        word: true,
        hint,
        example,
    }
}

/// Applies a transform property to `t` (each applied after the previous one).
pub(super) fn transform_prop(kw: &str, args: &[Arg], t: &mut DAffine3) -> SourceResult<bool> {
    let m = match kw {
        "translate" => DAffine3::from_translation(vec3(&args[0])?),
        "rotate" => rotation(vec3(&args[0])?),
        "scale" => {
            let s = match &args[0].value {
                Value::Num(n) => DVec3::splat(*n),
                _ => vec3(&args[0])?,
            };
            if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 {
                return Err(vec![
                    Error::new("scale by zero flattens the object")
                        .label("a zero component")
                        .help("use a small non-zero scale")
                        .at(args[0].span),
                ]);
            }
            DAffine3::from_scale(s)
        }
        "matrix" => {
            let mut xs = Vec::new();
            for a in args {
                match &a.value {
                    Value::Array(v) => {
                        for x in v.iter() {
                            xs.push(x.num().at(a.span)?);
                        }
                    }
                    Value::Vec3(v) => xs.extend(v.to_array()),
                    _ => xs.push(num(a)?),
                }
            }
            let span = args[0].span.join(args[args.len() - 1].span);
            if xs.len() != 12 {
                return Err(vec![
                    Error::new(format!("`matrix` needs 12 numbers, found {}", xs.len()))
                        .label("wrong count")
                        .help("write `matrix <a,b,c, d,e,f, g,h,i, tx,ty,tz>` as in POV-Ray")
                        .at(span),
                ]);
            }
            let m = DAffine3::from_cols(
                DVec3::new(xs[0], xs[1], xs[2]),
                DVec3::new(xs[3], xs[4], xs[5]),
                DVec3::new(xs[6], xs[7], xs[8]),
                DVec3::new(xs[9], xs[10], xs[11]),
            );
            // Flat means the determinant is small next to the columns' own lengths (the volume
            // of the box they span against its largest possible value): a matrix that only
            // scales the object down uniformly, by 1e-5 say, is not flat.
            let c = m.matrix3;
            let volume = c.x_axis.length() * c.y_axis.length() * c.z_axis.length();
            if !(volume.is_finite() && m.matrix3.determinant().abs() > 1e-12 * volume) {
                return Err(vec![
                    Error::new("this matrix is singular (it flattens the object)")
                        .label("flat")
                        .help(
                            "its first three columns (a,b,c / d,e,f / g,h,i) must not lie in \
                             one plane; `scale` by a small non-zero number shrinks an object",
                        )
                        .at(span),
                ]);
            }
            m
        }
        _ => return Ok(false),
    };
    *t = m * *t;
    Ok(true)
}

pub(super) const TRANSFORMS: [PropSpec; 4] = [
    p("translate", 1, 1, "a vector", "<1, 0, 0>"),
    p(
        "rotate",
        1,
        1,
        "a vector of angles in degrees",
        "<0, 30, 0>",
    ),
    p("scale", 1, 1, "a number or a vector", "2"),
    p(
        "matrix",
        1,
        12,
        "12 numbers",
        "<1,0,0, 0,1,0, 0,0,1, 0,0,0>",
    ),
];

/// `TRANSFORMS` followed by `extra` (`M` must be `N + 4`: checked when the static is built).
pub(super) const fn with_transforms<const N: usize, const M: usize>(
    extra: [PropSpec; N],
) -> [PropSpec; M] {
    assert!(M == N + TRANSFORMS.len());
    let mut out = [TRANSFORMS[0]; M];
    let mut i = 0;
    while i < M {
        out[i] = if i < TRANSFORMS.len() {
            TRANSFORMS[i]
        } else {
            extra[i - TRANSFORMS.len()]
        };
        i += 1;
    }
    out
}
