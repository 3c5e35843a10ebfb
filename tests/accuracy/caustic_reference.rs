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

fn render_sppm(iterations: u32, photons: u64, seed: u64) -> Image {
    let path = Path::new("tools/reference/caustic.scn");
    let loaded = sppm_lang::internals::eval::load_file(path, &EvalOptions::default())
        .expect("caustic.scn reads");
    let scene = loaded.scene.expect("caustic.scn evaluates");
    let opts = RenderOptions {
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

/// The default method (SPPM) on the two windows at 32 and 512 iterations.
fn sppm_windows(iterations: u32, photons: u64, seed: u64) -> (f64, f64) {
    let img = render_sppm(iterations, photons, seed);
    let (d, b) = (ratio(&img, DIRECT), ratio(&img, THROUGH));
    println!("sppm {iterations} iterations of {photons} photons: direct {d:.4}, through {b:.4}");
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
