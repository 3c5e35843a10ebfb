//! The parameters of the kinds that take more than a colour: a blend's parts and weight, a
//! thin glass's exclusions, a conductor's index (named metal, `eta`/`extinction` or artist
//! colours), and the colour checks they share.

use std::rc::Rc;

use super::MaterialBuilder;
use crate::diag::short_number;
use crate::diag::{At, Diagnostic, Error, SourceResult, suggest};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, color_def, range_error};
use crate::eval::value::{ColorDef, MatKind, MaterialDef, Value};
use crate::scene::metals::{MAX_ARTIST_REFLECTANCE, artist_to_eta_k, metal, metal_names};
use crate::scene::{Color, MAX_BLEND_DEPTH};
use crate::span::Span;

impl MaterialBuilder {
    /// A blend's kind: its two materials (or a declared blend's) and its weight (default 0.5),
    /// nested at most `MAX_BLEND_DEPTH` deep.
    pub(super) fn blend(&self, base: Option<MatKind>, span: Span) -> SourceResult<MatKind> {
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
    pub(super) fn thin_glass_conflicts(&self, thin: bool) -> SourceResult<()> {
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
    pub(super) fn conductor(&self, base: Option<MatKind>) -> SourceResult<MatKind> {
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
pub(super) fn blend_part(a: &Arg) -> SourceResult<Rc<MaterialDef>> {
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
pub(super) fn blend_weight(a: &Arg) -> SourceResult<ColorDef> {
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
pub(super) fn constant_color(a: &Arg) -> SourceResult<(Color, Span)> {
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
pub(super) fn named_metal(a: &Arg) -> SourceResult<(Color, Color, Span)> {
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
pub(super) fn reflectance(ev: &mut Evaluator, a: &Arg) -> SourceResult<ColorDef> {
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
