//! The backdrop (seen by camera rays that escape, directly or through mirrors and glass alone;
//! lights nothing) and the sky that lights (`background rgb`, `background texture { ... }`),
//! in every integrator.

use std::sync::atomic::AtomicBool;

use sppm_lang::EvalOptions;
use sppm_lang::Image;
use sppm_lang::internals::eval::load_source;
use sppm_lang::internals::render::{RenderOptions, render};

const INTEGRATORS: [&str; 5] = ["sppm", "ppm", "photon_map", "path", "whitted"];
const RES: u32 = 32;
const BACKDROP: [f64; 3] = [0.2, 0.4, 0.8];

/// Renders `text` (which sets no resolution or integrator) at `RES` x `RES` with `integrator`.
fn render_text(text: &str, integrator: &str, iterations: u32) -> Image {
    let text = format!(
        "settings {{ resolution <{RES}, {RES}> photons 4000 integrator {integrator} }}\n{text}"
    );
    let l = load_source("sky.scn", &text, &EvalOptions::default());
    let scene = l.scene.unwrap_or_else(|| panic!("{:?}", l.diagnostics));
    let opts = RenderOptions {
        iterations: Some(iterations),
        seed: Some(5),
        ..Default::default()
    };
    render(&scene, &opts, &AtomicBool::new(false), &mut |_| {})
        .unwrap()
        .image
}

/// Camera at height 1 looking along +z over a diffuse floor: the top rows see only the sky,
/// the bottom rows only the floor.
const VIEW: &str = "camera { location <0, 1, -5> look_at <0, 1, 0> fov 40 }\n\
                    plane { y, 0 material { diffuse 0.8 } }\n";
/// A mirror tilted 45 degrees in the middle of the picture: it turns the camera's rays (along
/// +z) straight up, into the sky.
const MIRROR: &str = "quad { <-0.6, 0.4, -0.6>, <1.2, 0, 0>, <0, 1.2, 1.2> \
                      material { mirror rgb 1 } }\n";

fn pixels(xs: std::ops::Range<u32>, ys: std::ops::Range<u32>) -> Vec<(u32, u32)> {
    ys.flat_map(|y| xs.clone().map(move |x| (x, y))).collect()
}
fn sky_pixels() -> Vec<(u32, u32)> {
    pixels(0..RES, 0..4)
}
fn floor_pixels() -> Vec<(u32, u32)> {
    pixels(0..RES, RES - 6..RES)
}
fn mirror_pixels() -> Vec<(u32, u32)> {
    pixels(13..19, 13..19)
}

fn assert_close(img: &Image, at: &[(u32, u32)], want: [f64; 3], tol: f64, what: &str) {
    for &(x, y) in at {
        let c = img.get(x, y);
        for k in 0..3 {
            assert!(
                (c[k] - want[k]).abs() <= tol,
                "{what}: pixel ({x}, {y}) is {c:?}, want {want:?}"
            );
        }
    }
}

/// Under a backdrop and no light, every integrator shows the backdrop where camera rays escape
/// and where a mirror turns them into the sky, and the floor gets nothing from it: the floor's
/// pixels are the same, bit for bit, as without the backdrop (black, except for Whitted's
/// constant ambient term, which stands for indirect light and is not the backdrop's).
#[test]
fn a_backdrop_is_seen_and_lights_nothing_in_every_integrator() {
    let with = format!(
        "{VIEW}{MIRROR}backdrop rgb <{}, {}, {}>\n",
        BACKDROP[0], BACKDROP[1], BACKDROP[2]
    );
    let without = format!("{VIEW}{MIRROR}");
    for integrator in INTEGRATORS {
        let img = render_text(&with, integrator, 4);
        let bare = render_text(&without, integrator, 4);
        assert_close(&img, &sky_pixels(), BACKDROP, 1e-6, integrator);
        assert_close(&img, &mirror_pixels(), BACKDROP, 1e-5, integrator);
        assert_close(&bare, &sky_pixels(), [0.0; 3], 0.0, integrator);
        assert_close(&bare, &mirror_pixels(), [0.0; 3], 0.0, integrator);
        for (x, y) in floor_pixels() {
            assert_eq!(
                img.get(x, y),
                bare.get(x, y),
                "{integrator}: floor ({x}, {y})"
            );
            if integrator != "whitted" {
                assert_eq!(img.get(x, y), [0.0; 3], "{integrator}: floor ({x}, {y})");
            }
        }
    }
}

/// A backdrop over a sky that lights: the floor is lit by the sky exactly as without the
/// backdrop (bit for bit), and the camera sees the backdrop, not the sky. A uniform sky `L`
/// over an infinite floor of albedo `a` gives it radiance `a L` (it sees only the sky), within
/// four standard errors of the floor's mean.
#[test]
fn a_backdrop_hides_the_sky_from_the_camera_but_not_from_the_floor() {
    let sky = "background rgb 1.5\n";
    let backdrop = format!(
        "backdrop rgb <{}, {}, {}>\n",
        BACKDROP[0], BACKDROP[1], BACKDROP[2]
    );
    for integrator in ["path", "sppm"] {
        let img = render_text(&format!("{VIEW}{sky}{backdrop}"), integrator, 16);
        let bare = render_text(&format!("{VIEW}{sky}"), integrator, 16);
        assert_close(&img, &sky_pixels(), BACKDROP, 1e-6, integrator);
        assert_close(&bare, &sky_pixels(), [1.5; 3], 1e-6, integrator);
        for (x, y) in floor_pixels() {
            assert_eq!(
                img.get(x, y),
                bare.get(x, y),
                "{integrator}: floor ({x}, {y})"
            );
        }
        let (mean, se) = floor_mean(&img, 1);
        let want = 0.8 * 1.5;
        println!("{integrator}: floor {mean:.5} ± {se:.5}, want {want}");
        assert!(
            (mean - want).abs() <= 4.0 * se + 1e-5 * want,
            "{integrator}: floor mean {mean} ± {se}, want {want}"
        );
    }
}

/// The floor's mean over its pixels and the standard error of that mean (pixels are
/// independent estimates: each has its own random stream, and the floor under an open sky
/// gets no indirect light, so SPPM's photons add nothing to it).
fn floor_mean(img: &Image, channel: usize) -> (f64, f64) {
    let v: Vec<f64> = floor_pixels()
        .iter()
        .map(|&(x, y)| img.get(x, y)[channel])
        .collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A sky texture lights as its analytic irradiance says. `gradient y` from A (horizon) to B
/// (zenith) is `L = A + (B - A) y` above the horizon, so an upward-facing diffuse floor of
/// albedo `a` reflects `a / π ∫ L cos θ dω = a (A / 3 + 2 B / 3)`. A constant map (A = B) is
/// the white furnace: `a L`. Tolerance: four standard errors of the floor's mean plus the
/// bake's bound (each texel within `slope × π / 256` of the sky it stands for).
#[test]
fn a_gradient_sky_lights_a_floor_as_its_analytic_irradiance() {
    let a = 0.8;
    for (lo, hi) in [(1.0, 1.0), (0.2, 1.1)] {
        let text = format!(
            "{VIEW}background texture {{ gradient y color_map {{ [0, rgb {lo}] [1, rgb {hi}] }} }}\n"
        );
        let want = a * (lo / 3.0 + 2.0 * hi / 3.0);
        let bake = a * (hi - lo) * std::f64::consts::PI / 256.0;
        for (integrator, iterations) in [("path", 64), ("sppm", 32)] {
            let img = render_text(&text, integrator, iterations);
            let (mean, se) = floor_mean(&img, 1);
            let tol = 4.0 * se + bake + 1e-5 * want;
            println!("{integrator} sky {lo}..{hi}: floor {mean:.5} ± {se:.5}, want {want:.5}");
            assert!(
                (mean - want).abs() <= tol,
                "{integrator}: floor mean {mean} want {want} (tolerance {tol})"
            );
        }
    }
}

/// Hostile skies and backdrops are refused with a diagnostic on the value: negative colours,
/// a colour map that is empty or has a negative entry; and a backdrop over a backdrop warns.
#[test]
fn hostile_skies_and_backdrops_get_spanned_diagnostics() {
    let cases = [
        ("backdrop rgb <-1, 0, 0>", "rgb <-1, 0, 0>"),
        ("background rgb <0, -2, 0>", "rgb <0, -2, 0>"),
        (
            "background texture { gradient y color_map { } }",
            "color_map",
        ),
        (
            "backdrop texture { gradient y color_map { [0, rgb -1] [1, rgb 1] } }",
            "rgb -1",
        ),
        ("backdrop rgb <1e300, 0, 0>", "rgb <1e300, 0, 0>"),
        (
            "backdrop sphere { <0, 0, 0>, 1 }",
            "sphere { <0, 0, 0>, 1 }",
        ),
        ("backdrop rgb <0/0, 0, 0>", "0/0"),
        (
            "background texture { image \"missing.png\" }",
            "\"missing.png\"",
        ),
    ];
    for (text, culprit) in cases {
        let l = load_source("h.scn", text, &EvalOptions::default());
        let e = l
            .diagnostics
            .iter()
            .find(|d| d.is_error())
            .unwrap_or_else(|| panic!("no error for {text}"));
        let span = &text[e.span.start as usize..e.span.end as usize];
        println!("{text}: `{span}`: {}", e.message);
        assert!(
            span.contains(culprit) || culprit.contains(span) && !span.is_empty(),
            "{text}: error `{}` at `{span}`",
            e.message
        );
        assert!(l.scene.is_none(), "{text}");
    }
    let l = load_source(
        "w.scn",
        "backdrop rgb 0.1\nbackdrop rgb 0.2\n",
        &EvalOptions::default(),
    );
    assert!(!l.has_errors());
    let w = &l.diagnostics[0];
    assert!(w.message.contains("replaces"), "{}", w.message);
    let text = "backdrop rgb 0.1\nbackdrop rgb 0.2\n";
    assert_eq!(
        &text[w.span.start as usize..w.span.end as usize],
        "backdrop rgb 0.2"
    );
}

/// A scene built through the library gets the same ranges: a NaN or negative backdrop colour
/// and a background or backdrop naming a texture the scene does not have are refused by the
/// render, not drawn.
#[test]
fn hostile_library_skies_are_refused() {
    use glam::DVec3;
    use sppm_lang::internals::scene::{Background, ColorParam, TextureId};
    let l = load_source("ok.scn", VIEW, &EvalOptions::default());
    let base = l.scene.expect("loads");
    let mut cases = Vec::new();
    for c in [DVec3::new(f64::NAN, 0.0, 0.0), DVec3::new(0.0, -1.0, 0.0)] {
        let mut s = base.clone();
        s.backdrop = Some(ColorParam::Const(c));
        cases.push(("backdrop colour", s));
    }
    let mut s = base.clone();
    s.backdrop = Some(ColorParam::Texture(TextureId(7)));
    cases.push(("backdrop texture", s));
    let mut s = base.clone();
    s.background = Background::Texture(TextureId(7));
    cases.push(("background texture", s));
    for (what, scene) in cases {
        let r = render(
            &scene,
            &RenderOptions {
                iterations: Some(1),
                ..Default::default()
            },
            &AtomicBool::new(false),
            &mut |_| {},
        );
        let Err(e) = r else {
            panic!("{what}: rendered");
        };
        assert!(
            e.message.contains("backdrop") || e.message.contains("background"),
            "{what}: {}",
            e.message
        );
    }
}

/// POV-Ray's sky words are answered with their translation: `background { ... }` is a
/// backdrop here, `sky_sphere { pigment { gradient ... } }` a background texture.
#[test]
fn povray_sky_words_get_their_translation() {
    for (text, want) in [
        ("background { color rgb <0.1, 0.2, 0.4> }", "`backdrop rgb"),
        (
            "sky_sphere { pigment { gradient y color_map { [0, rgb 1] [1, rgb 0.5] } } }",
            "`background texture {",
        ),
    ] {
        let l = load_source("pov.scn", text, &EvalOptions::default());
        let help = l
            .diagnostics
            .iter()
            .find(|d| d.is_error())
            .and_then(|d| d.help.clone())
            .unwrap_or_default();
        assert!(help.contains(want), "{text}: {help}");
    }
}

/// A baked sky and a textured backdrop give the same image for any thread count.
#[test]
fn sky_textures_render_the_same_on_any_thread_count() {
    let text = format!(
        "settings {{ resolution <24, 24> photons 3000 }}\n{VIEW}{MIRROR}\
         background texture {{ gradient y color_map {{ [0, rgb 0.3] [1, rgb <0.2, 0.5, 1>] }} }}\n\
         backdrop texture {{ marble color_map {{ [0, rgb 0.1] [1, rgb 0.9] }} }}\n"
    );
    let l = load_source("t.scn", &text, &EvalOptions::default());
    let scene = l.scene.unwrap_or_else(|| panic!("{:?}", l.diagnostics));
    let image = |threads: usize| {
        let opts = RenderOptions {
            iterations: Some(3),
            threads: Some(threads),
            ..Default::default()
        };
        render(&scene, &opts, &AtomicBool::new(false), &mut |_| {})
            .unwrap()
            .image
    };
    let one = image(1);
    assert!(one.mean()[0] > 0.0);
    assert_eq!(one.pixels, image(2).pixels);
}
