//! The progressive loop every integrator runs: iteration after iteration until `iterations`,
//! the time limit (checked before each iteration) or the cancel flag; after every finished
//! iteration it counts one camera path per pixel and reports progress with a snapshot on
//! demand. A cancelled iteration is dropped: the image holds the finished ones.
//!
//! [`render`] is the loop for integrators whose image is the mean of one sample per pixel and
//! iteration (path tracing, Whitted ray tracing, photon mapping), with pixel streams seeded from
//! (seed, iteration, pixel); SPPM and PPM run [`iterate`] with their own pass and pixel state.

use crate::integrators::Job;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use super::streams::Stream;
use crate::camera::Camera;
use crate::film::Image;
use crate::integrators::{Progress, RenderOutput, RenderStats};
use crate::prepare::EffectiveSettings;
use crate::sampling::Rng;

/// What a finished iteration adds to the statistics besides its camera paths.
pub(crate) struct Finished {
    pub(crate) photons: u64,
    pub(crate) deposits: u64,
}

/// Runs `pass(state, iteration, stats)` for every iteration; a pass adds the time it spends to
/// `stats` and returns `None` when it saw the cancel flag (its work is then dropped).
/// `image(state, iterations_done)` is the image after that many finished iterations. Returns
/// the output with the final state.
pub(crate) fn iterate<S>(
    settings: &EffectiveSettings,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
    mut state: S,
    mut pass: impl FnMut(&mut S, u32, &mut RenderStats) -> Option<Finished>,
    image: impl Fn(&S, u32) -> Image,
) -> (RenderOutput, S) {
    let start = Instant::now();
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
        let Some(finished) = pass(&mut state, iter, &mut stats) else {
            cancelled = true;
            break;
        };
        done = iter + 1;
        stats.camera_paths += u64::from(settings.width() * settings.height());
        stats.photons += finished.photons;
        stats.deposits += finished.deposits;
        let state_ref = &state;
        let snap = || image(state_ref, done);
        on_progress(&Progress {
            iteration: done,
            iterations: settings.iterations,
            elapsed: start.elapsed(),
            stats,
            snapshot: &snap,
        });
    }
    let output = RenderOutput {
        image: image(&state, done),
        iterations_done: done,
        cancelled,
        elapsed: start.elapsed(),
        stats,
    };
    (output, state)
}

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

/// The loop of integrators whose image is the mean over iterations of one value per pixel:
/// `values(iteration, stats)` returns every pixel's value in that iteration with the photons it
/// traced, or `None` when it saw the cancel flag.
pub(crate) fn render_means(
    job: Job<'_, '_>,
    mut values: impl FnMut(u32, &mut RenderStats) -> Option<(Vec<Vec3A>, u64)>,
) -> RenderOutput {
    let Job {
        settings,
        cancel,
        on_progress,
        ..
    } = job;
    let (w, h) = settings.resolution;
    let sums = vec![DVec3::ZERO; (w * h) as usize];
    let pass = |sums: &mut Vec<DVec3>, iter: u32, stats: &mut RenderStats| {
        let (values, photons) = values(iter, stats)?;
        sums.par_iter_mut()
            .zip(values.par_iter())
            .for_each(|(s, l)| *s += l.as_dvec3());
        Some(Finished {
            photons,
            deposits: 0,
        })
    };
    let image = |sums: &Vec<DVec3>, k| image_of(sums, w, h, k);
    iterate(settings, cancel, on_progress, sums, pass, image).0
}

/// Runs `setup(iteration)` then `pixel(&state, camera, x, y, rng)` for every pixel, per
/// iteration; the image is the mean of the pixel values. `setup` returns the photons it traced
/// (for the statistics) with its state.
pub(crate) fn render<T: Sync>(
    job: Job<'_, '_>,
    mut setup: impl FnMut(u32) -> (T, u64),
    pixel: impl Fn(&T, &Camera, u32, u32, &mut Rng) -> Vec3A + Sync,
) -> RenderOutput {
    let (settings, cancel) = (job.settings, job.cancel);
    let (w, h) = settings.resolution;
    let camera = job.scene.camera;
    render_means(job, |iter, stats| {
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
                let mut rng = Stream::Pixel.rng(seed, iter, i as u64);
                let l = pixel(&state, &camera, i % w, i / w, &mut rng);
                if l.is_finite() { l } else { Vec3A::ZERO }
            })
            .collect();
        stats.camera_time += t_camera.elapsed();
        (!cancel.load(Ordering::Relaxed)).then_some((values, photons))
    })
}
