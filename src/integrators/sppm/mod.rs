//! Stochastic progressive photon mapping (Hachisuka & Jensen 2009), formulated as in pbrt-v4.
//!
//! Every iteration: (1) a camera pass traces one jittered path per pixel through specular
//! bounces to a visible point on a non-specular surface, adding emitted and directly sampled
//! light; (2) a photon pass traces photons from the lights (chosen by power) and records where
//! they arrive from the second surface on, in a hash grid whose cells are sized from the visible
//! points' radii (a pixel's radius starts at its first visible point: the scene's `radius`, or
//! 1.5 pixel footprints there, [`crate::prepare::InitialRadius`], the footprint carried through
//! mirrors and glass by `common/footprint.rs`); every visible point then gathers the photons within its radius (the BSDF at
//! the point keeps only photons on the side it faces); (3) each pixel updates N, tau and its
//! radius with alpha. Radiance = Ld / k + tau / (k N_e pi r^2). The deposits are the same as
//! pbrt-v4's (photon looks up points); only the direction of the lookup differs (`grid.rs` says
//! why).
//!
//! Determinism: pixel and photon streams are seeded from (seed, iteration, index); photon hits
//! are filed in fixed-size chunks in photon order, and each pixel sums its own photons in a
//! fixed order (round by round, bucket by bucket, photon order within a bucket), so the image
//! does not depend on the thread count or on scheduling.
//!
//! Photons per iteration: the scene's `photons`, or chosen from the pixel count and the
//! photons' counted segments (`photon_count.rs`); the image divides by all photons traced.
//!
//! PPM runs the same loop with its own eye paths (`render_with`). Files: `pixels.rs` the
//! per-pixel state and its update, `pass.rs` the photon pass, `grid.rs` the photon grid,
//! `receiver.rs` the BSDF at a visible point, `balance.rs` how many extra camera samples
//! (`common/camera_samples.rs` shares them), `photon_count.rs` the photons per iteration.

use crate::integrators::Job;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::Vec3A;
use rayon::prelude::*;

use super::common::camera_path::{VisiblePoint, camera_path, gather_path};
use super::common::footprint;
use super::common::progressive::{Finished, iterate};
use super::common::streams::Stream;
use super::{Integrator, Progress, RenderOutput, RenderStats};
use crate::camera::Camera;
use crate::prepare::{EffectiveSettings, GATHER_RADIUS_FACTOR, PreparedScene};
use crate::sampling::Rng;

mod balance;
mod grid;
mod pass;
mod photon_count;
mod pixels;
mod receiver;
#[cfg(test)]
mod tests;

use super::common::camera_samples::{SampleStats, allocate};
use balance::PhotonNoise;
pub use pass::photon_flux;
use pass::{Gathered, PhotonPass, ROUND_CHUNKS, ROUND_HITS};
use photon_count::PhotonCount;
use pixels::{Pixel, StoredPoint, image_of, update};

/// Stochastic progressive photon mapping.
#[derive(Debug, Clone, Copy, Default)]
pub struct Sppm;

impl Integrator for Sppm {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput {
        render_with(job, camera_path, true).0
    }
}

/// Per-pixel SPPM state exposed for tests of the radius/N/tau update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelStats {
    pub n: f64,
    pub radius: f64,
    pub tau: [f64; 3],
}

/// The render and each pixel's final (N, radius, tau).
pub fn render_with_state(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
) -> (RenderOutput, Vec<PixelStats>) {
    let job = Job {
        scene,
        settings,
        cancel,
        on_progress,
    };
    render_with(job, camera_path, true)
}

/// The eye path of one pixel in an iteration's camera pass: emitted + direct light and the
/// visible point.
pub(crate) type EyePath = fn(
    &PreparedScene,
    &Camera,
    &EffectiveSettings,
    u32,
    u32,
    &mut Rng,
) -> (Vec3A, Option<VisiblePoint>);

/// The SPPM loop with `eye_path` for the camera pass (SPPM: a jittered path per iteration; PPM:
/// the same fixed eye ray in every iteration); `balanced`: with extra camera samples
/// (`balance.rs`).
pub(crate) fn render_with(
    job: Job<'_, '_>,
    eye_path: EyePath,
    balanced: bool,
) -> (RenderOutput, Vec<PixelStats>) {
    let Job {
        scene,
        settings,
        cancel,
        on_progress,
    } = job;
    let (w, h) = settings.resolution;
    let camera = scene.camera;
    let initial_radius = settings.initial_radius(&scene.scene.camera);
    // A pixel's radius is chosen at its first visible point (0 until then).
    let pixels = vec![Pixel::new(0.0); (w * h) as usize];
    // Final gathering is SPPM's (PPM's eye paths are fixed, without balancing).
    let final_gather = settings.final_gather && balanced;
    let state = State {
        gathered: Gathered::new(pixels.len()),
        gather_gathered: Gathered::new(if final_gather { pixels.len() } else { 0 }),
        gather: if final_gather {
            vec![Pixel::new(0.0); pixels.len()]
        } else {
            Vec::new()
        },
        photon_count: PhotonCount::new(settings.photons, pixels.len()),
        emitted: 0,
        pixels,
        photon_pass: PhotonPass::new(ROUND_HITS, ROUND_CHUNKS),
        samples: vec![SampleStats::default(); (w * h) as usize],
        noise: PhotonNoise::default(),
        extra: vec![0; (w * h) as usize],
        photon_segments: 0,
    };
    let pass = |st: &mut State, iter: u32, stats: &mut RenderStats| {
        let seed = settings.seed;
        // 1. Camera pass: each pixel's visible point with its emitted and direct light, and the
        //    mean of that light over the pixel's extra samples (`balance.rs`).
        let t_camera = Instant::now();
        let extra_paths: u64 = st.extra.iter().map(|&e| u64::from(e)).sum();
        let finite = |l: Vec3A| if l.is_finite() { l } else { Vec3A::ZERO };
        let lds: Vec<Vec3A> = st
            .pixels
            .par_iter_mut()
            .zip(st.samples.par_iter_mut().zip(st.extra.par_iter()))
            .enumerate()
            .map(|(i, (px, (samples, &extra)))| {
                if cancel.load(Ordering::Relaxed) {
                    return Vec3A::ZERO;
                }
                let rng0 = Stream::Camera.rng(seed, iter, i as u64);
                let mut rng = rng0.clone();
                let (x, y) = (i as u32 % w, i as u32 / w);
                let (l, vp) = eye_path(scene, &camera, settings, x, y, &mut rng);
                // The radius follows the pixel's footprint along the path just traced (PPM's
                // unbalanced eye rays run through the pixel's centre).
                if px.radius == 0.0
                    && let Some(vp) = vp.as_ref()
                    && let Some(r) = footprint::initial_radius(
                        initial_radius,
                        scene,
                        &camera,
                        settings,
                        (x, y),
                        !balanced,
                        rng0,
                        f64::from(vp.distance),
                    )
                {
                    px.radius = r;
                }
                px.vp = vp.as_ref().map(StoredPoint::new);
                let mut sum = finite(l);
                if !balanced {
                    return sum;
                }
                samples.add(sum);
                if extra > 0 {
                    let mut rng = Stream::CameraExtra.rng(seed, iter, i as u64);
                    for _ in 0..extra {
                        let l = finite(camera_path(scene, &camera, settings, x, y, &mut rng).0);
                        samples.add(l);
                        sum += l;
                    }
                }
                sum / (1 + extra) as f32
            })
            .collect();
        //    With final gathering, each visible point's gather path: its direct light and its
        //    gather point.
        let lgs: Vec<Vec3A> = st
            .gather
            .par_iter_mut()
            .zip(st.pixels.par_iter())
            .enumerate()
            .map(|(i, (g, px))| {
                let Some(vp) = px.vp.as_ref().map(StoredPoint::point) else {
                    return Vec3A::ZERO;
                };
                if cancel.load(Ordering::Relaxed) {
                    return Vec3A::ZERO;
                }
                let mut rng = Stream::Gather.rng(seed, iter, i as u64);
                let (l, gp) = gather_path(scene, settings, &vp, &mut rng);
                // The gather point's radius starts at a multiple of the visible point's own
                // initial radius: its blur is averaged over the gather direction.
                if g.radius == 0.0
                    && gp.is_some()
                    && let Some(r) = initial_radius.at(f64::from(vp.distance))
                {
                    g.radius = r * GATHER_RADIUS_FACTOR;
                }
                g.vp = gp.as_ref().map(StoredPoint::new);
                finite(l)
            })
            .collect();
        stats.camera_time += t_camera.elapsed();
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        // 2. Photon pass.
        let t_photon = Instant::now();
        let photons = st.photon_count.next();
        let deposits = st.photon_pass.run(
            scene,
            settings,
            &st.pixels,
            iter,
            photons,
            &mut st.gathered,
            final_gather.then_some((&st.gather, &mut st.gather_gathered)),
            cancel,
        );
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        stats.photon_time += t_photon.elapsed();
        // 3. Update the pixel statistics, share the next iteration's extra camera samples and
        //    choose its photon count.
        let photon_rays = st.photon_pass.segments - st.photon_segments;
        st.photon_segments = st.photon_pass.segments;
        if balanced {
            let parts = [
                (&st.pixels[..], &mut st.gathered.phi2[..]),
                (&st.gather[..], &mut st.gather_gathered.phi2[..]),
            ];
            st.noise.observe(parts, photons);
        } else {
            // PPM: no split, nothing to keep.
            st.gathered.phi2.fill(0.0);
        }
        let g = &mut st.gathered;
        update(&mut st.pixels, &lds, &mut g.phi, &mut g.m, settings.alpha);
        if final_gather {
            let g = &mut st.gather_gathered;
            update(&mut st.gather, &lgs, &mut g.phi, &mut g.m, settings.alpha);
        }
        st.photon_count.record(photons, photon_rays);
        if balanced {
            // The camera pass's casts: the photon pass's times the ratio that balances the two
            // parts' noise (1 until both are known, then 2 to 8).
            let spp = st.photon_count.segments_per_photon();
            let ratio = balance::camera_share(&st.samples, &st.noise, spp).unwrap_or(1.0);
            st.photon_count.set_camera_ratio(ratio);
            stats.camera_ratio = ratio;
            let mut camera_rays = photon_rays;
            if ratio > 1.0 {
                // The next photon pass's casts, from this one's per photon.
                let next = st.photon_count.next() as f64;
                let per_photon = photon_rays as f64 / photons.max(1) as f64;
                camera_rays = (ratio * next * per_photon).min(u64::MAX as f64) as u64;
            }
            allocate(&st.samples, camera_rays, &mut st.extra);
        }
        st.emitted += photons;
        stats.camera_paths += extra_paths;
        Some(Finished { photons, deposits })
    };
    let image = |st: &State, done| image_of(&st.pixels, &st.gather, w, h, done, st.emitted);
    let (output, state) = iterate(settings, cancel, on_progress, state, pass, image);
    let pixel_stats = state
        .pixels
        .iter()
        .map(|p| PixelStats {
            n: p.n,
            radius: p.radius,
            tau: p.tau.to_array(),
        })
        .collect();
    (output, pixel_stats)
}

/// The pixels with the photon pass's buffers, carried from iteration to iteration.
struct State {
    pixels: Vec<Pixel>,
    /// What each pixel's visible point gathered in this iteration.
    gathered: Gathered,
    /// Each pixel's final-gather estimate and what its gather point gathered in this
    /// iteration (empty without final gathering).
    gather: Vec<Pixel>,
    gather_gathered: Gathered,
    /// Photons per iteration, and the photons of all finished iterations.
    photon_count: PhotonCount,
    emitted: u64,
    photon_pass: PhotonPass,
    /// Each pixel's camera samples so far and its extra samples in the next iteration.
    samples: Vec<SampleStats>,
    extra: Vec<u32>,
    /// The photon part's noise, for the split of the casts between the two passes.
    noise: PhotonNoise,
    /// The photon pass's ray casts before this iteration.
    photon_segments: u64,
}
