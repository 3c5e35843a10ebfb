//! The photon pass of an SPPM iteration: photons are traced in rounds that bound the memory,
//! each round's hits are filed in a hash grid sized from the visible points, and every visible
//! point gathers the photons within its radius.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use super::grid::{Cells, HitBuffer, HitChunk, PhotonGrid, PhotonHit};
use super::pixels::Pixel;
use super::receiver::Receiver;
use crate::integrators::common::photons::{trace_classified_photon, trace_photon};
use crate::integrators::common::streams::Stream;
use crate::prepare::{EffectiveSettings, PreparedScene};

/// Photons per parallel task of the photon pass.
const PHOTON_CHUNK: u64 = 4096;

/// Photon hits a round aims to hold before its gather (44 bytes each while filed, 40 in the
/// grid: about 176 MB in all). A round traces groups of photons until it holds
/// this many hits, has used [`ROUND_CHUNKS`] chunks, or the iteration's photons are done. A
/// group is sized from the mean hits per photon of everything traced so far, so that it fills
/// the round without overshooting it much (a statistical bound, not a hard one; the first group
/// of a render assumes `max_depth` hits per photon, each filed in every level of every grid, the
/// most there can be). Every size comes from counts that do not depend on the thread count, so
/// the rounds do not either.
pub(super) const ROUND_HITS: usize = 1 << 21;
/// The most chunks in one round: bounds the per-chunk bookkeeping (each level's hits sorted by
/// slab, with a table of where each slab starts) where
/// photons leave few hits near the visible points (an open scene, a narrow view).
pub(super) const ROUND_CHUNKS: usize = 512;
/// The most photons traced in parallel between two checks of [`ROUND_HITS`].
const PHOTON_GROUP: u64 = 1 << 18;

/// The photon pass of every iteration, with the buffers it reuses from round to round and
/// from iteration to iteration (fresh pages cost a fault each).
pub(super) struct PhotonPass {
    pub(super) chunks: Vec<HitChunk>,
    grid: PhotonGrid,
    /// The final gather's hits and grid (every photon from the second surface on, around the
    /// gather points); with final gathering the visible points' own grid keeps only caustic
    /// photons.
    gather_chunks: Vec<HitChunk>,
    gather_grid: PhotonGrid,
    /// Photons traced and hits filed so far, over the whole render: their ratio sizes the
    /// groups. Before any photon, the estimate is `max_depth` hits per photon, each filed in
    /// every level (see [`Self::group_size`]), the most there can be, so that the first group
    /// cannot overfill a round by much.
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
            gather_chunks: Vec::new(),
            gather_grid: PhotonGrid::default(),
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
    /// [`PHOTON_GROUP`] and at most the chunks the round has left. `filings`: the most times
    /// one hit is filed (the levels of the grids it goes to).
    fn group_size(&self, held: usize, used: usize, max_depth: u32, filings: usize) -> u64 {
        let per_photon = if self.traced == 0 {
            f64::from(max_depth.max(1)) * filings.max(1) as f64
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
    /// bound the memory. With `gather_sums` (final gathering) the visible points gather only
    /// caustic photons and every gather point gathers all photons, adding to `gather_sums`.
    /// Returns the number of deposits; stops without a gather when `cancel` is set. Never
    /// inlined: `benches/instructions.rs` counts the instructions inside it.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(super) fn run(
        &mut self,
        scene: &PreparedScene,
        settings: &EffectiveSettings,
        pixels: &[Pixel],
        iter: u32,
        photons: u64,
        sums: &mut Gathered,
        final_gather: Option<(&[Pixel], &mut Gathered)>,
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
        let cells = Cells::new(points);
        let (gather_points, mut gather_sums) = final_gather.unzip();
        let gather_cells = gather_points.and_then(|points| {
            Cells::new(
                points
                    .iter()
                    .filter_map(|g| g.vp.as_ref().map(|vp| (vp.p, g.radius as f32))),
            )
        });
        if cells.is_none() && gather_cells.is_none() {
            return 0;
        }
        let caustic_only = gather_sums.is_some();
        let filings = cells.as_ref().map_or(0, Cells::levels)
            + gather_cells.as_ref().map_or(0, Cells::levels);
        let cancelled = || cancel.load(Ordering::Relaxed);
        let (mut next, mut deposits) = (0, 0);
        while next < photons {
            let (mut used, mut held) = (0, 0);
            while next < photons && held < self.round_hits && used < self.round_chunks {
                if cancelled() {
                    return deposits;
                }
                let hi = next
                    .saturating_add(self.group_size(held, used, settings.max_depth, filings))
                    .min(photons);
                let n = (hi - next).div_ceil(PHOTON_CHUNK) as usize;
                for chunks in [&mut self.chunks, &mut self.gather_chunks] {
                    if chunks.len() < used + n {
                        chunks.resize_with(used + n, HitChunk::default);
                    }
                }
                let group = &mut self.chunks[used..used + n];
                let gather_group = &mut self.gather_chunks[used..used + n];
                let filing = Filing {
                    cells: cells.as_ref(),
                    caustic_only,
                    gather_cells: gather_cells.as_ref(),
                };
                trace_photons(
                    scene,
                    settings,
                    &filing,
                    iter,
                    (next, hi),
                    (group, gather_group),
                    cancel,
                );
                let group = &self.chunks[used..used + n];
                let gather_group = &self.gather_chunks[used..used + n];
                let got = group.iter().map(HitChunk::len).sum::<usize>()
                    + gather_group.iter().map(HitChunk::len).sum::<usize>();
                self.segments += group.iter().map(|c| c.segments).sum::<u64>();
                self.traced += hi - next;
                self.filed += got as u64;
                (used, held, next) = (used + n, held + got, hi);
            }
            if cancelled() {
                return deposits;
            }
            if let Some(cells) = &cells {
                self.grid.build(cells, &self.chunks[..used]);
                deposits += gather(&self.grid, pixels, sums);
            }
            if let (Some(cells), Some(points), Some(sums)) =
                (&gather_cells, gather_points, gather_sums.as_deref_mut())
            {
                self.gather_grid.build(cells, &self.gather_chunks[..used]);
                deposits += gather(&self.gather_grid, points, sums);
            }
            self.rounds += 1;
        }
        deposits
    }
}

/// Where a photon pass files its hits: the visible points' cells (all photons, or only the
/// caustic ones with final gathering), and the gather points' cells (all photons).
struct Filing<'a> {
    cells: Option<&'a Cells>,
    caustic_only: bool,
    gather_cells: Option<&'a Cells>,
}

/// Traces photons `lo..hi` of iteration `iter` in parallel tasks of [`PHOTON_CHUNK`] photons,
/// filing their hits in `chunks` and `gather_chunks` (reset first; one per task, in photon
/// order).
fn trace_photons(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    filing: &Filing,
    iter: u32,
    (lo, hi): (u64, u64),
    (chunks, gather_chunks): (&mut [HitChunk], &mut [HitChunk]),
    cancel: &AtomicBool,
) {
    let tasks = chunks.par_iter_mut().zip(gather_chunks.par_iter_mut());
    // Each task's buffers for the hits as pushed, lent to one chunk after another.
    let buffers = || (HitBuffer::default(), HitBuffer::default());
    tasks
        .enumerate()
        .for_each_init(buffers, |buffers, (c, (chunk, gather_chunk))| {
            let (buffer, gather_buffer) = buffers;
            match filing.cells {
                Some(cells) => chunk.reset(cells, std::mem::take(buffer)),
                None => chunk.clear(),
            }
            match filing.gather_cells {
                Some(cells) => gather_chunk.reset(cells, std::mem::take(gather_buffer)),
                None => gather_chunk.clear(),
            }
            if cancel.load(Ordering::Relaxed) {
                return;
            }
            let first = lo + c as u64 * PHOTON_CHUNK;
            let rngs = Stream::Photon.rngs(settings.seed, iter);
            for i in first..(first + PHOTON_CHUNK).min(hi) {
                let mut rng = rngs.rng(i);
                trace_classified_photon(
                    scene,
                    settings.max_depth,
                    &mut rng,
                    |depth, sh, wi, beta, caustic| {
                        chunk.segments += 1;
                        if depth > 0 {
                            let hit = PhotonHit {
                                p: sh.hit.p,
                                wi,
                                beta,
                            };
                            if let Some(cells) = filing.cells
                                && (caustic || !filing.caustic_only)
                            {
                                chunk.push(cells, hit);
                            }
                            if let Some(cells) = filing.gather_cells {
                                gather_chunk.push(cells, hit);
                            }
                        }
                    },
                );
            }
            if let Some(cells) = filing.cells {
                *buffer = chunk.seal(cells);
            }
            if let Some(cells) = filing.gather_cells {
                *gather_buffer = gather_chunk.seal(cells);
            }
        });
}

/// What each pixel's visible point gathered in an iteration: the flux (f64, summed in the
/// grid's photon order), the number of photons, and the sum of the squared luminances of the
/// photons' contributions to the pixel (their flux times the visible point's throughput: the
/// photon part's own noise, [`super::balance::PhotonNoise`]).
pub(super) struct Gathered {
    pub(super) phi: Vec<DVec3>,
    pub(super) m: Vec<u64>,
    pub(super) phi2: Vec<f64>,
}

impl Gathered {
    pub(super) fn new(pixels: usize) -> Self {
        Gathered {
            phi: vec![DVec3::ZERO; pixels],
            m: vec![0; pixels],
            phi2: vec![0.0; pixels],
        }
    }
}

/// Each point (a pixel's visible point, or its gather point) gathers the flux of the photons
/// within its radius: adds it to `phi` and their number to `m`. Returns the number of deposits.
fn gather(grid: &PhotonGrid, points: &[Pixel], sums: &mut Gathered) -> u64 {
    points
        .par_iter()
        .zip(sums.phi.par_iter_mut().zip(sums.m.par_iter_mut()))
        .zip(sums.phi2.par_iter_mut())
        .map(|((px, (ph, mm)), ph2)| {
            let Some(vp) = px.vp.as_ref() else {
                return 0;
            };
            let r = px.radius as f32;
            // Points without a finite positive radius gather nothing (they also left the cells
            // out).
            if !(r > 0.0 && r.is_finite()) {
                return 0;
            }
            let receiver = Receiver::new(vp.point());
            let weight = (vp.beta * Vec3A::new(0.2126, 0.7152, 0.0722)).as_dvec3();
            let mut found = 0;
            grid.for_each_within(vp.p, r, |wi, beta| {
                let f = receiver.f(wi);
                if f != Vec3A::ZERO {
                    found += 1;
                    let d = beta * f;
                    if d.is_finite() {
                        *ph += d.as_dvec3();
                        *mm += 1;
                        *ph2 += d.as_dvec3().dot(weight).powi(2);
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
