//! `pattern { ... }` inside a function body: POV-Ray's `function { pattern { checker } }`, a
//! pattern's value in [0, 1] at the function's first three parameters (x, y, z).

use glam::{DAffine3, DVec3};

use super::Evaluator;
use super::args::{Arg, count, num, vec3};
use super::function::{Compiler, Piece};
use super::props::transform_prop;
use crate::diag::{Error, SourceResult};
use crate::scene::{MAX_OCTAVES, Op, PatternFn, PatternKind};
use crate::span::Span;
use crate::syntax::ast::{Item, Name};

/// The patterns a function can use.
const PATTERNS: &[&str] = &[
    "checker", "stripes", "gradient", "brick", "noise", "marble", "wood",
];
/// The other words of a pattern block, with the arguments each takes.
const MODIFIERS: &[(&str, usize)] = &[
    ("size", 1),
    ("mortar", 1),
    ("octaves", 1),
    ("turbulence", 1),
    ("scale", 1),
    ("translate", 1),
    ("rotate", 1),
];

fn unsupported(what: &str, span: Span) -> Vec<crate::diag::Diagnostic> {
    vec![
        Error::new(format!("`{what}` is not a pattern a function can use"))
            .label("not supported in `pattern { ... }`")
            .help(format!(
                "the patterns are {}, with `size` and `mortar` (brick), `octaves` and \
                 `turbulence` (noise, marble, wood) and `scale`, `translate`, `rotate`",
                PATTERNS.join(", ")
            ))
            .at(span),
    ]
}

impl Evaluator {
    pub(super) fn compile_pattern(
        &mut self,
        c: &mut Compiler,
        items: &[Item],
        span: Span,
    ) -> SourceResult<Piece> {
        if c.params.len() < 3 {
            return Err(vec![
                Error::new(format!(
                    "a pattern needs a function of at least three parameters, this one has {}",
                    c.params.len()
                ))
                .label("the pattern is read at the first three parameters")
                .help("write `function { pattern { ... } }` (parameters x, y, z)")
                .at(span),
            ]);
        }
        // Each keyword with the values that follow it.
        let mut props: Vec<(Name, Vec<Arg>)> = Vec::new();
        for item in items {
            match item {
                Item::Keyword(k) => props.push((k.clone(), Vec::new())),
                Item::Comma(_) => {}
                Item::Expr(e) => {
                    // A word before any keyword is a pattern the language lacks (`bozo`).
                    if let (None, crate::syntax::ast::ExprKind::Ident(n)) = (props.last(), &e.kind)
                    {
                        return Err(unsupported(n, e.span));
                    }
                    let value = self.eval(e)?;
                    match props.last_mut() {
                        Some(last) => last.1.push(Arg {
                            value,
                            span: e.span,
                        }),
                        None => {
                            let what = match &e.kind {
                                crate::syntax::ast::ExprKind::Ident(n) => n.clone(),
                                _ => "this value".to_string(),
                            };
                            return Err(unsupported(&what, e.span));
                        }
                    }
                }
                Item::Directive(d) => {
                    return Err(vec![
                        Error::new("a directive inside a function's pattern")
                            .label("not read here")
                            .help("declare values before the function and use them by name")
                            .at(d.span),
                    ]);
                }
            }
        }
        let mut kind: Option<(&str, Span)> = None;
        let mut direction = DVec3::Y;
        let (mut size, mut mortar) = (DVec3::new(0.2, 0.075, 0.1), 0.01);
        let (mut octaves, mut turbulence) = (6u32, 1.0);
        let mut transform = DAffine3::IDENTITY;
        for (k, args) in &props {
            let word = k.text.as_str();
            let want = if let Some(p) = PATTERNS.iter().find(|p| **p == word) {
                if let Some((old, at)) = kind {
                    return Err(vec![
                        Error::new(format!("a pattern is one of them: {old} or {p}, not both"))
                            .label("second pattern")
                            .help("keep one of the two")
                            .at(k.span)
                            .with_extra(at, "first pattern here"),
                    ]);
                }
                kind = Some((p, k.span));
                usize::from(*p == "gradient")
            } else if let Some((_, n)) = MODIFIERS.iter().find(|(m, _)| *m == word) {
                *n
            } else {
                return Err(unsupported(word, k.span));
            };
            let optional = word == "gradient";
            if args.len() > want || (!optional && args.len() < want) {
                return Err(vec![
                    Error::new(format!(
                        "`{word}` takes {want} value{} here, found {}",
                        if want == 1 { "" } else { "s" },
                        args.len()
                    ))
                    .label("wrong number of values")
                    .help(
                        "in a function's pattern, `checker`, `stripes` and `brick` take no \
                         colours: the function returns 0 or 1",
                    )
                    .at(k.span),
                ]);
            }
            match word {
                "gradient" => {
                    if let Some(a) = args.first() {
                        let d = vec3(a)?;
                        direction = d.try_normalize().ok_or_else(|| {
                            vec![
                                Error::new("the gradient direction is a zero vector")
                                    .label("zero vector")
                                    .help("give a direction, e.g. `gradient <0, 1, 0>`")
                                    .at(a.span),
                            ]
                        })?;
                    }
                }
                "size" => size = vec3(&args[0])?,
                "mortar" => mortar = num(&args[0])?,
                "octaves" => {
                    octaves = count(&args[0], "octaves", f64::from(MAX_OCTAVES))? as u32;
                }
                "turbulence" => turbulence = num(&args[0])?,
                "scale" | "translate" | "rotate" => {
                    transform_prop(word, args, &mut transform)?;
                }
                _ => {}
            }
        }
        let Some((name, _)) = kind else {
            return Err(vec![
                Error::new("a pattern block needs a pattern")
                    .label("no pattern")
                    .help(format!(
                        "write one of {}, e.g. `function {{ pattern {{ checker }} }}`",
                        PATTERNS.join(", ")
                    ))
                    .at(span),
            ]);
        };
        let kind = match name {
            "checker" => PatternKind::Checker,
            "stripes" => PatternKind::Stripes,
            "gradient" => PatternKind::Gradient(direction),
            "brick" => PatternKind::Brick { size, mortar },
            "noise" => PatternKind::Noise { octaves },
            "marble" => PatternKind::Marble {
                turbulence,
                octaves,
            },
            _ => PatternKind::Wood {
                turbulence,
                octaves,
            },
        };
        Ok(Piece::Code(vec![
            Op::Load(0),
            Op::Load(1),
            Op::Load(2),
            Op::Pattern(Box::new(PatternFn {
                kind,
                inverse: transform.inverse(),
            })),
        ]))
    }
}
