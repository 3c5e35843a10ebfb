//! Glossy surfaces against an independent reference: `tools/reference/glossy.scn` (rough metal
//! floor and a rough copper sphere, `roughness 0.25`, lit by a rectangle and a small sphere)
//! rendered by Mitsuba 3 (`tools/reference/glossy.py`, `glossy.exr`, the model mapping in
//! `tools/reference/README.md`). Our path tracer and SPPM must converge to it: the image mean
//! within 1 %, and no fireflies: the 99.99th percentile of the per-pixel error shrinks from N to
//! 4N iterations, over the whole image (where the directly seen lights' edges dominate it) and
//! over the pixels away from them (the reference and its 8 neighbours below 2: the glossy
//! reflections and the walls they light).

use std::path::Path;
use std::sync::atomic::AtomicBool;

use sppm_lang::EvalOptions;
use sppm_lang::film::Image;
use sppm_lang::render::{RenderOptions, render};
use sppm_lang::scene::{ColorSpace, Integrator, load_image};

struct Checkpoint {
    iterations: u32,
    mean_ratio: f64,
    p9999: f64,
    p9999_off_lights: f64,
}

/// The 99.99th percentile of `errors` (sorted in place).
fn p9999(errors: &mut [f64]) -> f64 {
    errors.sort_by(f64::total_cmp);
    errors[((errors.len() - 1) as f64 * 0.9999).round() as usize]
}

/// Renders the scene with `integrator` and measures the image at `n` and `4n` iterations.
fn checkpoints(integrator: Integrator, n: u32, photons: u64) -> Vec<Checkpoint> {
    let reference = load_image(Path::new("tools/reference/glossy.exr"), ColorSpace::Linear)
        .expect("tools/reference/glossy.exr loads");
    let loaded = sppm_lang::load_file(
        Path::new("tools/reference/glossy.scn"),
        &EvalOptions::default(),
    )
    .expect("glossy.scn reads");
    let mut scene = loaded.scene.expect("glossy.scn evaluates");
    scene.settings.integrator = integrator;
    assert_eq!(
        scene.settings.resolution,
        (reference.width, reference.height)
    );
    let opts = RenderOptions {
        iterations: Some(4 * n),
        photons: Some(photons),
        seed: Some(11),
        ..Default::default()
    };
    let ref_mean = reference
        .pixels
        .iter()
        .map(|p| p.iter().map(|&v| f64::from(v)).sum::<f64>())
        .sum::<f64>();
    // Pixels away from the directly seen lights: the reference there and at the 8 neighbours
    // is below 2.
    let (w, h) = (reference.width as i64, reference.height as i64);
    let value = |x: i64, y: i64| {
        let p = reference.pixels[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize];
        (p[0] + p[1] + p[2]) / 3.0
    };
    let off_lights: Vec<bool> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| (-1..=1).all(|dy| (-1..=1).all(|dx| value(x + dx, y + dy) < 2.0)))
        .collect();
    let measure = |img: &Image, iterations: u32| {
        let errors: Vec<f64> = img
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, b)| (0..3).map(|c| (a[c] - f64::from(b[c])).abs()).sum::<f64>() / 3.0)
            .collect();
        let mut away: Vec<f64> = errors
            .iter()
            .zip(&off_lights)
            .filter(|(_, off)| **off)
            .map(|(e, _)| *e)
            .collect();
        let mean = img
            .pixels
            .iter()
            .map(|p| p.iter().sum::<f64>())
            .sum::<f64>();
        Checkpoint {
            iterations,
            mean_ratio: mean / ref_mean,
            p9999: p9999(&mut errors.clone()),
            p9999_off_lights: p9999(&mut away),
        }
    };
    let mut out = Vec::new();
    let result = render(&scene, &opts, &AtomicBool::new(false), &mut |p| {
        if p.iteration == n {
            out.push(measure(&p.image(), n));
        }
    })
    .expect("renders");
    out.push(measure(&result.image, 4 * n));
    for c in &out {
        println!(
            "{integrator:?} {} iterations: mean / reference {:.4}, 99.99th percentile error \
             {:.3}, away from the lights {:.3}",
            c.iterations, c.mean_ratio, c.p9999, c.p9999_off_lights
        );
    }
    out
}

fn check(integrator: Integrator, n: u32, photons: u64) {
    let c = checkpoints(integrator, n, photons);
    let (first, last) = (&c[0], &c[1]);
    assert!(
        (last.mean_ratio - 1.0).abs() < 0.01,
        "{integrator:?}: mean {:.4} of the reference's",
        last.mean_ratio
    );
    for (what, a, b) in [
        ("whole image", first.p9999, last.p9999),
        (
            "away from the lights",
            first.p9999_off_lights,
            last.p9999_off_lights,
        ),
    ] {
        assert!(
            b < a,
            "{integrator:?}, {what}: 99.99th percentile error {a:.3} at {} iterations, {b:.3} \
             at {}",
            first.iterations,
            last.iterations
        );
    }
}

#[test]
fn path_tracing_converges_to_the_mitsuba_reference() {
    check(Integrator::Path, 16, 0);
}

#[test]
fn sppm_converges_to_the_mitsuba_reference() {
    check(Integrator::Sppm, 8, 100_000);
}
