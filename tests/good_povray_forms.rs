//! POV-Ray's forms the language accepts as POV-Ray reads them: vectors without commas, its
//! colour-map entries, and its string functions. The expected strings are what POV-Ray 3.7.0
//! prints for the same expressions (checked with Debian's `povray`, `#debug` of each).

use glam::DVec3;
use sppm_lang::scene::*;
use sppm_lang::{EvalOptions, Loaded, load_source};

fn load(text: &str) -> Loaded {
    let l = load_source("test.scn", text, &EvalOptions::default());
    assert!(
        !l.has_errors(),
        "{}",
        sppm_lang::render_plain(&l.sources, &l.diagnostics, 100)
    );
    l
}

/// The `#debug` messages of `text`, in order.
fn debug_lines(text: &str) -> Vec<String> {
    load(text)
        .diagnostics
        .iter()
        .filter(|d| d.severity == sppm_lang::Severity::Note)
        .map(|d| d.message.clone())
        .collect()
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
    let Shape::Sphere { center, radius } = s.objects[0].shape else {
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
    let Shape::Sphere { center, radius } = o.shape else {
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
