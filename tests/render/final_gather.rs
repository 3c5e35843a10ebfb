//! SPPM with final gathering (`final_gather on`): a visible point gathers only the caustic
//! photons, and a gather path brings the rest from the next diffuse surface. Tested where every
//! pixel's value is known: the white furnace (every radiance 1), also with a glass and a mirror
//! ball inside (lossless, so the radiance stays 1 through them), where light reaches the
//! visible points through specular bounces both ways: a path counted by both the caustic
//! photons and the gather path, or by neither, moves the pixels that see or surround the balls.

use crate::common;

use common::*;
use glam::DVec3;
use sppm_lang::Image;
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::scene::{Integrator, Scene};
use std::sync::atomic::AtomicBool;

/// The image mean's relative error (every pixel should be 1) and the worst pixel's.
fn errors(img: &Image) -> (f64, f64) {
    let (mut sum, mut worst, mut n) = (0.0, 0.0f64, 0.0);
    for p in &img.pixels {
        for c in p {
            assert!(c.is_finite() && *c >= 0.0, "{p:?}");
            sum += c;
            worst = worst.max((c - 1.0).abs());
            n += 1.0;
        }
    }
    (sum / n - 1.0, worst)
}

/// The emitting furnace with a glass ball and a mirror ball in front of the camera.
fn furnace_with_balls(res: u32) -> Scene {
    let mut s = furnace_emitting(res);
    let (glass, mirror) = glass_and_mirror(&mut s);
    add_object(
        &mut s,
        sphere(DVec3::new(-0.1, 0.0, 0.6), 0.25),
        glass,
        None,
    );
    add_object(
        &mut s,
        sphere(DVec3::new(0.3, 0.25, 0.55), 0.15),
        mirror,
        None,
    );
    s
}

#[test]
fn final_gathering_keeps_the_furnace_at_one() {
    let mut s = furnace_emitting(16);
    s.settings.final_gather = true;
    let (mean, worst) = errors(&run(&s, 64, 20_000));
    println!("furnace with final gathering: mean rel err {mean:.4}, worst pixel {worst:.4}");
    assert!(mean.abs() < 0.01 && worst < 0.05, "{mean} {worst}");
}

/// The furnace with lossless balls (every radiance still 1), also against the path tracer on
/// the same scene. Measured (seed 1): final gathering +0.16 %, path +0.04 %.
#[test]
fn final_gathering_agrees_with_path_tracing_around_glass_and_mirror_balls() {
    let mut s = furnace_with_balls(24);
    s.settings.final_gather = true;
    let (gathered, worst) = errors(&run(&s, 64, 40_000));
    s.settings.integrator = Some(Integrator::Path);
    let (path, _) = errors(&run(&s, 1024, 0));
    println!("balls: final gathering {gathered:+.4} (worst pixel {worst:.4}), path {path:+.4}");
    assert!(
        gathered.abs() < 0.005 && (gathered - path).abs() < 0.003 && worst < 0.1,
        "{gathered} {path} {worst}"
    );
}

/// `vcm`'s final gather (its merges at a camera path's second vertex, four times as wide, a
/// technique of its own in the weights) in the furnace with the lossless balls, where light
/// reaches the gather's vertices through specular bounces both ways and every radiance is 1:
/// the mean of six seeds' image means within 0.3 % of 1 with and without the gather (their
/// spread is about 0.1 %, so 0.3 % is some seven standard errors). Weights that did not sum to
/// one beside specular vertices would move it. The radius is fixed at 0.1 (the gather's
/// 0.4), where both read within 0.06 %. At the default radius of this 16-pixel image (1.5
/// pixel footprints, about 0.19 at the wall; the gather's four times that, beside balls of
/// radius 0.15 and 0.25) the gather reads -0.29 +- 0.04 % at 256 iterations, and at a fixed
/// 0.2 -0.32 %: a bias of the wide radius near small objects, which shrinks with it (about
/// -0.6 % at 64 iterations, one seed). The light side's re-weighting (`Parts::gathered`) carries too small a share
/// here to show (dropped, the means move by 0.03 % at 0.1): the brute-force test of the
/// weights checks it.
#[test]
fn vcm_with_final_gathering_keeps_the_furnace_with_balls_at_one() {
    let mut s = furnace_with_balls(16);
    s.settings.integrator = Some(Integrator::Vcm);
    s.settings.radius = Some(0.1);
    for gather in [false, true] {
        s.settings.final_gather = gather;
        let means: Vec<f64> = (1..=6u64)
            .map(|seed| {
                let opts = RenderOptions {
                    iterations: Some(256),
                    seed: Some(seed),
                    ..Default::default()
                };
                let out = render(&s, &opts, &AtomicBool::new(false), &mut |_| {}).unwrap();
                errors(&out.image).0
            })
            .collect();
        let mean = means.iter().sum::<f64>() / means.len() as f64;
        println!("balls, vcm, final gather {gather}: mean rel err {mean:+.5} {means:+.5?}");
        assert!(
            mean.abs() < 0.003,
            "final gather {gather}: {mean} {means:?}"
        );
    }
}

/// A caustic that only the split can get wrong: a small spherical light above a glass ball over
/// a diffuse floor, nothing else. The floor under the ball is lit through the glass; with final
/// gathering the caustic photons carry that light, and a gather path that meets the light
/// through the ball must not count it again (or the caustic would double), nor may the
/// caustic photons be lost (or it would vanish). Compared with plain SPPM, on the caustic's
/// pixels and on the whole image.
#[test]
fn a_caustic_is_counted_once_with_final_gathering() {
    let text = r#"
        settings { resolution <32, 32>  seed 1  alpha 0.7 }
        camera { location <0, 1.2, 2.6>  look_at <0, 0.2, 0>  fov 50 }
        area_light { sphere { <0, 2.6, 0>, 0.5 }  radiance rgb <4, 4, 4> }
        quad { <-2, 0, -2>, <4, 0, 0>, <0, 0, 4>  material { diffuse rgb <0.8, 0.8, 0.8> } }
        sphere { <0, 0.55, 0>, 0.5  material { glass ior 1.5 } }
    "#;
    let loaded = sppm_lang::internals::eval::load_source("caustic.scn", text, &Default::default());
    let scene = loaded.scene.expect("the caustic scene loads");
    let mut images = Vec::new();
    for final_gather in [false, true] {
        let mut s = scene.clone();
        s.settings.final_gather = final_gather;
        images.push(run(&s, 48, 100_000));
    }
    // The caustic: the pixels brighter than twice the image mean without final gathering.
    let lum = |p: &[f64; 3]| (p[0] + p[1] + p[2]) / 3.0;
    let base = &images[0];
    let mean_of = |img: &Image, keep: &dyn Fn(usize) -> bool| {
        let v: Vec<f64> = (0..img.pixels.len())
            .filter(|&i| keep(i))
            .map(|i| lum(&img.pixels[i]))
            .collect();
        (v.iter().sum::<f64>() / v.len().max(1) as f64, v.len())
    };
    let all = |_: usize| true;
    let (image_mean, _) = mean_of(base, &all);
    let caustic = |i: usize| lum(&base.pixels[i]) > 2.0 * image_mean;
    let (c0, n) = mean_of(base, &caustic);
    let (c1, _) = mean_of(&images[1], &caustic);
    let (m1, _) = mean_of(&images[1], &all);
    println!(
        "caustic ({n} px): {c0:.4} without, {c1:.4} with final gathering; image {image_mean:.4} / {m1:.4}"
    );
    assert!(n >= 8, "{n} caustic pixels");
    assert!((c1 / c0 - 1.0).abs() < 0.1, "caustic {c0} vs {c1}");
    assert!(
        (m1 / image_mean - 1.0).abs() < 0.05,
        "image {image_mean} vs {m1}"
    );
}
