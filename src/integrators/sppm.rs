//! Stochastic progressive photon mapping (Hachisuka & Jensen 2009), formulated as in pbrt-v4.
//!
//! Every iteration: (1) a camera pass traces one jittered path per pixel through specular
//! bounces to a visible point on a non-specular surface, adding emitted and directly sampled
//! light; (2) a hash grid is built over the visible points; (3) a photon pass traces photons from
//! the lights (chosen by power) and, from the second surface on, deposits flux at every visible
//! point within its radius (the BSDF at the point keeps only photons on the side it faces);
//! (4) each pixel updates N, tau and its radius with alpha. Radiance = Ld / k + tau / (k N_e pi r^2).
//!
//! Determinism: pixel and photon streams are seeded from (seed, iteration, index); photons are
//! traced in fixed-size chunks whose deposit lists are merged in chunk order, so the image does
//! not depend on the thread count or on scheduling.

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
use crate::materials::{Bsdf, TransportMode};
use crate::render::{
    EffectiveSettings, PreparedScene, Progress, RenderOutput, RenderStats, SurfaceHit,
};
use crate::sampling::{Rng, stream_seed};

mod grid;
use grid::Grid;

/// Photons per deposit chunk (fixed: independent of the thread count).
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

/// Deposits a photon's flux at every visible point around the hit (from the second surface on:
/// direct light is sampled by the camera pass).
#[inline]
fn deposit(
    grid: &Grid,
    pixels: &[Pixel],
    sh: &SurfaceHit,
    wi: Vec3A,
    beta: Vec3A,
    out: &mut Vec<(u32, Vec3A)>,
) {
    grid.for_each_within(sh.hit.p, |r| {
        let pix = r.pixel();
        let f = match r.f(wi) {
            Some(f) => f,
            None => match pixels[pix as usize].vp.as_ref() {
                Some(vp) => vp.bsdf.f(vp.wo, wi),
                None => Vec3A::ZERO,
            },
        };
        if f != Vec3A::ZERO {
            out.push((pix, beta * f));
        }
    });
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
    let camera = match Camera::new(&scene.scene.camera, w, h) {
        Ok(c) => c,
        Err(_) => unreachable!("camera validated before rendering"),
    };
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
    let n_chunks = settings.photons.div_ceil(PHOTON_CHUNK);
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
        // 2. Grid over visible points; 3. photon pass.
        let t_photon = Instant::now();
        let grid = Grid::build(
            pixels
                .iter()
                .enumerate()
                .filter_map(|(i, px)| px.vp.as_ref().map(|vp| (i as u32, vp, px.radius as f32))),
        );
        let deposits: Vec<Vec<(u32, Vec3A)>> = match &grid {
            Some(grid) if !scene.lights.is_empty() => (0..n_chunks)
                .into_par_iter()
                .map(|c| {
                    let mut out = Vec::new();
                    if cancel.load(Ordering::Relaxed) {
                        return out;
                    }
                    let lo = c * PHOTON_CHUNK;
                    let hi = (lo + PHOTON_CHUNK).min(settings.photons);
                    for i in lo..hi {
                        let mut rng = Rng::new(stream_seed(seed, iter, STREAM_PHOTON, i));
                        trace_photon(
                            scene,
                            settings.max_depth,
                            &mut rng,
                            |depth, sh, wi, beta| {
                                if depth > 0 {
                                    deposit(grid, &pixels, sh, wi, beta, &mut out);
                                }
                            },
                        );
                    }
                    out
                })
                .collect(),
            _ => Vec::new(),
        };
        if cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        // Merge in chunk order (deterministic f64 sums).
        for chunk in &deposits {
            for &(pix, f) in chunk {
                if f.is_finite() {
                    phi[pix as usize] += f.as_dvec3();
                    m[pix as usize] += 1;
                }
            }
            stats.deposits += chunk.len() as u64;
        }
        stats.photon_time += t_photon.elapsed();
        // 4. Update the pixel statistics.
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
