//! The per-pixel progressive loop shared by the path tracer, the Whitted ray tracer and the
//! photon-map integrator: every iteration adds one sample per pixel (after an optional
//! per-iteration setup, e.g. building photon maps), reports progress, and honours the time
//! limit and the cancel flag. Pixel streams are seeded from (seed, iteration, pixel).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::film::Image;
use crate::integrators::{Progress, RenderOutput, RenderStats};
use crate::prepare::{EffectiveSettings, PreparedScene};
use crate::sampling::{Rng, stream_seed};

/// Stream kind of per-pixel camera samples (distinct from SPPM's camera/photon streams).
pub(crate) const STREAM_PIXEL: u32 = 2;

fn image_of(sums: &[DVec3], width: u32, height: u32, k: u32) -> Image {
    let mut img = Image::new(width, height);
    if k == 0 {
        return img;
    }
    let inv = 1.0 / k as f64;
    img.pixels
        .par_iter_mut()
        .zip(sums.par_iter())
        .for_each(|(out, s)| *out = (*s * inv).to_array());
    img
}

/// Runs `setup(iteration)` then `pixel(&state, camera, x, y, rng)` for every pixel, per
/// iteration; the image is the mean of the pixel values. `setup` returns the photons it traced
/// (for the statistics) with its state.
pub(crate) fn render<T: Sync>(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
    mut setup: impl FnMut(u32) -> (T, u64),
    pixel: impl Fn(&T, &Camera, u32, u32, &mut Rng) -> Vec3A + Sync,
) -> RenderOutput {
    let start = Instant::now();
    let (w, h) = (settings.width, settings.height);
    let camera = scene.camera;
    let mut sums = vec![DVec3::ZERO; (w * h) as usize];
    let mut stats = RenderStats::default();
    let mut done = 0u32;
    let mut cancelled = false;
    for iter in 0..settings.iterations {
        if let Some(t) = settings.time_limit
            && start.elapsed().as_secs_f64() >= t
        {
            break;
        }
        if cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        let t_setup = Instant::now();
        let (state, photons) = setup(iter);
        stats.photon_time += t_setup.elapsed();
        let t_camera = Instant::now();
        let seed = settings.seed;
        let values: Vec<Vec3A> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                if cancel.load(Ordering::Relaxed) {
                    return Vec3A::ZERO;
                }
                let mut rng = Rng::new(stream_seed(seed, iter, STREAM_PIXEL, i as u64));
                let l = pixel(&state, &camera, i % w, i / w, &mut rng);
                if l.is_finite() { l } else { Vec3A::ZERO }
            })
            .collect();
        stats.camera_time += t_camera.elapsed();
        if cancel.load(Ordering::Relaxed) {
            // The unfinished pass is dropped: the image holds the finished iterations.
            cancelled = true;
            break;
        }
        sums.par_iter_mut()
            .zip(values.par_iter())
            .for_each(|(s, l)| *s += l.as_dvec3());
        done = iter + 1;
        stats.camera_paths += (w * h) as u64;
        stats.photons += photons;
        let sums_ref = &sums;
        let snap = move || image_of(sums_ref, w, h, done);
        on_progress(&Progress {
            iteration: done,
            iterations: settings.iterations,
            elapsed: start.elapsed(),
            stats,
            snapshot: &snap,
        });
    }
    RenderOutput {
        image: image_of(&sums, w, h, done),
        iterations_done: done,
        cancelled,
        elapsed: start.elapsed(),
        stats,
    }
}
