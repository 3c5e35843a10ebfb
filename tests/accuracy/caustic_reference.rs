//! `tools/reference/caustic.scn` (a glass ball focusing two small sphere lights onto a diffuse
//! floor) against Mitsuba 3 (`tools/reference/caustic.py`, `caustic.exr`, model mapping and
//! the reference's own noise in `tools/reference/README.md`). Two windows: the first light's
//! spot on the floor seen directly (the reference there is Mitsuba's particle tracer), and the
//! second light's spot behind the ball, seen through the ball (Mitsuba's path tracer); the
//! second window stops a row above a pixel holding a reflection of a light in the ball, whose
//! noise would swamp the window's.
//! Each window counts only the pixels of its class in `caustic.mask.exr` (1: every camera ray
//! of the pixel sees the floor or the wall directly; 2: every one meets the ball).

use std::path::Path;
use std::sync::atomic::AtomicBool;

use sppm_lang::EvalOptions;
use sppm_lang::Image;
use sppm_lang::Integrator;
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::scene::{ColorSpace, ImageData, load_image};

/// (x0, y0, x1, y1) half-open, in pixels of the 64x64 image, and the mask class counted: the
/// same as `WINDOWS` in `tools/reference/caustic.py`.
const DIRECT: ((usize, usize, usize, usize), f32) = ((22, 38, 38, 50), 1.0);
const THROUGH: ((usize, usize, usize, usize), f32) = ((34, 3, 58, 13), 2.0);

fn load(name: &str) -> ImageData {
    let path = Path::new("tools/reference").join(name);
    load_image(&path, ColorSpace::Linear).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The sum of all channels over the window's pixels of its class, and their count.
fn window_sum(
    pixel: impl Fn(usize, usize) -> [f64; 3],
    mask: &ImageData,
    ((x0, y0, x1, y1), class): ((usize, usize, usize, usize), f32),
) -> (f64, usize) {
    let (mut sum, mut n) = (0.0, 0);
    for y in y0..y1 {
        for x in x0..x1 {
            if mask.pixels[y * mask.width as usize + x][0] == class {
                sum += pixel(x, y).iter().sum::<f64>();
                n += 1;
            }
        }
    }
    (sum, n)
}

/// Our window mean over the reference's.
fn ratio(img: &Image, window: ((usize, usize, usize, usize), f32)) -> f64 {
    let (reference, mask) = (load("caustic.exr"), load("caustic.mask.exr"));
    assert_eq!((img.width, img.height), (reference.width, reference.height));
    let at = |x: usize, y: usize| reference.pixels[y * reference.width as usize + x].map(f64::from);
    let ours = |x: usize, y: usize| img.get(x as u32, y as u32);
    let (theirs, n) = window_sum(at, &mask, window);
    let (mine, m) = window_sum(ours, &mask, window);
    assert!(n > 0 && n == m);
    mine / theirs
}

/// `caustic.scn` rendered by `integrator` (`photons` per iteration: SPPM's; `vcm` traces one
/// light path per pixel or a quarter as many whatever it is given).
fn render_with(integrator: Integrator, iterations: u32, photons: u64, seed: u64) -> Image {
    let path = Path::new("tools/reference/caustic.scn");
    let loaded = sppm_lang::internals::eval::load_file(path, &EvalOptions::default())
        .expect("caustic.scn reads");
    let scene = loaded.scene.expect("caustic.scn evaluates");
    let opts = RenderOptions {
        integrator: Some(integrator),
        iterations: Some(iterations),
        photons: Some(photons),
        seed: Some(seed),
        ..Default::default()
    };
    render(&scene, &opts, &AtomicBool::new(false), &mut |_| {})
        .expect("renders")
        .image
}

/// Each window holds its spot: far brighter than the rest of its class.
#[test]
fn the_windows_hold_the_two_spots() {
    let (reference, mask) = (load("caustic.exr"), load("caustic.mask.exr"));
    let at = |x: usize, y: usize| reference.pixels[y * reference.width as usize + x].map(f64::from);
    let mean = |w| {
        let (sum, n) = window_sum(at, &mask, w);
        assert!(n > 100, "{n} pixels in {w:?}");
        sum / n as f64
    };
    let (direct, through) = (mean(DIRECT), mean(THROUGH));
    let (floor, ball) = (mean(((0, 0, 64, 64), 1.0)), mean(((0, 0, 64, 64), 2.0)));
    println!(
        "direct {direct:.4} (floor and wall {floor:.4}), through {through:.4} (ball {ball:.4})"
    );
    // Measured: 4.0 and 2.05 times.
    assert!(direct > 3.0 * floor && through > 1.5 * ball);
}

/// SPPM on the two windows at 32 and 512 iterations.
fn sppm_windows(iterations: u32, photons: u64, seed: u64) -> (f64, f64) {
    let img = render_with(Integrator::Sppm, iterations, photons, seed);
    let (d, b) = (ratio(&img, DIRECT), ratio(&img, THROUGH));
    println!("sppm {iterations} iterations of {photons} photons: direct {d:.4}, through {b:.4}");
    (d, b)
}

/// VCM on the two windows.
fn vcm_windows(iterations: u32, seed: u64) -> (f64, f64) {
    let img = render_with(Integrator::Vcm, iterations, 0, seed);
    let (d, b) = (ratio(&img, DIRECT), ratio(&img, THROUGH));
    println!("vcm {iterations} iterations, seed {seed}: direct {d:.4}, through {b:.4}");
    (d, b)
}

/// Both windows' means (as fractions of the reference's) within `tolerance` of 1.
fn assert_windows_within(d: f64, b: f64, tolerance: f64) {
    assert!(
        (d - 1.0).abs() < tolerance,
        "direct window {d:.4} of the reference's"
    );
    assert!(
        (b - 1.0).abs() < tolerance,
        "through window {b:.4} of the reference's"
    );
}

/// At 32 iterations the blur of the radius leaves both windows up to 1 % dark (two seeds at
/// 800 000 photons: direct 0.992 and 0.991, through 0.998 and 0.998 of the reference's).
#[test]
fn sppm_caustic_windows_at_32_iterations() {
    let (d, b) = sppm_windows(32, 800_000, 5);
    assert_windows_within(d, b, 0.02);
}

/// The 0.5 % target at 512 iterations, on the mean of four seeds (the renders' own noise is
/// about 0.5 % between seeds even at 200 000 photons, so one render cannot tell).
#[test]
#[ignore = "measured 2026-11-29 (dev profile, about 150 CPU-s): seeds 5-8 at 512 iterations of \
            200 000 photons read direct 1.0007, 0.9920, 1.0028, 0.9932 (mean 0.9972 +- 0.0027) \
            and through 0.9995, 0.9956, 0.9989, 0.9933 (mean 0.9968 +- 0.0015, the reference's \
            own noise there 0.063 %): both windows hold 0.5 %"]
fn sppm_caustic_windows_at_512_iterations() {
    let (mut d, mut b) = (0.0, 0.0);
    for seed in 5..=8 {
        let (x, y) = sppm_windows(512, 200_000, seed);
        (d, b) = (d + x / 4.0, b + y / 4.0);
    }
    println!("means of four seeds: direct {d:.4}, through {b:.4}");
    assert_windows_within(d, b, 0.005);
}

/// VCM's windows over `seeds` renders of `iterations` each: each render's ratios printed, then
/// their means and standard errors (the seeds' spread over the square root of their count).
fn vcm_mean_windows(iterations: u32, seeds: std::ops::Range<u64>) -> (f64, f64) {
    let (d, b): (Vec<f64>, Vec<f64>) = seeds.map(|seed| vcm_windows(iterations, seed)).unzip();
    let mean_se = |v: &[f64]| {
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt())
    };
    let ((dm, ds), (bm, bs)) = (mean_se(&d), mean_se(&b));
    println!(
        "vcm {iterations} iterations, {} seeds: direct {dm:.4} +- {ds:.4}, through {bm:.4} +- {bs:.4}",
        d.len()
    );
    (dm, bm)
}

/// VCM at 32 iterations: the 2 % target on the mean of 64 seeds. One render is far noisier
/// than SPPM's (32 iterations of at most one light path per pixel, 4096 at this size, against
/// SPPM's 800 000 photons an iteration, for a twentieth of its CPU time): over seeds 5-68 a
/// render's windows spread by 5.5 % (direct) and 5.8 % (through), from 0.90 to 1.14, so one
/// render cannot meet 2 % (seed 5 read 1.053 and 0.915). Measured 2026-11-30 (dev profile,
/// about 20 CPU-s for the 64, SPPM's one render about 6.5): direct 1.0023 +- 0.0068, through
/// 0.9944 +- 0.0073 (mean +- standard error); 32 seeds (1.0121 +- 0.0095, 0.9826 +- 0.0097)
/// were too few to tell a bias from noise at 2 %.
#[test]
fn vcm_caustic_windows_at_32_iterations() {
    let (d, b) = vcm_mean_windows(32, 5..69);
    assert_windows_within(d, b, 0.02);
}

/// VCM's 0.5 % target at 512 iterations, on the mean of 32 seeds: a render's windows spread
/// by about 1 % between seeds at 512 iterations, so four cannot tell 0.5 %; 32 renders cost
/// about as much CPU as SPPM's four.
#[test]
#[ignore = "measured 2026-11-30 (dev profile, about 140 CPU-s): seeds 5-36 at 512 iterations \
            read direct 1.0041 +- 0.0018 and through 0.9991 +- 0.0021 with each pixel's radius \
            following the light vertices it found (with the radius shrinking by the iteration \
            count: 0.9995 +- 0.0017, seeds 0.982 to 1.019, and 0.9998 +- 0.0020, 0.976 to \
            1.018; the reference's own noise there 0.063 %): both windows hold 0.5 %"]
fn vcm_caustic_windows_at_512_iterations() {
    let (d, b) = vcm_mean_windows(512, 5..37);
    assert_windows_within(d, b, 0.005);
}
