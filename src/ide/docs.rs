//! One line about each kind of block and each directive, and the section of the language
//! reference (docs/language.md) that tells the rest: what hover shows for a keyword.

/// The language reference, relative to the repository.
pub const REFERENCE: &str = "docs/language.md";

/// `(block, one line, section anchor)`. A test checks that every kind of block the evaluator
/// knows has its line.
const BLOCKS: &[(&str, &str, &str)] = &[
    ("sphere", "`sphere { <center>, radius }`", "objects"),
    (
        "plane",
        "`plane { <normal>, offset }`: the points with dot(n, p) = offset",
        "objects",
    ),
    (
        "quad",
        "`quad { <corner>, <edge_u>, <edge_v> }`: a parallelogram",
        "objects",
    ),
    ("box", "`box { <corner1>, <corner2> }`", "objects"),
    (
        "cylinder",
        "`cylinder { <base>, <cap>, radius [open] }`",
        "objects",
    ),
    (
        "cone",
        "`cone { <base>, base_radius, <cap>, cap_radius [open] }`",
        "objects",
    ),
    (
        "torus",
        "`torus { major, minor }` about the y axis",
        "objects",
    ),
    ("disk", "`disk { <center>, <normal>, radius }`", "objects"),
    ("triangle", "`triangle { <a>, <b>, <c> }`", "objects"),
    (
        "mesh",
        "`mesh { \"file.obj\" }`: a triangle mesh from an OBJ file",
        "objects",
    ),
    (
        "revolve",
        "`revolve { profile bezier { ... } }`: a surface of revolution",
        "revolve",
    ),
    (
        "prism",
        "`prism { h1, h2, N, <x, z>... }`: a shape swept along y",
        "prism",
    ),
    (
        "superellipsoid",
        "`superellipsoid { <e, n> }`",
        "superellipsoid",
    ),
    (
        "sphere_sweep",
        "`sphere_sweep { linear_spline | cubic_spline | b_spline N, <c1>, r1, ... }`",
        "sphere-sweep",
    ),
    (
        "blob",
        "`blob { threshold t sphere { <c>, r, strength s } ... }`: spheres and capsules of density",
        "blob",
    ),
    (
        "isosurface",
        "`isosurface { function { f(x, y, z) } contained_by { box { ... } } }`: where f meets the threshold",
        "isosurface",
    ),
    (
        "contained_by",
        "`contained_by { box { <a>, <b> } }`: an isosurface's container (a box or a sphere)",
        "isosurface",
    ),
    (
        "height_field",
        "`height_field { png \"h.png\" smooth water_level w }`: a terrain over the unit square",
        "height-field",
    ),
    (
        "text",
        "`text { ttf \"font.ttf\" \"string\" thickness, offset }`: letters extruded along z",
        "text",
    ),
    (
        "bezier_patch",
        "`bezier_patch { 16 points }`: a bicubic patch",
        "objects",
    ),
    (
        "bezier_mesh",
        "`bezier_mesh { 16·k points }`: k bicubic patches",
        "objects",
    ),
    (
        "union",
        "`union { objects... }`: a group; transforms and material apply to all",
        "objects",
    ),
    (
        "group",
        "`group { objects... }`: the same as `union`",
        "objects",
    ),
    (
        "object",
        "`object { Declared transforms material }`: a declared object placed",
        "objects",
    ),
    (
        "area_light",
        "`area_light { <shape> radiance <color> [two_sided] }`: an emitting shape",
        "objects",
    ),
    (
        "merge",
        "`merge { objects... }`: CSG union without inner surfaces",
        "csg",
    ),
    (
        "intersection",
        "`intersection { objects... }`: CSG, inside all",
        "csg",
    ),
    (
        "difference",
        "`difference { first, others... }`: CSG, the first minus the others",
        "csg",
    ),
    (
        "material",
        "`material { diffuse | mirror | glass | glossy | conductor | coated | blend ... }`",
        "materials",
    ),
    (
        "texture",
        "`texture { pattern [options] [color_map { ... }] }`: a colour that varies",
        "textures",
    ),
    (
        "normal",
        "`normal { pattern amount }`: bumps on a material's surface",
        "bumps-and-normal-maps",
    ),
    (
        "bump_map",
        "`bump_map { png \"height.png\" }`: bumps from an image",
        "bumps-and-normal-maps",
    ),
    (
        "color_map",
        "`color_map { [pos, color] ... }`: a pattern's colours",
        "textures",
    ),
    (
        "bezier",
        "`bezier { points }`: a revolve's profile of Bézier segments",
        "revolve",
    ),
    (
        "spline",
        "`spline { points }`: a revolve's profile through its points",
        "revolve",
    ),
    (
        "settings",
        "`settings { resolution W, H iterations N ... }`: how the scene renders",
        "settings",
    ),
    (
        "camera",
        "`camera { location <v> look_at <v> fov deg ... }`",
        "camera",
    ),
    (
        "light",
        "`light { <position> intensity <color> }`: a point light",
        "lights",
    ),
    (
        "spotlight",
        "`spotlight { <position> point_at <target> intensity <color> ... }`",
        "lights",
    ),
    (
        "environment",
        "`environment { image \"sky.hdr\" ... }`: light from every direction",
        "background",
    ),
];

/// `(directive, one line)`; all are in the section "Directives".
pub const DIRECTIVES: &[(&str, &str)] = &[
    ("declare", "`#declare Name = value`: binds a global name"),
    (
        "local",
        "`#local Name = value`: binds in the current macro or included file",
    ),
    ("if", "`#if (c) ... #elif (c) ... #else ... #end`"),
    ("elif", "`#elif (c)`: the next condition of an `#if`"),
    ("else", "`#else`: the branch taken when no condition held"),
    (
        "end",
        "`#end`: ends `#if`, `#while`, `#for`, `#macro`, `#switch`, `#ifdef`",
    ),
    ("while", "`#while (c) ... #end`"),
    ("for", "`#for (I, from, to [, step]) ... #end` (inclusive)"),
    (
        "macro",
        "`#macro Name(A, B) ... #end`: its body stands where it is called",
    ),
    (
        "include",
        "`#include \"file.scn\"`: relative to this file; `std/...` is built in",
    ),
    (
        "ifdef",
        "`#ifdef (Name) ... [#else ...] #end`: whether a name is declared",
    ),
    (
        "ifndef",
        "`#ifndef (Name) ... [#else ...] #end`: whether a name is not declared",
    ),
    ("undef", "`#undef Name`: removes a declaration"),
    (
        "switch",
        "`#switch (v) #case (a) ... #range (lo, hi) ... #else ... #end`",
    ),
    ("case", "`#case (v)`: a clause of a `#switch`"),
    ("range", "`#range (lo, hi)`: a clause of a `#switch`"),
    (
        "break",
        "`#break`: leaves the innermost `#switch`, `#while` or `#for`",
    ),
    ("debug", "`#debug expr`: a note when the scene is evaluated"),
    (
        "warning",
        "`#warning expr`: a warning when the scene is evaluated",
    ),
    ("error", "`#error expr`: an error that stops the evaluation"),
];

/// The line about a kind of block and its section's anchor.
pub fn block(name: &str) -> Option<(&'static str, &'static str)> {
    let name = if name == "colour_map" {
        "color_map"
    } else {
        name
    };
    BLOCKS
        .iter()
        .find(|(b, _, _)| *b == name)
        .map(|(_, line, anchor)| (*line, *anchor))
}

/// The line about a directive (the word without its `#`).
pub fn directive(word: &str) -> Option<&'static str> {
    DIRECTIVES.iter().find(|(d, _)| *d == word).map(|(_, l)| *l)
}

/// A markdown link to a section of the language reference.
pub fn link(anchor: &str) -> String {
    format!("[{REFERENCE}#{anchor}]({REFERENCE}#{anchor})")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_block_the_evaluator_knows_has_its_line() {
        for b in crate::eval::block_names() {
            assert!(block(b).is_some(), "no line for `{b}`");
        }
        assert_eq!(BLOCKS.len(), crate::eval::block_names().count());
    }

    #[test]
    fn every_anchor_is_a_section_of_the_reference() {
        let reference = std::fs::read_to_string(crate::repo_root().join(REFERENCE)).unwrap();
        let anchors: Vec<String> = reference
            .lines()
            .filter_map(|l| l.strip_prefix("## ").or_else(|| l.strip_prefix("### ")))
            .map(|h| h.to_lowercase().replace(' ', "-"))
            .collect();
        for (_, _, a) in BLOCKS {
            assert!(anchors.iter().any(|x| x == a), "no section `{a}`");
        }
        assert!(anchors.iter().any(|x| x == "directives"));
    }
}
