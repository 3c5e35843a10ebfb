//! `material { ... }`: the kind (diffuse, mirror, glass, glossy, conductor, coated, blend), its parameters, and
//! materials that extend a declared one.

use crate::diag::short_number;
use std::rc::Rc;

mod kinds;

use super::transparency::transparency;
use super::{Sink, unexpected};
use crate::diag::{Diagnostic, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, color_def, num, range_error};
use crate::eval::props::{PropSpec, p};
use crate::eval::value::{ColorDef, MatKind, MaterialDef, NormalDef, Value};
use crate::scene::{COAT_IOR_RANGE, Color, IOR_RANGE, MIN_ROUGHNESS};
use crate::span::Span;
use crate::syntax::ast::Name;
use kinds::{blend_part, blend_weight, constant_color, named_metal, reflectance};

#[derive(Default)]
pub(super) struct MaterialBuilder {
    kind: Option<(&'static str, Span)>,
    base: Option<Rc<MaterialDef>>,
    /// Where the declared material was named.
    base_span: Option<Span>,
    albedo: Option<ColorDef>,
    ior: Option<(f64, Span)>,
    absorb: Option<ColorDef>,
    tint: Option<Color>,
    tint_def: Option<ColorDef>,
    /// Where `tint` was given a texture (a mirror's tint may be one, a glass's may not).
    tint_texture: Option<Span>,
    specular: Option<ColorDef>,
    roughness: Option<ColorDef>,
    /// A constant roughness as written, checked against the kind's range when it is known.
    roughness_num: Option<(f64, Span)>,
    /// `thin` was written (a glass pane), with its span.
    thin: Option<Span>,
    /// A conductor's named metal (`conductor "Au"`), with the name's span.
    metal: Option<(Color, Color, Span)>,
    eta: Option<(Color, Span)>,
    extinction: Option<(Color, Span)>,
    reflectance: Option<(Color, Span)>,
    edge_tint: Option<(Color, Span)>,
    /// POV-Ray's filter and transmit: from `filter f`/`transmit t`, or from an `rgbf`/`rgbt`/
    /// `rgbft` colour (the properties win), with where each was written.
    filter: Option<(f64, Span)>,
    transmit: Option<(f64, Span)>,
    /// A blend's two materials.
    blend: Option<(Rc<MaterialDef>, Rc<MaterialDef>)>,
    /// A blend's weight (the share of the second material) and where it was written.
    weight: Option<(ColorDef, Span)>,
    /// A bump or normal map (`normal { ... }`, `bump_map { ... }`), with where it was written.
    normal: Option<(Rc<NormalDef>, Span)>,
    /// The properties beyond the kind that were written (`ior`, `absorb`, `tint`, `specular`,
    /// `roughness`), with their keywords' spans: each must belong to the material's kind.
    written: Vec<(&'static str, Span)>,
    touched: bool,
}

/// The properties each kind uses beyond its colour.
fn uses(kind: &str) -> &'static [&'static str] {
    match kind {
        "mirror" => &["tint", "filter", "transmit"],
        "glass" => &["ior", "absorb", "tint", "roughness", "thin"],
        "glossy" => &["specular", "roughness", "filter", "transmit"],
        "conductor" => &["eta", "extinction", "reflectance", "edge_tint", "roughness"],
        "coated" => &["ior", "roughness", "filter", "transmit"],
        "blend" => &["weight"],
        _ => &["filter", "transmit"],
    }
}

static MAT_PROPS: [PropSpec; 20] = [
    p("diffuse", 1, 1, "a color or texture", "rgb <0.8, 0.8, 0.8>"),
    p("mirror", 0, 1, "a color (optional)", "rgb <0.9, 0.9, 0.9>"),
    p("glass", 0, 0, "nothing", ""),
    p("thin", 0, 0, "nothing", ""),
    p("glossy", 1, 1, "a color or texture", "rgb <0.5, 0.5, 0.5>"),
    p("coated", 1, 1, "a color or texture", "rgb <0.8, 0.1, 0.1>"),
    p("ior", 1, 1, "a number", "1.5"),
    p("absorb", 1, 1, "a color", "rgb <0.1, 0.02, 0.02>"),
    p("tint", 1, 1, "a color", "rgb <1, 1, 1>"),
    p("specular", 1, 1, "a color", "rgb <0.04, 0.04, 0.04>"),
    p("roughness", 1, 1, "a number in (0, 1]", "0.2"),
    p("conductor", 0, 1, "a metal's name (optional)", "\"Au\""),
    p("eta", 1, 1, "a color", "rgb <0.18, 0.49, 1.38>"),
    p("extinction", 1, 1, "a color", "rgb <3.12, 2.35, 1.83>"),
    p("reflectance", 1, 1, "a color", "rgb <0.95, 0.64, 0.54>"),
    p("edge_tint", 1, 1, "a color", "rgb <1, 0.9, 0.8>"),
    p("filter", 1, 1, "a number from 0 to 1", "0.9"),
    p("transmit", 1, 1, "a number from 0 to 1", "0.9"),
    p("blend", 2, 2, "two materials", "Polish, Wood"),
    p("weight", 1, 1, "a number in [0, 1] or a texture", "0.3"),
];

impl MaterialBuilder {
    fn set_kind(&mut self, k: &'static str, span: Span) -> SourceResult<()> {
        if let Some((old, old_span)) = self.kind {
            return Err(vec![
                Error::new(format!("a material is either {old} or {k}, not both"))
                    .label("second kind")
                    .help(
                        "use one of diffuse, mirror, glass, glossy, conductor, coated, blend \
                         per material",
                    )
                    .at(span)
                    .with_extra(old_span, "first kind here"),
            ]);
        }
        self.kind = Some((k, span));
        Ok(())
    }

    pub(super) fn finish(self, ev: &mut Evaluator, span: Span) -> SourceResult<Value> {
        let (filter, transmit) = (self.filter, self.transmit);
        if !self.touched
            && let Some(base) = self.base
        {
            return Ok(Value::Material(base));
        }
        let base_kind = self.base.as_ref().map(|b| match b.kind {
            MatKind::Diffuse(_) => "diffuse",
            MatKind::Mirror(_) => "mirror",
            MatKind::Glass { .. } => "glass",
            MatKind::Glossy { .. } => "glossy",
            MatKind::Conductor { .. } => "conductor",
            MatKind::Coated { .. } => "coated",
            MatKind::Blend { .. } => "blend",
        });
        // A kind written beside a declared material of another kind replaces it whole (its
        // properties belong to its kind): said, since nothing of the declared one is kept.
        if let (Some((kind, kind_span)), Some(declared), Some(at)) =
            (self.kind, base_kind, self.base_span)
            && kind != declared
        {
            let name = ev.sources.snippet(at);
            ev.warn(
                Diagnostic::warning(
                    at,
                    format!("`{name}` is a {declared} material: `{kind}` replaces it whole"),
                )
                .with_label("nothing of this material is kept")
                .with_extra(kind_span, "the kind used")
                .with_help(format!(
                    "an override keeps the declared material's kind; drop `{name}` for a new \
                     {kind} material, or `{kind}` to change `{name}`'s properties"
                )),
            );
        }
        let kind_name = self.kind.map(|k| k.0).or(base_kind);
        let Some(kind_name) = kind_name else {
            return Err(vec![
                Error::new(
                    "a material needs a kind: diffuse, mirror, glass, glossy, conductor, coated \
                     or blend",
                )
                .label("no kind given")
                .help("write e.g. `material { diffuse rgb <0.8, 0.8, 0.8> }`")
                .at(span),
            ]);
        };
        let base = self.base.as_ref().map(|b| b.kind.clone());
        let misplaced = |what: &str, s: Option<Span>| -> SourceResult<()> {
            match s {
                Some(s) => Err(vec![
                    Error::new(format!("`{what}` does not apply to a {kind_name} material"))
                        .label("not used by this kind")
                        .help(format!(
                            "drop `{what}`, or use the kind of material it belongs to"
                        ))
                        .at(s),
                ]),
                None => Ok(()),
            }
        };
        // A property the kind does not use would be dropped without a word (`glass roughness
        // 0.3` is not frosted glass): refused, as POV-Ray users expect a finish to matter.
        if let Some(&(what, s)) = self
            .written
            .iter()
            .find(|w| !uses(kind_name).contains(&w.0))
        {
            misplaced(what, Some(s))?;
        }
        if let Some((r, s)) = self.roughness_num {
            // A conductor and a glass may be perfectly smooth.
            let lowest = if kind_name == "conductor" || kind_name == "glass" {
                0.0
            } else {
                MIN_ROUGHNESS
            };
            if r < lowest {
                return Err(range_error(
                    s,
                    format!(
                        "roughness must be from {} to 1, found {}",
                        short_number(lowest),
                        short_number(r)
                    ),
                    "e.g. `roughness 0.2`",
                ));
            }
        }
        let one = ColorDef::Const(Color::ONE);
        let kind = match kind_name {
            "diffuse" => {
                let base_albedo = match base {
                    Some(MatKind::Diffuse(a)) => Some(a),
                    _ => None,
                };
                MatKind::Diffuse(
                    self.albedo
                        .or(base_albedo)
                        .unwrap_or(ColorDef::Const(Color::splat(0.5))),
                )
            }
            "mirror" => {
                let base_tint = match base {
                    Some(MatKind::Mirror(t)) => Some(t),
                    _ => None,
                };
                MatKind::Mirror(self.tint_def.or(self.albedo).or(base_tint).unwrap_or(one))
            }
            "glass" => {
                if let Some(at) = self.tint_texture {
                    return Err(vec![
                        Error::new("a glass tint is a constant colour, not a texture")
                            .label("a texture")
                            .help(
                                "write e.g. `tint rgb <0.9, 1, 0.9>`; for glass coloured by a \
                                 texture, give the texture to `absorb`",
                            )
                            .at(at),
                    ]);
                }
                let (mut ior, mut absorb, mut tint, mut roughness, mut thin) =
                    (1.5, ColorDef::Const(Color::ZERO), Color::ONE, None, false);
                if let Some(MatKind::Glass {
                    ior: i,
                    absorb: a,
                    tint: t,
                    roughness: r,
                    thin: th,
                }) = base
                {
                    (ior, absorb, tint, roughness, thin) = (i, a, t, r, th);
                }
                thin |= self.thin.is_some();
                roughness = self.roughness.clone().or(roughness);
                self.thin_glass_conflicts(thin)?;
                if let Some((i, s)) = self.ior {
                    if i < IOR_RANGE.0 {
                        return Err(range_error(
                            s,
                            format!("ior must be at least 1, found {}", short_number(i)),
                            "glass has an index of refraction ≥ 1 (1.5 for window glass)",
                        ));
                    }
                    if i > IOR_RANGE.1 || i.is_nan() {
                        return Err(range_error(
                            s,
                            format!("ior {} is out of range", crate::diag::short_number(i)),
                            "real materials have an index of refraction from 1 to about 4 \
                             (at most 100 is accepted)",
                        ));
                    }
                    ior = i;
                }
                MatKind::Glass {
                    ior,
                    absorb: self.absorb.unwrap_or(absorb),
                    tint: self.tint.unwrap_or(tint),
                    roughness,
                    thin,
                }
            }
            "conductor" => self.conductor(base)?,
            "blend" => self.blend(base, span)?,
            "coated" => {
                let (mut albedo, mut ior, mut roughness) =
                    (ColorDef::Const(Color::splat(0.5)), 1.5, None);
                if let Some(MatKind::Coated {
                    albedo: a,
                    ior: i,
                    roughness: r,
                }) = base
                {
                    (albedo, ior, roughness) = (a, i, r);
                }
                if let Some((i, s)) = self.ior {
                    let (lo, hi) = COAT_IOR_RANGE;
                    if !(lo..=hi).contains(&i) {
                        return Err(range_error(
                            s,
                            format!(
                                "a coat's ior must be from 1 to 3, found {}",
                                short_number(i)
                            ),
                            "varnish, lacquer and glaze have an index of refraction near 1.5",
                        ));
                    }
                    ior = i;
                }
                MatKind::Coated {
                    albedo: self.albedo.unwrap_or(albedo),
                    ior,
                    roughness: self.roughness.or(roughness),
                }
            }
            _ => {
                // An override of a declared glossy material keeps what it does not write.
                let (albedo, specular, roughness) = match base {
                    Some(MatKind::Glossy {
                        albedo,
                        specular,
                        roughness,
                    }) => (albedo, specular, roughness),
                    _ => (
                        ColorDef::Const(Color::splat(0.5)),
                        ColorDef::Const(Color::splat(0.04)),
                        ColorDef::Const(Color::splat(0.2)),
                    ),
                };
                MatKind::Glossy {
                    albedo: self.albedo.unwrap_or(albedo),
                    specular: self.specular.unwrap_or(specular),
                    roughness: self.roughness.unwrap_or(roughness),
                }
            }
        };
        let kind = transparency(ev, filter, transmit, kind)?;
        let normal = match self.normal {
            Some((n, _)) => Some(n),
            None => self.base.as_ref().and_then(|b| b.normal.clone()),
        };
        Ok(Value::Material(Rc::new(MaterialDef { kind, span, normal })))
    }
}

impl MaterialBuilder {
    /// A colour argument, with an `rgbf`/`rgbt`/`rgbft` colour's filter and transmit taken
    /// out (kept unless the properties give them).
    fn unfiltered(&mut self, a: &Arg) -> Arg {
        match a.value {
            Value::Filtered(c, f, t) => {
                self.filter = self.filter.or(Some((f, a.span)));
                self.transmit = self.transmit.or(Some((t, a.span)));
                Arg {
                    value: Value::Color(c),
                    span: a.span,
                }
            }
            _ => Arg {
                value: a.value.clone(),
                span: a.span,
            },
        }
    }
}

impl Sink for MaterialBuilder {
    fn kind(&self) -> String {
        "a material".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &MAT_PROPS
    }
    fn property(&mut self, ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        self.touched = true;
        if let Some(&w) = [
            "ior",
            "absorb",
            "tint",
            "specular",
            "roughness",
            "eta",
            "extinction",
            "reflectance",
            "edge_tint",
            "filter",
            "transmit",
            "weight",
            "thin",
        ]
        .iter()
        .find(|w| **w == kw.text)
        {
            self.written.push((w, kw.span));
        }
        match kw.text.as_str() {
            "diffuse" => {
                self.set_kind("diffuse", kw.span)?;
                let a = self.unfiltered(&args[0]);
                self.albedo = Some(reflectance(ev, &a)?);
            }
            "mirror" => {
                self.set_kind("mirror", kw.span)?;
                if let Some(a) = args.first() {
                    let a = self.unfiltered(a);
                    self.tint_def = Some(reflectance(ev, &a)?);
                }
            }
            "glass" => self.set_kind("glass", kw.span)?,
            "thin" => self.thin = Some(kw.span),
            "glossy" => {
                self.set_kind("glossy", kw.span)?;
                let a = self.unfiltered(&args[0]);
                self.albedo = Some(reflectance(ev, &a)?);
            }
            "filter" | "transmit" => {
                let x = num(&args[0])?;
                if !(0.0..=1.0).contains(&x) {
                    return Err(range_error(
                        args[0].span,
                        format!("{} must be from 0 to 1, found {}", kw.text, short_number(x)),
                        "the share of the light that passes through, e.g. `filter 0.9`",
                    ));
                }
                let v = Some((x, kw.span.join(args[0].span)));
                if kw.text == "filter" {
                    self.filter = v;
                } else {
                    self.transmit = v;
                }
            }
            "conductor" => {
                self.set_kind("conductor", kw.span)?;
                if let Some(a) = args.first() {
                    self.metal = Some(named_metal(a)?);
                }
            }
            "blend" => {
                self.set_kind("blend", kw.span)?;
                self.blend = Some((blend_part(&args[0])?, blend_part(&args[1])?));
            }
            "weight" => self.weight = Some((blend_weight(&args[0])?, args[0].span)),
            "eta" => self.eta = Some(constant_color(&args[0])?),
            "extinction" => self.extinction = Some(constant_color(&args[0])?),
            "reflectance" => self.reflectance = Some(constant_color(&args[0])?),
            "edge_tint" => self.edge_tint = Some(constant_color(&args[0])?),
            "coated" => {
                self.set_kind("coated", kw.span)?;
                let a = self.unfiltered(&args[0]);
                self.albedo = Some(reflectance(ev, &a)?);
            }
            "ior" => self.ior = Some((num(&args[0])?, args[0].span)),
            "absorb" => {
                let c = color_def(&args[0])?;
                if let ColorDef::Const(c) = c
                    && c.min_element() < 0.0
                {
                    return Err(range_error(
                        args[0].span,
                        "absorption must not be negative".into(),
                        "use components ≥ 0",
                    ));
                }
                self.absorb = Some(c);
            }
            "tint" => {
                // A mirror's tint may be a texture (as `mirror <color>`); a glass's is a
                // constant colour, checked when the kind is known.
                let def = reflectance(ev, &args[0])?;
                self.tint = match &def {
                    ColorDef::Const(c) => Some(*c),
                    ColorDef::Tex(_) => {
                        self.tint_texture = Some(args[0].span);
                        None
                    }
                };
                self.tint_def = Some(def);
            }
            "specular" => self.specular = Some(reflectance(ev, &args[0])?),
            "roughness" => {
                // The lower bound depends on the kind (a conductor may be perfectly smooth):
                // checked in `finish`.
                if let Value::Num(r) = args[0].value {
                    if !(0.0..=1.0).contains(&r) {
                        return Err(range_error(
                            args[0].span,
                            format!(
                                "roughness must be from 0.001 to 1 (0 to 1 for a conductor or \
                                 glass), found {}",
                                crate::diag::short_number(r)
                            ),
                            "e.g. `roughness 0.2`",
                        ));
                    }
                    self.roughness_num = Some((r, args[0].span));
                }
                self.roughness = Some(color_def(&args[0])?);
            }
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::Normal(n) => {
                if let Some((_, first)) = &self.normal {
                    return Err(vec![
                        Error::new("a material has one normal")
                            .label("second normal")
                            .help("keep one `normal { ... }` (or `bump_map { ... }`) per material")
                            .at(span)
                            .with_extra(*first, "first normal here"),
                    ]);
                }
                self.touched = true;
                self.normal = Some((n, span));
                Ok(())
            }
            Value::Material(m) if self.base.is_none() => {
                self.base = Some(m);
                self.base_span = Some(span);
                Ok(())
            }
            // A colour declared and then used as a material (POV-Ray's `pigment { Red }`), or
            // `diffuse rgb 1, 0, 0`: a colour's components without their brackets (the first is
            // taken as a gray, the others come here after a comma).
            Value::Color(_) | Value::Texture(_) | Value::Num(_) => {
                let what = ev.sources.snippet(span);
                let after_comma = ev
                    .sources
                    .get(span.file)
                    .and_then(|f| f.text.get(..span.start as usize))
                    .is_some_and(|before| before.trim_end().ends_with(','));
                let help = if after_comma && matches!(v, Value::Num(_)) {
                    format!(
                        "`{what}` follows a comma: a colour's three components go in angle \
                         brackets, e.g. `diffuse rgb <1, 0, 0>`"
                    )
                } else {
                    format!(
                        "`{what}` is {}, not a material: write `material {{ diffuse {what} }}` \
                         for a matte surface of that colour (or `glossy {what}`)",
                        v.type_name()
                    )
                };
                Err(unexpected(self, &v, span, &help))
            }
            v => Err(unexpected(
                self,
                &v,
                span,
                "a material takes a declared material and properties, e.g. `material { diffuse rgb <0.8, 0.8, 0.8> }`",
            )),
        }
    }
}
