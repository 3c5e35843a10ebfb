//! Stochastic progressive photon mapping (Hachisuka & Jensen 2009), formulated as in pbrt-v4.
//!
//! Every iteration: (1) a camera pass traces one jittered path per pixel through specular
//! bounces to a visible point on a non-specular surface, adding emitted and directly sampled
//! light; (2) a photon pass traces photons from the lights (chosen by power) and records where
//! they arrive from the second surface on, in a hash grid whose cells are sized from the visible
//! points' radii; every visible point then gathers the photons within its radius (the BSDF at
//! the point keeps only photons on the side it faces); (3) each pixel updates N, tau and its
//! radius with alpha. Radiance = Ld / k + tau / (k N_e pi r^2). The deposits are the same as
//! pbrt-v4's (photon looks up points); only the direction of the lookup differs (`grid.rs` says
//! why).
//!
//! Determinism: pixel and photon streams are seeded from (seed, iteration, index); photon hits
//! are filed in fixed-size chunks in photon order, and each pixel sums its own photons in a
//! fixed order (round by round, bucket by bucket, photon order within a bucket), so the image
//! does not depend on the thread count or on scheduling.

use std::f64::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use super::direct::direct_lighting;
use crate::accel::spawn_ray;
use crate::camera::Camera;
use crate::film::Image;
use crate::geometry::Ray;
use crate::integrators::{Progress, RenderOutput, RenderStats};
use crate::materials::{Bsdf, TransportMode};
use crate::prepare::{EffectiveSettings, PreparedScene, SurfaceHit};
use crate::sampling::{Rng, stream_seed};

mod grid;
mod receiver;
use grid::{Cells, HitChunk, PhotonGrid, PhotonHit};
use receiver::Receiver;

/// Photons per parallel task of the photon pass.
const PHOTON_CHUNK: u64 = 4096;
const STREAM_CAMERA: u32 = 0;
const STREAM_PHOTON: u32 = 1;

#[derive(Clone, Copy)]
pub(crate) struct VisiblePoint {
    pub(crate) p: Vec3A,
    pub(crate) wo: Vec3A,
    pub(crate) bsdf: Bsdf,
    pub(crate) beta: Vec3A,
}

#[derive(Clone)]
struct Pixel {
    /// Sum over iterations of emitted + direct radiance.
    ld: DVec3,
    tau: DVec3,
    n: f64,
    radius: f64,
    vp: Option<VisiblePoint>,
}

/// Per-pixel SPPM state exposed for tests of the radius/N/tau update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelStats {
    pub n: f64,
    pub radius: f64,
    pub tau: [f64; 3],
}

/// The initial gather radius: the scene's `radius`, else the width of one pixel's footprint at
/// the look-at distance, so that the first estimates blur about one pixel there whatever the
/// scene's size and the image resolution. The factor 1 was chosen with `sppm-lang chart` on the
/// Cornell box (README, "Speed against accuracy"): among 0.25x to 4x of it, it gave the lowest
/// error over a 30 s budget on the whole image and on the caustic.
pub fn initial_radius(scene: &PreparedScene, settings: &EffectiveSettings) -> f64 {
    if let Some(r) = settings.radius {
        return r;
    }
    let cam = &scene.scene.camera;
    let distance = (cam.look_at - cam.location).length();
    let fov = cam.fov.to_radians();
    let footprint = 2.0 * distance * (0.5 * fov).tan() / f64::from(settings.height.max(1));
    if footprint.is_finite() && footprint > 0.0 {
        footprint
    } else {
        1.0
    }
}

fn image_of(pixels: &[Pixel], width: u32, height: u32, iters: u32, photons: u64) -> Image {
    let mut img = Image::new(width, height);
    if iters == 0 {
        return img;
    }
    let k = iters as f64;
    let np = (photons as f64 * k).max(1.0);
    img.pixels
        .par_iter_mut()
        .zip(pixels.par_iter())
        .for_each(|(out, px)| {
            let area = PI * px.radius * px.radius;
            let indirect = if photons > 0 && area > 0.0 {
                px.tau / (np * area)
            } else {
                DVec3::ZERO
            };
            let l = px.ld / k + indirect;
            *out = l.to_array();
        });
    img
}

/// Camera pass for one pixel: sets its visible point and returns emitted + direct light.
/// `fixed_eye`: the eye ray goes through the pixel center and the lens center (PPM).
pub(crate) fn camera_path(
    scene: &PreparedScene,
    camera: &Camera,
    settings: &EffectiveSettings,
    x: u32,
    y: u32,
    rng: &mut Rng,
    fixed_eye: bool,
) -> (Vec3A, Option<VisiblePoint>) {
    let jitter = rng.vec2();
    let lens = rng.vec2();
    let mut ray = if fixed_eye {
        camera.ray(x, y, glam::Vec2::splat(0.5), glam::Vec2::splat(0.5))
    } else {
        camera.ray(x, y, jitter, lens)
    };
    let mut beta = Vec3A::ONE;
    let mut l = Vec3A::ZERO;
    for _depth in 0..settings.max_depth {
        let Some(sh) = scene.intersect(&ray, f32::INFINITY) else {
            // Only reached at depth 0 or after specular bounces: nothing else samples it.
            l += beta * scene.background_radiance(ray.d);
            break;
        };
        let wo = -ray.d;
        attenuate_inside(scene, &sh, &ray, &mut beta);
        if let Some((_, al)) = scene.area_light(sh.prim) {
            l += beta * al.le(sh.hit.n, wo);
        }
        let bsdf = scene.bsdf(&sh);
        if !bsdf.is_specular() {
            l += beta * direct_lighting(scene, &sh, &bsdf, wo, rng);
            let vp = VisiblePoint {
                p: sh.hit.p,
                wo,
                bsdf,
                beta,
            };
            return (l, Some(vp));
        }
        let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2(), TransportMode::Radiance) else {
            break;
        };
        beta *= s.weight;
        if beta.max_element() <= 0.0 {
            break;
        }
        ray = spawn_ray(sh.hit.p, sh.hit.n, s.wi);
    }
    (l, None)
}

/// Beer–Lambert absorption along a segment that ran inside an absorbing dielectric (the ray
/// hits the surface from its inner side).
#[inline]
pub(crate) fn attenuate_inside(
    scene: &PreparedScene,
    sh: &SurfaceHit,
    ray: &Ray,
    beta: &mut Vec3A,
) {
    if ray.d.dot(sh.hit.n) > 0.0
        && let Some(sigma) = scene.absorption(sh)
    {
        let dist = sh.hit.t * ray.d.length();
        *beta *= (-sigma * dist).exp();
    }
}

/// One photon path from a light chosen by power. `at_hit(depth, hit, wi, beta)` runs at every
/// surface the photon reaches, `beta` being the photon's flux there (before the surface's BSDF).
pub(crate) fn trace_photon(
    scene: &PreparedScene,
    max_depth: u32,
    rng: &mut Rng,
    mut at_hit: impl FnMut(u32, &SurfaceHit, Vec3A, Vec3A),
) {
    let Some((li, pl)) = scene.light_distr.sample(rng.f32()) else {
        return;
    };
    let (u1, u2) = (rng.vec2(), rng.vec2());
    let Some(ps) = scene.lights[li].sample_photon(u1, u2) else {
        return;
    };
    let mut beta = ps.beta / pl;
    let mut ray = if ps.n == Vec3A::ZERO {
        Ray::new(ps.p, ps.dir)
    } else {
        spawn_ray(ps.p, ps.n, ps.dir)
    };
    for depth in 0..max_depth {
        let Some(sh) = scene.intersect(&ray, f32::INFINITY) else {
            return;
        };
        attenuate_inside(scene, &sh, &ray, &mut beta);
        let wi = -ray.d;
        at_hit(depth, &sh, wi, beta);
        let bsdf = scene.bsdf(&sh);
        let Some(s) = bsdf.sample(wi, rng.f32(), rng.vec2(), TransportMode::Importance) else {
            return;
        };
        let bnew = beta * s.weight;
        // Russian roulette keeps the photon's power roughly constant.
        let q = (1.0 - bnew.max_element() / beta.max_element()).max(0.0);
        if rng.f32() < q {
            return;
        }
        beta = bnew / (1.0 - q);
        if !beta.is_finite() || beta.max_element() <= 0.0 {
            return;
        }
        ray = spawn_ray(sh.hit.p, sh.hit.n, s.wi);
    }
}

/// Photon hits a round aims to hold before its gather (48 bytes each while filed, as much
/// again in the grid: about 200 MB in all). A round traces groups of photons until it holds
/// this many hits, has used [`ROUND_CHUNKS`] chunks, or the iteration's photons are done. A
/// group is sized from the mean hits per photon of everything traced so far, so that it fills
/// the round without overshooting it much (a statistical bound, not a hard one; the first group
/// of a render assumes `max_depth` hits per photon, the most there can be). Every size comes
/// from counts that do not depend on the thread count, so the rounds do not either.
const ROUND_HITS: usize = 1 << 21;
/// The most chunks in one round: bounds the per-chunk bookkeeping (a slab list each) where
/// photons leave few hits near the visible points (an open scene, a narrow view).
const ROUND_CHUNKS: usize = 512;
/// The most photons traced in parallel between two checks of [`ROUND_HITS`].
const PHOTON_GROUP: u64 = 1 << 18;

/// The photon pass of every iteration, with the buffers it reuses from round to round and
/// from iteration to iteration (fresh pages cost a fault each).
struct PhotonPass {
    chunks: Vec<HitChunk>,
    grid: PhotonGrid,
    /// Photons traced and hits filed so far, over the whole render: their ratio sizes the
    /// groups. Before any photon, the estimate is `max_depth` hits per photon (see
    /// [`Self::group_size`]), the most there can be, so that the first group cannot overfill a
    /// round by much.
    traced: u64,
    filed: u64,
    round_hits: usize,
    round_chunks: usize,
    /// Gathers done so far.
    rounds: u64,
}

impl PhotonPass {
    fn new(round_hits: usize, round_chunks: usize) -> Self {
        PhotonPass {
            chunks: Vec::new(),
            grid: PhotonGrid::default(),
            traced: 0,
            filed: 0,
            round_hits: round_hits.max(1),
            round_chunks: round_chunks.max(1),
            rounds: 0,
        }
    }

    /// The photons of the next group of a round that holds `held` hits in `used` chunks: enough
    /// for the hits the round still misses, in whole chunks, at least one chunk, at most
    /// [`PHOTON_GROUP`] and at most the chunks the round has left.
    fn group_size(&self, held: usize, used: usize, max_depth: u32) -> u64 {
        let per_photon = if self.traced == 0 {
            f64::from(max_depth.max(1))
        } else {
            (self.filed as f64 / self.traced as f64).max(1e-3)
        };
        let missing = self.round_hits.saturating_sub(held) as f64;
        let photons = (missing / per_photon).min(PHOTON_GROUP as f64) as u64;
        let chunks = photons
            .div_ceil(PHOTON_CHUNK)
            .clamp(1, self.round_chunks.saturating_sub(used).max(1) as u64);
        chunks * PHOTON_CHUNK
    }

    /// Traces iteration `iter`'s photons, recording their hits, and lets every visible point
    /// gather the photons within its radius (adding to `phi` and `m`), in rounds that bound the
    /// memory. Returns the number of deposits; stops without a gather when `cancel` is set.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &mut self,
        scene: &PreparedScene,
        settings: &EffectiveSettings,
        pixels: &[Pixel],
        iter: u32,
        phi: &mut [DVec3],
        m: &mut [u64],
        cancel: &AtomicBool,
    ) -> u64 {
        // Photons deposit from their second surface on: with fewer than 2 bounces there is
        // nothing to gather, so none is traced.
        if scene.lights.is_empty() || settings.max_depth < 2 {
            return 0;
        }
        let points = pixels
            .iter()
            .filter_map(|px| px.vp.as_ref().map(|vp| (vp.p, px.radius as f32)));
        let Some(cells) = Cells::new(points) else {
            return 0;
        };
        let cancelled = || cancel.load(Ordering::Relaxed);
        let (mut next, mut deposits) = (0, 0);
        while next < settings.photons {
            let (mut used, mut held) = (0, 0);
            while next < settings.photons && held < self.round_hits && used < self.round_chunks {
                if cancelled() {
                    return deposits;
                }
                let hi = next
                    .saturating_add(self.group_size(held, used, settings.max_depth))
                    .min(settings.photons);
                let n = (hi - next).div_ceil(PHOTON_CHUNK) as usize;
                if self.chunks.len() < used + n {
                    self.chunks.resize_with(used + n, HitChunk::default);
                }
                let group = &mut self.chunks[used..used + n];
                trace_photons(scene, settings, &cells, iter, (next, hi), group, cancel);
                let got = group.iter().map(HitChunk::len).sum::<usize>();
                self.traced += hi - next;
                self.filed += got as u64;
                (used, held, next) = (used + n, held + got, hi);
            }
            if cancelled() {
                return deposits;
            }
            self.grid.build(cells, &self.chunks[..used]);
            deposits += gather(&self.grid, pixels, phi, m);
            self.rounds += 1;
        }
        deposits
    }
}

/// Traces photons `lo..hi` of iteration `iter` in parallel tasks of [`PHOTON_CHUNK`] photons,
/// filing their hits in `chunks` (reset first; one per task, in photon order).
fn trace_photons(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    cells: &Cells,
    iter: u32,
    (lo, hi): (u64, u64),
    chunks: &mut [HitChunk],
    cancel: &AtomicBool,
) {
    chunks.par_iter_mut().enumerate().for_each(|(c, chunk)| {
        chunk.reset(cells);
        if cancel.load(Ordering::Relaxed) {
            return;
        }
        let first = lo + c as u64 * PHOTON_CHUNK;
        for i in first..(first + PHOTON_CHUNK).min(hi) {
            let mut rng = Rng::new(stream_seed(settings.seed, iter, STREAM_PHOTON, i));
            trace_photon(
                scene,
                settings.max_depth,
                &mut rng,
                |depth, sh, wi, beta| {
                    if depth > 0 {
                        let p = sh.hit.p;
                        chunk.push(cells, PhotonHit { p, wi, beta });
                    }
                },
            );
        }
    });
}

/// Each visible point gathers the flux of the photons within its radius: adds it to `phi`
/// (f64, in the grid's photon order) and their number to `m`. Returns the number of deposits.
fn gather(grid: &PhotonGrid, pixels: &[Pixel], phi: &mut [DVec3], m: &mut [u64]) -> u64 {
    pixels
        .par_iter()
        .zip(phi.par_iter_mut().zip(m.par_iter_mut()))
        .map(|(px, (ph, mm))| {
            let Some(vp) = px.vp.as_ref() else {
                return 0;
            };
            let r = px.radius as f32;
            // Points without a positive radius gather nothing (they also left the cells out).
            if r.is_nan() || r <= 0.0 {
                return 0;
            }
            let receiver = Receiver::new(vp);
            let mut found = 0;
            grid.for_each_within(vp.p, r * r, |wi, beta| {
                let f = receiver.f(wi);
                if f != Vec3A::ZERO {
                    found += 1;
                    let d = beta * f;
                    if d.is_finite() {
                        *ph += d.as_dvec3();
                        *mm += 1;
                    }
                }
            });
            found
        })
        .sum()
}

/// Flux statistics of `photons` photon paths (for energy-conservation checks): the mean over
/// photons of the flux arriving at surfaces, summed over all hits, over hits from the second on,
/// and of the flux absorbed (`beta * (1 - albedo)` needs the albedo: the caller passes it).
pub fn photon_flux(
    scene: &PreparedScene,
    photons: u64,
    max_depth: u32,
    seed: u64,
    albedo: f64,
) -> [f64; 3] {
    let mut sums = [0.0f64; 3];
    for i in 0..photons {
        let mut rng = Rng::new(stream_seed(seed, 0, STREAM_PHOTON, i));
        trace_photon(scene, max_depth, &mut rng, |depth, _, _, beta| {
            let b = beta.as_dvec3().element_sum() / 3.0;
            sums[0] += b;
            if depth > 0 {
                sums[1] += b;
            }
            sums[2] += b * (1.0 - albedo);
        });
    }
    sums.map(|s| s / photons as f64)
}

pub fn render(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
) -> RenderOutput {
    render_with_state(scene, settings, cancel, on_progress).0
}

/// The render and each pixel's final (N, radius, tau).
pub fn render_with_state(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
) -> (RenderOutput, Vec<PixelStats>) {
    render_progressive(scene, settings, cancel, on_progress, false)
}

/// The progressive loop shared with PPM: `fixed_eye` keeps every pixel's eye ray at the pixel
/// center and the lens center in every iteration (Hachisuka 2008: no re-jitter).
pub(crate) fn render_progressive(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
    fixed_eye: bool,
) -> (RenderOutput, Vec<PixelStats>) {
    let start = Instant::now();
    let (w, h) = (settings.width, settings.height);
    let camera = scene.camera;
    let r0 = initial_radius(scene, settings);
    let mut pixels = vec![
        Pixel {
            ld: DVec3::ZERO,
            tau: DVec3::ZERO,
            n: 0.0,
            radius: r0,
            vp: None,
        };
        (w * h) as usize
    ];
    let mut stats = RenderStats::default();
    let mut done = 0u32;
    let mut cancelled = false;
    let mut phi = vec![DVec3::ZERO; pixels.len()];
    let mut m = vec![0u64; pixels.len()];
    let mut photon_pass = PhotonPass::new(ROUND_HITS, ROUND_CHUNKS);
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
        let seed = settings.seed;
        // 1. Camera pass.
        let t_camera = Instant::now();
        let lds: Vec<Vec3A> = pixels
            .par_iter_mut()
            .enumerate()
            .map(|(i, px)| {
                if cancel.load(Ordering::Relaxed) {
                    return Vec3A::ZERO;
                }
                let mut rng = Rng::new(stream_seed(seed, iter, STREAM_CAMERA, i as u64));
                let (x, y) = (i as u32 % w, i as u32 / w);
                let (l, vp) = camera_path(scene, &camera, settings, x, y, &mut rng, fixed_eye);
                px.vp = vp;
                if l.is_finite() { l } else { Vec3A::ZERO }
            })
            .collect();
        stats.camera_time += t_camera.elapsed();
        if cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        // 2. Photon pass.
        let t_photon = Instant::now();
        let deposits = photon_pass.run(scene, settings, &pixels, iter, &mut phi, &mut m, cancel);
        if cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        stats.deposits += deposits;
        stats.photon_time += t_photon.elapsed();
        // 3. Update the pixel statistics.
        let alpha = settings.alpha;
        pixels
            .par_iter_mut()
            .zip(lds.par_iter())
            .zip(phi.par_iter_mut().zip(m.par_iter_mut()))
            .for_each(|((px, l), (ph, mm))| {
                px.ld += l.as_dvec3();
                if *mm > 0
                    && let Some(vp) = px.vp
                {
                    let mf = *mm as f64;
                    let n_new = px.n + alpha * mf;
                    let r_new = px.radius * (n_new / (px.n + mf)).sqrt();
                    let flux = vp.beta.as_dvec3() * *ph;
                    px.tau = (px.tau + flux) * (r_new * r_new) / (px.radius * px.radius);
                    px.n = n_new;
                    px.radius = r_new;
                }
                *ph = DVec3::ZERO;
                *mm = 0;
                px.vp = None;
            });
        done = iter + 1;
        stats.camera_paths += (w * h) as u64;
        stats.photons += settings.photons;
        let px_ref = &pixels;
        let snap = move || image_of(px_ref, w, h, done, settings.photons);
        on_progress(&Progress {
            iteration: done,
            iterations: settings.iterations,
            elapsed: start.elapsed(),
            stats,
            snapshot: &snap,
        });
    }
    let image = image_of(&pixels, w, h, done, settings.photons);
    let state = pixels
        .iter()
        .map(|p| PixelStats {
            n: p.n,
            radius: p.radius,
            tau: p.tau.to_array(),
        })
        .collect();
    (
        RenderOutput {
            image,
            iterations_done: done,
            cancelled,
            elapsed: start.elapsed(),
            stats,
        },
        state,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prepare::{RenderOptions, effective_settings};
    use crate::scene::Scene;
    use crate::{EvalOptions, load_file};

    /// The Cornell example at `res` x `res` pixels with `photons` per iteration, seed 4.
    fn cornell(res: u32, photons: u64) -> (Scene, EffectiveSettings) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/cornell.scn");
        let mut scene = load_file(&path, &EvalOptions::default())
            .unwrap()
            .scene
            .unwrap();
        scene.settings.resolution = (res, res);
        let options = RenderOptions {
            photons: Some(photons),
            seed: Some(4),
            ..Default::default()
        };
        let settings = effective_settings(&scene, &options).unwrap();
        (scene, settings)
    }

    /// The camera pass of iteration `iter` (seed 4), every radius 0.05.
    fn visible_points(
        prepared: &PreparedScene,
        settings: &EffectiveSettings,
        iter: u32,
    ) -> Vec<Pixel> {
        let (w, h) = (settings.width, settings.height);
        let camera = Camera::new(&prepared.scene.camera, w, h).unwrap();
        (0..w * h)
            .map(|i| {
                let mut rng = Rng::new(stream_seed(4, iter, STREAM_CAMERA, u64::from(i)));
                let (x, y) = (i % w, i / w);
                let vp = camera_path(prepared, &camera, settings, x, y, &mut rng, false).1;
                Pixel {
                    ld: DVec3::ZERO,
                    tau: DVec3::ZERO,
                    n: 0.0,
                    radius: 0.05,
                    vp,
                }
            })
            .collect()
    }

    /// Splitting the photons into rounds (to bound the memory) changes nothing but the order of
    /// the f64 sums: the same deposits reach the same pixels. Checked on the Cornell box with
    /// one round against rounds of about 3000 hits (so small that groups often overfill them)
    /// and against rounds of at most 2 chunks, over two iterations, so that the group sizes
    /// adapt across iterations; the chunk cap must hold.
    #[test]
    fn rounds_split_the_photons_without_changing_the_sums() {
        let (scene, settings) = cornell(24, 30_000);
        let prepared = PreparedScene::new(&scene).unwrap();
        let cancel = AtomicBool::new(false);
        let mut results = Vec::new();
        for (round_hits, round_chunks) in [
            (usize::MAX, usize::MAX),
            (3000, usize::MAX),
            (usize::MAX, 2),
        ] {
            let mut pass = PhotonPass::new(round_hits, round_chunks);
            let mut phi = vec![DVec3::ZERO; 24 * 24];
            let mut m = vec![0u64; 24 * 24];
            let mut deposits = 0;
            for iter in 0..2 {
                let pixels = visible_points(&prepared, &settings, iter);
                deposits += pass.run(
                    &prepared, &settings, &pixels, iter, &mut phi, &mut m, &cancel,
                );
            }
            assert!(
                pass.chunks.len() <= round_chunks,
                "{} chunks",
                pass.chunks.len()
            );
            results.push((pass.rounds, deposits, phi, m));
        }
        let one = &results[0];
        assert_eq!(one.0, 2, "one round per iteration");
        assert!(one.1 > 1000, "{} deposits", one.1);
        // Rounds of 3000 hits: many; rounds of 2 chunks: 30 000 photons are 8 chunks, so 4
        // rounds per iteration.
        for (many, least) in results[1..].iter().zip([10, 8]) {
            println!("rounds {} and {}, deposits {}", one.0, many.0, one.1);
            assert!(many.0 >= least, "{} rounds", many.0);
            assert_eq!(one.1, many.1);
            assert_eq!(one.3, many.3);
            for (a, b) in one.2.iter().zip(&many.2) {
                assert!(
                    (*a - *b).abs().max_element() <= 1e-12 * a.abs().max_element(),
                    "{a} {b}"
                );
            }
        }
    }

    /// With many rounds (small rounds, so that the group sizes adapt from round to round), the
    /// sums are bit for bit the same on 1, 2 and 3 threads: round and group boundaries come
    /// from photon counts, and each pixel adds its photons in a fixed order.
    #[test]
    fn rounds_give_the_same_sums_on_any_thread_count() {
        let (scene, settings) = cornell(24, 30_000);
        let prepared = PreparedScene::new(&scene).unwrap();
        let cancel = AtomicBool::new(false);
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut pass = PhotonPass::new(3000, 3);
                let mut phi = vec![DVec3::ZERO; 24 * 24];
                let mut m = vec![0u64; 24 * 24];
                for iter in 0..2 {
                    let pixels = visible_points(&prepared, &settings, iter);
                    pass.run(
                        &prepared, &settings, &pixels, iter, &mut phi, &mut m, &cancel,
                    );
                }
                let bits: Vec<[u64; 3]> =
                    phi.iter().map(|v| v.to_array().map(f64::to_bits)).collect();
                (pass.rounds, bits, m)
            })
        };
        let one = run(1);
        assert!(one.0 >= 10, "{} rounds", one.0);
        assert!(one.2.iter().sum::<u64>() > 1000);
        for threads in [2, 3] {
            assert!(run(threads) == one, "{threads} threads differ from 1");
        }
    }

    /// With one bounce a photon's only hit is its first, which the camera pass's direct light
    /// already counts: nothing can be gathered, so no photon is traced.
    #[test]
    fn one_bounce_traces_no_photon() {
        let (scene, mut settings) = cornell(16, 100_000);
        settings.max_depth = 1;
        let prepared = PreparedScene::new(&scene).unwrap();
        let pixels = visible_points(&prepared, &settings, 0);
        let (mut phi, mut m) = (vec![DVec3::ZERO; 256], vec![0u64; 256]);
        let mut pass = PhotonPass::new(ROUND_HITS, ROUND_CHUNKS);
        let cancel = AtomicBool::new(false);
        let deposits = pass.run(&prepared, &settings, &pixels, 0, &mut phi, &mut m, &cancel);
        assert_eq!((deposits, pass.traced, pass.rounds), (0, 0, 0));
        // Two bounces do trace and gather.
        settings.max_depth = 2;
        let mut pass = PhotonPass::new(ROUND_HITS, ROUND_CHUNKS);
        let deposits = pass.run(&prepared, &settings, &pixels, 0, &mut phi, &mut m, &cancel);
        assert!(
            pass.traced == 100_000 && deposits > 0,
            "{} {deposits}",
            pass.traced
        );
    }

    /// A cancelled photon pass stops before its next group: it traces nothing more, builds no
    /// grid and gathers nothing (watch mode cancels a render on every save, so a cancel must
    /// not walk the rest of a large iteration). Checked with the flag set before the pass and
    /// with a flag that is set while the first group is traced.
    #[test]
    fn a_cancelled_photon_pass_stops_at_once() {
        let (scene, settings) = cornell(16, 1_000_000_000);
        let prepared = PreparedScene::new(&scene).unwrap();
        let pixels = visible_points(&prepared, &settings, 0);
        let (mut phi, mut m) = (vec![DVec3::ZERO; 256], vec![0u64; 256]);
        // Set before the pass: nothing is traced.
        let mut pass = PhotonPass::new(ROUND_HITS, ROUND_CHUNKS);
        let cancel = AtomicBool::new(true);
        let deposits = pass.run(&prepared, &settings, &pixels, 0, &mut phi, &mut m, &cancel);
        assert_eq!((deposits, pass.rounds, pass.traced), (0, 0, 0));
        assert!(pass.chunks.is_empty());
        // Set from another thread soon after the start: the pass of 10^9 photons (minutes of
        // work) returns within the group in flight instead of walking the rest of the
        // iteration (it may have finished a round or two first on a slow, loaded machine).
        let mut pass = PhotonPass::new(ROUND_HITS, ROUND_CHUNKS);
        let cancel = AtomicBool::new(false);
        let start = std::time::Instant::now();
        let deposits = std::thread::scope(|s| {
            s.spawn(|| {
                std::thread::sleep(std::time::Duration::from_millis(50));
                cancel.store(true, Ordering::Relaxed);
            });
            pass.run(&prepared, &settings, &pixels, 0, &mut phi, &mut m, &cancel)
        });
        println!(
            "cancelled after {} photons, {:?}",
            pass.traced,
            start.elapsed()
        );
        assert!(pass.traced < 200_000_000, "{} photons traced", pass.traced);
        assert!(
            pass.chunks.len() <= ROUND_CHUNKS,
            "{} chunks",
            pass.chunks.len()
        );
        assert_eq!(
            deposits,
            m.iter().sum::<u64>(),
            "a deposit count without its sums"
        );
    }
}
