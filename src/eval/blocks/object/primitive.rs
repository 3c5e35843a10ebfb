//! The primitive shapes (`sphere`, `plane`, `quad`, `box`, `cylinder`, `cone`, `torus`, `disk`,
//! `triangle`, `mesh`): their positional values and the checks on them.

use crate::diag::short_number;
use glam::{DAffine3, DVec3};

use super::{ObjectBuilder, article};
use crate::diag::{At, Diagnostic, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::range_error;
use crate::eval::builtins::unit;
use crate::eval::value::{Part, ShapeDef, Value};
use crate::scene::{ShapeDecl, TORUS_MAX_ASPECT};
use crate::span::Span;

/// What each primitive's positional values are: (name, kind) with kind `v` vector, `n` number,
/// `s` string.
fn signature(kind: &str) -> &'static [(&'static str, char)] {
    match kind {
        "sphere" => &[("center", 'v'), ("radius", 'n')],
        "plane" => &[("normal", 'v'), ("offset", 'n')],
        "quad" => &[("corner", 'v'), ("first edge", 'v'), ("second edge", 'v')],
        "box" => &[("first corner", 'v'), ("opposite corner", 'v')],
        "cylinder" => &[("base point", 'v'), ("cap point", 'v'), ("radius", 'n')],
        "cone" => &[
            ("base point", 'v'),
            ("base radius", 'n'),
            ("cap point", 'v'),
            ("cap radius", 'n'),
        ],
        "disk" => &[("center", 'v'), ("normal", 'v'), ("radius", 'n')],
        "torus" => &[("major radius", 'n'), ("minor radius", 'n')],
        "triangle" => &[
            ("first vertex", 'v'),
            ("second vertex", 'v'),
            ("third vertex", 'v'),
        ],
        "mesh" => &[("OBJ file name", 's')],
        _ => &[],
    }
}

fn example(kind: &str) -> &'static str {
    match kind {
        "sphere" => "sphere { <0, 1, 0>, 0.5 }",
        "plane" => "plane { <0, 1, 0>, 0 }",
        "quad" => "quad { <-1, 0, -1>, <2, 0, 0>, <0, 0, 2> }",
        "box" => "box { <-1, 0, -1>, <1, 1, 1> }",
        "cylinder" => "cylinder { <0, 0, 0>, <0, 1, 0>, 0.1 }",
        "cone" => "cone { <0, 0, 0>, 0.5, <0, 1, 0>, 0 }",
        "disk" => "disk { <0, 0, 0>, <0, 1, 0>, 1 }",
        "torus" => "torus { 1, 0.25 }",
        "triangle" => "triangle { <0, 0, 0>, <1, 0, 0>, <0, 1, 0> }",
        "mesh" => "mesh { \"bunny.obj\" }",
        _ => "",
    }
}

/// Where `text` (one value's source) has a `-` or `+` after a space and before what follows
/// it, outside brackets: `<0, 1, 0> -0.5` is one value, a subtraction, as in POV-Ray.
fn sign_after_space(text: &str) -> Option<usize> {
    let b = text.as_bytes();
    let mut depth = 0i32;
    for (i, &c) in b.iter().enumerate() {
        match c {
            b'<' | b'(' | b'[' => depth += 1,
            b'>' | b')' | b']' => depth -= 1,
            b'-' | b'+' if depth == 0 && i > 0 => {
                let before = b[i - 1].is_ascii_whitespace();
                let after = b.get(i + 1).is_some_and(|n| !n.is_ascii_whitespace());
                if before && after {
                    return Some(i);
                }
            }
            _ => {}
        }
    }
    None
}

impl ObjectBuilder {
    /// The help for too few values when one of them is two values joined by a sign: "put a
    /// comma before the negative value".
    fn missing_comma(&self, ev: &Evaluator) -> Option<String> {
        if self.values.len() >= signature(self.kind).len() {
            return None;
        }
        self.values.iter().find_map(|(_, span)| {
            let text = ev.sources.snippet(*span);
            let at = sign_after_space(text)?;
            let (left, right) = (text[..at].trim_end(), &text[at..]);
            Some(format!(
                "`{text}` is one value: a `{}` after a value {} it, as in POV-Ray; for two \
                 values write a comma between them: `{left}, {right}`",
                &right[..1],
                if right.starts_with('-') {
                    "subtracts from"
                } else {
                    "adds to"
                },
            ))
        })
    }

    pub(super) fn primitive(&mut self, ev: &mut Evaluator) -> SourceResult<Part> {
        let sig = signature(self.kind);
        let names: Vec<&str> = sig.iter().map(|(n, _)| *n).collect();
        if self.values.len() != sig.len() {
            let span = if self.values.len() > sig.len() {
                self.values[sig.len()].1
            } else {
                self.span
            };
            return Err(vec![
                Error::new(format!(
                    "{} needs {} value{} ({}), found {}",
                    self.kind,
                    sig.len(),
                    if sig.len() == 1 { "" } else { "s" },
                    names.join(", "),
                    self.values.len()
                ))
                .label(if self.values.len() > sig.len() {
                    "one value too many"
                } else {
                    "missing values"
                })
                .help(
                    self.missing_comma(ev)
                        .unwrap_or_else(|| format!("write e.g. `{}`", example(self.kind))),
                )
                .at(span),
            ]);
        }
        let mut vs = Vec::new();
        let mut ns = Vec::new();
        let mut strs = Vec::new();
        for ((name, k), (v, s)) in sig.iter().zip(&self.values) {
            // "the radius of a sphere: expected a number, ..."
            let named = |e: Error| Error {
                message: format!(
                    "the {name} of {} {}: {}",
                    article(self.kind),
                    self.kind,
                    e.message
                ),
                ..e
            };
            match k {
                'v' => vs.push((v.vec3().map_err(named).at(*s)?, *s)),
                'n' => ns.push((v.num().map_err(named).at(*s)?, *s)),
                _ => match v {
                    Value::Str(p) => strs.push((p.to_string(), *s)),
                    v => {
                        return Err(vec![
                            Error::new(format!(
                                "expected a file name string, found {}",
                                v.type_name()
                            ))
                            .label("not a string")
                            .help("write the file name in double quotes, e.g. `\"model.obj\"`")
                            .at(*s),
                        ]);
                    }
                },
            }
        }
        let radius = |(r, s): (f64, Span)| -> SourceResult<f64> {
            if r <= 0.0 {
                return Err(range_error(
                    s,
                    format!("radius must be positive, found {}", short_number(r)),
                    "use a radius greater than 0",
                ));
            }
            Ok(r)
        };
        let nonzero = |(v, s): (DVec3, Span), what: &str| -> SourceResult<DVec3> {
            if v.abs().max_element() == 0.0 {
                return Err(vec![
                    Error::new(format!("the {what} is a zero vector"))
                        .label("zero length")
                        .help(format!("the {what} needs a direction, e.g. `<0, 1, 0>`"))
                        .at(s),
                ]);
            }
            Ok(v)
        };
        let shape = match self.kind {
            "sphere" => ShapeDecl::Sphere {
                center: vs[0].0,
                radius: radius(ns[0])?,
            },
            "plane" => ShapeDecl::Plane {
                normal: unit(nonzero(vs[0], "normal")?).unwrap_or(DVec3::Y),
                offset: ns[0].0,
            },
            "quad" => {
                let (u, v) = (
                    nonzero(vs[1], "first edge")?,
                    nonzero(vs[2], "second edge")?,
                );
                if u.cross(v).length_squared() < 1e-24 {
                    return Err(vec![
                        Error::new("the quad's edges are parallel (it has no area)")
                            .label("parallel to the first edge")
                            .help("give two edges in different directions, e.g. `<1, 0, 0>, <0, 1, 0>`")
                            .at(vs[2].1),
                    ]);
                }
                ShapeDecl::Quad {
                    origin: vs[0].0,
                    edge_u: u,
                    edge_v: v,
                }
            }
            "box" => ShapeDecl::Box {
                min: vs[0].0.min(vs[1].0),
                max: vs[0].0.max(vs[1].0),
            },
            "cylinder" => {
                if vs[0].0 == vs[1].0 {
                    return Err(vec![
                        Error::new("the cylinder's base and cap are the same point")
                            .label("zero height")
                            .help("move the cap away from the base, e.g. `<0, 1, 0>` above `<0, 0, 0>`")
                            .at(vs[1].1),
                    ]);
                }
                ShapeDecl::Cylinder {
                    base: vs[0].0,
                    cap: vs[1].0,
                    radius: radius(ns[0])?,
                    open: self.open,
                }
            }
            "cone" => {
                if vs[0].0 == vs[1].0 {
                    return Err(vec![
                        Error::new("the cone's base and cap are the same point")
                            .label("zero height")
                            .help("move the cap away from the base, e.g. `<0, 1, 0>` above `<0, 0, 0>`")
                            .at(vs[1].1),
                    ]);
                }
                for &(r, s) in &ns[..2] {
                    if !r.is_finite() || r < 0.0 {
                        return Err(range_error(
                            s,
                            format!(
                                "a cone's radius must be finite and at least 0, found {}",
                                short_number(r)
                            ),
                            "use 0 for a pointed end, a positive radius otherwise",
                        ));
                    }
                }
                if ns[0].0 == 0.0 && ns[1].0 == 0.0 {
                    return Err(range_error(
                        ns[1].1,
                        "both radii of this cone are 0: it would be a line".to_string(),
                        "give the base or the cap a positive radius",
                    ));
                }
                ShapeDecl::Cone {
                    base: vs[0].0,
                    base_radius: ns[0].0,
                    cap: vs[1].0,
                    cap_radius: ns[1].0,
                    open: self.open,
                }
            }
            "torus" => {
                let (major, minor) = (radius(ns[0])?, radius(ns[1])?);
                if minor >= major {
                    return Err(range_error(
                        ns[1].1,
                        format!(
                            "a torus's minor radius must be below its major radius ({}), found {}",
                            short_number(major),
                            short_number(minor)
                        ),
                        "the first value is the distance from the axis to the tube's centre, \
                         the second the tube's radius: e.g. `torus { 1, 0.25 }`",
                    ));
                }
                if major > TORUS_MAX_ASPECT * minor {
                    return Err(range_error(
                        ns[1].1,
                        format!(
                            "this torus's tube is too thin for its ring: major / minor = {}, at \
                             most {} can be intersected reliably",
                            short_number(major / minor),
                            short_number(TORUS_MAX_ASPECT)
                        ),
                        "make the minor radius at least the major radius / 1000",
                    ));
                }
                ShapeDecl::Torus { major, minor }
            }
            "disk" => ShapeDecl::Disk {
                center: vs[0].0,
                normal: unit(nonzero(vs[1], "normal")?).unwrap_or(DVec3::Y),
                radius: radius(ns[0])?,
            },
            "triangle" => {
                let [a, b, c] = [vs[0].0, vs[1].0, vs[2].0];
                if (b - a).cross(c - a).length_squared() < 1e-24 {
                    ev.warn(
                        Diagnostic::warning(self.span, "this triangle has no area")
                            .with_label("degenerate triangle"),
                    );
                }
                ShapeDecl::Triangle {
                    vertices: [a, b, c],
                }
            }
            "mesh" => {
                let (path, span) = &strs[0];
                let part = Part {
                    shape: ShapeDef::Mesh {
                        path: ev.resolve_path(path, *span),
                        span: *span,
                    },
                    transform: DAffine3::IDENTITY,
                    material: None,
                    emission: None,
                    span: self.span,
                };
                return Ok(part);
            }
            k => unreachable!("primitive {k}"),
        };
        Ok(self.part(shape))
    }
}
