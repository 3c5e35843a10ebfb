//! Glossy surfaces against an independent reference: `tools/reference/glossy.scn` (rough metal
//! floor and a rough copper sphere, `roughness 0.25`, lit by a rectangle and a small sphere)
//! rendered by Mitsuba 3 (`tools/reference/glossy.py`, `glossy.exr`, the model mapping in
//! `tools/reference/README.md`). Our path tracer and SPPM must converge to it: the image mean
//! within 1 %, and no fireflies: the 99.99th percentile of the per-pixel error shrinks from N to
//! 4N iterations, over the whole image (where the directly seen lights' edges dominate it) and
//! over the pixels away from them (the reference and its 8 neighbours below 2: the glossy
//! reflections and the walls they light).
//!
//! The material sheet reference (`tools/reference/materials.py` writes `materials.scn`, the
//! Mitsuba render `materials.exr`, a per-pixel sphere index `materials.mask.exr` and the
//! spheres' names `materials.labels`): rows of spheres, one material per row (`coated` against
//! Mitsuba's `plastic`/`roughplastic`, named metals against `conductor`/`roughconductor`) at
//! several roughnesses, under a uniform sky and a rectangle light. Each sphere's mean over the
//! pixels well inside it must be within 1 % of Mitsuba's in every channel, for the path tracer
//! (512 samples per pixel) and for SPPM (256 iterations of 200 000 photons), except where the
//! two models are known to differ ([`MODEL_DIFFERS`]), and the 99.99th percentile of the
//! per-pixel error must shrink from N to 4N iterations. The Monte Carlo error of a sphere's
//! mean, from the spread between seeds, is about 0.7 % at 64 samples per pixel and 0.4 % at 256
//! (path and SPPM alike; the reference's own is below 0.1 %): at 64 a correct renderer missed
//! 1 % on a rough copper sphere (1.4 %), hence the sample counts above. Since the coat dims a
//! coloured base at every bounce (its blue is 0.075), 50 000 photons left SPPM's smooth coat
//! 1.4 % low in blue at seed 11 (0.5 % at 200 000). A row added to the script's table is
//! checked here without a change.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use sppm_lang::EvalOptions;
use sppm_lang::Image;
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::scene::{ColorSpace, Integrator, load_image};

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
    let loaded = sppm_lang::internals::eval::load_file(
        Path::new("tools/reference/glossy.scn"),
        &EvalOptions::default(),
    )
    .expect("glossy.scn reads");
    let mut scene = loaded.scene.expect("glossy.scn evaluates");
    scene.settings.integrator = Some(integrator);
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

/// Spheres whose material is not the same function as its Mitsuba counterpart: printed, not
/// held to 1 %. Rough `coated` against `roughplastic` (`nonlinear` true;
/// `tools/reference/coat_terms.py`): the same terms, but Mitsuba's internal reflectance `Ri`
/// is a plain mean over 64 nodes, about 1.6 % below the integral ours takes, so its base
/// light, divided by `1 - c Ri`, is dimmer where the base is bright: predicted +1.1 % in red
/// at roughness 0.2, measured +0.9 % (path) and +1.1 % (SPPM) in red, within 0.3 % in green
/// and blue, shrinking with roughness. Both agree with a random walk through the layer only
/// as well as their `Ri` (docs/measurements.md, "Coated against a random walk").
const MODEL_DIFFERS: [&str; 3] = ["coated 0.2", "coated 0.45", "coated 0.8"];

/// The Mitsuba image, each pixel's sphere index, the spheres' names, the image size.
type MaterialReference = (Vec<[f32; 3]>, Vec<usize>, Vec<String>, (u32, u32));

/// A material sheet's reference: the Mitsuba image, each pixel's sphere (0: none, k + 1: sphere
/// k of `<sheet>.labels`) and the spheres' names.
fn material_reference(sheet: &str) -> MaterialReference {
    let dir = Path::new("tools/reference");
    let reference = load_image(&dir.join(format!("{sheet}.exr")), ColorSpace::Linear)
        .unwrap_or_else(|e| panic!("tools/reference/{sheet}.exr loads: {e:?}"));
    let mask = load_image(&dir.join(format!("{sheet}.mask.exr")), ColorSpace::Linear)
        .unwrap_or_else(|e| panic!("tools/reference/{sheet}.mask.exr loads: {e:?}"));
    assert_eq!(
        (mask.width, mask.height),
        (reference.width, reference.height)
    );
    let labels: Vec<String> = std::fs::read_to_string(dir.join(format!("{sheet}.labels")))
        .unwrap_or_else(|e| panic!("tools/reference/{sheet}.labels reads: {e}"))
        .lines()
        .map(str::to_owned)
        .collect();
    let index: Vec<usize> = mask.pixels.iter().map(|p| p[0].round() as usize).collect();
    assert!(index.iter().all(|&k| k <= labels.len()));
    (
        reference.pixels,
        index,
        labels,
        (reference.width, reference.height),
    )
}

/// Per-sphere mean of each channel over the pixels `index` assigns to it.
fn sphere_means(pixels: &[[f64; 3]], index: &[usize], spheres: usize) -> Vec<[f64; 3]> {
    let mut sum = vec![[0.0f64; 3]; spheres];
    let mut count = vec![0usize; spheres];
    for (p, &k) in pixels.iter().zip(index) {
        if k > 0 {
            for c in 0..3 {
                sum[k - 1][c] += p[c];
            }
            count[k - 1] += 1;
        }
    }
    sum.iter()
        .zip(&count)
        .map(|(s, &n)| {
            assert!(n > 100, "a sphere covers only {n} pixels");
            s.map(|v| v / n as f64)
        })
        .collect()
}

/// Renders the material sheet `sheet` (`tools/reference/<sheet>.scn`) with `integrator` to `4n`
/// iterations, checks that the 99.99th percentile of the per-pixel error, over the whole image
/// and over the spheres' pixels, shrinks from `n` to `4n`, and returns each sphere's label and
/// its mean over Mitsuba's, per channel (printed).
fn sheet_ratios(
    sheet: &str,
    integrator: Integrator,
    n: u32,
    photons: u64,
) -> Vec<(String, [f64; 3])> {
    let (reference, index, labels, size) = material_reference(sheet);
    let loaded = sppm_lang::internals::eval::load_file(
        Path::new(&format!("tools/reference/{sheet}.scn")),
        &EvalOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{sheet}.scn reads: {e:?}"));
    let mut scene = loaded
        .scene
        .unwrap_or_else(|| panic!("{sheet}.scn evaluates"));
    scene.settings.integrator = Some(integrator);
    assert_eq!(scene.settings.resolution, size);
    let opts = RenderOptions {
        iterations: Some(4 * n),
        photons: Some(photons),
        seed: Some(11),
        ..Default::default()
    };
    let reference64: Vec<[f64; 3]> = reference.iter().map(|p| p.map(f64::from)).collect();
    let want = sphere_means(&reference64, &index, labels.len());
    // 99.99th percentiles of the per-pixel error: whole image, spheres' pixels.
    let tails = |img: &Image| {
        let errors: Vec<f64> = img
            .pixels
            .iter()
            .zip(&reference64)
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f64>() / 3.0)
            .collect();
        let mut on: Vec<f64> = errors
            .iter()
            .zip(&index)
            .filter(|(_, k)| **k > 0)
            .map(|(e, _)| *e)
            .collect();
        (p9999(&mut errors.clone()), p9999(&mut on))
    };
    let mut early = None;
    let result = render(&scene, &opts, &AtomicBool::new(false), &mut |p| {
        if p.iteration == n {
            early = Some(tails(&p.image()));
        }
    })
    .expect("renders");
    let late = tails(&result.image);
    let early = early.expect("a progress report at iteration n");
    let got = sphere_means(&result.image.pixels, &index, labels.len());
    let mut out = Vec::new();
    for ((label, g), w) in labels.iter().zip(&got).zip(&want) {
        let ratio = [0, 1, 2].map(|c| g[c] / w[c]);
        println!(
            "{integrator:?} {label:>18}: ours {:.4} {:.4} {:.4}, Mitsuba {:.4} {:.4} {:.4}, \
             ratio {:.4} {:.4} {:.4}",
            g[0], g[1], g[2], w[0], w[1], w[2], ratio[0], ratio[1], ratio[2],
        );
        out.push((label.clone(), ratio));
    }
    println!(
        "{integrator:?} 99.99th percentile error: whole image {:.4} at {n} iterations, {:.4} at \
         {}; spheres {:.4}, {:.4}",
        early.0,
        late.0,
        4 * n,
        early.1,
        late.1
    );
    assert!(
        late.0 < early.0 && late.1 < early.1,
        "{integrator:?}: the 99.99th percentile error did not shrink from {n} to {} \
         iterations: whole image {:.4} -> {:.4}, spheres {:.4} -> {:.4}",
        4 * n,
        early.0,
        late.0,
        early.1,
        late.1
    );
    out
}

/// [`sheet_ratios`], and each sphere's mean within 1 % of Mitsuba's in every channel, except
/// the spheres of [`MODEL_DIFFERS`] (printed only).
fn check_materials(sheet: &str, integrator: Integrator, n: u32, photons: u64) {
    let failures: Vec<String> = sheet_ratios(sheet, integrator, n, photons)
        .into_iter()
        .filter(|(label, ratio)| {
            !MODEL_DIFFERS.contains(&label.as_str())
                && ratio.iter().any(|r| (r - 1.0).abs() >= 0.01)
        })
        .map(|(label, ratio)| format!("{label}: ratio {ratio:.4?}"))
        .collect();
    assert!(
        failures.is_empty(),
        "{integrator:?}: sphere means off Mitsuba's by 1 % or more: {failures:?}"
    );
}

#[test]
fn materials_path_tracing_matches_mitsuba_per_sphere() {
    check_materials("materials", Integrator::Path, 128, 0);
}

#[test]
fn materials_sppm_matches_mitsuba_per_sphere() {
    check_materials("materials", Integrator::Sppm, 64, 200_000);
}

/// The second sheet: frosted glass (`roughdielectric`, alpha = roughness²), thin glass
/// (`thindielectric`) at four indices and a blend of a diffuse and a rough gold (`blendbsdf`)
/// at four weights, over a striped floor; every sphere held to 1 %.
#[test]
fn glass_and_blend_path_tracing_matches_mitsuba_per_sphere() {
    check_materials("glass_blend", Integrator::Path, 128, 0);
}

/// SPPM on the second sheet needs four times the photons of the first: the sky's photons
/// reach the roughest glass (0.8, whose surface gathers photons) and the mostly diffuse blend
/// through the floor and the other glass, and at 50 000 photons a sphere's mean still moved by
/// 1.2-2.2 % between seeds (1.7 % low and 2.2 % high on the frosted 0.8 at seeds 11 and 5);
/// at 200 000 every sphere of two seeds was within 0.75 % (about a minute on two cores).
#[test]
fn glass_and_blend_sppm_matches_mitsuba_per_sphere() {
    check_materials("glass_blend", Integrator::Sppm, 64, 200_000);
}

/// The bump sheet's mildest amount: the steepest lean on its tiles is atan(0.02 * 2 pi / 0.8)
/// = 9 degrees (the others lean up to 25, 57 and 78 degrees).
const BUMP_MILD: f64 = 0.02;

/// The bump sheet (`tools/reference/materials.py --sheet bumps`): flat tiles of a white-ish
/// diffuse and a rough gold (roughness 0.2), each bumped by the same image height at four
/// amounts, against Mitsuba's `bumpmap` over the same BSDFs. Both lean the normal alike (the
/// same image, bilinear, the same amount); they shade differently. Ours puts the material
/// on one facet of a two-facet microsurface whose mean normal is the surface's: a ray meets
/// the leaned facet, or first the mirror facet across it (a share that grows with the lean,
/// about `sin(lean) tan(view angle)`), and light the leaned facet sends into the surface is
/// mirrored out. Mitsuba shades with the leaned normal alone and drops what then points
/// below the surface. Measured (path, 256 samples; ours over Mitsuba): diffuse 1.003, 1.031,
/// 1.219, 1.958 and gold 1.080, 1.314, 1.894, 1.898 at amounts 0.02, 0.06, 0.2, 0.6. So:
/// - on the mild diffuse tile the models agree within 1 %: a Lambertian facet scatters the
///   same whichever facet the ray met first;
/// - on the mild gold tile within 10 %, not closer: the share of rays that meet the mirror
///   facet first (up to 8 % at a 9 degree lean seen 30 degrees off the normal) leave the
///   gold lobe in another direction, a second highlight that here falls on the light;
/// - on every tile ours is at least Mitsuba's (less 1 % for noise): Mitsuba loses the light
///   its leaned normal sends below the surface, and is black where that normal faces away
///   from the viewer, which ours, keeping the energy, never is.
fn check_bumps(integrator: Integrator, n: u32, photons: u64) {
    let mut failures = Vec::new();
    for (label, ratio) in sheet_ratios("bumps", integrator, n, photons) {
        let amount: f64 = label
            .rsplit(' ')
            .next()
            .and_then(|a| a.parse().ok())
            .unwrap_or_else(|| panic!("bumps.labels: {label} ends in an amount"));
        let mild_tolerance = if label.contains("diffuse") {
            0.01
        } else {
            0.10
        };
        if amount <= BUMP_MILD && ratio.iter().any(|r| (r - 1.0).abs() >= mild_tolerance) {
            failures.push(format!("mild {label}: ratio {ratio:.4?}"));
        }
        if ratio.iter().any(|&r| r < 0.99) {
            failures.push(format!("{label}: ratio {ratio:.4?} below Mitsuba's"));
        }
    }
    assert!(failures.is_empty(), "{integrator:?}: {failures:?}");
}

#[test]
fn bumps_path_tracing_against_mitsuba_bumpmap() {
    check_bumps(Integrator::Path, 128, 0);
}

#[test]
fn bumps_sppm_against_mitsuba_bumpmap() {
    check_bumps(Integrator::Sppm, 64, 200_000);
}
