//! POV-Ray's transparent colours (`rgbf`, `rgbt`, `rgbft`, `filter`, `transmit`) on a
//! material: transparency is a material here, so they make it a glass or are dropped, with a
//! warning that says which.

use crate::diag::short_number;
use crate::diag::{Diagnostic, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::range_error;
use crate::eval::value::{ColorDef, MatKind};
use crate::scene::Color;
use crate::span::Span;

/// POV-Ray's filter and transmit on a colour material: when they pass at least half the light,
/// the surface becomes a glass of index 1 (POV-Ray's, without an `interior`: no refraction)
/// tinted by what passes (`filter · colour + transmit`), and its opaque rest is dropped; below
/// half they are dropped. A warning says which.
pub(super) fn transparency(
    ev: &mut Evaluator,
    filter: Option<(f64, Span)>,
    transmit: Option<(f64, Span)>,
    kind: MatKind,
) -> SourceResult<MatKind> {
    let (f, t) = (filter.map_or(0.0, |f| f.0), transmit.map_or(0.0, |t| t.0));
    let Some(at) = filter.or(transmit).map(|x| x.1) else {
        return Ok(kind);
    };
    for (x, s) in filter.iter().chain(&transmit) {
        if !(0.0..=1.0).contains(x) {
            return Err(range_error(
                *s,
                format!(
                    "filter and transmit must be from 0 to 1, found {}",
                    short_number(*x)
                ),
                "the share of the light that passes through, e.g. `rgbf <1, 1, 1, 0.9>`",
            ));
        }
    }
    if f + t <= 0.0 {
        return Ok(kind);
    }
    let color = match &kind {
        MatKind::Diffuse(c) | MatKind::Mirror(c) => c,
        MatKind::Glossy { albedo, .. } | MatKind::Coated { albedo, .. } => albedo,
        _ => return Ok(kind),
    };
    let ColorDef::Const(c) = color else {
        return Err(vec![
            Error::new("POV-Ray's filter and transmit over a texture have no counterpart")
                .label("transparency of a textured surface")
                .help(
                    "transparency is a material here: use `material { glass ior n tint \
                     rgb <...> }` (its `absorb` may be a texture), or drop the filter",
                )
                .at(at),
        ]);
    };
    let words = match (f > 0.0, t > 0.0) {
        (true, true) => format!(
            "filter {} and transmit {}",
            short_number(f),
            short_number(t)
        ),
        (true, false) => format!("filter {}", short_number(f)),
        _ => format!("transmit {}", short_number(t)),
    };
    if f + t < 0.5 {
        ev.warn(
            Diagnostic::warning(
                at,
                format!("POV-Ray's {words} is dropped: the surface stays opaque"),
            )
            .with_label("transparency dropped")
            .with_help(
                "transparency is a material here, and a surface that lets through less \
                     than half the light is kept opaque; for a clear surface write \
                     `material { glass ior 1.5 tint rgb <...> }`",
            ),
        );
        return Ok(kind);
    }
    let tint = (*c * f + Color::splat(t)).clamp(Color::ZERO, Color::ONE);
    ev.warn(
        Diagnostic::warning(
            at,
            format!(
                "POV-Ray's {words} makes this a glass here: `glass ior 1 tint rgb <{}, {}, {}>`",
                short_number(tint.x),
                short_number(tint.y),
                short_number(tint.z)
            ),
        )
        .with_label("a transparent colour")
        .with_help(format!(
            "the light POV-Ray lets through (filter · colour + transmit) passes a glass of \
             index 1 (no refraction, as POV-Ray without `interior`) with that tint; the \
             opaque rest ({}) is dropped. Write `material {{ glass ior 1.5 tint rgb <...> }}` \
             to say it (POV-Ray's `interior {{ ior 1.5 }}`)",
            short_number((1.0 - f - t).max(0.0))
        )),
    );
    Ok(MatKind::Glass {
        ior: 1.0,
        absorb: ColorDef::Const(Color::ZERO),
        tint,
        roughness: None,
        thin: false,
    })
}
