//! The photon pass of an SPPM iteration: photons are traced in rounds that bound the memory,
//! each round's hits are filed in a hash grid sized from the visible points, and every visible
//! point gathers the photons within its radius.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use super::grid::{Cells, HitChunk, PhotonGrid, PhotonHit};
use super::pixels::Pixel;
use super::receiver::Receiver;
use crate::integrators::common::photons::trace_photon;
use crate::integrators::common::streams::Stream;
use crate::prepare::{EffectiveSettings, PreparedScene};

/// Photons per parallel task of the photon pass.
const PHOTON_CHUNK: u64 = 4096;

/// Photon hits a round aims to hold before its gather (48 bytes each while filed, as much
/// again in the grid: about 200 MB in all). A round traces groups of photons until it holds
/// this many hits, has used [`ROUND_CHUNKS`] chunks, or the iteration's photons are done. A
/// group is sized from the mean hits per photon of everything traced so far, so that it fills
/// the round without overshooting it much (a statistical bound, not a hard one; the first group
/// of a render assumes `max_depth` hits per photon, the most there can be). Every size comes
/// from counts that do not depend on the thread count, so the rounds do not either.
pub(super) const ROUND_HITS: usize = 1 << 21;
/// The most chunks in one round: bounds the per-chunk bookkeeping (a slab list each) where
/// photons leave few hits near the visible points (an open scene, a narrow view).
pub(super) const ROUND_CHUNKS: usize = 512;
/// The most photons traced in parallel between two checks of [`ROUND_HITS`].
const PHOTON_GROUP: u64 = 1 << 18;

/// The photon pass of every iteration, with the buffers it reuses from round to round and
/// from iteration to iteration (fresh pages cost a fault each).
pub(super) struct PhotonPass {
    pub(super) chunks: Vec<HitChunk>,
    grid: PhotonGrid,
    /// Photons traced and hits filed so far, over the whole render: their ratio sizes the
    /// groups. Before any photon, the estimate is `max_depth` hits per photon (see
    /// [`Self::group_size`]), the most there can be, so that the first group cannot overfill a
    /// round by much.
    pub(super) traced: u64,
    filed: u64,
    round_hits: usize,
    round_chunks: usize,
    /// Surfaces all photons so far reached (their ray casts), for [`super::balance`].
    pub(super) segments: u64,
    /// Gathers done so far.
    pub(super) rounds: u64,
}

impl PhotonPass {
    pub(super) fn new(round_hits: usize, round_chunks: usize) -> Self {
        PhotonPass {
            chunks: Vec::new(),
            grid: PhotonGrid::default(),
            traced: 0,
            filed: 0,
            round_hits: round_hits.max(1),
            round_chunks: round_chunks.max(1),
            segments: 0,
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

    /// Traces iteration `iter`'s `photons` photons, recording their hits, and lets every
    /// visible point gather the photons within its radius (adding to `sums`), in rounds that
    /// bound the memory. Returns the number of deposits; stops without a gather when `cancel`
    /// is set.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run(
        &mut self,
        scene: &PreparedScene,
        settings: &EffectiveSettings,
        pixels: &[Pixel],
        iter: u32,
        photons: u64,
        sums: &mut Gathered,
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
        while next < photons {
            let (mut used, mut held) = (0, 0);
            while next < photons && held < self.round_hits && used < self.round_chunks {
                if cancelled() {
                    return deposits;
                }
                let hi = next
                    .saturating_add(self.group_size(held, used, settings.max_depth))
                    .min(photons);
                let n = (hi - next).div_ceil(PHOTON_CHUNK) as usize;
                if self.chunks.len() < used + n {
                    self.chunks.resize_with(used + n, HitChunk::default);
                }
                let group = &mut self.chunks[used..used + n];
                trace_photons(scene, settings, &cells, iter, (next, hi), group, cancel);
                let got = group.iter().map(HitChunk::len).sum::<usize>();
                self.segments += group.iter().map(|c| c.segments).sum::<u64>();
                self.traced += hi - next;
                self.filed += got as u64;
                (used, held, next) = (used + n, held + got, hi);
            }
            if cancelled() {
                return deposits;
            }
            self.grid.build(cells, &self.chunks[..used]);
            deposits += gather(&self.grid, pixels, sums);
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
            let mut rng = Stream::Photon.rng(settings.seed, iter, i);
            trace_photon(
                scene,
                settings.max_depth,
                &mut rng,
                |depth, sh, wi, beta| {
                    chunk.segments += 1;
                    if depth > 0 {
                        let p = sh.hit.p;
                        chunk.push(cells, PhotonHit { p, wi, beta });
                    }
                },
            );
        }
    });
}

/// What each pixel's visible point gathered in an iteration: the flux (f64, summed in the
/// grid's photon order) and the number of photons.
pub(super) struct Gathered {
    pub(super) phi: Vec<DVec3>,
    pub(super) m: Vec<u64>,
}

impl Gathered {
    pub(super) fn new(pixels: usize) -> Self {
        Gathered {
            phi: vec![DVec3::ZERO; pixels],
            m: vec![0; pixels],
        }
    }
}

/// Each visible point gathers the flux of the photons within its radius: adds it to `phi`
/// and their number to `m`. Returns the number of deposits.
fn gather(grid: &PhotonGrid, pixels: &[Pixel], sums: &mut Gathered) -> u64 {
    pixels
        .par_iter()
        .zip(sums.phi.par_iter_mut().zip(sums.m.par_iter_mut()))
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

/// Flux statistics of the first `photons` photon paths of the photon pass's first iteration
/// (for energy-conservation checks): the mean over
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
        let mut rng = Stream::Photon.rng(seed, 0, i);
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
