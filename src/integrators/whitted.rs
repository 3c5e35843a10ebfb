//! Whitted-style ray tracing: eye rays follow perfect reflection and refraction (the branch at
//! glass is chosen by Fresnel, one per sample), and glossy surfaces as the shared camera path
//! does, up to `max_depth`; at the first diffuse surface the shared [`direct_lighting`] samples
//! the lights with shadow rays (area lights by the solid angle they subtend where that pays,
//! else over their surface: soft shadows), and a constant ambient term stands for all
//! indirect light. No light ever reaches a diffuse surface through glass or a mirror: caustics
//! stay dark (a known limitation, not a bug). One jittered sample per pixel per iteration,
//! seeded from (seed, iteration, pixel).
//!
//! With `antialias adaptive` every iteration then compares each pixel's sample with its four
//! neighbours' and supersamples the pixels where they differ, as classic ray tracers did
//! (Whitted 1980; the path signature test from Mitchell 1987): in colour by more than the
//! threshold (per channel, on `x / (1 + x)` so that the threshold means the same on a lamp as
//! on a dark wall), or in the sequence of objects their eye paths met. Such a pixel's value in
//! that iteration is the mean of 16 samples on a 4x4 rotated grid (every sample in its own
//! sixteenth of the pixel's width and of its height), shifted as a whole by a random offset
//! (toroidally, within the pixel) from its own stream, so that the iterations average over the
//! whole pixel. The choice depends on the first samples only and the supersample on other
//! random numbers, so each iteration's value stays an unbiased estimate of the pixel.
//!
//! [`direct_lighting`]: crate::integrators::direct_lighting

use crate::integrators::Job;
use std::f32::consts::PI;
use std::sync::atomic::Ordering;
use std::time::Instant;

use glam::{Vec2, Vec3A};
use rayon::prelude::*;

use super::common::camera_path::{VisiblePoint, camera_path, signed_camera_path};
use super::common::progressive::{self, render_means};
use super::common::streams::Stream;
use super::{Integrator, RenderOutput};

/// Uniform ambient radiance arriving at every non-specular surface (reflected as
/// `pi * f(wo, n) * AMBIENT`, i.e. `albedo * AMBIENT` on a diffuse surface).
pub const AMBIENT: f32 = 0.05;

/// Whitted-style ray tracing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Whitted;

impl Integrator for Whitted {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput {
        if let Some(threshold) = job.settings.adaptive_threshold() {
            return render_adaptive(job, threshold as f32);
        }
        let (scene, settings) = (job.scene, job.settings);
        progressive::render(
            job,
            |_| ((), 0),
            |_, camera, x, y, rng| {
                let (l, vp) = camera_path(scene, camera, settings, x, y, rng);
                with_ambient(l, vp)
            },
        )
    }
}

/// The eye path's light plus the ambient term at its visible point.
fn with_ambient(l: Vec3A, vp: Option<VisiblePoint>) -> Vec3A {
    match vp {
        Some(vp) => {
            let n = vp.bsdf.frame.n;
            let n = if n.dot(vp.wo) < 0.0 { -n } else { n };
            l + vp.beta * vp.bsdf.f(vp.wo, n) * (PI * AMBIENT)
        }
        None => l,
    }
}

/// The 4x4 rotated grid: sample `k = 4 i + j` at `((4 i + j + 0.5) / 16, (4 j + 3 - i + 0.5) /
/// 16)`, a square grid turned by atan(1/4) so that no two samples share a sixteenth of the
/// pixel in x or in y.
fn rotated_grid(k: u32) -> Vec2 {
    let (i, j) = ((k / 4) as f32, (k % 4) as f32);
    Vec2::new((4.0 * i + j + 0.5) / 16.0, (4.0 * j + 3.0 - i + 0.5) / 16.0)
}

/// Whether two first samples differ enough to supersample: another sequence of objects, or a
/// channel of `x / (1 + x)` apart by more than `threshold`.
fn differ(a: (Vec3A, u64), b: (Vec3A, u64), threshold: f32) -> bool {
    let m = |c: Vec3A| c / (Vec3A::ONE + c.max(Vec3A::ZERO));
    a.1 != b.1 || (m(a.0) - m(b.0)).abs().max_element() > threshold
}

/// Whitted ray tracing with adaptive supersampling (see the module doc).
fn render_adaptive(job: Job<'_, '_>, threshold: f32) -> RenderOutput {
    let (scene, settings, cancel) = (job.scene, job.settings, job.cancel);
    let (w, h) = settings.resolution;
    let camera = scene.camera;
    let seed = settings.seed;
    let finite = |l: Vec3A| if l.is_finite() { l } else { Vec3A::ZERO };
    render_means(job, |iter, stats| {
        let t_camera = Instant::now();
        // 1. One jittered sample per pixel (as without adaptive anti-aliasing).
        let first: Vec<(Vec3A, u64)> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                if cancel.load(Ordering::Relaxed) {
                    return (Vec3A::ZERO, 0);
                }
                let mut rng = Stream::Pixel.rng(seed, iter, u64::from(i));
                let jitter = rng.vec2();
                let at = (i % w, i / w, jitter);
                let (l, vp, signature) = signed_camera_path(scene, &camera, settings, at, &mut rng);
                (finite(with_ambient(l, vp)), signature)
            })
            .collect();
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        // 2. Pixels that differ from a neighbour take the mean of a rotated-grid supersample.
        let values: Vec<Vec3A> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let here = first[i as usize];
                let neighbours = [
                    (x > 0).then(|| i - 1),
                    (x + 1 < w).then(|| i + 1),
                    (y > 0).then(|| i - w),
                    (y + 1 < h).then(|| i + w),
                ];
                let edge = neighbours
                    .into_iter()
                    .flatten()
                    .any(|n| differ(here, first[n as usize], threshold));
                if !edge || cancel.load(Ordering::Relaxed) {
                    return here.0;
                }
                let mut rng = Stream::Supersample.rng(seed, iter, u64::from(i));
                let shift = rng.vec2();
                let mut sum = Vec3A::ZERO;
                for k in 0..16 {
                    let jitter = (rotated_grid(k) + shift).fract();
                    let (l, vp, _) =
                        signed_camera_path(scene, &camera, settings, (x, y, jitter), &mut rng);
                    sum += finite(with_ambient(l, vp));
                }
                sum / 16.0
            })
            .collect();
        stats.camera_time += t_camera.elapsed();
        (!cancel.load(Ordering::Relaxed)).then_some((values, 0))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rotated grid puts one sample in every sixteenth of the pixel along x and along y.
    #[test]
    fn the_rotated_grid_stratifies_both_axes() {
        let (mut xs, mut ys) = ([0; 16], [0; 16]);
        for k in 0..16 {
            let p = rotated_grid(k);
            assert!(p.cmpge(Vec2::ZERO).all() && p.cmplt(Vec2::ONE).all(), "{p}");
            xs[(p.x * 16.0) as usize] += 1;
            ys[(p.y * 16.0) as usize] += 1;
        }
        assert_eq!((xs, ys), ([1; 16], [1; 16]));
    }
}

#[cfg(test)]
mod adaptive_tests {
    use std::sync::atomic::AtomicBool;

    use crate::eval::{EvalOptions, load_file};
    use crate::render::{RenderOptions, render};
    use crate::scene::{Antialias, Integrator, Scene};

    fn cornell(antialias: Antialias, iterations: u32, seed: u64) -> Vec<[f64; 3]> {
        cornell_on(antialias, iterations, seed, None)
    }

    fn cornell_on(
        antialias: Antialias,
        iterations: u32,
        seed: u64,
        threads: Option<usize>,
    ) -> Vec<[f64; 3]> {
        let path = crate::repo_root().join("examples/cornell.scn");
        let mut scene: Scene = load_file(&path, &EvalOptions::default())
            .unwrap()
            .scene
            .unwrap();
        scene.settings.resolution = (48, 48);
        scene.settings.integrator = Some(Integrator::Whitted);
        scene.settings.antialias = antialias;
        let options = RenderOptions {
            iterations: Some(iterations),
            seed: Some(seed),
            threads,
            ..Default::default()
        };
        let out = render(&scene, &options, &AtomicBool::new(false), &mut |_| {}).unwrap();
        out.image.pixels.iter().map(|p| p.map(f64::from)).collect()
    }

    /// Adaptive anti-aliasing supersamples the pixels on edges (object silhouettes, the
    /// light's edge, shadow boundaries) and leaves the others as plain jitter made them: the
    /// pixels it does not touch are bit for bit the jittered ones, it touches between 5 % and
    /// 60 % of them, and at 4 iterations its whole-image error against a 256-iteration
    /// jittered render is well under plain jitter's (all of jitter's error at this resolution
    /// is on edges and in the soft shadows).
    #[test]
    fn adaptive_antialiasing_supersamples_edges_and_cuts_their_error() {
        let reference = cornell(Antialias::Jitter, 256, 99);
        let jitter = cornell(Antialias::Jitter, 4, 1);
        let adaptive = cornell(Antialias::Adaptive, 4, 1);
        let rmse = |img: &[[f64; 3]]| {
            let se: f64 = img
                .iter()
                .zip(&reference)
                .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>())
                .sum();
            (se / (3 * img.len()) as f64).sqrt()
        };
        let touched = jitter.iter().zip(&adaptive).filter(|(a, b)| a != b).count();
        let share = touched as f64 / jitter.len() as f64;
        let (e_jitter, e_adaptive) = (rmse(&jitter), rmse(&adaptive));
        println!(
            "supersampled {:.1} % of the pixels; rmse jitter {e_jitter:.4}, adaptive {e_adaptive:.4}",
            100.0 * share
        );
        assert!((0.05..0.6).contains(&share), "{share}");
        assert!(e_adaptive < 0.6 * e_jitter, "{e_adaptive} vs {e_jitter}");
    }

    /// The supersampled pixels and their samples do not depend on the thread count.
    #[test]
    fn adaptive_antialiasing_is_the_same_on_any_thread_count() {
        let one = cornell_on(Antialias::Adaptive, 2, 3, Some(1));
        let bits = |img: &[[f64; 3]]| -> Vec<[u64; 3]> {
            img.iter().map(|p| p.map(f64::to_bits)).collect()
        };
        for threads in [2, 3] {
            let other = cornell_on(Antialias::Adaptive, 2, 3, Some(threads));
            assert!(
                bits(&one) == bits(&other),
                "{threads} threads differ from 1"
            );
        }
    }
}
