//! The ranges of what a scene looks like: materials, emission, lights, textures and the
//! background. The language refuses values outside them where they are written; a `Scene`
//! built by hand gets the same ranges here, so that nothing reaches the renderer that would
//! overflow (a radiance of 1e308 has an infinite power), divide by zero (a glass of index 0),
//! run without end (a noise of 2^32 octaves per lookup) or index nothing (an empty colour map).

use glam::DVec3;

use super::{fmt, invalid};
use crate::diag::Diagnostic;
use crate::scene::{
    Background, ColorMap, ColorParam, LightDecl, Material, Pattern, ScalarParam, Scene, Texture,
};
use crate::span::Span;

/// Largest colour component accepted anywhere (reflectance, radiance, intensity): products
/// with areas, powers and photon counts stay far inside f32 and f64.
pub const MAX_COLOR: f64 = 1e9;
/// Smallest glossy roughness: below it the lobe's width underflows (use a mirror instead).
pub const MIN_ROUGHNESS: f64 = 1e-3;
/// Glass indices of refraction accepted (real materials lie from 1 to about 4).
pub const IOR_RANGE: (f64, f64) = (1.0, 100.0);
/// Coat indices of refraction accepted (varnishes and glazes lie from 1.3 to 2; the coated
/// BSDF tabulates its coat's reflectance over this range).
pub const COAT_IOR_RANGE: (f64, f64) = (1.0, 3.0);
/// Most octaves of a noise-based pattern (each lookup pays one noise evaluation per octave).
pub const MAX_OCTAVES: u32 = 16;

/// Why colour `c` is out of range: not finite, negative or above [`MAX_COLOR`].
pub fn color_problem(c: DVec3) -> Option<String> {
    if !c.is_finite() {
        return Some("is not finite".into());
    }
    if c.min_element() < 0.0 {
        return Some(format!("is negative ({})", fmt(c.min_element())));
    }
    if c.max_element() > MAX_COLOR {
        return Some(format!("is above 1e9 ({})", fmt(c.max_element())));
    }
    None
}

/// When an environment map's brightest pixel times `intensity` (its brightest radiance) is
/// above [`MAX_COLOR`]: what is wrong, and the largest intensity that fits this image.
pub fn environment_too_bright(
    image: &crate::scene::ImageData,
    intensity: f64,
) -> Option<(String, f64)> {
    let brightest = crate::scene::brightest_pixel(image);
    (brightest * intensity > MAX_COLOR).then(|| {
        (
            format!(
                "the environment's brightest pixel ({}) times its intensity ({}) is {}, above \
                 the colour limit 1e9",
                fmt(brightest),
                fmt(intensity),
                fmt(brightest * intensity)
            ),
            MAX_COLOR / brightest,
        )
    })
}

const COLOR_HELP: &str = "use finite components from 0 to 1e9";

fn color(c: DVec3, what: &str, span: Span) -> Result<(), Diagnostic> {
    match color_problem(c) {
        Some(why) => Err(invalid(
            span,
            format!("{what} {why}"),
            "out of range",
            COLOR_HELP,
        )),
        None => Ok(()),
    }
}

/// The appearance of the whole scene (see the module docs); the first problem found.
pub(super) fn validate(scene: &Scene) -> Result<(), Diagnostic> {
    for (i, m) in scene.materials.iter().enumerate() {
        material(m, i)?;
    }
    for obj in &scene.objects {
        if let Some(e) = &obj.emission {
            color(e.radiance, "the area light's radiance", obj.span)?;
        }
    }
    for light in &scene.lights {
        let (intensity, span, what) = match light {
            LightDecl::Point {
                intensity, span, ..
            } => (*intensity, *span, "the point light's intensity"),
            LightDecl::Spot {
                intensity, span, ..
            } => (*intensity, *span, "the spot light's intensity"),
        };
        color(intensity, what, span)?;
    }
    for (i, t) in scene.textures.iter().enumerate() {
        texture(t, i)?;
    }
    if let Background::Color(c) = scene.background {
        color(c, "the background colour", Span::detached())?;
    }
    if let Some(ColorParam::Const(c)) = scene.backdrop {
        color(c, "the backdrop colour", Span::detached())?;
    }
    Ok(())
}

/// A glass's (or a pane's) index of refraction is within [`IOR_RANGE`].
fn glass_ior(ior: f64, index: usize) -> Result<(), Diagnostic> {
    let (lo, hi) = IOR_RANGE;
    if !(ior >= lo && ior <= hi) {
        return Err(invalid(
            Span::detached(),
            format!("material {index}'s ior {} is out of range", fmt(ior)),
            "out of range",
            "glass has an index of refraction from 1 to 100 (1.5 for window glass)",
        ));
    }
    Ok(())
}

fn material(m: &Material, index: usize) -> Result<(), Diagnostic> {
    let span = Span::detached();
    let param = |p: &ColorParam, what: &str| match p {
        ColorParam::Const(c) => color(*c, &format!("material {index}'s {what}"), span),
        ColorParam::Texture(_) => Ok(()),
    };
    match m {
        Material::Diffuse { albedo } => param(albedo, "albedo"),
        Material::Mirror { tint } => param(tint, "tint"),
        Material::Glass {
            ior,
            absorb,
            tint,
            roughness,
        } => {
            glass_ior(*ior, index)?;
            param(absorb, "absorb")?;
            color(*tint, &format!("material {index}'s tint"), span)?;
            match roughness {
                ScalarParam::Const(r) if !(0.0..=1.0).contains(r) => Err(invalid(
                    span,
                    format!("material {index}'s roughness {} is out of range", fmt(*r)),
                    "out of range",
                    "use 0 for smooth glass or a roughness up to 1 (frosted)",
                )),
                _ => Ok(()),
            }
        }
        Material::ThinGlass { ior, tint } => {
            glass_ior(*ior, index)?;
            color(*tint, &format!("material {index}'s tint"), span)
        }
        Material::Glossy {
            albedo,
            specular,
            roughness,
        } => {
            param(albedo, "albedo")?;
            param(specular, "specular")?;
            match roughness {
                ScalarParam::Const(r) if !(MIN_ROUGHNESS..=1.0).contains(r) => Err(invalid(
                    span,
                    format!("material {index}'s roughness {} is out of range", fmt(*r)),
                    "out of range",
                    "use a roughness from 0.001 to 1 (a mirror for a perfect reflection)",
                )),
                _ => Ok(()),
            }
        }
        Material::Conductor { eta, k, roughness } => {
            color(*eta, &format!("material {index}'s eta"), span)?;
            color(*k, &format!("material {index}'s k"), span)?;
            if (0.0..=1.0).contains(roughness) {
                Ok(())
            } else {
                Err(invalid(
                    span,
                    format!(
                        "material {index}'s roughness {} is out of range",
                        fmt(*roughness)
                    ),
                    "out of range",
                    "use a roughness from 0 (a polished metal) to 1",
                ))
            }
        }
        Material::Bumped { normal, .. } => {
            if normal.amount.is_finite() && normal.transform.is_finite() {
                Ok(())
            } else {
                Err(invalid(
                    span,
                    format!("material {index}'s normal is not finite"),
                    "not finite",
                    "a bump amount and a normal's transform are finite numbers",
                ))
            }
        }
        Material::Blend { weight, .. } => match weight {
            ScalarParam::Const(w) if !(0.0..=1.0).contains(w) => Err(invalid(
                span,
                format!(
                    "material {index}'s blend weight {} is out of range",
                    fmt(*w)
                ),
                "out of range",
                "a blend weight is from 0 (the first material) to 1 (the second)",
            )),
            _ => Ok(()),
        },
        Material::Coated {
            albedo,
            ior,
            roughness,
        } => {
            param(albedo, "albedo")?;
            let (lo, hi) = COAT_IOR_RANGE;
            if !(*ior >= lo && *ior <= hi) {
                return Err(invalid(
                    span,
                    format!("material {index}'s coat ior {} is out of range", fmt(*ior)),
                    "out of range",
                    "a coat has an index of refraction from 1 to 3 (1.5 for varnish)",
                ));
            }
            match roughness {
                ScalarParam::Const(r) if *r != 0.0 && !(MIN_ROUGHNESS..=1.0).contains(r) => {
                    Err(invalid(
                        span,
                        format!("material {index}'s roughness {} is out of range", fmt(*r)),
                        "out of range",
                        "use 0 for a smooth coat or a roughness from 0.001 to 1",
                    ))
                }
                _ => Ok(()),
            }
        }
    }
}

fn texture(t: &Texture, index: usize) -> Result<(), Diagnostic> {
    let span = t.span;
    let name = |what: &str| format!("texture {index}'s {what}");
    if !(t.transform.matrix3.is_finite() && t.transform.translation.is_finite()) {
        return Err(invalid(
            span,
            name("transform is not finite"),
            "transforms overflow",
            "check the scale, rotate and translate applied to the texture",
        ));
    }
    let octaves = |n: u32| {
        if (1..=MAX_OCTAVES).contains(&n) {
            Ok(())
        } else {
            Err(invalid(
                span,
                name(&format!(
                    "octaves must be from 1 to {MAX_OCTAVES}, found {n}"
                )),
                "out of range",
                "e.g. 6 octaves",
            ))
        }
    };
    let turbulence = |x: f64| {
        if x >= 0.0 && x.is_finite() {
            Ok(())
        } else {
            Err(invalid(
                span,
                name(&format!("turbulence {} is out of range", fmt(x))),
                "out of range",
                "use a finite turbulence of at least 0, e.g. 1",
            ))
        }
    };
    let map = |m: &ColorMap| color_map(m, &name("color map"), span);
    let two = |a: DVec3, b: DVec3| {
        color(a, &name("first color"), span)?;
        color(b, &name("second color"), span)
    };
    match &t.pattern {
        Pattern::Checker { a, b } | Pattern::Stripes { a, b } => two(*a, *b),
        Pattern::Gradient { direction, map: m } => {
            if !(direction.is_finite() && direction.length_squared() > 0.0) {
                return Err(invalid(
                    span,
                    name("gradient direction must be a finite, non-zero vector"),
                    "no direction",
                    "e.g. `gradient <0, 1, 0>`",
                ));
            }
            map(m)
        }
        Pattern::Noise { map: m, octaves: n } => {
            octaves(*n)?;
            map(m)
        }
        Pattern::Marble {
            map: m,
            turbulence: x,
            octaves: n,
        }
        | Pattern::Wood {
            map: m,
            turbulence: x,
            octaves: n,
        } => {
            octaves(*n)?;
            turbulence(*x)?;
            map(m)
        }
        Pattern::Brick {
            brick,
            mortar,
            size,
            mortar_width,
        } => {
            two(*brick, *mortar)?;
            if !(size.is_finite() && size.min_element() > 0.0) {
                return Err(invalid(
                    span,
                    name("brick size must have positive, finite components"),
                    "out of range",
                    "e.g. `size <0.2, 0.075, 0.1>`",
                ));
            }
            if !(mortar_width.is_finite() && *mortar_width > 0.0) {
                return Err(invalid(
                    span,
                    name(&format!(
                        "mortar width {} is out of range",
                        fmt(*mortar_width)
                    )),
                    "out of range",
                    "use a positive, finite width, e.g. 0.01",
                ));
            }
            Ok(())
        }
        // An image's pixels are looked up within its stated size (black where it holds fewer).
        Pattern::Image { .. } => Ok(()),
    }
}

/// At least two entries, positions in [0, 1] in ascending order, colours in range (as the
/// language's `color_map` builds them).
fn color_map(m: &ColorMap, what: &str, span: Span) -> Result<(), Diagnostic> {
    let bad = |message: String| {
        Err(invalid(
            span,
            message,
            "bad color map",
            "give at least two entries `(position, colour)` sorted by position in [0, 1]",
        ))
    };
    if m.0.len() < 2 {
        return bad(format!("{what} has {} entries, fewer than two", m.0.len()));
    }
    for (k, (p, c)) in m.0.iter().enumerate() {
        if !(0.0..=1.0).contains(p) {
            return bad(format!("{what}'s position {} is not in [0, 1]", fmt(*p)));
        }
        if k > 0 && *p < m.0[k - 1].0 {
            return bad(format!("{what}'s positions are not in ascending order"));
        }
        if let Some(why) = color_problem(*c) {
            return bad(format!("{what}'s colour at {} {why}", fmt(*p)));
        }
    }
    Ok(())
}
