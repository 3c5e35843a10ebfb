//! `examples/smallppm.scn` (the smallpt box lit by a point light, with a mirror ball and a glass
//! ball) against an independent reference: Mitsuba 3's particle tracer
//! (`tools/reference/smallppm.py`, `smallppm.exr`, model mapping in `tools/reference/README.md`).
//! The point light reaches the walls by way of the two balls as well as directly (the glass
//! ball's focused caustic on the floor, the mirror's broad reflection of the light), and no path
//! tracer can find that light: a path meets a point light only through a shadow ray from a
//! diffuse surface. The particle tracer finds every path whose last surface before the eye is
//! diffuse, so the reference holds where the camera sees a diffuse surface directly
//! (`smallppm.mask.exr`); everything here is measured on those pixels, at half the example's
//! resolution (the reference box-filtered 2x2, a half-size pixel kept where all four are).

use std::path::Path;
use std::sync::atomic::AtomicBool;

use sppm_lang::EvalOptions;
use sppm_lang::Image;
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::scene::{ColorSpace, ImageData, Integrator, load_image};

/// The floor around the glass ball's focused caustic (just behind the ball), in half-size
/// pixels (x0, y0, x1, y1, half-open): wide enough that the blur of a gather radius stays
/// inside it.
const CAUSTIC: (usize, usize, usize, usize) = (70, 75, 110, 96);

struct Reference {
    width: usize,
    height: usize,
    /// Per half-size pixel: the reference's RGB, and whether it holds there.
    pixels: Vec<([f64; 3], bool)>,
}

fn load(name: &str) -> ImageData {
    let path = Path::new("tools/reference").join(name);
    load_image(&path, ColorSpace::Linear).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn reference() -> Reference {
    let (image, mask) = (load("smallppm.exr"), load("smallppm.mask.exr"));
    assert_eq!((image.width, image.height), (mask.width, mask.height));
    let (w, h) = (image.width as usize / 2, image.height as usize / 2);
    let at = |img: &ImageData, x: usize, y: usize| img.pixels[y * img.width as usize + x];
    let pixels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let quad = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| (2 * x + dx, 2 * y + dy));
            let mut rgb = [0.0; 3];
            for &(qx, qy) in &quad {
                for (c, v) in rgb.iter_mut().zip(at(&image, qx, qy)) {
                    *c += f64::from(v) / 4.0;
                }
            }
            let valid = quad.iter().all(|&(qx, qy)| at(&mask, qx, qy)[0] > 0.5);
            (rgb, valid)
        })
        .collect();
    Reference {
        width: w,
        height: h,
        pixels,
    }
}

/// Our image's mean over the reference's, on the valid pixels (within `window` if given).
fn mean_ratio(img: &Image, r: &Reference, window: Option<(usize, usize, usize, usize)>) -> f64 {
    assert_eq!(
        (img.width as usize, img.height as usize),
        (r.width, r.height)
    );
    let inside = |i: usize| {
        let (x, y) = (i % r.width, i / r.width);
        window.is_none_or(|(x0, y0, x1, y1)| (x0..x1).contains(&x) && (y0..y1).contains(&y))
    };
    let (mut ours, mut theirs) = (0.0, 0.0);
    for (i, (p, (q, valid))) in img.pixels.iter().zip(&r.pixels).enumerate() {
        if *valid && inside(i) {
            ours += p.iter().sum::<f64>();
            theirs += q.iter().sum::<f64>();
        }
    }
    ours / theirs
}

fn render_half(integrator: Integrator, iterations: u32) -> Image {
    let loaded = sppm_lang::internals::eval::load_file(
        Path::new("examples/smallppm.scn"),
        &EvalOptions::default(),
    )
    .expect("smallppm.scn reads");
    let mut scene = loaded.scene.expect("smallppm.scn evaluates");
    scene.settings.integrator = Some(integrator);
    let (w, h) = scene.settings.resolution;
    scene.settings.resolution = (w / 2, h / 2);
    let opts = RenderOptions {
        iterations: Some(iterations),
        seed: Some(3),
        ..Default::default()
    };
    render(&scene, &opts, &AtomicBool::new(false), &mut |_| {})
        .expect("renders")
        .image
}

#[test]
fn the_reference_masks_the_balls_and_nothing_else() {
    let r = reference();
    let valid = r.pixels.iter().filter(|(_, v)| *v).count();
    let share = valid as f64 / r.pixels.len() as f64;
    // Two balls of radius 0.165 seen from about 2.5 m through a 30.5 degree field of view
    // cover about 8 % of the image (their edges' half-size pixels with them).
    assert!(
        (0.85..0.95).contains(&share),
        "{share:.3} of the pixels valid"
    );
    // The caustic lies on the floor, seen directly beside the ball's outline.
    let (x0, y0, x1, y1) = CAUSTIC;
    let in_caustic = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .filter(|&(x, y)| r.pixels[y * r.width + x].1)
        .count();
    assert!(
        in_caustic * 2 > (x1 - x0) * (y1 - y0),
        "{in_caustic} valid caustic pixels"
    );
}

#[test]
fn sppm_finds_the_light_the_path_tracer_cannot() {
    let r = reference();
    let sppm = render_half(Integrator::Sppm, 24);
    let path = render_half(Integrator::Path, 48);
    let (s, p) = (mean_ratio(&sppm, &r, None), mean_ratio(&path, &r, None));
    let (sc, pc) = (
        mean_ratio(&sppm, &r, Some(CAUSTIC)),
        mean_ratio(&path, &r, Some(CAUSTIC)),
    );
    println!(
        "mean over the reference's: sppm {s:.4} (caustic {sc:.4}), path {p:.4} (caustic {pc:.4})"
    );
    assert!(
        (s - 1.0).abs() < 0.01,
        "sppm: mean {s:.4} of the reference's"
    );
    assert!(
        (sc - 1.0).abs() < 0.03,
        "sppm: caustic {sc:.4} of the reference's"
    );
    // The path tracer misses the light that went by way of a ball: about 5 % of the image and
    // a fifth of the floor around the caustic.
    assert!(p < 0.97, "path: mean {p:.4} of the reference's");
    assert!(pc < 0.85, "path: caustic {pc:.4} of the reference's");
}
