//! `texture { ... }` (a pattern, its mapping and transform) and `color_map { ... }`.

use std::rc::Rc;

use glam::{DAffine3, DVec3};

use super::{Sink, unexpected};
use crate::diag::{At, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{
    Arg, count, file_name, num, positive, range_error, surface_color, vec3, word,
};
use crate::eval::props::{PropSpec, p, transform_prop, w, with_transforms};
use crate::eval::value::{PatternDef, TextureDef, Value};
use crate::scene::{Color, ColorMap, MAX_OCTAVES, Mapping, Pattern, Wrap};
use crate::span::Span;
use crate::syntax::ast::Name;

#[derive(Default)]
pub(super) struct TextureBuilder {
    pattern: Option<(&'static str, Span)>,
    a: Color,
    b: Color,
    direction: Option<DVec3>,
    map: Option<Rc<ColorMap>>,
    octaves: Option<u32>,
    turbulence: Option<f64>,
    mortar: Option<f64>,
    size: Option<DVec3>,
    image: Option<(String, Span)>,
    wrap: Wrap,
    bilinear: bool,
    mapping: Option<Mapping>,
    linear: bool,
    transform: DAffine3,
    /// The properties only some patterns use, as written (with the keyword's span): each must
    /// belong to the texture's pattern.
    written: Vec<(&'static str, Span)>,
}

/// The properties only some patterns use.
const PATTERN_PROPS: [&str; 8] = [
    "color_map",
    "octaves",
    "turbulence",
    "mortar",
    "size",
    "wrap",
    "interpolate",
    "linear",
];

/// The properties of [`PATTERN_PROPS`] that pattern `kind` uses.
fn uses(kind: &str) -> &'static [&'static str] {
    match kind {
        "gradient" => &["color_map"],
        "noise" => &["color_map", "octaves"],
        "marble" | "wood" => &["color_map", "octaves", "turbulence"],
        "brick" => &["mortar", "size"],
        "image" => &["wrap", "interpolate", "linear"],
        _ => &[],
    }
}

/// The patterns that use property `what`, for the help of a property written for another one.
fn users(what: &str) -> String {
    let names: Vec<String> = ["gradient", "noise", "marble", "wood", "brick", "image"]
        .iter()
        .filter(|k| uses(k).contains(&what))
        .map(|k| format!("`{k}`"))
        .collect();
    names.join(", ")
}

static TEX_PROPS: [PropSpec; 19] = with_transforms([
    p(
        "checker",
        2,
        2,
        "two colors",
        "rgb <1, 1, 1>, rgb <0, 0, 0>",
    ),
    p(
        "stripes",
        2,
        2,
        "two colors",
        "rgb <1, 1, 1>, rgb <0, 0, 0>",
    ),
    p("gradient", 0, 1, "a direction (optional)", "<0, 1, 0>"),
    p("noise", 0, 0, "nothing", ""),
    p("marble", 0, 0, "nothing", ""),
    p("wood", 0, 0, "nothing", ""),
    p(
        "brick",
        2,
        2,
        "two colors (brick, mortar)",
        "rgb <0.6, 0.2, 0.1>, rgb <0.8, 0.8, 0.8>",
    ),
    p("image", 1, 1, "a file name", "\"wood.png\""),
    w("wrap", "`repeat`, `clamp` or `mirror`", "repeat"),
    p("interpolate", 0, 0, "nothing", ""),
    w(
        "map",
        "`uv`, `planar`, `spherical`, `cylindrical` or `solid`",
        "uv",
    ),
    p("linear", 0, 0, "nothing", ""),
    p("octaves", 1, 1, "a number", "6"),
    p("turbulence", 1, 1, "a number", "1"),
    p("mortar", 1, 1, "a number", "0.01"),
]);
pub(super) static TEX_PROPS_SIZE: [PropSpec; 1] =
    [p("size", 1, 1, "a vector", "<0.2, 0.075, 0.1>")];

impl TextureBuilder {
    fn set(&mut self, k: &'static str, span: Span) -> SourceResult<()> {
        if let Some((old, old_span)) = self.pattern {
            return Err(vec![
                Error::new(format!("a texture has one pattern: {old} or {k}, not both"))
                    .label("second pattern")
                    .help("keep one of the two patterns (a texture shows one)")
                    .at(span)
                    .with_extra(old_span, "first pattern here"),
            ]);
        }
        self.pattern = Some((k, span));
        Ok(())
    }

    pub(super) fn finish(self, ev: &mut Evaluator, span: Span) -> SourceResult<Value> {
        let Some((kind, _)) = self.pattern else {
            return Err(vec![
                Error::new("a texture needs a pattern")
                    .label("no pattern")
                    .help("e.g. `texture { checker rgb <1, 1, 1>, rgb <0, 0, 0> scale 0.1 }`")
                    .at(span),
            ]);
        };
        // A property the pattern does not use would be dropped without a word (`checker ...
        // color_map { ... }` shows two colours, not the map).
        if let Some(&(what, at)) = self.written.iter().find(|w| !uses(kind).contains(&w.0)) {
            return Err(vec![
                Error::new(format!("`{what}` does not apply to a {kind} texture"))
                    .label("not used by this pattern")
                    .help(format!(
                        "drop `{what}`, or use a pattern it belongs to ({})",
                        users(what)
                    ))
                    .at(at),
            ]);
        }
        let map = self
            .map
            .map(|m| (*m).clone())
            .unwrap_or_else(|| ColorMap(vec![(0.0, Color::ZERO), (1.0, Color::ONE)]));
        let octaves = self.octaves.unwrap_or(6);
        let turbulence = self.turbulence.unwrap_or(1.0);
        let pattern = match kind {
            "checker" => PatternDef::Ready(Pattern::Checker {
                a: self.a,
                b: self.b,
            }),
            "stripes" => PatternDef::Ready(Pattern::Stripes {
                a: self.a,
                b: self.b,
            }),
            "gradient" => PatternDef::Ready(Pattern::Gradient {
                direction: self.direction.unwrap_or(DVec3::Y),
                map,
            }),
            "noise" => PatternDef::Ready(Pattern::Noise { map, octaves }),
            "marble" => PatternDef::Ready(Pattern::Marble {
                map,
                turbulence,
                octaves,
            }),
            "wood" => PatternDef::Ready(Pattern::Wood {
                map,
                turbulence,
                octaves,
            }),
            "brick" => PatternDef::Ready(Pattern::Brick {
                brick: self.a,
                mortar: self.b,
                size: self.size.unwrap_or(DVec3::new(0.2, 0.075, 0.1)),
                mortar_width: self.mortar.unwrap_or(0.01),
            }),
            _ => {
                let (path, pspan) = self.image.expect("image path");
                PatternDef::Image {
                    path: ev.resolve_path(&path, pspan),
                    linear: self.linear,
                    wrap: self.wrap,
                    bilinear: self.bilinear,
                    span: pspan,
                }
            }
        };
        let mapping = self.mapping.unwrap_or(if kind == "image" {
            Mapping::Uv
        } else {
            Mapping::Solid
        });
        Ok(Value::Texture(Rc::new(TextureDef {
            pattern,
            mapping,
            transform: self.transform.inverse(),
            span,
        })))
    }
}

impl Sink for TextureBuilder {
    fn kind(&self) -> String {
        "a texture".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &TEX_PROPS
    }
    fn prop_spec(&self, name: &str) -> Option<&'static PropSpec> {
        TEX_PROPS
            .iter()
            .chain(TEX_PROPS_SIZE.iter())
            .find(|p| p.name == name)
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        if transform_prop(&kw.text, &args, &mut self.transform)? {
            return Ok(());
        }
        if let Some(&w) = PATTERN_PROPS.iter().find(|w| **w == kw.text) {
            self.written.push((w, kw.span));
        }
        match kw.text.as_str() {
            k @ ("checker" | "stripes" | "brick") => {
                self.set(
                    if k == "checker" {
                        "checker"
                    } else if k == "stripes" {
                        "stripes"
                    } else {
                        "brick"
                    },
                    kw.span,
                )?;
                self.a = surface_color(&args[0])?;
                self.b = surface_color(&args[1])?;
            }
            "gradient" => {
                self.set("gradient", kw.span)?;
                if let Some(a) = args.first() {
                    match &a.value {
                        Value::ColorMap(m) => self.map = Some(m.clone()),
                        _ => {
                            let d = vec3(a)?;
                            if d.length_squared() == 0.0 {
                                return Err(vec![
                                    Error::new("the gradient direction is a zero vector")
                                        .label("zero vector")
                                        .help("give the direction the colours change along, e.g. `gradient <0, 1, 0>`")
                                        .at(a.span),
                                ]);
                            }
                            self.direction = Some(d);
                        }
                    }
                }
            }
            "noise" => self.set("noise", kw.span)?,
            "marble" => self.set("marble", kw.span)?,
            "wood" => self.set("wood", kw.span)?,
            "image" => {
                self.set("image", kw.span)?;
                self.image = Some((file_name(&args[0])?.to_string(), args[0].span));
            }
            "wrap" => {
                self.wrap = match word(&args[0], &["repeat", "clamp", "mirror"])?.as_str() {
                    "repeat" => Wrap::Repeat,
                    "clamp" => Wrap::Clamp,
                    _ => Wrap::Mirror,
                }
            }
            "interpolate" => self.bilinear = true,
            "linear" => self.linear = true,
            "map" => {
                self.mapping = Some(
                    match word(
                        &args[0],
                        &["uv", "planar", "spherical", "cylindrical", "solid"],
                    )?
                    .as_str()
                    {
                        "uv" => Mapping::Uv,
                        "planar" => Mapping::Planar,
                        "spherical" => Mapping::Spherical,
                        "cylindrical" => Mapping::Cylindrical,
                        _ => Mapping::Solid,
                    },
                )
            }
            "octaves" => {
                self.octaves = Some(count(&args[0], "octaves", f64::from(MAX_OCTAVES))? as u32)
            }
            "turbulence" => {
                let t = num(&args[0])?;
                if t < 0.0 {
                    return Err(range_error(
                        args[0].span,
                        format!(
                            "turbulence must not be negative, found {}",
                            crate::diag::short_number(t)
                        ),
                        "use a number ≥ 0",
                    ));
                }
                self.turbulence = Some(t);
            }
            "mortar" => self.mortar = Some(positive(&args[0], "mortar width")?),
            "size" => {
                let s = vec3(&args[0])?;
                if s.min_element() <= 0.0 {
                    return Err(range_error(
                        args[0].span,
                        "brick size components must be positive".into(),
                        "e.g. `size <0.2, 0.075, 0.1>`",
                    ));
                }
                self.size = Some(s);
            }
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::ColorMap(m) => {
                self.map = Some(m);
                self.written.push(("color_map", span));
                Ok(())
            }
            v => Err(unexpected(
                self,
                &v,
                span,
                "a texture takes a pattern keyword, `color_map { ... }` and transforms",
            )),
        }
    }
}

#[derive(Default)]
pub(super) struct ColorMapBuilder(Vec<(f64, Color)>);

impl ColorMapBuilder {
    pub(super) fn finish(mut self, span: Span) -> SourceResult<Value> {
        if self.0.len() < 2 {
            return Err(vec![
                Error::new("a color map needs at least two entries")
                    .help("e.g. `color_map { [0, rgb <0, 0, 0>] [1, rgb <1, 1, 1>] }`")
                    .at(span),
            ]);
        }
        self.0.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(Value::ColorMap(Rc::new(ColorMap(self.0))))
    }
}

impl Sink for ColorMapBuilder {
    fn kind(&self) -> String {
        "a color map".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &[]
    }
    fn property(&mut self, _ev: &mut Evaluator, _kw: &Name, _args: Vec<Arg>) -> SourceResult<()> {
        unreachable!()
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        // `[pos, color]`, or POV-Ray's range `[a, b, color A, color B]`: `[a, A] [b, B]`.
        let entries = match &v {
            Value::Array(a) if a.len() == 2 => vec![(&a[0], &a[1])],
            Value::Array(a) if a.len() == 4 => vec![(&a[0], &a[2]), (&a[1], &a[3])],
            _ => {
                return Err(unexpected(
                    self,
                    &v,
                    span,
                    "entries look like `[0.5, rgb <1, 0, 0>]`, or POV-Ray's \
                     `[0.2 0.6 color A color B]` (from A at 0.2 to B at 0.6)",
                ));
            }
        };
        for (pos, c) in entries {
            let pos = pos.num().at(span)?;
            let c = c.color().at(span)?;
            let c = surface_color(&Arg {
                value: Value::Color(c),
                span,
            })?;
            if !(0.0..=1.0).contains(&pos) {
                return Err(range_error(
                    span,
                    format!(
                        "color map positions must be in [0, 1], found {}",
                        crate::diag::short_number(pos)
                    ),
                    "use a position from 0 to 1",
                ));
            }
            self.0.push((pos, c));
        }
        Ok(())
    }
}
