//! The standard library: scene files built into the binary, included as `std/NAME.scn`
//! before any file of that name is looked for on disk.

/// `(include path, text)` of every standard file.
pub(crate) const FILES: &[(&str, &str)] = &[
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
        _ if file.ends_with(".inc") => {
            "POV-Ray's include files are not available here; the built-in ones are \
             `std/colors.scn` and `std/materials.scn`"
        }
        _ => return None,
    })
}
