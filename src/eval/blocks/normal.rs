//! `normal { ... }` (a bump or normal map: POV-Ray's normal patterns, a texture as a height,
//! an image's normals) and `bump_map { ... }` (an image as a height, POV-Ray's spelling).

use std::rc::Rc;

use glam::DAffine3;

use super::{Sink, unexpected};
use crate::diag::{Diagnostic, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, file_name, num, range_error};
use crate::eval::props::{PropSpec, p, transform_prop, with_transforms};
use crate::eval::value::{NormalDef, NormalSource, PatternDef, TextureDef, Value};
use crate::scene::{Mapping, NormalKind, Wrap};
use crate::span::Span;
use crate::syntax::ast::Name;

/// The largest bump amount accepted: the slope a height gives is multiplied by it, and past a
/// few hundred every normal lies on the horizon.
const MAX_AMOUNT: f64 = 1000.0;

/// The built-in patterns, with the kind each stands for.
const PATTERNS: [(&str, NormalKind); 5] = [
    ("bumps", NormalKind::Bumps),
    ("dents", NormalKind::Dents),
    ("wrinkles", NormalKind::Wrinkles),
    ("ripples", NormalKind::Ripples),
    ("waves", NormalKind::Waves),
];

static NORMAL_PROPS: [PropSpec; 12] = with_transforms([
    p("bumps", 0, 1, "an amount (optional)", "0.5"),
    p("dents", 0, 1, "an amount (optional)", "0.5"),
    p("wrinkles", 0, 1, "an amount (optional)", "0.5"),
    p("ripples", 0, 1, "an amount (optional)", "0.5"),
    p("waves", 0, 1, "an amount (optional)", "0.5"),
    p("amount", 1, 1, "a number", "0.5"),
    p("bump_size", 1, 1, "a number", "2"),
    p("normal_map", 1, 1, "a file name", "\"bricks_normal.png\""),
]);

static BUMP_MAP_PROPS: [PropSpec; 9] = with_transforms([
    p("png", 1, 1, "a file name", "\"height.png\""),
    p("jpeg", 1, 1, "a file name", "\"height.jpg\""),
    p("image", 1, 1, "a file name", "\"height.png\""),
    p("bump_size", 1, 1, "a number", "2"),
    p("interpolate", 0, 1, "a number (optional, ignored)", "2"),
]);

pub(super) struct NormalBuilder {
    /// `bump_map { ... }` rather than `normal { ... }`.
    bump_map: bool,
    /// The source as written: a pattern, a texture, or an image file (for a height when
    /// `bump_map`, else for a normal map).
    source: Option<(Written, Span)>,
    amount: Option<(f64, Span)>,
    base: Option<Rc<NormalDef>>,
    transform: DAffine3,
}

enum Written {
    Pattern(NormalKind),
    Texture(Rc<TextureDef>),
    Image(String),
}

impl NormalBuilder {
    pub(super) fn new(bump_map: bool) -> Self {
        Self {
            bump_map,
            source: None,
            amount: None,
            base: None,
            transform: DAffine3::IDENTITY,
        }
    }

    fn set(&mut self, w: Written, span: Span) -> SourceResult<()> {
        if let Some((_, old)) = &self.source {
            return Err(vec![
                Error::new("a normal has one pattern")
                    .label("second pattern")
                    .help("keep one: a bump pattern, a texture, a `bump_map` or a `normal_map`")
                    .at(span)
                    .with_extra(*old, "first pattern here"),
            ]);
        }
        self.source = Some((w, span));
        Ok(())
    }

    fn amount(&mut self, a: &Arg) -> SourceResult<()> {
        let x = num(a)?;
        if !x.is_finite() || x.abs() > MAX_AMOUNT {
            return Err(range_error(
                a.span,
                format!(
                    "a bump amount must be from -{MAX_AMOUNT} to {MAX_AMOUNT}, found {}",
                    crate::diag::short_number(x)
                ),
                "0.5 gives clear bumps; a negative amount turns bumps into dents",
            ));
        }
        self.amount = Some((x, a.span));
        Ok(())
    }

    pub(super) fn finish(self, ev: &mut Evaluator, span: Span) -> SourceResult<Value> {
        let image = |path: &str, at: Span, mapping: Mapping, transform: DAffine3| {
            Rc::new(TextureDef {
                pattern: PatternDef::Image {
                    path: ev.resolve_path(path, at),
                    // Heights and normals are data, not colours.
                    linear: true,
                    wrap: Wrap::Repeat,
                    bilinear: true,
                    span: at,
                },
                mapping,
                transform,
                span,
            })
        };
        // A bump map's and a normal map's transforms place the image; the others' place the
        // pattern (or the texture) in the object.
        let inverse = self.transform.inverse();
        let (source, transform) = match self.source {
            Some((Written::Pattern(k), _)) => (NormalSource::Pattern(k), inverse),
            Some((Written::Texture(t), _)) => (NormalSource::Height(t), inverse),
            Some((Written::Image(path), at)) if self.bump_map => (
                NormalSource::Height(image(&path, at, Mapping::Planar, inverse)),
                DAffine3::IDENTITY,
            ),
            Some((Written::Image(path), at)) => (
                NormalSource::Map(image(&path, at, Mapping::Uv, inverse)),
                DAffine3::IDENTITY,
            ),
            None => match &self.base {
                Some(b) => (b.source.clone(), b.transform * inverse),
                None => {
                    let (what, example) = if self.bump_map {
                        (
                            "a bump map needs an image",
                            "`bump_map { png \"height.png\" bump_size 2 }`",
                        )
                    } else {
                        (
                            "a normal needs a pattern",
                            "`normal { bumps 0.5 scale 0.1 }`",
                        )
                    };
                    return Err(vec![
                        Error::new(what)
                            .label("no pattern")
                            .help(format!(
                                "e.g. {example}; the patterns are bumps, dents, wrinkles, \
                                 ripples, waves, a texture, `bump_map {{ ... }}` and \
                                 `normal_map \"file.png\"`"
                            ))
                            .at(span),
                    ]);
                }
            },
        };
        let default = match source {
            NormalSource::Pattern(_) => 0.5,
            NormalSource::Height(_) | NormalSource::Map(_) => 1.0,
        };
        let amount = self
            .amount
            .map(|a| a.0)
            .or(self.base.as_ref().map(|b| b.amount))
            .unwrap_or(default);
        if let (NormalSource::Map(_), Some((a, at))) = (&source, self.amount)
            && a < 0.0
        {
            return Err(range_error(
                at,
                format!(
                    "a normal map's amount must not be negative, found {}",
                    crate::diag::short_number(a)
                ),
                "1 leans the normals as the map says, 0 not at all",
            ));
        }
        if amount == 0.0 {
            let at = self.amount.map_or(span, |a| a.1);
            ev.warn(
                Diagnostic::warning(at, "a bump amount of 0 leaves the surface smooth")
                    .with_label("no bumps")
                    .with_help("give an amount, e.g. `bumps 0.5`, or drop the normal"),
            );
        }
        Ok(Value::Normal(Rc::new(NormalDef {
            source,
            amount,
            transform,
            span,
        })))
    }
}

impl Sink for NormalBuilder {
    fn kind(&self) -> String {
        if self.bump_map {
            "a bump map".into()
        } else {
            "a normal".into()
        }
    }
    fn props(&self) -> &'static [PropSpec] {
        if self.bump_map {
            &BUMP_MAP_PROPS
        } else {
            &NORMAL_PROPS
        }
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        if transform_prop(&kw.text, &args, &mut self.transform)? {
            return Ok(());
        }
        if let Some(&(_, k)) = PATTERNS.iter().find(|(n, _)| *n == kw.text) {
            self.set(Written::Pattern(k), kw.span)?;
            if let Some(a) = args.first() {
                self.amount(a)?;
            }
            return Ok(());
        }
        match kw.text.as_str() {
            "amount" | "bump_size" => self.amount(&args[0])?,
            "normal_map" | "png" | "jpeg" | "image" => {
                let f = file_name(&args[0])?.to_string();
                self.set(Written::Image(f), kw.span.join(args[0].span))?;
            }
            "interpolate" => {}
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::Texture(t) if !self.bump_map => self.set(Written::Texture(t), span),
            Value::Normal(n) if self.base.is_none() && !self.bump_map => {
                self.base = Some(n);
                Ok(())
            }
            v => Err(unexpected(
                self,
                &v,
                span,
                if self.bump_map {
                    "a bump map takes an image file: `bump_map { png \"height.png\" bump_size 2 }`"
                } else {
                    "a normal takes a pattern (`bumps 0.5`), a texture as a height, a declared \
                     normal or a `bump_map { ... }`, e.g. `normal { bumps 0.5 scale 0.1 }`"
                },
            )),
        }
    }
}
