//! Random and mutated scene text never panics, hangs or overflows the stack.

use proptest::prelude::*;
use std::sync::atomic::AtomicBool;

use sppm_lang::EvalOptions;
use sppm_lang::internals::eval::load_source;
use sppm_lang::internals::render::{RenderOptions, render};

const SEED_SCENE: &str = include_str!("../../examples/cornell.scn");

const TOKENS: &[&str] = &[
    "sphere",
    "{",
    "}",
    "<",
    ">",
    ",",
    "(",
    ")",
    "[",
    "]",
    "#declare",
    "#macro",
    "#end",
    "#if",
    "#while",
    "#for",
    "#local",
    "X",
    "M",
    "=",
    "1",
    "-2.5",
    "0",
    "rgb",
    "material",
    "diffuse",
    "translate",
    "union",
    "quad",
    "+",
    "*",
    "/",
    "-",
    "&&",
    "!",
    "radius",
    "settings",
    "camera",
    "\"a.png\"",
    "texture",
    "checker",
    "revolve",
    "profile",
    "bezier",
    "area_light",
    "radiance",
    "M(",
    "X)",
    "1e308",
    "// c\n",
    "/*",
    "*/",
    "\n",
];

fn options() -> EvalOptions {
    EvalOptions {
        max_iterations: 200,
        max_depth: 32,
        max_objects: 10_000,
        max_steps: 1_000_000,
        ..EvalOptions::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    #[test]
    fn token_soup_does_not_panic(idx in prop::collection::vec(0..TOKENS.len(), 0..60)) {
        let text: Vec<&str> = idx.iter().map(|&i| TOKENS[i]).collect();
        let loaded = load_source("soup.scn", &text.join(" "), &options());
        // Either a scene or at least one error.
        prop_assert!(loaded.scene.is_some() || loaded.has_errors());
    }

    #[test]
    fn mutated_scene_does_not_panic(cuts in prop::collection::vec((0usize..2000, 0usize..TOKENS.len(), 0u8..3), 1..6)) {
        let mut text = SEED_SCENE.to_string();
        for (pos, tok, kind) in cuts {
            let mut p = pos % (text.len() + 1);
            while !text.is_char_boundary(p) { p -= 1; }
            match kind {
                0 => text.insert_str(p, TOKENS[tok]),
                1 => { let mut e = (p + tok).min(text.len()); while !text.is_char_boundary(e) { e -= 1; } text.replace_range(p..e, ""); }
                _ => text.insert(p, ' '),
            }
        }
        let loaded = load_source("mutated.scn", &text, &options());
        prop_assert!(loaded.scene.is_some() || loaded.has_errors());
        // Rendering diagnostics never panics either.
        let _ = sppm_lang::render_plain(&loaded.sources, &loaded.diagnostics, 80);
        // An accepted mutant renders (tiny), or prepare refuses it with a message: no panic,
        // no NaN in the image.
        if let Some(mut scene) = loaded.scene.filter(|_| !loaded.diagnostics.iter().any(|d| d.is_error())) {
            scene.settings.resolution = (16, 16);
            let options = RenderOptions {
                iterations: Some(1),
                photons: Some(500),
                threads: Some(1),
                ..RenderOptions::default()
            };
            let cancel = AtomicBool::new(false);
            match render(&scene, &options, &cancel, &mut |_| {}) {
                Ok(out) => prop_assert!(
                    out.image.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())),
                    "non-finite pixel in a render of:\n{}", text
                ),
                Err(e) => prop_assert!(!e.message.is_empty()),
            }
        }
    }
}

#[test]
fn exponential_recursion_is_bounded() {
    let text = "#macro T(N) sphere { <0,0,0>, 1 } #if (N > 0) T(N-1) T(N-1) #end #end T(30)";
    let loaded = load_source("exp.scn", text, &options());
    assert!(loaded.has_errors());
    assert!(
        loaded.diagnostics[0]
            .message
            .contains("more than 10000 objects"),
        "{:?}",
        loaded.diagnostics[0]
    );
}

#[test]
fn deep_recursion_with_big_limit_does_not_overflow() {
    let text = "#macro D(N) #if (N > 0) D(N - 1) #end #end D(20000)";
    let opts = EvalOptions {
        max_depth: 30_000,
        ..EvalOptions::default()
    };
    let loaded = load_source("deep.scn", text, &opts);
    assert!(!loaded.has_errors(), "{:?}", loaded.diagnostics);
}
