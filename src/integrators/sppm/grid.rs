//! One gather round's photons in a hash grid whose cells are sized from the visible points.
//!
//! The photon pass first traces its photons and records where they arrive; then every visible
//! point gathers the photons within its radius. Stored this way round (photons in the grid,
//! points looking up), a lookup reads a run of photons that its neighbours in the image read
//! too, and each point sums its own flux: no per-deposit list to merge, and the order of every
//! sum is fixed by the photons' indices, whatever the thread count. (Points in the grid with
//! each photon looking them up made every photon hit a random read of the point arrays, and
//! that lookup waited on memory for a third of the photon pass.)
//!
//! The cells are a little over `r_max` wide, so the photons within `r <= r_max` of a point lie
//! in the (at most) 3x3x3 cells that meet the cube of half-width `r` around it. A photon is stored once per level (below), in the cell
//! that holds it; the entries of a bucket are contiguous, positions (all the distance test
//! reads, four entries at a time: `grid/points.rs`) in one array and the photon's direction
//! and flux in a parallel one.
//!
//! Radii can span orders of magnitude (each pixel's radius follows the distance to its visible
//! point: an infinite floor seen up to the horizon). Cells sized by the largest radius would
//! then put every photon near the camera into a few cells, each scanned by every point there
//! (docs/measurements.md, "Photon grid levels"). So the points are split into levels
//! by radius, a factor [`LEVEL_FACTOR`] apart, each level with its own cells over its own
//! points; a photon is filed in every level whose points it may reach, and a point looks up its
//! own level only. Radii above a quarter of the largest make one level: the grid of one level
//! is the grid of all points.

use arrayvec::ArrayVec;
use glam::{Vec3, Vec3A};
use rayon::prelude::*;

use crate::geometry::Aabb;

/// A photon's arrival at a surface (from the second on: direct light is sampled by the camera
/// pass), kept until its round's gather.
#[derive(Clone, Copy, Debug)]
pub(super) struct PhotonHit {
    pub(super) p: Vec3A,
    /// Toward where the photon came from.
    pub(super) wi: Vec3A,
    /// The photon's flux.
    pub(super) beta: Vec3A,
}

/// Radius ratio between neighbouring levels.
const LEVEL_FACTOR: f32 = 4.0;

/// Most levels: radii below `r_max / LEVEL_FACTOR^(MAX_LEVELS - 1)` share the last.
const MAX_LEVELS: usize = 8;

/// The cell geometry of one iteration's visible points, one [`Level`] per radius class.
#[derive(Clone, Debug)]
pub(super) struct Cells {
    /// The largest radius: level `k` holds the radii in `(r_max / F^(k+1), r_max / F^k]`
    /// (the last level everything below), `F` = [`LEVEL_FACTOR`].
    r_max: f32,
    levels: Vec<Option<Level>>,
}

/// The cell geometry of the points of one level.
#[derive(Clone, Copy, Debug)]
struct Level {
    /// The points' bounds grown by the largest radius: no photon outside reaches a point.
    bounds: Aabb,
    inv_cell: f32,
    res: [i32; 3],
    /// log2 of the range of [`row`] (a power of two, at least twice the number of points); the
    /// table has `2^bits + res[0]` buckets.
    bits: u32,
    /// log2 of the buckets per slab: a filed photon's slab is `bucket >> slab_shift` (a
    /// division per photon hit cost more than the rest of the filing).
    slab_shift: u32,
}

/// The bucket of the cell `(0, y, z)`: a spatial hash of `y` and `z` (two of the classic three
/// primes, then a Fibonacci multiply whose top `bits` bits index a power-of-two range). Cell
/// `(x, y, z)` has bucket `row(y, z) + x` (the table has `2^bits + res_x` buckets, so this never
/// wraps): cells next to each other along `x` have consecutive buckets and their entries are one
/// contiguous run, so a lookup of at most 3x3x3 cells reads at most 9 runs.
#[inline]
fn row(y: i32, z: i32, bits: u32) -> u32 {
    let h = (y as u32).wrapping_mul(19_349_663) ^ (z as u32).wrapping_mul(83_492_791);
    h.wrapping_mul(0x9E37_79B9) >> (32 - bits)
}

/// `x.floor() as i32` for `|x| < 2^31` without a call to `floorf` (x86-64 without SSE4.1 has no
/// rounding instruction).
#[inline]
fn floor_i32(x: f32) -> i32 {
    let i = x as i32;
    if (i as f32) > x { i - 1 } else { i }
}

impl Cells {
    /// The cells for visible points at `(position, radius)`; `None` without a point of finite
    /// positive radius (a point without one gathers nothing). Two passes over the points, no
    /// copy of them (an image's worth of points is large).
    pub(super) fn new(points: impl Iterator<Item = (Vec3A, f32)> + Clone) -> Option<Cells> {
        let valid = |(_, r): &(Vec3A, f32)| *r > 0.0 && r.is_finite();
        let r_max = points
            .clone()
            .filter(valid)
            .fold(0.0f32, |m, (_, r)| m.max(r));
        if r_max <= 0.0 {
            return None;
        }
        let mut cells = Cells {
            r_max,
            levels: Vec::new(),
        };
        let mut stats = [LevelStats::default(); MAX_LEVELS];
        for (p, r) in points.filter(valid) {
            stats[cells.level_of(r)].add(p, r);
        }
        let used = stats.iter().rposition(|s| s.n > 0).map_or(0, |k| k + 1);
        cells.levels = stats[..used].iter().map(Level::new).collect();
        Some(cells)
    }

    /// The number of levels that hold points.
    pub(super) fn levels(&self) -> usize {
        self.levels.iter().flatten().count()
    }

    /// The level of a point of radius `r` (the same arithmetic wherever it is asked).
    #[inline]
    fn level_of(&self, r: f32) -> usize {
        let (mut k, mut bound) = (0, self.r_max / LEVEL_FACTOR);
        while k + 1 < MAX_LEVELS && r <= bound {
            k += 1;
            bound /= LEVEL_FACTOR;
        }
        k
    }

    /// Whether a photon at `p` can be within reach of a point (photons outside are not kept).
    #[cfg(test)]
    pub(super) fn contains(&self, p: Vec3A) -> bool {
        self.levels.iter().flatten().any(|l| l.contains(p))
    }
}

/// The number, largest radius and bounds of one level's points.
#[derive(Clone, Copy)]
struct LevelStats {
    n: usize,
    max_r: f32,
    bounds: Aabb,
}

impl Default for LevelStats {
    fn default() -> Self {
        LevelStats {
            n: 0,
            max_r: 0.0,
            bounds: Aabb::EMPTY,
        }
    }
}

impl LevelStats {
    fn add(&mut self, p: Vec3A, r: f32) {
        self.n += 1;
        self.max_r = self.max_r.max(r);
        self.bounds = self.bounds.with_point(p);
    }
}

impl Level {
    /// The cells for the points of one level; `None` without a point.
    fn new(stats: &LevelStats) -> Option<Level> {
        let LevelStats { n, max_r, bounds } = *stats;
        if n == 0 {
            return None;
        }
        let bounds = Aabb::new(
            bounds.min - Vec3A::splat(max_r),
            bounds.max + Vec3A::splat(max_r),
        );
        // A little over r_max: a point's lookup (`bucket_runs`) then meets at most 3 cells per
        // axis, and its candidates cover about (2 r + r_max)^2 of a surface around it. 2x2x2
        // cells of 2 r_max made that 16 r_max^2 (the gather's distance tests were a quarter of
        // the photon pass's instructions at the default radius); cells of 1.5 r_max ran fewer
        // instructions at the smallest radii but fewer photons per CPU second
        // (docs/measurements.md, "Photon pass").
        let cell = max_r * 1.01;
        let diag = bounds.diagonal();
        // Cap the resolution so that huge scenes with a tiny radius stay in range (cells only
        // grow: a lookup still finds every photon within r_max).
        let inv_cell = (1.0 / cell).min(1024.0 / diag.max_element().max(1e-30));
        let res = [0, 1, 2].map(|a| ((diag[a] * inv_cell) as i32 + 1).max(1));
        let bits = (2 * n).next_power_of_two().trailing_zeros().max(1);
        let table = (1usize << bits) + res[0] as usize;
        Some(Level {
            bounds,
            inv_cell,
            res,
            bits,
            // The smallest power of two that splits the table into at most `SLABS` slabs.
            slab_shift: table.div_ceil(SLABS).next_power_of_two().trailing_zeros(),
        })
    }

    /// Whether a photon at `p` can be within reach of a point of the level.
    #[inline]
    fn contains(&self, p: Vec3A) -> bool {
        !(p.cmplt(self.bounds.min).any() || p.cmpgt(self.bounds.max).any())
    }

    fn table_size(&self) -> usize {
        (1usize << self.bits) + self.res[0] as usize
    }

    /// Buckets per slab.
    #[inline]
    fn slab_width(&self) -> u32 {
        1 << self.slab_shift
    }

    /// The number of slabs (the last may be narrower).
    fn slabs(&self) -> usize {
        self.table_size().div_ceil(self.slab_width() as usize)
    }

    /// The bucket of the cell that holds `p`.
    #[inline]
    fn bucket(&self, p: Vec3A) -> u32 {
        let c = (p - self.bounds.min) * self.inv_cell;
        // Axis by axis: `[0, 1, 2].map(..)` stayed a call of ~69 instructions per filed hit
        // (docs/measurements.md, "Photon pass").
        // `max` then `min` rather than `clamp`, whose check of its bounds' order cost a
        // quarter of the filing (`res` is at least 1, so the result is the same).
        let x = (c.x as i32).max(0).min(self.res[0] - 1);
        let y = (c.y as i32).max(0).min(self.res[1] - 1);
        let z = (c.z as i32).max(0).min(self.res[2] - 1);
        row(y, z, self.bits) + x as u32
    }

    /// The bucket runs `lo..hi` of the cells that meet the cube of half-width `r` around `p`
    /// (`r` at most the level's largest radius): at most 3 per axis, since a cell is wider than
    /// that largest radius. Each row of cells along `x` is a run of consecutive buckets; runs
    /// that share a bucket (two rows hashed close together) are merged, so that no entry is
    /// listed twice (the point would take that photon twice).
    #[inline]
    fn bucket_runs(&self, p: Vec3A, r: f32) -> ArrayVec<(u32, u32), 9> {
        let mut out = ArrayVec::new();
        if !self.contains(p) {
            return out;
        }
        // The cube is padded by 0.1 % so that the rounding of the distance test cannot take a
        // photon from a cell outside it; `2 r (1.001) < 2 cells` keeps it within 3 cells per
        // axis (`min` only guards that bound).
        let pad = Vec3A::splat(r * 1.001);
        let lo_c = (p - pad - self.bounds.min) * self.inv_cell;
        let hi_c = (p + pad - self.bounds.min) * self.inv_cell;
        let range = |a: usize| {
            let lo = floor_i32(lo_c[a]).max(0);
            let hi = floor_i32(hi_c[a]).min(self.res[a] - 1).min(lo + 2);
            (lo, hi)
        };
        let ((x0, x1), (y0, y1), (z0, z1)) = (range(0), range(1), range(2));
        if x0 > x1 || y0 > y1 || z0 > z1 {
            return out;
        }
        let len = (x1 - x0 + 1) as u32;
        // The rows' first buckets, sorted (insertion sort of at most 9).
        let mut first = ArrayVec::<u32, 9>::new();
        for z in z0..=z1 {
            for y in y0..=y1 {
                let b = row(y, z, self.bits) + x0 as u32;
                let at = first.iter().position(|&f| f > b).unwrap_or(first.len());
                first.insert(at, b);
            }
        }
        let (mut lo_b, mut hi_b) = (first[0], first[0] + len);
        for &b in &first[1..] {
            if b <= hi_b {
                hi_b = hi_b.max(b + len);
            } else {
                out.push((lo_b, hi_b));
                (lo_b, hi_b) = (b, b + len);
            }
        }
        out.push((lo_b, hi_b));
        out
    }
}

/// Slabs of buckets (at most): the photon pass files every hit under the slab of its bucket, so
/// that the grid is built slab by slab, in parallel, each slab's writes staying within a
/// window of the grid (the scatter of a counting sort over the whole grid waited on a cache
/// miss per photon).
const SLABS: usize = 64;

/// A photon hit as filed: the position with its bucket, then the direction and flux (40
/// bytes, no padding: a round's hits are the photon pass's largest memory, and fresh pages cost
/// a fault each).
#[derive(Clone, Copy, Debug)]
struct Filed {
    p: Vec3,
    bucket: u32,
    wi: Vec3,
    beta: Vec3,
}

impl Filed {
    const ZERO: Filed = Filed {
        p: Vec3::ZERO,
        bucket: 0,
        wi: Vec3::ZERO,
        beta: Vec3::ZERO,
    };
}

/// One parallel task's photon hits, per level sorted by slab (in push order within a slab).
/// Kept from round to round (and iteration to iteration) so that its memory is reused.
///
/// The hits are pushed into a [`HitBuffer`] the task lends the chunk ([`HitChunk::reset`]),
/// then sorted by slab into one array per level, sized to the hits ([`HitChunk::seal`]), which
/// gives the buffer back for the task's next chunk. (A growing array per slab and chunk held
/// about a third more memory than its hits, and copied them as it grew.)
#[derive(Default)]
pub(super) struct HitChunk {
    levels: Vec<SlabHits>,
    pending: HitBuffer,
    /// Surfaces the chunk's photons reached (filed or not): its ray casts.
    pub(super) segments: u64,
}

/// One level's hits of a chunk: slab `s`'s are `hits[starts[s]..starts[s + 1]]`, their buckets
/// at the same indices of `buckets`.
#[derive(Default)]
struct SlabHits {
    /// The hits' buckets apart, for the grid build's counting pass, which then reads 4 bytes
    /// per hit rather than its 40-byte record.
    buckets: Vec<u32>,
    hits: Vec<Filed>,
    starts: Vec<u32>,
}

/// Photon hits per level as pushed, before a chunk sorts them by slab: the memory one task
/// reuses from chunk to chunk.
#[derive(Default)]
pub(super) struct HitBuffer(Vec<Vec<Filed>>);

impl HitChunk {
    /// Empties the chunk for a round over `cells`, its hits to be pushed into `buffer` (whose
    /// memory [`Self::seal`] gives back).
    pub(super) fn reset(&mut self, cells: &Cells, buffer: HitBuffer) {
        let n = cells.levels.len();
        self.levels.resize_with(n, SlabHits::default);
        for (l, level) in self.levels.iter_mut().zip(&cells.levels) {
            l.buckets.clear();
            l.hits.clear();
            l.starts.clear();
            l.starts.resize(level.map_or(0, |l| l.slabs()) + 1, 0);
        }
        self.pending = buffer;
        self.pending.0.resize_with(n, Vec::new);
        for v in &mut self.pending.0 {
            v.clear();
        }
        self.segments = 0;
    }

    /// Drops the hits and the count (a pass that files nothing here).
    pub(super) fn clear(&mut self) {
        for l in &mut self.levels {
            l.buckets.clear();
            l.hits.clear();
            l.starts.fill(0);
        }
        for v in &mut self.pending.0 {
            v.clear();
        }
        self.segments = 0;
    }

    /// Files `hit` in every level whose points it may reach (none: dropped).
    #[inline]
    pub(super) fn push(&mut self, cells: &Cells, hit: PhotonHit) {
        for (pending, level) in self.pending.0.iter_mut().zip(&cells.levels) {
            let Some(level) = level else { continue };
            if !level.contains(hit.p) {
                continue;
            }
            pending.push(Filed {
                p: hit.p.into(),
                bucket: level.bucket(hit.p),
                wi: hit.wi.into(),
                beta: hit.beta.into(),
            });
        }
    }

    /// Sorts the pushed hits by slab (a stable counting sort: push order within a slab), for
    /// [`PhotonGrid::build`], and returns the emptied buffer they were pushed into.
    pub(super) fn seal(&mut self, cells: &Cells) -> HitBuffer {
        let levels = self.levels.iter_mut().zip(&mut self.pending.0);
        for ((sorted, pending), level) in levels.zip(&cells.levels) {
            let Some(level) = level else {
                pending.clear();
                continue;
            };
            let starts = &mut sorted.starts;
            for h in pending.iter() {
                starts[(h.bucket >> level.slab_shift) as usize + 1] += 1;
            }
            for s in 1..starts.len() {
                starts[s] += starts[s - 1];
            }
            // Where each slab's next hit goes (at most `SLABS` slabs).
            let slabs = starts.len() - 1;
            let mut next = [0u32; SLABS];
            next[..slabs].copy_from_slice(&starts[..slabs]);
            let n = pending.len();
            sorted.buckets.clear();
            sorted.buckets.reserve_exact(n);
            sorted.buckets.resize(n, 0);
            sorted.hits.clear();
            sorted.hits.reserve_exact(n);
            sorted.hits.resize(n, Filed::ZERO);
            let (buckets, hits) = (&mut sorted.buckets[..n], &mut sorted.hits[..n]);
            for h in pending.iter() {
                let s = (h.bucket >> level.slab_shift) as usize;
                let j = next[s] as usize;
                buckets[j] = h.bucket;
                hits[j] = *h;
                next[s] += 1;
            }
            pending.clear();
        }
        std::mem::take(&mut self.pending)
    }

    /// Level `k`'s hits in slab `s` and their buckets (none before [`Self::seal`]).
    fn slab(&self, k: usize, s: usize) -> (&[u32], &[Filed]) {
        let l = &self.levels[k];
        let range = l.starts[s] as usize..l.starts[s + 1] as usize;
        (&l.buckets[range.clone()], &l.hits[range])
    }

    /// Hits filed (a hit filed in two levels counts twice: the memory it takes).
    pub(super) fn len(&self) -> usize {
        self.levels.iter().map(|l| l.hits.len()).sum()
    }
}

/// The photons of one gather round, by level and cell. Its arrays are reused by the next build.
#[derive(Default)]
pub(super) struct PhotonGrid {
    cells: Option<Cells>,
    levels: Vec<LevelGrid>,
}

/// The photons of one level, by cell.
#[derive(Default)]
struct LevelGrid {
    cells: Option<Level>,
    /// Bucket `b`'s entries are `starts[b]..starts[b + 1]`.
    starts: Vec<u32>,
    /// Per entry: the photon's position.
    points: Vec<Vec3A>,
    /// Per entry: the photon's `wi` and flux.
    flux: Vec<(Vec3, Vec3)>,
}

impl PhotonGrid {
    /// Rebuilds the grid over the photons filed in `chunks` under `cells`; within a bucket the
    /// photons keep their order (chunk after chunk, then as pushed).
    pub(super) fn build(&mut self, cells: &Cells, chunks: &[HitChunk]) {
        self.levels
            .resize_with(cells.levels.len(), LevelGrid::default);
        for (k, (grid, level)) in self.levels.iter_mut().zip(&cells.levels).enumerate() {
            match level {
                Some(level) => grid.build(*level, chunks, k),
                None => grid.cells = None,
            }
        }
        self.cells = Some(cells.clone());
    }

    /// Calls `f(wi, flux)` for every photon within `r` of `p`, for a point of radius `r` that
    /// was among the points `cells` were made from, each once, in entry order.
    #[inline]
    pub(super) fn for_each_within(&self, p: Vec3A, r: f32, f: impl FnMut(Vec3A, Vec3A)) {
        let Some(cells) = &self.cells else {
            return;
        };
        if let Some(grid) = self.levels.get(cells.level_of(r)) {
            grid.for_each_within(p, r, f);
        }
    }
}

impl LevelGrid {
    /// [`PhotonGrid::build`] for level `k`.
    fn build(&mut self, cells: Level, chunks: &[HitChunk], k: usize) {
        let (size, width) = (cells.table_size(), cells.slab_width() as usize);
        let totals: Vec<usize> = (0..cells.slabs())
            .map(|s| chunks.iter().map(|c| c.slab(k, s).0.len()).sum())
            .collect();
        let n: usize = totals.iter().sum();
        // Rounds hold a few million hits (`ROUND_HITS`); entry indices are u32.
        assert!(u32::try_from(n).is_ok(), "{n} photon hits in one grid");
        self.cells = Some(cells);
        self.starts.resize(size + 1, 0);
        self.starts[size] = n as u32;
        // Every entry is written below: growing fills the new part only, once.
        self.points.resize(n, Vec3A::ZERO);
        self.flux.resize(n, (Vec3::ZERO, Vec3::ZERO));
        // Each slab's part of the entry arrays.
        let mut parts = Vec::with_capacity(totals.len());
        let (mut points, mut flux) = (&mut self.points[..n], &mut self.flux[..n]);
        let mut base = 0;
        for &t in &totals {
            let (p, rest_p) = points.split_at_mut(t);
            let (f, rest_f) = flux.split_at_mut(t);
            parts.push((base, p, f));
            (points, flux, base) = (rest_p, rest_f, base + t);
        }
        self.starts[..size]
            .par_chunks_mut(width)
            .zip(parts)
            .enumerate()
            .for_each(|(s, (starts, (base, points, flux)))| {
                let first = s * width;
                starts.fill(0);
                // The counting pass reads the buckets alone.
                for c in chunks {
                    for &b in c.slab(k, s).0 {
                        starts[b as usize - first] += 1;
                    }
                }
                let mut next = base as u32;
                for c in starts.iter_mut() {
                    (*c, next) = (next, next + *c);
                }
                let mut fill = starts.to_vec();
                for c in chunks {
                    for h in c.slab(k, s).1 {
                        let b = h.bucket as usize - first;
                        let k = fill[b] as usize - base;
                        fill[b] += 1;
                        points[k] = h.p.into();
                        flux[k] = (h.wi, h.beta);
                    }
                }
            });
    }

    /// Calls `f(wi, flux)` for every photon within `r` of `p` (`r` at most the level's
    /// largest radius), each once, in entry order.
    #[inline]
    fn for_each_within(&self, p: Vec3A, r: f32, mut f: impl FnMut(Vec3A, Vec3A)) {
        let Some(cells) = &self.cells else {
            return;
        };
        let r2 = r * r;
        // Every run's entries are located and their first cache lines asked for before the
        // first run is read, so that the runs' cache misses overlap (the entries themselves,
        // and their order, are the runs').
        let mut runs = cells.bucket_runs(p, r);
        for run in &mut runs {
            *run = (self.starts[run.0 as usize], self.starts[run.1 as usize]);
            if run.0 < run.1 {
                points::prefetch(&self.points, run.0 as usize);
                points::prefetch(&self.flux, run.0 as usize);
            }
        }
        for (start, end) in runs {
            points::within(&self.points, start as usize, end as usize, p, r2, |k| {
                let (wi, beta) = self.flux[k];
                f(wi.into(), beta.into());
            });
        }
    }
}

mod points;
#[cfg(test)]
mod tests;
