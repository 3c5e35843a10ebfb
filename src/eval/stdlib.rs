//! The standard library: scene files built into the binary, included as `std/NAME.scn`
//! before any file of that name is looked for on disk.

/// `(include path, text)` of every standard file.
pub const FILES: &[(&str, &str)] = &[
    ("std/colors.scn", include_str!("stdlib/colors.scn")),
    ("std/materials.scn", include_str!("stdlib/materials.scn")),
];

/// The text of a standard file, by the path an `#include` names.
pub(crate) fn get(path: &str) -> Option<&'static str> {
    FILES.iter().find(|(p, _)| *p == path).map(|(_, t)| *t)
}

/// The standard file that declares `name`, if one does.
pub(crate) fn declaring(name: &str) -> Option<&'static str> {
    FILES
        .iter()
        .find(|(_, text)| {
            text.lines().any(|l| {
                l.strip_prefix("#declare ")
                    .and_then(|rest| rest.strip_prefix(name))
                    .is_some_and(|rest| rest.starts_with([' ', '=']))
            })
        })
        .map(|(p, _)| *p)
}

/// What a POV-Ray include file is here: the standard file to include instead, or why there is
/// none.
pub(crate) fn povray_include(name: &str) -> Option<&'static str> {
    let file = name.rsplit(['/', '\\']).next().unwrap_or(name);
    Some(match file {
        "colors.inc" => {
            "named colours are `#include \"std/colors.scn\"` here (the same names, linear RGB)"
        }
        "glass.inc" | "metals.inc" | "finish.inc" | "textures.inc" | "golds.inc" | "woods.inc"
        | "stones.inc" | "stones1.inc" | "stones2.inc" => {
            "common materials (glasses with measured IORs, metals, diffuse albedos) are \
             `#include \"std/materials.scn\"` here"
        }
        "rand.inc" => {
            "its `RRand`, `VRand`, `VRand_In_Sphere`, `VRand_On_Sphere` and `Rand_Normal` are \
             built in here (with `seed` and `rand`): remove the `#include`"
        }
        _ if POVRAY_INCLUDES.contains(&file) => {
            "POV-Ray's include files are not available here; the built-in ones are \
             `std/colors.scn` and `std/materials.scn`"
        }
        _ => return None,
    })
}

/// The other include files POV-Ray 3.7 installs. Any other `.inc` is the scene's own file.
const POVRAY_INCLUDES: &[&str] = &[
    "arrays.inc",
    "chars.inc",
    "consts.inc",
    "debug.inc",
    "functions.inc",
    "glass_old.inc",
    "logo.inc",
    "makegrass.inc",
    "math.inc",
    "meshmaker.inc",
    "rad_def.inc",
    "rand.inc",
    "screen.inc",
    "shapes.inc",
    "shapes2.inc",
    "shapes3.inc",
    "shapes_old.inc",
    "shapesq.inc",
    "skies.inc",
    "stage1.inc",
    "stars.inc",
    "stdcam.inc",
    "stdinc.inc",
    "stoneold.inc",
    "strings.inc",
    "sunpos.inc",
    "transforms.inc",
    "woodmaps.inc",
];

#[cfg(test)]
mod tests {
    use super::povray_include;

    #[test]
    fn only_povray_s_own_include_files_get_the_povray_hint() {
        for name in [
            "colors.inc",
            "metals.inc",
            "shapes.inc",
            "../povray/skies.inc",
        ] {
            assert!(povray_include(name).is_some(), "{name}");
        }
        for name in ["walls.inc", "scene/parts.inc", "shapes.scn"] {
            assert_eq!(povray_include(name), None, "{name}");
        }
    }
}
