//! `material { ... }`: the kind (diffuse, mirror, glass, glossy, conductor, coated, blend), its parameters, and
//! materials that extend a declared one.

use crate::diag::short_number;
use std::rc::Rc;

use super::transparency::transparency;
use super::{Sink, unexpected};
use crate::diag::{At, Diagnostic, Error, SourceResult, suggest};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, color_def, num, range_error};
use crate::eval::props::{PropSpec, p};
use crate::eval::value::{ColorDef, MatKind, MaterialDef, Value};
use crate::scene::metals::{MAX_ARTIST_REFLECTANCE, artist_to_eta_k, metal, metal_names};
use crate::scene::{COAT_IOR_RANGE, Color, IOR_RANGE, MAX_BLEND_DEPTH, MIN_ROUGHNESS};
use crate::span::Span;
use crate::syntax::ast::Name;

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
        Ok(Value::Material(Rc::new(MaterialDef { kind, span })))
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

impl MaterialBuilder {
    /// A blend's kind: its two materials (or a declared blend's) and its weight (default 0.5),
    /// nested at most `MAX_BLEND_DEPTH` deep.
    fn blend(&self, base: Option<MatKind>, span: Span) -> SourceResult<MatKind> {
        let (parts, mut weight) = match base {
            Some(MatKind::Blend { a, b, weight, .. }) => (Some((a, b)), weight),
            _ => (None, ColorDef::Const(Color::splat(0.5))),
        };
        let Some((a, b)) = self.blend.clone().or(parts) else {
            return Err(vec![Error::new("a blend needs its two materials").at(span)]);
        };
        if let Some((w, _)) = &self.weight {
            weight = w.clone();
        }
        let depth_of = |m: &MaterialDef| match m.kind {
            MatKind::Blend { depth, .. } => depth,
            _ => 0,
        };
        let depth = 1 + depth_of(&a).max(depth_of(&b));
        if depth > MAX_BLEND_DEPTH {
            let at = self.kind.map_or(span, |k| k.1);
            return Err(vec![
                Error::new(format!(
                    "blends nest {depth} deep here, more than {MAX_BLEND_DEPTH}"
                ))
                .label("too deeply nested")
                .help(format!(
                    "a blend of blends may nest at most {MAX_BLEND_DEPTH} deep (each level \
                     is a choice at every hit)"
                ))
                .at(at),
            ]);
        }
        Ok(MatKind::Blend {
            a,
            b,
            weight,
            depth,
        })
    }

    /// A thin pane (`thin`, written here or in the declared glass it extends) takes neither an
    /// absorption, since it encloses no medium, nor a roughness: it is two smooth faces.
    fn thin_glass_conflicts(&self, thin: bool) -> SourceResult<()> {
        if !thin {
            return Ok(());
        }
        let at = |what: &str| self.written.iter().find(|w| w.0 == what).map(|w| w.1);
        let why = [
            (
                "absorb",
                "a thin glass encloses no medium to absorb in",
                "drop `absorb` and colour the pane with `tint`, or drop `thin` for solid glass",
            ),
            (
                "roughness",
                "a thin glass is smooth",
                "drop `roughness`, or drop `thin` for frosted solid glass",
            ),
        ];
        for (what, message, help) in why {
            if let Some(s) = at(what) {
                let mut e = Error::new(format!("`{what}` does not apply to thin glass: {message}"))
                    .label("not used by a thin glass")
                    .help(help)
                    .at(s);
                if let Some(t) = self.thin {
                    e = e.with_extra(t, "thin here");
                }
                return Err(vec![e]);
            }
        }
        Ok(())
    }

    /// A conductor's kind: its index from exactly one of a named metal, `eta` with
    /// `extinction`, or `reflectance` with an optional `edge_tint`; an override of a declared
    /// conductor keeps what it does not write.
    fn conductor(&self, base: Option<MatKind>) -> SourceResult<MatKind> {
        let (mut eta, mut k, mut roughness) = match base {
            Some(MatKind::Conductor { eta, k, roughness }) => (eta, k, roughness),
            _ => {
                let al = metal("Al").map_or([1.0; 3], |m| m.eta);
                let al_k = metal("Al").map_or([0.0; 3], |m| m.k);
                (Color::from(al), Color::from(al_k), 0.0)
            }
        };
        let ways = [
            self.metal.map(|m| m.2),
            self.eta.or(self.extinction).map(|e| e.1),
            self.reflectance.or(self.edge_tint).map(|e| e.1),
        ];
        let given: Vec<Span> = ways.iter().flatten().copied().collect();
        if given.len() > 1 {
            return Err(vec![
                Error::new("a conductor's colour is given twice")
                    .label("second description")
                    .help(
                        "give one of: a metal's name (`conductor \"Au\"`), `eta` with \
                         `extinction`, or `reflectance` with `edge_tint`",
                    )
                    .at(given[1])
                    .with_extra(given[0], "first description here"),
            ]);
        }
        if let Some((e, x, _)) = self.metal {
            (eta, k) = (e, x);
        }
        match (self.eta, self.extinction) {
            (Some((e, _)), Some((x, _))) => (eta, k) = (e, x),
            (Some((_, s)), None) | (None, Some((_, s))) => {
                return Err(vec![
                    Error::new("`eta` and `extinction` go together")
                        .label("the other one is missing")
                        .help(
                            "a metal's complex index of refraction is `eta rgb <..> \
                             extinction rgb <..>` (gold: eta rgb <0.18, 0.49, 1.38> \
                             extinction rgb <3.12, 2.35, 1.83>)",
                        )
                        .at(s),
                ]);
            }
            (None, None) => {}
        }
        match (self.reflectance, self.edge_tint) {
            (Some((r, s)), g) => {
                if r.max_element() > MAX_ARTIST_REFLECTANCE {
                    return Err(range_error(
                        s,
                        format!(
                            "a conductor's reflectance must be at most 0.99, found {}",
                            short_number(r.max_element())
                        ),
                        "use components from 0 to 0.99 (polished silver is about 0.97)",
                    ));
                }
                (eta, k) = artist_to_eta_k(r, g.map_or(r, |g| g.0));
            }
            (None, Some((_, s))) => {
                return Err(vec![
                    Error::new("`edge_tint` needs a `reflectance`")
                        .label("no reflectance")
                        .help("write e.g. `reflectance rgb <0.95, 0.64, 0.54> edge_tint rgb <1, 0.9, 0.8>`")
                        .at(s),
                ]);
            }
            (None, None) => {}
        }
        if let Some(ColorDef::Tex(_)) = self.roughness {
            let at = self
                .written
                .iter()
                .find(|w| w.0 == "roughness")
                .map(|w| w.1);
            return Err(vec![
                Error::new("a conductor's roughness is a number, not a texture")
                    .label("a texture")
                    .help("write e.g. `roughness 0.2`")
                    .at(at.unwrap_or(self.metal.map_or(Span::detached(), |m| m.2))),
            ]);
        }
        if let Some((r, _)) = self.roughness_num {
            roughness = r;
        }
        Ok(MatKind::Conductor { eta, k, roughness })
    }
}

/// One of a blend's materials: a declared material or a `material { ... }` block.
fn blend_part(a: &Arg) -> SourceResult<Rc<MaterialDef>> {
    match &a.value {
        Value::Material(m) => Ok(m.clone()),
        v => Err(vec![
            Error::new(format!(
                "a blend's parts are materials, found {}",
                v.type_name()
            ))
            .label("not a material")
            .help(
                "write two materials, declared or as blocks: `blend Polish, material { diffuse \
                 0.8 } weight 0.3`",
            )
            .at(a.span),
        ]),
    }
}

/// A blend's weight: a number from 0 to 1 or a texture (its luminance).
fn blend_weight(a: &Arg) -> SourceResult<ColorDef> {
    match &a.value {
        Value::Texture(t) => Ok(ColorDef::Tex(t.clone())),
        _ => {
            let w = a
                .value
                .num()
                .map_err(|e| {
                    e.help("a blend's weight is a number from 0 to 1 or a `texture { ... }`")
                })
                .at(a.span)?;
            if !(0.0..=1.0).contains(&w) {
                return Err(range_error(
                    a.span,
                    format!(
                        "a blend's weight must be from 0 to 1, found {}",
                        short_number(w)
                    ),
                    "0 shows only the first material, 1 only the second",
                ));
            }
            Ok(ColorDef::Const(Color::splat(w)))
        }
    }
}

/// A constant colour from a conductor's property: not a texture, not negative.
fn constant_color(a: &Arg) -> SourceResult<(Color, Span)> {
    match color_def(a)? {
        ColorDef::Const(c) if c.min_element() < 0.0 => Err(range_error(
            a.span,
            format!(
                "a conductor's colour must not be negative, found {}",
                short_number(c.min_element())
            ),
            "use components >= 0",
        )),
        ColorDef::Const(c) => Ok((c, a.span)),
        ColorDef::Tex(_) => Err(vec![
            Error::new("a conductor's colours are constants, not textures")
                .label("a texture")
                .help("write a colour, e.g. `rgb <0.95, 0.64, 0.54>`")
                .at(a.span),
        ]),
    }
}

/// A named metal (`conductor "Au"`): the table's entry, or an error naming the nearest.
fn named_metal(a: &Arg) -> SourceResult<(Color, Color, Span)> {
    let Value::Str(name) = &a.value else {
        return Err(vec![
            Error::new(format!(
                "a conductor's argument is a metal's name, found {}",
                a.value.type_name()
            ))
            .label("not a name")
            .help("write the name in quotes, e.g. `conductor \"Au\"`, or give `eta`/`extinction` or `reflectance`")
            .at(a.span),
        ]);
    };
    if let Some(m) = metal(name) {
        return Ok((Color::from(m.eta), Color::from(m.k), a.span));
    }
    let known: Vec<&str> = metal_names().collect();
    let help = match suggest(name, known.iter().copied()) {
        Some(s) => format!("did you mean `\"{s}\"`?"),
        None => format!("the known metals are {}", known.join(", ")),
    };
    Err(vec![
        Error::new(format!("`{name}` is not a known metal"))
            .label("unknown metal")
            .help(help)
            .at(a.span),
    ])
}

/// A surface's colour (`diffuse`, `mirror`, `glossy`); a constant above 1 gives a warning: the
/// renderer clamps it to 1, since no surface reflects more light than reaches it (POV-Ray users
/// brighten a colour this way).
fn reflectance(ev: &mut Evaluator, a: &Arg) -> SourceResult<ColorDef> {
    let def = color_def(a)?;
    if let ColorDef::Const(c) = &def {
        warn_above_one(ev, *c, a.span);
    }
    Ok(def)
}

/// The warning of [`reflectance`] for a constant colour `c` written at `span`.
fn warn_above_one(ev: &mut Evaluator, c: Color, span: Span) {
    if c.max_element() > 1.0 {
        ev.warn(
            Diagnostic::warning(
                span,
                format!(
                    "a reflectance of {} is clamped to 1: a surface cannot reflect more light \
                     than reaches it",
                    short_number(c.max_element())
                ),
            )
            .with_label("above 1")
            .with_help(
                "use components from 0 to 1; for a brighter picture raise the lights or \
                 `settings { exposure k }`",
            ),
        );
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
