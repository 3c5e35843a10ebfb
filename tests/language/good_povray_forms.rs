//! POV-Ray's forms the language accepts as POV-Ray reads them: vectors without commas, its
//! colour-map entries, and its string functions. The expected strings are what POV-Ray 3.7.0
//! prints for the same expressions (checked with Debian's `povray`, `#debug` of each).

use crate::common;

use common::{debug, load, render_text};
use glam::DVec3;
use sppm_lang::EvalOptions;
use sppm_lang::internals::eval::load_source;
use sppm_lang::internals::scene::*;

/// The `#debug` messages of `text`, in order.
fn debug_lines(text: &str) -> Vec<String> {
    debug(&load(text))
}

/// Each `(expression, shown)`: `#debug expression` shows `shown`.
fn check_shown(cases: &[(&str, &str)]) {
    let text: String = cases
        .iter()
        .map(|(e, _)| format!("#debug {e}\n"))
        .chain(["sphere { <0, 0, 0>, 1 }\n".to_string()])
        .collect();
    let shown = debug_lines(&text);
    assert_eq!(shown.len(), cases.len(), "{shown:?}");
    for ((e, want), got) in cases.iter().zip(&shown) {
        assert_eq!(got, want, "#debug {e}");
    }
}

/// A component is as long an expression as reads: a blank-separated `-` or `+` joins its two
/// sides, as POV-Ray 3.7 reads `<1 -2 3>` (as `<-1, 3>`).
#[test]
fn vectors_without_commas() {
    check_shown(&[
        ("<47.2 33 40.6>", "<47.2, 33, 40.6>"),
        ("<1 -2 3>", "<-1, 3>"),
        ("<1 - 2 3>", "<-1, 3>"),
        ("<1 +2 3>", "<3, 3>"),
        ("<1 (2) 3>", "<1, 2, 3>"),
        ("<1 2*3 4>", "<1, 6, 4>"),
        ("<1, 2 3,>", "<1, 2, 3>"),
        ("<1 x.x 3>", "<1, 1, 3>"),
        ("<1 2>", "<1, 2>"),
    ]);
    let l = load("sphere { <0 1 2> 0.5 } #declare C = <1 2 3 4 5>; #debug str(C[4])");
    let s = l.scene.as_ref().unwrap();
    let ShapeDecl::Sphere { center, radius } = s.objects[0].shape else {
        panic!("not a sphere")
    };
    assert_eq!((center, radius), (DVec3::new(0.0, 1.0, 2.0), 0.5));
    assert_eq!(l.diagnostics.last().unwrap().message, "5");
}

fn gradient_map(text: &str) -> Vec<(f64, DVec3)> {
    let l = load(text);
    let s = l.scene.unwrap();
    let Pattern::Gradient { map, .. } = &s.textures[0].pattern else {
        panic!("not a gradient: {:?}", s.textures[0].pattern)
    };
    map.0.clone()
}

/// POV-Ray's colour-map entries: `color`/`colour` before a colour, no commas, the range form
/// `[a b color A color B]` (the same as `[a A] [b B]`), and `colour_map`.
#[test]
fn povray_color_map_entries() {
    let plain = gradient_map(
        "sphere { <0, 0, 0>, 1 material { diffuse texture { gradient y color_map {
           [0, rgb <1, 0, 0>] [0.5, rgb <0, 0, 1>] [0.75, rgb 0.5] [1, rgb <0, 1, 0>] } } } }",
    );
    assert_eq!(plain.len(), 4);
    for form in [
        "color_map { [0.0 0.5 color rgb <1,0,0> color rgb <0,0,1>] [0.75 colour rgb 0.5] \
         [1 color <0 1 0>] }",
        "colour_map { [0 rgb <1,0,0>] [0.5, color rgb <0,0,1>] [0.75 rgb 0.5] \
         [1, <0, 1, 0>] }",
        "color_map { [0, 0.5, rgb <1,0,0>, rgb <0,0,1>] [0.75 rgb 0.5] [1 Green] }",
    ] {
        let text = format!(
            "#declare Green = rgb <0, 1, 0>;
             sphere {{ <0, 0, 0>, 1 material {{ diffuse texture {{ gradient y {form} }} }} }}"
        );
        assert_eq!(gradient_map(&text), plain, "{form}");
    }
}

#[test]
fn string_functions_write_what_povray_writes() {
    check_shown(&[
        // str(x, width, decimals): C's `%*.*f`; a negative width pads with zeros.
        ("str(3.14159, 0, 2)", "3.14"),
        ("str(3.14159, 8, 2)", "    3.14"),
        ("str(3.14159, -8, 2)", "00003.14"),
        ("str(-3.14159, -8, 2)", "-0003.14"),
        ("str(1/3, 0, -1)", "0.333333"),
        ("str(2, 0, -1)", "2.000000"),
        ("str(12345.678, 3, 0)", "12346"),
        ("str(2.5, 0, 0)", "2"),
        ("str(3.5, 0, 0)", "4"),
        ("str(-42, -6, 0)", "-00042"),
        ("str(1, 1.9, 2.9)", "1.00"),
        // One argument: as `#debug` writes the number.
        ("str(0.1 + 0.2)", "0.3"),
        ("vstr(3, <1, 2, 3>, \", \", 0, 1)", "1.0, 2.0, 3.0"),
        ("vstr(2, <1, 2, 3>, \", \", 0, 1)", "1.0, 2.0"),
        ("vstr(4, <1, 2, 3>, \", \", 0, 1)", "1.0, 2.0, 3.0, 0.0"),
        (
            "vstr(5, <1, 2, 3, 4, 5>, \",\", 4, 1)",
            " 1.0, 2.0, 3.0, 4.0, 5.0",
        ),
        ("vstr(2, <0.25, 7>, \"/\", -5, 2)", "00.25/07.00"),
        ("concat(\"a\")", "a"),
        ("concat(\"a\", \"bc\", str(1), \"\")", "abc1"),
        ("substr(\"hello\", 2, 3)", "ell"),
        ("substr(\"hello\", 6, 0)", ""),
        ("substr(\"héllo\", 2, 1)", "é"),
        ("str(strlen(\"hello\"))", "5"),
        ("str(strlen(\"héllo\"))", "5"),
        ("chr(65) + chr(97)", "Aa"),
        ("chr(233)", "é"),
        ("str(asc(\"A\"))", "65"),
        ("str(asc(\"\"))", "0"),
        ("strupr(\"abc\") + strlwr(\"ABC\")", "ABCabc"),
        ("str(val(\"3.5e2\"))", "350"),
        ("str(val(\"  12abc\"))", "12"),
        ("str(val(\"-.5x\"))", "-0.5"),
        ("str(val(\"1e\"))", "1"),
        ("str(val(\"abc\"))", "0"),
        ("str(val(\"\"))", "0"),
    ]);
}

/// A string `str` pads to a large width costs its length in steps, as a joined string does:
/// a loop of them runs out of budget instead of building gigabytes.
#[test]
fn wide_strings_cost_their_length() {
    let text = "#for (I, 1, 1000) #declare S = str(I, 100000, 0); #end sphere { <0, 0, 0>, 1 }";
    let options = EvalOptions {
        max_steps: 1_000_000,
        ..EvalOptions::default()
    };
    let l = load_source("wide.scn", text, &options);
    assert!(l.has_errors(), "{:?}", l.diagnostics);
    assert!(
        l.diagnostics[0]
            .message
            .starts_with("the evaluation took more than"),
        "{}",
        l.diagnostics[0].message
    );
    // The same loop with a narrow width fits the budget.
    let l = load_source("narrow.scn", &text.replace("100000", "10"), &options);
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
}

/// User functions as POV-Ray writes them: named parameters or the implicit x, y, z, the
/// function language's maths, constants captured when the function is defined, calls of
/// earlier functions, and calls wherever a number stands.
#[test]
fn user_functions_compute_where_numbers_stand() {
    let shown = debug_lines(
        "#declare K = 2;
         #declare F = function(a, b) { a * K + b };
         #declare K = 100;
         #declare Len = function { sqrt(x*x + y*y + z*z) };
         #declare G = function(t) { F(t, 1) * 2 + Len(t, 0, 0) };
         #declare S = function(a) { select(a, -1, 1) + select(a, 10, 20, 30) };
         #declare M = function(a, b) { mod(a, b) + pow(a, 2) + min(a, b, 0) + max(a, b) };
         #declare C = function(a) { (a > 1 ? 5 : 7) + (a == 3) + atan2(0, -1) / pi + abs(-a) };
         #declare H = function(u) { div(u, 2) + int(-u / 2) + floor(u / 2) + ceil(u / 2) };
         #debug str(F(3, 4), 0, 3)
         #debug str(Len(3, 4, 12), 0, 3)
         #debug str(G(3), 0, 3)
         #debug str(S(-2), 0, 0)
         #debug str(S(0), 0, 0)
         #debug str(S(2), 0, 0)
         #debug str(M(7, 3), 0, 3)
         #debug str(C(3), 0, 3)
         #debug str(C(1), 0, 3)
         #debug str(H(7), 0, 0)
         sphere { <F(1, 0), 0, 0>, Len(0, 0.5, 0) }",
    );
    assert_eq!(
        shown,
        [
            "10.000", "13.000", "17.000", "9", "21", "31", "57.000", "10.000", "9.000", "7"
        ]
    );
}

/// A function declared in a macro with `#local` sees the macro's arguments as constants; the
/// sphere's radius and position come from function calls.
#[test]
fn functions_in_macros_and_objects() {
    let l = load(
        "#macro Scaled(S) #local F = function(a) { a * S }; F(2) #end
         #declare Half = function(v) { v / 2 };
         sphere { <Scaled(3), Half(4), 0>, Half(1) }
         #debug str(Scaled(5), 0, 1)",
    );
    let o = &l.scene.as_ref().unwrap().objects[0];
    let ShapeDecl::Sphere { center, radius } = o.shape else {
        panic!("{:?}", o.shape)
    };
    let c = o.transform.transform_point3(center);
    assert!((c - DVec3::new(6.0, 2.0, 0.0)).length() < 1e-12, "{c}");
    assert!((radius * o.transform.matrix3.x_axis.length() - 0.5).abs() < 1e-12);
}

/// `function { pattern { ... } }`: the pattern's value at (x, y, z), 0 or 1 for checker,
/// the sawtooth for gradient, with the block's transforms.
#[test]
fn pattern_functions_give_the_pattern_value() {
    let shown = debug_lines(
        "#declare P = function { pattern { checker } };
         #declare Q = function { pattern { checker scale 2 } };
         #declare R = function { pattern { gradient x } };
         #declare B = function { pattern { brick size <1, 1, 1> mortar 0.2 } };
         #declare N = function { pattern { noise octaves 3 } };
         #declare T = function(a, b, c) { P(a, b, c) * 10 + R(a, 0, 0) };
         #debug str(P(0.5, 0.5, 0.5), 0, 0)
         #debug str(P(1.5, 0.5, 0.5), 0, 0)
         #debug str(Q(1.5, 0.5, 0.5), 0, 0)
         #debug str(R(2.25, 7, 7), 0, 2)
         #debug str(B(0.5, 0.5, 0.25), 0, 0)
         #debug str(B(0.5, 0.02, 0.25), 0, 0)
         #debug str(T(1.25, 0.5, 0.5), 0, 2)
         #declare V = N(0.3, 0.6, 0.9);
         #if (V >= 0 & V <= 1 & V != N(1.3, 0.6, 0.9)) #debug \"noise in [0, 1]\" #end",
    );
    assert_eq!(
        shown,
        ["0", "1", "0", "0.25", "1", "0", "10.25", "noise in [0, 1]"]
    );
}

/// The image of `text` rendered with the scene's own settings (seed, iterations, integrator).
fn render_image(text: &str) -> sppm_lang::Image {
    render_text(
        text,
        &sppm_lang::internals::render::RenderOptions::default(),
    )
    .image
}

/// The largest difference of one channel of one pixel between two images of the same size.
fn max_difference(a: &sppm_lang::Image, b: &sppm_lang::Image) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f64::max)
}

/// A POV-Ray scene as POV-Ray writes it (left-handed: x to the right of a camera looking along
/// +z): objects off the axis, a box turned about all three axes, a checker floor and a
/// gradient on the box (procedural patterns, which mirror by hand only with the texture),
/// a triangle, a mirror ball and a light to one side. `extra` goes into `settings`,
/// `camera` into the camera.
fn povray_scene(extra: &str, camera: &str) -> String {
    format!(
        "settings {{ resolution <40, 30> iterations 2 seed 5 integrator whitted {extra} }}
         camera {{ location <1.5, 2, -5> look_at <0.3, 0.6, 0> fov 45 {camera} }}
         light {{ <3, 4, -2> intensity 60 }}
         plane {{ y, 0 material {{ diffuse texture {{
             checker rgb 0.8, rgb <0.1, 0.3, 0.1> scale 0.7 }} }} }}
         box {{ <-0.5, 0, -0.5>, <0.5, 1, 0.5> rotate <10, 30, 20> translate <1.2, 0.2, 0.5>
                material {{ diffuse texture {{ gradient x
                    color_map {{ [0, rgb <1, 0, 0>] [1, rgb <0, 0, 1>] }} scale 0.4 }} }} }}
         sphere {{ <-1, 0.6, 0.3>, 0.6 material {{ mirror rgb 0.8 }} }}
         triangle {{ <-2.5, 0, 1>, <-0.8, 2, 1.5>, <0.2, 0.3, 2>
                     material {{ diffuse rgb <0.2, 0.4, 0.8> }} }}"
    )
}

/// The same scene mirrored by hand into right-handed coordinates: every x negated, the angles
/// of the rotations about y and z negated, two vertices of the triangle exchanged (its facing
/// side), and `scale <-1, 1, 1>` after each pattern's transforms (a checker and a gradient are
/// not symmetric about x = 0).
const HAND_MIRRORED: &str = "
    settings { resolution <40, 30> iterations 2 seed 5 integrator whitted }
    camera { location <-1.5, 2, -5> look_at <-0.3, 0.6, 0> fov 45 }
    light { <-3, 4, -2> intensity 60 }
    plane { y, 0 material { diffuse texture {
        checker rgb 0.8, rgb <0.1, 0.3, 0.1> scale 0.7 scale <-1, 1, 1> } } }
    box { <-0.5, 0, -0.5>, <0.5, 1, 0.5> rotate <10, -30, -20> translate <-1.2, 0.2, 0.5>
          material { diffuse texture { gradient x
              color_map { [0, rgb <1, 0, 0>] [1, rgb <0, 0, 1>] } scale 0.4 scale <-1, 1, 1> } } }
    sphere { <1, 0.6, 0.3>, 0.6 material { mirror rgb 0.8 } }
    triangle { <2.5, 0, 1>, <-0.2, 0.3, 2>, <0.8, 2, 1.5>
               material { diffuse rgb <0.2, 0.4, 0.8> } }";

/// `settings { handedness left }` renders a POV-Ray scene's numbers as the hand-mirrored
/// right-handed twin renders: the same picture, pixel for pixel, with the same seed (the
/// camera's rays are exact mirror images, so only rounding could differ: within 1e-6).
/// Unmirrored, the same numbers give another picture.
#[test]
fn handedness_left_renders_the_hand_mirrored_twin() {
    let left = render_image(&povray_scene("handedness left", ""));
    let twin = render_image(HAND_MIRRORED);
    let d = max_difference(&left, &twin);
    assert!(d <= 1e-6, "left-handed vs hand-mirrored: {d}");
    let right = render_image(&povray_scene("", ""));
    let d = max_difference(&left, &right);
    assert!(d > 0.1, "mirroring changed nothing: {d}");
}

/// A camera `right` says which way the picture faces for itself, as in POV-Ray: `right <-1.33,
/// 0, 0>` (POV-Ray's right-handed camera) is not mirrored again under `handedness left`, and
/// `right <1.33, 0, 0>` (POV-Ray's default) gives the left-handed picture without the setting.
#[test]
fn a_camera_right_vector_sets_the_handedness_once() {
    let native = render_image(&povray_scene("", ""));
    let right_handed = render_image(&povray_scene("handedness left", "right <-1.33, 0, 0>"));
    assert_eq!(max_difference(&native, &right_handed), 0.0);
    let left = render_image(&povray_scene("handedness left", ""));
    let pov_default = render_image(&povray_scene("", "right x*4/3"));
    assert_eq!(max_difference(&left, &pov_default), 0.0);
    let right_left = render_image(&povray_scene("handedness right", "right -x*4/3"));
    assert_eq!(max_difference(&native, &right_left), 0.0);
}

/// The roughness here of a POV-Ray highlight of exponent `e` (`specular`: 1 / roughness,
/// `phong_size n`: about 4n): Walter et al.'s Beckmann alpha sqrt(2 / (e + 2)), alpha being
/// roughness² here (docs/povray.md, "Finishes").
fn roughness_of_exponent(e: f64) -> f64 {
    (2.0 / (e + 2.0)).sqrt().sqrt()
}

/// The coat ior whose head-on reflection is POV-Ray's `reflection f`.
fn ior_of_reflection(f: f64) -> f64 {
    (1.0 + f.sqrt()) / (1.0 - f.sqrt())
}

/// The standard library's POV-Ray names: finish.inc's finishes are coats whose roughness and
/// ior follow the documented rule from finish.inc's own numbers (to the two decimals written),
/// an override gives one its colour, and the metals are the measured conductors.
#[test]
fn povray_named_materials_follow_the_finish_rule() {
    let names = [
        ("Dull", 1.0 / 0.15, 0.04),
        ("Shiny", 1.0 / 0.001, 0.04),
        ("Glossy", 1.0 / 0.0001, 0.13),
        ("Phong_Dull", 4.0 * 1.0, 0.04),
        ("Phong_Shiny", 4.0 * 200.0, 0.04),
        ("Phong_Glossy", 4.0 * 300.0, 0.13),
    ];
    let objects: String = names
        .iter()
        .map(|(n, _, _)| format!("sphere {{ <0, 0, 0>, 1 material {{ {n} }} }}\n"))
        .collect();
    let l = load(&format!(
        "#include \"std/materials.scn\"
         {objects}
         sphere {{ <0, 0, 0>, 1 material {{ Shiny coated rgb <0.6, 0, 0> }} }}
         sphere {{ <0, 0, 0>, 1 material {{ Gold_Satin }} }}
         sphere {{ <0, 0, 0>, 1 material {{ Gold_Metal }} }}
         sphere {{ <0, 0, 0>, 1 material {{ Glass }} }}"
    ));
    assert!(l.diagnostics.is_empty(), "{:?}", l.diagnostics);
    let s = l.scene.unwrap();
    let m = |i: usize| s.material(s.objects[i].material).clone();
    for (i, (name, e, f)) in names.iter().enumerate() {
        let Material::Coated {
            albedo: ColorParam::Const(albedo),
            ior,
            roughness: ScalarParam::Const(r),
        } = m(i)
        else {
            panic!("{name}: {:?}", m(i))
        };
        assert_eq!(albedo, DVec3::splat(0.6), "{name}");
        assert!(
            (r - roughness_of_exponent(*e)).abs() < 0.006,
            "{name}: roughness {r}"
        );
        assert!(
            (ior - ior_of_reflection(*f)).abs() < 0.006,
            "{name}: ior {ior}"
        );
    }
    let n = names.len();
    let Material::Coated { albedo, ior, .. } = m(n) else {
        panic!("{:?}", m(n))
    };
    assert_eq!(albedo, ColorParam::Const(DVec3::new(0.6, 0.0, 0.0)));
    assert_eq!(ior, 1.5);
    let au = metals::metal("Au").unwrap();
    for (i, want) in [(n + 1, 0.15), (n + 2, roughness_of_exponent(4.0 * 80.0))] {
        let Material::Conductor { eta, k, roughness } = m(i) else {
            panic!("{:?}", m(i))
        };
        assert_eq!((eta, k), (DVec3::from(au.eta), DVec3::from(au.k)));
        assert!((roughness - want).abs() < 0.006, "roughness {roughness}");
    }
    assert!(matches!(m(n + 3), Material::Glass { ior, .. } if ior == 1.5));
}

/// The material and the warnings of `sphere { ... material { <mat> } }`.
fn material_of(mat: &str) -> (Material, Vec<String>) {
    let l = load(&format!("sphere {{ <0, 0, 0>, 1 material {{ {mat} }} }}"));
    let warnings = l.diagnostics.iter().map(|d| d.message.clone()).collect();
    let s = l.scene.unwrap();
    (s.material(s.objects[0].material).clone(), warnings)
}

/// POV-Ray's `rgbf`, `rgbt`, `rgbft`, `filter` and `transmit` on a colour material: at least
/// half the light let through makes it a glass of index 1 tinted by filter · colour +
/// transmit, with a warning that says so; less is dropped, with a warning; none is no change.
#[test]
fn povray_filter_and_transmit_become_glass() {
    let glass = |tint: DVec3| Material::Glass {
        ior: 1.0,
        absorb: ColorParam::Const(DVec3::ZERO),
        tint,
        roughness: ScalarParam::Const(0.0),
    };
    for (mat, tint) in [
        (
            "diffuse rgbf <1, 0.5, 0.5, 0.9>",
            DVec3::new(0.9, 0.45, 0.45),
        ),
        (
            "diffuse rgb <1, 0.5, 0.5> filter 0.9",
            DVec3::new(0.9, 0.45, 0.45),
        ),
        ("coated rgbt <1, 0, 0, 0.7>", DVec3::splat(0.7)),
        ("glossy rgb <1, 0, 0> transmit 0.7", DVec3::splat(0.7)),
        (
            "diffuse rgbft <1, 0.5, 0, 0.4, 0.2>",
            DVec3::new(0.6, 0.4, 0.2),
        ),
        ("mirror rgbf 1", DVec3::ONE),
        // The property wins over the colour's component.
        ("diffuse rgbf <1, 1, 1, 0.2> filter 0.8", DVec3::splat(0.8)),
    ] {
        let (m, warnings) = material_of(mat);
        let want = glass(tint);
        let close = match (&m, &want) {
            (Material::Glass { tint: a, ior, .. }, Material::Glass { tint: b, .. }) => {
                *ior == 1.0 && (*a - *b).abs().max_element() < 1e-12
            }
            _ => false,
        };
        assert!(close, "{mat}: {m:?}");
        assert_eq!(warnings.len(), 1, "{mat}: {warnings:?}");
        assert!(
            warnings[0].contains("makes this a glass"),
            "{mat}: {warnings:?}"
        );
    }
    let (m, warnings) = material_of("diffuse rgb <1, 0, 0> transmit 0.2");
    assert!(matches!(m, Material::Diffuse { .. }), "{m:?}");
    assert!(warnings[0].contains("dropped"), "{warnings:?}");
    let (m, warnings) = material_of("diffuse rgbf <1, 0, 0, 0>");
    assert_eq!(
        m,
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::X)
        }
    );
    assert!(warnings.is_empty(), "{warnings:?}");
}
