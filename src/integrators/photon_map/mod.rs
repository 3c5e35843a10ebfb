//! Photon mapping (Jensen 1996/2001), two passes per iteration:
//! 1. photons leave the lights (chosen by power) and are stored at every non-specular surface
//!    from the second one on (the first is direct light, which is ray traced): photons whose
//!    path from the light was all specular go to the caustic map, the others to the global map;
//!    each map is a kd-tree;
//! 2. eye rays pass through specular surfaces to the first non-specular hit, where emitted and
//!    direct light come from [`direct_lighting`] (shadow rays) and indirect light is the
//!    k-nearest-neighbour density estimate of both maps (`sum f * flux / (pi r_k^2)`).
//!
//! No final gathering: the global map is looked up directly at the first diffuse hit (cheap;
//! its low-frequency blotches and the light leaking at corners, where the k-NN disc reaches
//! past the surface, are the method's known failure). Iterations are independent passes (new
//! photons, new jittered eye rays) averaged; the bias of each pass does not go away with more
//! iterations, only the noise does.
//!
//! [`direct_lighting`]: crate::integrators::direct_lighting

use crate::integrators::Job;
use std::f32::consts::PI;
use std::sync::atomic::AtomicBool;

use glam::Vec3A;
use rayon::prelude::*;

use super::common::camera_path::camera_path;
use super::common::photons::trace_photon;
use super::common::progressive;
use super::common::streams::Stream;
use super::{Integrator, RenderOutput};
use crate::prepare::{EffectiveSettings, PreparedScene};
use crate::scene::DEFAULT_PHOTONS;
use kdtree::KdTree;

mod kdtree;

/// Photons in each global-map estimate.
pub const K_GLOBAL: usize = 50;
/// Photons in each caustic-map estimate.
pub const K_CAUSTIC: usize = 30;
const CHUNK: u64 = 4096;

/// A stored photon: incident direction (toward where it came from) and flux.
#[derive(Clone, Copy)]
pub(crate) struct Photon {
    wi: Vec3A,
    beta: Vec3A,
}

struct Maps {
    global: KdTree<Photon>,
    caustic: KdTree<Photon>,
    /// Photons emitted in this pass.
    emitted: u64,
}

fn build_maps(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    iter: u32,
    cancel: &AtomicBool,
) -> Maps {
    let photons = settings.photons.unwrap_or(DEFAULT_PHOTONS);
    let n_chunks = photons.div_ceil(CHUNK);
    type Stored = Vec<(Vec3A, Photon)>;
    let chunks: Vec<(Stored, Stored)> = if scene.lights.is_empty() {
        Vec::new()
    } else {
        (0..n_chunks)
            .into_par_iter()
            .map(|c| {
                let (mut global, mut caustic) = (Vec::new(), Vec::new());
                // A cancelled pass (or a passed deadline) stores nothing more; the camera pass
                // that follows sees the same flag and drops the iteration.
                if cancel.load(std::sync::atomic::Ordering::Relaxed) {
                    return (global, caustic);
                }
                let lo = c * CHUNK;
                let hi = (lo + CHUNK).min(photons);
                for i in lo..hi {
                    let mut rng = Stream::PhotonMap.rng(settings.seed, iter, i);
                    let mut all_specular = true;
                    trace_photon(
                        scene,
                        settings.max_depth,
                        &mut rng,
                        |depth, sh, wi, beta| {
                            let specular = scene.bsdf(sh).is_specular();
                            // A blend stores photons even where this point shows its
                            // specular part (see `blend_stores_photons`).
                            let store = !specular || scene.blend_stores_photons(sh);
                            if store && depth > 0 && beta.is_finite() {
                                let ph = (sh.hit.p, Photon { wi, beta });
                                if all_specular {
                                    caustic.push(ph);
                                } else {
                                    global.push(ph);
                                }
                            }
                            all_specular &= specular;
                        },
                    );
                }
                (global, caustic)
            })
            .collect()
    };
    let (mut global, mut caustic) = (Vec::new(), Vec::new());
    if cancel.load(std::sync::atomic::Ordering::Relaxed) {
        // The iteration is dropped: no trees to build.
        return Maps {
            global: KdTree::new(global),
            caustic: KdTree::new(caustic),
            emitted: 0,
        };
    }
    for (g, c) in chunks {
        global.extend(g);
        caustic.extend(c);
    }
    Maps {
        global: KdTree::new(global),
        caustic: KdTree::new(caustic),
        emitted: if scene.lights.is_empty() { 0 } else { photons },
    }
}

/// Reflected radiance density estimate from the `k` nearest photons of `map`.
fn estimate(
    map: &KdTree<Photon>,
    k: usize,
    emitted: u64,
    p: Vec3A,
    wo: Vec3A,
    bsdf: &crate::materials::Bsdf,
    scratch: &mut Vec<usize>,
) -> Vec3A {
    if map.is_empty() || emitted == 0 {
        return Vec3A::ZERO;
    }
    let r2 = map.nearest(p, k, scratch);
    if r2.is_nan() || r2 <= 0.0 {
        return Vec3A::ZERO;
    }
    let mut sum = Vec3A::ZERO;
    for &i in scratch.iter() {
        let ph = &map.item(i).1;
        sum += bsdf.f(wo, ph.wi) * ph.beta;
    }
    sum / (PI * r2 * emitted as f32)
}

/// Jensen's two-pass photon mapping.
#[derive(Debug, Clone, Copy, Default)]
pub struct PhotonMap;

impl Integrator for PhotonMap {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput {
        let (scene, settings, cancel) = (job.scene, job.settings, job.cancel);
        progressive::render(
            job,
            |iter| {
                let maps = build_maps(scene, settings, iter, cancel);
                let n = maps.emitted;
                (maps, n)
            },
            |maps, camera, x, y, rng| {
                let (l, vp) = camera_path(scene, camera, settings, x, y, rng);
                let Some(vp) = vp else { return l };
                let mut scratch = Vec::with_capacity(K_GLOBAL);
                let g = estimate(
                    &maps.global,
                    K_GLOBAL,
                    maps.emitted,
                    vp.p,
                    vp.wo,
                    &vp.bsdf,
                    &mut scratch,
                );
                let c = estimate(
                    &maps.caustic,
                    K_CAUSTIC,
                    maps.emitted,
                    vp.p,
                    vp.wo,
                    &vp.bsdf,
                    &mut scratch,
                );
                l + vp.beta * (g + c)
            },
        )
    }
}
