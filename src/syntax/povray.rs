//! POV-Ray spellings and their sppm-lang form: one table that the diagnostics consult when a
//! name, block, directive or property is unknown (docs/povray.md is the same mapping for
//! readers).

/// One POV-Ray spelling. `context` limits it to the inside of one kind of block (`"camera"`);
/// `None` applies anywhere.
pub struct PovSpelling {
    pub word: &'static str,
    pub context: Option<&'static str>,
    /// What to write here instead, as a sentence for a diagnostic's help.
    pub hint: &'static str,
}

/// POV-Ray's area-light options that have no counterpart.
const AREA_LIGHT_OPTIONS: &str = "POV-Ray's area-light options (`jitter`, `circular`, `orient`, \
     `adaptive`) are not needed here: an `area_light { quad { ... } radiance ... }` is sampled \
     over its whole surface; remove it";

const fn pov(word: &'static str, hint: &'static str) -> PovSpelling {
    PovSpelling {
        word,
        context: None,
        hint,
    }
}

const fn pov_in(context: &'static str, word: &'static str, hint: &'static str) -> PovSpelling {
    PovSpelling {
        word,
        context: Some(context),
        hint,
    }
}

/// A light's `color` (or `colour`).
const LIGHT_COLOR: &str = "POV-Ray's light colour `color C` is `intensity C` here, in W/sr and \
     falling off with the squared distance d (POV-Ray's lights do not fade): `intensity` π·d² \
     times the colour gives POV-Ray's brightness at distance d";

/// The table, context-bound entries first (they win over a general one of the same word).
pub const POVRAY_SPELLINGS: &[PovSpelling] = &[
    pov_in(
        "camera",
        "angle",
        "POV-Ray's camera `angle` (horizontal, degrees) is `fov` here: the vertical field of view \
         in degrees, e.g. `fov 40`",
    ),
    pov_in(
        "camera",
        "direction",
        "POV-Ray's camera `direction` is `look_at <point>` and `fov degrees` here",
    ),
    pov_in("camera", "sky", "POV-Ray's camera `sky` is `up <v>` here"),
    pov_in(
        "camera",
        "perspective",
        "the camera is always a perspective (pinhole or thin-lens) camera here: remove `perspective`",
    ),
    pov_in(
        "spotlight",
        "radius",
        "POV-Ray's spotlight `radius` (the cone of full intensity) is `falloff` here, and its \
         `falloff` (the outer cone) is `angle` here: `angle a falloff f` with f ≤ a, half-angles \
         in degrees",
    ),
    pov_in(
        "spotlight",
        "tightness",
        "POV-Ray's `tightness` has no counterpart: the intensity is full inside `falloff` and \
         fades to nothing at `angle`; remove `tightness`",
    ),
    pov_in(
        "light",
        "fade_distance",
        "lights always fade with the squared distance here (physically); remove `fade_distance` \
         and `fade_power`",
    ),
    pov_in(
        "light",
        "fade_power",
        "lights always fade with the squared distance here (physically); remove `fade_distance` \
         and `fade_power`",
    ),
    pov_in(
        "light",
        "shadowless",
        "every light casts shadows here; remove `shadowless`",
    ),
    pov_in(
        "light",
        "parallel",
        "there are no parallel (directional) lights here: a `light` far away, or an \
         `environment`, comes close; remove `parallel`",
    ),
    pov_in("light", "color", LIGHT_COLOR),
    pov_in("light", "colour", LIGHT_COLOR),
    pov(
        "light_source",
        "POV-Ray's `light_source { <pos> color ... }` is `light { <pos> intensity rgb <...> }` here \
         (intensity in W/sr, falling off with the squared distance d, where POV-Ray's lights do \
         not fade: intensity π·d²·c gives POV-Ray's colour c at distance d), or \
         `spotlight { <pos> point_at <target> intensity ... }`",
    ),
    pov(
        "pigment",
        "POV-Ray's `pigment { color ... }` is the colour of a material here: \
         `material { diffuse rgb <...> }` (a `texture { ... }` may stand for the colour)",
    ),
    pov(
        "finish",
        "POV-Ray's `finish { ... }` is the kind of material here: pigment times `diffuse` is \
         `material { diffuse c }`; with `specular`/`phong` or a small `reflection` a coat, \
         `coated c [ior n] roughness r`; `metallic` a metal, `conductor \"Au\" roughness r`; \
         `reflection 1` a `mirror`; docs/povray.md (Finishes) gives the numbers, and \
         `#include \"std/materials.scn\"` declares finish.inc's `Dull`, `Shiny`, `Glossy`",
    ),
    pov(
        "normal",
        "POV-Ray's `normal { ... }` goes inside the material here: `material { diffuse \
         rgb <...> normal { bumps 0.5 scale 0.1 } }` (also dents, wrinkles, ripples, waves, a \
         `texture { ... }` as a height, `bump_map { png \"h.png\" bump_size 2 }`, \
         `normal_map \"n.png\"`); docs/povray.md (Normals)",
    ),
    pov(
        "interior",
        "POV-Ray's `interior { ior n }` is `material { glass ior n }` here, its filter colour \
         `tint rgb <...>` (absorption, POV-Ray's `fade_color`: `absorb rgb <...>`)",
    ),
    pov(
        "color",
        "POV-Ray's `color rgb <r, g, b>` is `rgb <r, g, b>` here: leave out `color`",
    ),
    pov(
        "colour",
        "POV-Ray's `colour rgb <r, g, b>` is `rgb <r, g, b>` here: leave out `colour`",
    ),
    pov(
        "background",
        "POV-Ray's `background { color ... }` is `backdrop rgb <r, g, b>` here (no braces): \
         seen where rays leave the scene, lighting nothing; `background rgb <...>` here is a sky \
         that also lights the scene",
    ),
    pov(
        "global_settings",
        "POV-Ray's `global_settings { ... }` is `settings { ... }` here (resolution, iterations, \
         photons, integrator, ...)",
    ),
    pov(
        "#version",
        "POV-Ray's `#version` is not needed here: remove it",
    ),
    pov(
        "array",
        "POV-Ray's `array[3] { a, b, c }` is `[a, b, c]` here; index it as `A[0]`",
    ),
    pov(
        "reflection",
        "POV-Ray's `finish { reflection f }` over a pigment is a coat here: `material { coated \
         c ior n }` with n = (1 + √f) / (1 − √f) (0.04 is ior 1.5); `reflection 1` is \
         `material { mirror rgb <...> }`; a metal `conductor \"Au\"`",
    ),
    pov(
        "metallic",
        "POV-Ray's `finish { metallic ... }` is a metal here: `material { conductor \"Au\" \
         roughness r }` (measured Ag, Al, Au, Cr, Cu, brass, ...) or `conductor reflectance \
         rgb <...>`; `#include \"std/materials.scn\"` has `Gold_Metal`, `Polished_Chrome`, ...",
    ),
    pov(
        "phong",
        "POV-Ray's highlight `phong p phong_size n` is a rough coat here: `material { coated c \
         roughness r }` with r = (2 / (4n + 2))^¼ (phong_size 40 gives 0.33); on a metal \
         `conductor \"Au\" roughness r`",
    ),
    pov(
        "ambient",
        "there is no ambient term here: light comes from lights, the sky and other surfaces; \
         remove `ambient` (a glowing surface, `ambient 1 diffuse 0`, is `area_light { <shape> \
         radiance rgb <...> }`)",
    ),
    pov(
        "phong_size",
        "POV-Ray's `phong_size n` is a coat's roughness here: `material { coated c roughness r }` \
         with r = (2 / (4n + 2))^¼ (40 gives 0.33, 200 gives 0.22)",
    ),
    pov(
        "brilliance",
        "POV-Ray's `brilliance` has no counterpart: diffuse reflection is Lambertian here, and a \
         metal's look comes from `conductor`; remove it",
    ),
    pov(
        "emission",
        "an emitting surface is `area_light { <shape> radiance rgb <...> }` here",
    ),
    pov(
        "sky_sphere",
        "POV-Ray's `sky_sphere { pigment { gradient y color_map { ... } } }` is `background \
         texture { gradient y color_map { ... } }` here (a sky that lights the scene, as with \
         POV-Ray's radiosity); an image sky is `environment { image \"sky.hdr\" }`",
    ),
    pov(
        "radiosity",
        "global illumination is always on here (the integrator of `settings { integrator ... }`); \
         remove `radiosity`",
    ),
    pov(
        "lathe",
        "POV-Ray's `lathe` and `sor` are `revolve { profile spline { <r, h>, ... } }` here",
    ),
    pov(
        "sor",
        "POV-Ray's `lathe` and `sor` are `revolve { profile spline { <r, h>, ... } }` here",
    ),
    pov(
        "bicubic_patch",
        "POV-Ray's `bicubic_patch` is `bezier_patch { 16 points }` here",
    ),
    pov(
        "mesh2",
        "meshes are read from OBJ files here: `mesh { \"file.obj\" }`",
    ),
    pov(
        "no_shadow",
        "every object casts shadows here; remove `no_shadow`",
    ),
    pov(
        "hollow",
        "`hollow` is not needed here (there is no participating media); remove it",
    ),
    pov(
        "photons",
        "caustics are always photon-mapped here; remove POV-Ray's `photons { ... }` (the number \
         of photons per iteration is `settings { photons n }`)",
    ),
    pov(
        "image_map",
        "POV-Ray's `image_map { png \"f.png\" }` is `texture { image \"f.png\" }` here, standing \
         for a colour: `material { diffuse texture { image \"f.png\" } }`",
    ),
    pov(
        "smooth_triangle",
        "POV-Ray's `smooth_triangle` has no counterpart: write `triangle { <a>, <b>, <c> }` (flat), \
         or load a mesh with vertex normals: `mesh { \"file.obj\" }`",
    ),
    pov(
        "polygon",
        "POV-Ray's `polygon` has no counterpart: build it from `triangle { <a>, <b>, <c> }`s or a \
         `quad { <corner>, <edge_u>, <edge_v> }`",
    ),
    pov(
        "fog",
        "there are no participating media here (`fog`, `media`, `atmosphere`): remove it",
    ),
    pov(
        "media",
        "there are no participating media here (`fog`, `media`, `atmosphere`): remove it",
    ),
    pov(
        "atmosphere",
        "there are no participating media here (`fog`, `media`, `atmosphere`): remove it",
    ),
    pov(
        "fisheye",
        "the camera is a perspective or `orthographic` (pinhole or thin-lens) camera here: \
         remove `fisheye`",
    ),
    pov(
        "panoramic",
        "the camera is always a perspective (pinhole or thin-lens) camera here: remove `panoramic`",
    ),
    pov(
        "bounded_by",
        "bounds are automatic here: remove `bounded_by`",
    ),
    pov(
        "clipped_by",
        "POV-Ray's `clipped_by` has no counterpart; `intersection { A B }` keeps what is inside \
         both (closing the cut)",
    ),
    pov(
        "dimension_size",
        "POV-Ray's `dimension_size(A, 1)` is `len(A)` here",
    ),
    pov(
        "int",
        "POV-Ray's `int(x)` (towards zero) is `floor(x)` for x ≥ 0 here (`ceil(x)` below 0)",
    ),
    pov(
        "div",
        "POV-Ray's `div(a, b)` is `floor(a / b)` for a / b ≥ 0 here",
    ),
    pov(
        "vaxis_rotate",
        "there is no `vaxis_rotate` here: `vrotate(v, <ax, ay, az>)` turns about x, then y, then z",
    ),
    pov("#elseif", "POV-Ray's `#elseif` is `#elif (condition)` here"),
    pov_in("light", "jitter", AREA_LIGHT_OPTIONS),
    pov_in(
        "light",
        "circular",
        "POV-Ray's area-light options (`jitter`, `circular`, `orient`, `adaptive`) are not \
         needed here: a round area light is `area_light { disk { ... } radiance ... }`; remove it",
    ),
    pov_in(
        "light",
        "orient",
        "POV-Ray's area-light options (`jitter`, `circular`, `orient`, `adaptive`) are not \
         needed here: an `area_light { sphere { ... } }` is sampled by the cone it subtends; \
         remove it",
    ),
    pov_in("light", "adaptive", AREA_LIGHT_OPTIONS),
    pov_in(
        "light",
        "tightness",
        "POV-Ray's `tightness` has no counterpart (and a `light` shines alike in every \
         direction; a cone of light is `spotlight { ... angle a falloff f }`); remove it",
    ),
    pov_in(
        "camera",
        "focal_point",
        "POV-Ray's `focal_point <p>` is `focus_distance d` here: the distance from the camera \
         to the plane in focus (with `aperture`)",
    ),
    pov(
        "max_trace_level",
        "POV-Ray's `max_trace_level` is `settings { max_depth N }` here",
    ),
    pov(
        "assumed_gamma",
        "there is no `assumed_gamma` here: colours are linear, images are read and written as \
         sRGB; remove it",
    ),
    pov(
        "looks_like",
        "POV-Ray's `looks_like` has no counterpart: a visible emitter is an \
         `area_light { sphere { ... } radiance ... }` here; remove it",
    ),
    pov(
        "no_image",
        "POV-Ray's `no_image` has no counterpart: every object is seen, reflected and casts \
         shadows here; remove it",
    ),
    pov(
        "no_reflection",
        "POV-Ray's `no_reflection` has no counterpart: every object is seen, reflected and \
         casts shadows here; remove it",
    ),
    pov(
        "double_illuminate",
        "POV-Ray's `double_illuminate` has no counterpart: light through thin surfaces is a \
         material's business here; remove it",
    ),
    pov(
        "sturm",
        "every root is isolated robustly here (no `sturm` needed); remove it",
    ),
    pov(
        "#endif",
        "POV-Ray's `#endif` is `#end` here (every block directive closes with `#end`)",
    ),
    pov(
        "#default",
        "POV-Ray's `#default` has no counterpart: an object without a material is diffuse gray 0.5; \
         declare a material and use it: `material { Mine }`",
    ),
];

/// What to write here instead of the POV-Ray spelling `word` (written inside a block of kind
/// `context`, e.g. `"a camera"`, or at the top level); `None` when `word` is no known POV-Ray
/// spelling.
pub fn povray_hint(word: &str, context: &str) -> Option<&'static str> {
    POVRAY_SPELLINGS
        .iter()
        .find(|s| s.word == word && s.context.is_none_or(|c| context.ends_with(c)))
        .map(|s| s.hint)
}
