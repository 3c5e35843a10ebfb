//! The generated 100 000-object scene of the parse benchmark, shared with the test that checks
//! it evaluates to exactly that many objects (`tests/language/good_scenes.rs`).

use std::fmt::Write;

/// A scene of `n` objects: three declared materials, a camera, and a repeating mix of spheres,
/// boxes, cylinders and disks with `rotate`, `translate` and `scale` transforms.
pub fn big_scene(n: usize) -> String {
    scene_text(n, false)
}

/// The same scene in POV-Ray 3.7's language (for the comparison with POV-Ray's parser): the
/// same objects, transforms and declared materials, with POV-Ray's spelling of the materials
/// and the camera, and `disc` for `disk`.
#[allow(dead_code)]
pub fn big_scene_pov(n: usize) -> String {
    scene_text(n, true)
}

fn scene_text(n: usize, pov: bool) -> String {
    let mut s = String::from(if pov {
        "#version 3.7;\n\
         global_settings { assumed_gamma 1 }\n\
         #declare M = material { texture { pigment { color rgb <0.7, 0.7, 0.7> } } }\n\
         #declare G = material { texture { pigment { color rgbf <1, 1, 1, 1> } } interior { ior 1.5 } }\n\
         #declare Red = material { texture { pigment { color rgb <0.8, 0.1, 0.1> } } }\n\
         camera { location <0, 5, -20> look_at <0, 0, 0> angle 40 }\n"
    } else {
        "#declare M = material { diffuse rgb <0.7, 0.7, 0.7> }\n\
         #declare G = material { glass ior 1.5 }\n\
         #declare Red = material { diffuse rgb <0.8, 0.1, 0.1> }\n\
         camera { location <0, 5, -20> look_at <0, 0, 0> fov 40 }\n"
    });
    let disk = if pov { "disc" } else { "disk" };
    let mats = ["M", "G", "Red"];
    for i in 0..n {
        let (x, y, z) = (
            (i % 316) as f64 * 0.1,
            (i % 7) as f64 * 0.05,
            (i / 316) as f64 * 0.1,
        );
        let m = mats[i % 3];
        let _ = match i % 5 {
            0 => writeln!(
                s,
                "sphere {{ <{x:.1}, {y:.2}, {z:.1}>, 0.04 material {{ {m} }} }}"
            ),
            1 => writeln!(
                s,
                "box {{ <{x:.1}, 0, {z:.1}>, <{:.2}, 0.05, {:.2}> material {{ {m} }} rotate <0, {}, 0> }}",
                x + 0.05,
                z + 0.05,
                i % 90
            ),
            2 => writeln!(
                s,
                "cylinder {{ <{x:.1}, 0, {z:.1}>, <{x:.1}, 0.1, {z:.1}>, 0.02 material {{ {m} }} translate <0, {y:.2}, 0> }}"
            ),
            3 => writeln!(
                s,
                "sphere {{ <0, 0, 0>, 0.03 scale <1, 2, 1> translate <{x:.1}, {y:.2}, {z:.1}> material {{ {m} }} }}"
            ),
            _ => writeln!(
                s,
                "{disk} {{ <{x:.1}, 0, {z:.1}>, <0, 1, 0>, 0.03 material {{ {m} }} }}"
            ),
        };
    }
    s
}
