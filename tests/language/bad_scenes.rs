//! Every scene in `tests/bad/` yields spanned diagnostics; the rendered text is snapshotted.
//! Files named `warn_*` must evaluate (warnings only); all others must fail with errors.

use std::path::Path;

use sppm_lang::internals::eval::load_file;
use sppm_lang::{EvalOptions, render_plain};

#[test]
fn bad_scenes_give_spanned_diagnostics() {
    let mut paths: Vec<_> = std::fs::read_dir("tests/bad")
        .expect("tests/bad")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "scn"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 40, "only {} bad scenes", paths.len());
    let options = EvalOptions {
        max_iterations: 1000,
        max_depth: 64,
        ..EvalOptions::default()
    };
    for path in &paths {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let rel = Path::new("tests/bad").join(path.file_name().unwrap());
        let loaded = load_file(&rel, &options).expect("readable");
        assert!(!loaded.diagnostics.is_empty(), "{name}: no diagnostic");
        for d in &loaded.diagnostics {
            assert!(
                loaded.sources.get(d.span.file).is_some(),
                "{name}: diagnostic without a source span: {}",
                d.message
            );
        }
        if name.starts_with("warn_") {
            assert!(!loaded.has_errors(), "{name}: expected warnings only");
            assert!(loaded.scene.is_some());
        } else {
            assert!(loaded.has_errors(), "{name}: expected an error");
            assert!(loaded.scene.is_none());
        }
        let text = render_plain(&loaded.sources, &loaded.diagnostics, 100);
        insta::assert_snapshot!(name, text);
    }
}

/// The first error of `text` (message, help).
fn first_error(text: &str) -> (String, String) {
    let l = sppm_lang::internals::eval::load_source("habit.scn", text, &EvalOptions::default());
    let d = l
        .diagnostics
        .iter()
        .find(|d| d.is_error())
        .unwrap_or_else(|| panic!("no error for {text:?}"));
    (d.message.clone(), d.help.clone().unwrap_or_default())
}

/// POV-Ray habits and near-misses that parsed as something else, or got the wrong advice: a
/// directive's word is a whole word (`#elseif` was `#else` followed by a call `if(...)`, and the
/// scene was accepted), bare POV-Ray words get their spelling here, and `direction -z*2` (a
/// subtraction to the parser) is recognised by its first word; the built-in
/// constants cannot be declared.
#[test]
fn pov_habits_get_their_spelling_here() {
    let cases: [(&str, &str); 23] = [
        (
            "#declare A = 1;\n#if (A == 1) sphere { <0,0,0>, 1 } #elseif (A == 2) box { <0,0,0>, <1,1,1> } #end\n",
            "`#elif (condition)`",
        ),
        ("#if (1) sphere { <0,0,0>, 1 }\n#endif\n", "is `#end` here"),
        (
            "#if (0) sphere { <0,0,0>, 1 } #elsebox { <0,0,0>, <1,1,1> } #end\n",
            "write `#else box`",
        ),
        ("#declareX = 1;\n", "write `#declare X`"),
        (
            "light { <0, 5, 0> intensity 10 shadowless }\n",
            "remove `shadowless`",
        ),
        (
            "camera { location <0, 0, -5> direction -z*2 }\n",
            "`look_at <point>`",
        ),
        (
            "camera { location <0, 0, -5> perspective }\n",
            "perspective",
        ),
        (
            "settings { max_trace_level 5 }\n",
            "`settings { max_depth N }`",
        ),
        ("light { <0, 5, 0> intensity 10 jitter }\n", "area_light"),
        ("#declare M = [[0 0.5] [1 0.25]];\n", "separated by commas"),
        // Built-in constants are not names to declare (POV-Ray refuses them too).
        ("#for (x, 0, 3) #end\n", "choose another name"),
        ("#declare pi = 3;\n", "choose another name"),
        ("#macro M(y) #end\n", "choose another name"),
        ("#ifdef (pi) #end\n#undef pi\n", "always defined"),
        ("settings { seed 9007199254740994 }\n", "up to 2^53"),
        // A string left open: named as such, not "expected an expression".
        (
            "#declare Name = \"abc;\nsphere { <0,0,0>, 1 }\n",
            "cannot span lines",
        ),
        ("#declare P = \"a\\\"b;\n", "cannot span lines"),
        ("#declare C = \"abc\"[0];\n", "not indexed"),
        ("#declare C = <1, 2>.z;\n", "`.x` and `.y`"),
        (
            "camera { location <0, 0, -5> look_at <0, 0, -4.9999999999> aperture 0.1 }\n",
            "at least 1e-9",
        ),
        (
            "sphere { <0, 0, 0>, 1 material { diffuse rgb 1, 0, 0 } }\n",
            "go in angle brackets",
        ),
        // A sign after a space joins two values (POV-Ray reads it so too).
        ("sphere { <0, 1, 0> -0.5 }\n", "`<0, 1, 0>, -0.5`"),
        ("disk { <0, 0, 0> <0, 1, 0> +1 }\n", "adds to it"),
    ];
    for (text, want) in cases {
        let (message, help) = first_error(text);
        assert!(
            help.contains(want),
            "{text:?}: {message} / help: {help} (wanted {want:?})"
        );
        assert!(!help.contains("declare it first"), "{text:?}: {help}");
    }
    // A well-formed `#else` and `#end` still parse, with and without space after them.
    let ok = sppm_lang::internals::eval::load_source(
        "ok.scn",
        "#if (0) sphere { <0,0,0>, 1 } #else sphere { <0,0,0>, 2 } #end\n\
         #if(1)#if(1)sphere { <0,0,0>, 3 }#end#end\n",
        &EvalOptions::default(),
    );
    assert!(!ok.has_errors(), "{:?}", ok.diagnostics);
}

/// Block comments nest, as in POV-Ray; one left open is named as such, and nesting them
/// deeper than the parser's bound is an error, not a stack overflow.
#[test]
fn block_comments_nest() {
    let l = sppm_lang::internals::eval::load_source(
        "c.scn",
        "/* outer /* inner */ still a comment */ sphere { <0, 0, 0>, 1 }\n",
        &EvalOptions::default(),
    );
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
    let (message, _) = first_error("/* outer /* inner */ sphere { <0, 0, 0>, 1 }\n");
    assert!(message.contains("never closed"), "{message}");
    let deep = format!("{} sphere {{ <0, 0, 0>, 1 }}", "/* ".repeat(100_000));
    let (message, _) = first_error(&deep);
    assert!(message.contains("nesting deeper"), "{message}");
}

/// A material property its kind does not use is an error, not silently dropped: `mirror
/// roughness 0.2` is not a blurred mirror, and `diffuse ... specular` is not a highlight. A
/// material that extends a declared one takes the properties of the declared one's kind;
/// `thin` belongs to glass alone, and a thin glass takes neither `absorb` nor `roughness`.
#[test]
fn a_material_property_belongs_to_its_kind() {
    for (body, what, kind) in [
        ("diffuse rgb 0.5 thin", "thin", "diffuse"),
        ("glossy rgb 0.5 thin", "thin", "glossy"),
        ("glass specular rgb 0.1", "specular", "glass"),
        ("diffuse rgb 0.5 specular rgb 0.1", "specular", "diffuse"),
        ("diffuse rgb 0.5 tint rgb 1", "tint", "diffuse"),
        ("mirror roughness 0.2", "roughness", "mirror"),
        ("glossy rgb 0.5 ior 1.5", "ior", "glossy"),
        ("glossy rgb 0.5 absorb rgb 0.1", "absorb", "glossy"),
    ] {
        let text = format!("sphere {{ <0, 0, 0>, 1 material {{ {body} }} }}\n");
        let (message, _) = first_error(&text);
        assert_eq!(
            message,
            format!("`{what}` does not apply to a {kind} material"),
            "{text}"
        );
    }
    for (body, what) in [
        ("glass thin absorb rgb 0.1", "absorb"),
        ("glass absorb rgb 0.1 thin", "absorb"),
        ("glass thin roughness 0.2", "roughness"),
    ] {
        let text = format!("sphere {{ <0, 0, 0>, 1 material {{ {body} }} }}\n");
        let (message, _) = first_error(&text);
        assert!(
            message.starts_with(&format!("`{what}` does not apply to thin glass")),
            "{text}: {message}"
        );
    }
    let declared = "#declare P = material { glass thin }\n\
                    sphere { <0, 0, 0>, 1 material { P absorb rgb 0.1 } }\n";
    assert!(first_error(declared).0.contains("thin glass"));
    let ok = sppm_lang::internals::eval::load_source(
        "ok.scn",
        "#declare G = material { glass ior 1.5 }\n\
         #declare F = material { glass ior 1.5 roughness 0.3 }\n\
         #declare P = material { glass ior 1.5 thin }\n\
         #declare T = texture { checker rgb 0.1, rgb 0.6 }\n\
         sphere { <0, 4, 0>, 1 material { F absorb rgb 0.1 roughness T } }\n\
         sphere { <2, 4, 0>, 1 material { P tint rgb 0.9 } }\n\
         sphere { <4, 4, 0>, 1 material { glass roughness 0 } }\n\
         #declare R = material { glossy rgb 0.5 roughness 0.3 }\n\
         sphere { <0, 0, 0>, 1 material { G ior 1.33 absorb rgb 0.1 tint rgb 0.9 } }\n\
         sphere { <2, 0, 0>, 1 material { R specular rgb 0.1 } }\n\
         sphere { <4, 0, 0>, 1 material { mirror tint rgb 0.9 } }\n",
        &EvalOptions::default(),
    );
    assert!(!ok.has_errors(), "{:?}", ok.diagnostics);
    let (message, _) = first_error(
        "#declare D = material { diffuse rgb 0.5 }\nsphere { <0, 0, 0>, 1 material { D ior 1.5 } }\n",
    );
    assert_eq!(message, "`ior` does not apply to a diffuse material");
}

/// The help for an `up` parallel to the view direction names an axis across it (`up <0, 0, 1>`
/// for a camera looking along z would be refused in turn), and that `up` is accepted.
#[test]
fn a_parallel_up_gets_an_up_that_works() {
    let text = |camera: &str| format!("camera {{ {camera} }}\nsphere {{ <0, 0, 0>, 1 }}\n");
    for (bad, want) in [
        (
            "location <0, 1, 5> look_at <0, 1, 0> up <0, 0, 1>",
            "up <0, 1, 0>",
        ),
        ("location <0, 5, 0> look_at <0, 0, 0>", "up <0, 0, 1>"),
    ] {
        let (message, help) = first_error(&text(bad));
        assert!(message.contains("parallel"), "{bad}: {message}");
        assert!(help.contains(&format!("`{want}`")), "{bad}: {help}");
        let fixed = match bad.find(" up ") {
            Some(i) => format!("{} {want}", &bad[..i]),
            None => format!("{bad} {want}"),
        };
        let l = sppm_lang::internals::eval::load_source(
            "up.scn",
            &text(&fixed),
            &EvalOptions::default(),
        );
        assert!(!l.has_errors(), "{fixed}: {:?}", l.diagnostics);
    }
}

/// "Unused, remove it" only for a name the sources never mention again: one used only in an
/// `#if` branch or a `#while` body not run this time, or in a macro not called, is used there
/// (removing it would break the scene once the condition changes).
#[test]
fn a_name_used_only_where_evaluation_did_not_go_is_not_unused() {
    let unused = |text: &str| -> Vec<String> {
        let l = sppm_lang::internals::eval::load_source("u.scn", text, &EvalOptions::default());
        assert!(!l.has_errors(), "{:?}", l.diagnostics);
        l.diagnostics
            .iter()
            .filter(|d| d.message.starts_with("unused"))
            .map(|d| d.message.clone())
            .collect()
    };
    assert!(unused("#declare A = 1;\n#if (false) #debug str(A) #end\n").is_empty());
    assert!(unused("#declare A = 1;\n#while (false) #debug str(A) #end\n").is_empty());
    // (The macro itself is never called: that one is named.)
    assert_eq!(
        unused("#declare A = 1;\n#macro M() A #end\n"),
        ["unused macro `M`"]
    );
    // Never mentioned again: still named, also beside one that is.
    assert_eq!(
        unused("#declare A = 1;\n#declare B = 2;\n#if (false) #debug str(A) #end\n"),
        ["unused declaration `B`"]
    );
    assert_eq!(
        unused("#declare Alpha = 1;\n"),
        ["unused declaration `Alpha`"]
    );
}

/// Numbers in messages are short (at most 6 significant digits, exponent form when huge): a
/// value of 1e300 is not printed with 301 digits, `0.1 + 0.2` is `0.3`. A literal too large for
/// a number is named as such (not blamed on a division or a power).
#[test]
fn messages_show_numbers_short() {
    let big = format!("1{}", "0".repeat(329));
    let cases: &[(&str, &str)] = &[
        ("settings { max_depth 1e300 }", "found 1e300"),
        ("settings { max_depth 0.1 + 0.2 }", "found 0.3"),
        ("settings { resolution <1e300, 10> }", "found 1e300 x 10"),
        (
            "sphere { <0, 0, 0>, 1 material { diffuse texture { marble turbulence -1e300 } } }",
            "found -1e300",
        ),
        (
            "sphere { <0, 0, 0>, 1 material { diffuse texture { noise octaves 0.1 + 0.2 } } }",
            "found 0.3",
        ),
        (
            "sphere { <0, 0, 0>, 1 material { diffuse texture { gradient <0, 1, 0> color_map { [0, rgb 0] [1e300, rgb 1] } } } }",
            "found 1e300",
        ),
        ("#declare A = ln(-1e300);", "found -1e300"),
        (
            "revolve { profile bezier { <0, 0>, <0.35, 0>, <0.4, 0.3>, <0.15, 0.6> } angle 1e300, 1 }",
            "found 1e300, 1",
        ),
        ("#declare A = asin(1e300);", "found 1e300"),
    ];
    for (text, wanted) in cases {
        let (message, help) = first_error(text);
        assert!(message.contains(wanted), "{text}: {message}");
        assert!(!message.contains("00000000"), "{text}: {message}");
        assert!(!message.contains("0000000000004"), "{text}: {message}");
        assert!(!help.is_empty(), "{text}: no help");
    }
    let (message, help) = first_error(&format!("#declare A = {big};"));
    assert!(message.contains("too large"), "{message}");
    assert!(!help.contains("division"), "{help}");
}
