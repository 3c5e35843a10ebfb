//! The hash grid over one iteration's visible points, which the photon pass looks up at every
//! photon hit.
//!
//! Layout, chosen for the photon pass's memory traffic (the lookup was the largest part of it,
//! waiting on cache misses): every visible point is stored **once**, in the cell that holds its
//! position; the cells are `2 r_max` wide (a little more), so the points within `r_max` of a
//! photon lie in the 2x2x2 cells nearest to it, and a lookup reads those cells' buckets (at most
//! 4 contiguous runs: see [`row`]). The entries of a bucket are contiguous: the position and radius^2 (16 bytes, all the distance test reads)
//! in one array, and in a parallel array a [`Receiver`] (48 bytes: what evaluating the point's
//! BSDF for the photon's direction needs). At 256x256 that is 4 MB per iteration, where listing
//! each point in every cell its disc overlaps (8 copies) and reading the BSDF from the pixel took
//! 10 MB of entries and 15 MB of pixels.

use arrayvec::ArrayVec;
use glam::{Vec3A, Vec4};

use super::VisiblePoint;
use crate::geometry::Aabb;

/// Set in [`Receiver::pixel`] when the point's BSDF depends on the directions (glossy): the
/// photon pass then evaluates the full BSDF kept in the pixel. Pixel indices stay below 2^27
/// (the renderer's resolution limit), so the bit is free.
const FULL_BSDF: u32 = 1 << 31;

/// A visible point's BSDF reduced for the photon pass: [`crate::materials::Bsdf::f`] with its
/// `wo` fixed. Both side tests are kept in the same form (`(wo . n) * (wi . n) <= 0` rejects),
/// so the result is bit-identical to calling the BSDF.
#[derive(Clone, Copy, Debug)]
pub(super) struct Receiver {
    /// Geometric normal, and `wo . ng` in `w`.
    ng: Vec4,
    /// Shading normal, and `wo . ns` in `w`.
    ns: Vec4,
    /// The constant BSDF value (unused with `FULL_BSDF`).
    f: [f32; 3],
    /// The pixel the point belongs to, with the `FULL_BSDF` flag.
    pixel: u32,
}

impl Receiver {
    fn new(pixel: u32, vp: &VisiblePoint) -> Self {
        let (ng, ns) = (vp.bsdf.ng, vp.bsdf.frame.n);
        let (f, flag) = match vp.bsdf.constant_f() {
            Some(f) => (f.to_array(), 0),
            None => ([0.0; 3], FULL_BSDF),
        };
        Receiver {
            ng: ng.extend(vp.wo.dot(ng)),
            ns: ns.extend(vp.wo.dot(ns)),
            f,
            pixel: pixel | flag,
        }
    }

    /// The pixel the visible point belongs to.
    #[inline]
    pub(super) fn pixel(&self) -> u32 {
        self.pixel & !FULL_BSDF
    }

    /// The BSDF for light arriving from `wi` (toward the point's `wo`), or `None` when the
    /// caller must evaluate the point's full BSDF.
    #[inline]
    pub(super) fn f(&self, wi: Vec3A) -> Option<Vec3A> {
        if self.pixel & FULL_BSDF != 0 {
            return None;
        }
        let (ng, ns) = (
            Vec3A::from(self.ng.truncate()),
            Vec3A::from(self.ns.truncate()),
        );
        if self.ng.w * wi.dot(ng) <= 0.0 || self.ns.w * wi.dot(ns) <= 0.0 {
            return Some(Vec3A::ZERO);
        }
        Some(Vec3A::from_array(self.f))
    }
}

pub(super) struct Grid {
    /// The points' bounds grown by the largest radius: no photon outside finds a point.
    bounds: Aabb,
    inv_cell: f32,
    res: [i32; 3],
    /// log2 of the range of [`row`] (a power of two, at least twice the number of points); the
    /// table has `2^bits + res[0]` buckets.
    bits: u32,
    /// Bucket `b`'s entries are `starts[b]..starts[b + 1]`.
    starts: Vec<u32>,
    /// Per entry: the visible point's position and radius^2.
    points: Vec<Vec4>,
    /// Per entry: the point's BSDF and pixel.
    receivers: Vec<Receiver>,
}

/// The bucket of the cell `(0, y, z)`: a spatial hash of `y` and `z` (two of the classic three
/// primes, then a Fibonacci multiply whose top `bits` bits index a power-of-two range). Cell
/// `(x, y, z)` has bucket `row(y, z) + x` (the table has `2^bits + res_x` buckets, so this never
/// wraps): cells next to each other along `x` have consecutive buckets and their entries are one
/// contiguous run, so a lookup of 2x2x2 cells reads at most 4 runs.
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

impl Grid {
    /// The grid over `(pixel, visible point, radius)`; `None` without a point of positive
    /// radius.
    pub(super) fn build<'a>(
        points: impl Iterator<Item = (u32, &'a VisiblePoint, f32)>,
    ) -> Option<Grid> {
        let points: Vec<(u32, &VisiblePoint, f32)> = points.filter(|(_, _, r)| *r > 0.0).collect();
        if points.is_empty() {
            return None;
        }
        let max_r = points.iter().map(|(_, _, r)| *r).fold(0.0, f32::max);
        let bounds = points
            .iter()
            .fold(Aabb::EMPTY, |b, (_, vp, _)| b.with_point(vp.p));
        let bounds = Aabb::new(
            bounds.min - Vec3A::splat(max_r),
            bounds.max + Vec3A::splat(max_r),
        );
        // A little over 2 r_max, so that rounding never puts a point within r_max of a photon
        // outside the photon's 2x2x2 cells.
        let cell = 2.0 * max_r * 1.001;
        let diag = bounds.diagonal();
        // Cap the resolution so that huge scenes with a tiny radius stay in range (cells only
        // grow: a lookup still finds every point within r_max).
        let inv_cell = (1.0 / cell).min(1024.0 / diag.max_element().max(1e-30));
        let res = [0, 1, 2].map(|a| ((diag[a] * inv_cell) as i32 + 1).max(1));
        let bits = (2 * points.len())
            .next_power_of_two()
            .trailing_zeros()
            .max(1);
        let size = (1usize << bits) + res[0] as usize;
        let bucket_of = |p: Vec3A| -> u32 {
            let c = (p - bounds.min) * inv_cell;
            let [x, y, z] = [0, 1, 2].map(|a| (c[a] as i32).clamp(0, res[a] - 1));
            row(y, z, bits) + x as u32
        };
        let buckets: Vec<u32> = points.iter().map(|(_, vp, _)| bucket_of(vp.p)).collect();
        let mut starts = vec![0u32; size + 1];
        for &b in &buckets {
            starts[b as usize + 1] += 1;
        }
        for i in 0..size {
            starts[i + 1] += starts[i];
        }
        // Each point's entry, in point order within each bucket (a counting sort).
        let mut fill = starts.clone();
        let mut order = vec![0u32; points.len()];
        for (k, &b) in buckets.iter().enumerate() {
            order[fill[b as usize] as usize] = k as u32;
            fill[b as usize] += 1;
        }
        let entry_points = order
            .iter()
            .map(|&k| {
                let (_, vp, r) = points[k as usize];
                vp.p.extend(r * r)
            })
            .collect();
        let receivers = order
            .iter()
            .map(|&k| {
                let (pixel, vp, _) = points[k as usize];
                Receiver::new(pixel, vp)
            })
            .collect();
        Some(Grid {
            bounds,
            inv_cell,
            res,
            bits,
            starts,
            points: entry_points,
            receivers,
        })
    }

    /// The entry ranges of the 2x2x2 cells nearest to `p` (fewer at the grid's border). Each
    /// row of (at most) two cells along `x` is a run of consecutive buckets; runs that share a
    /// bucket (two rows hashed close together) are merged, so that no entry is listed twice
    /// (it would take the photon twice).
    #[inline]
    fn ranges(&self, p: Vec3A) -> ArrayVec<(u32, u32), 4> {
        let mut out = ArrayVec::new();
        if p.cmplt(self.bounds.min).any() || p.cmpgt(self.bounds.max).any() {
            return out;
        }
        // The cube of half-width r_max around `p` is under half a cell wide, so it meets the
        // cell holding `c - 0.5` and the next one on each axis.
        let c = (p - self.bounds.min) * self.inv_cell - Vec3A::splat(0.5);
        let lo = [floor_i32(c.x), floor_i32(c.y), floor_i32(c.z)];
        let (x0, x1) = (lo[0].max(0), (lo[0] + 1).min(self.res[0] - 1));
        if x0 > x1 {
            return out;
        }
        let len = (x1 - x0 + 1) as u32;
        // The rows' first buckets, sorted (a 4-element sorting network; unused slots stay at
        // u32::MAX and sort last).
        let mut first = [u32::MAX; 4];
        let mut n = 0;
        for z in lo[2].max(0)..=(lo[2] + 1).min(self.res[2] - 1) {
            for y in lo[1].max(0)..=(lo[1] + 1).min(self.res[1] - 1) {
                first[n] = row(y, z, self.bits) + x0 as u32;
                n += 1;
            }
        }
        if n == 0 {
            return out;
        }
        for (i, j) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
            if first[i] > first[j] {
                first.swap(i, j);
            }
        }
        let (mut lo_b, mut hi_b) = (first[0], first[0] + len);
        for &b in &first[1..n] {
            if b <= hi_b {
                hi_b = hi_b.max(b + len);
            } else {
                out.push((self.starts[lo_b as usize], self.starts[hi_b as usize]));
                (lo_b, hi_b) = (b, b + len);
            }
        }
        out.push((self.starts[lo_b as usize], self.starts[hi_b as usize]));
        out
    }

    /// Calls `f` with every visible point whose disc holds `p` (distance <= its radius), each
    /// once.
    #[inline]
    pub(super) fn for_each_within(&self, p: Vec3A, mut f: impl FnMut(&Receiver)) {
        for (start, end) in self.ranges(p) {
            for k in start as usize..end as usize {
                let q = self.points[k];
                if (Vec3A::from(q.truncate()) - p).length_squared() <= q.w {
                    f(&self.receivers[k]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::{Bsdf, Lobes};
    use crate::sampling::{Rng, uniform_sphere};

    /// A visible point at `p` seen from `wo`, with shading normal `ns` and geometric `ng`.
    fn point(p: Vec3A, wo: Vec3A, lobes: Lobes, ns: Vec3A, ng: Vec3A) -> VisiblePoint {
        VisiblePoint {
            p,
            wo,
            bsdf: Bsdf::new(lobes, ns, ns.any_orthonormal_vector(), ng),
            beta: Vec3A::ONE,
        }
    }

    fn diffuse_point(p: Vec3A) -> VisiblePoint {
        let white = Lobes::Diffuse { albedo: Vec3A::ONE };
        point(p, Vec3A::Y, white, Vec3A::Y, Vec3A::Y)
    }

    fn random_in(rng: &mut Rng, size: f32) -> Vec3A {
        Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * size
    }

    /// The lookup must find every point whose disc holds the photon (the grid is only a
    /// filter; a point it misses loses that photon's flux), and each once. Checked against
    /// brute force over points with mixed radii, with photons everywhere (also outside the
    /// points' bounds and on cell borders), and with few points, where the table is small and
    /// cells often share a bucket.
    #[test]
    fn lookups_find_every_point_within_its_radius_once() {
        let mut rng = Rng::new(3);
        for (n_points, size) in [(3usize, 1.0f32), (40, 1.0), (2000, 4.0)] {
            let vps: Vec<VisiblePoint> = (0..n_points)
                .map(|_| diffuse_point(random_in(&mut rng, size)))
                .collect();
            let radii: Vec<f32> = (0..n_points).map(|_| 0.05 + 0.2 * rng.f32()).collect();
            let grid = Grid::build(
                vps.iter()
                    .zip(&radii)
                    .enumerate()
                    .map(|(i, (vp, &r))| (i as u32, vp, r)),
            )
            .unwrap();
            let mut found = 0;
            for i in 0..20_000 {
                let q = if i % 4 < 2 {
                    // On a border between the points' cells (integer cell coordinates) or
                    // between the lookup's choices of cells (an integer plus 0.5).
                    let c = random_in(&mut rng, 1.0) * Vec3A::from(grid.res.map(|r| r as f32));
                    grid.bounds.min
                        + (c.floor() + Vec3A::splat(0.5 * (i % 4) as f32)) / grid.inv_cell
                } else {
                    random_in(&mut rng, size * 1.4) - Vec3A::splat(size * 0.2)
                };
                let mut got = Vec::new();
                grid.for_each_within(q, |r| got.push(r.pixel()));
                got.sort_unstable();
                let n = got.len();
                got.dedup();
                assert_eq!(got.len(), n, "a point found twice at {q:?}");
                let want: Vec<u32> = (0..n_points as u32)
                    .filter(|&i| {
                        let (p, r) = (vps[i as usize].p, radii[i as usize]);
                        (p - q).length_squared() <= r * r
                    })
                    .collect();
                assert_eq!(got, want, "at {q:?} ({n_points} points)");
                found += n;
            }
            // The photons do land in discs (the test is not vacuous).
            assert!(found > 100, "{found} finds for {n_points} points");
        }
    }

    /// A receiver gives exactly what the BSDF gives, for every side combination (front and
    /// back, shading normal tilted away from the geometric one) and both kinds of lobes.
    #[test]
    fn receivers_match_the_bsdf_bit_for_bit() {
        let mut rng = Rng::new(5);
        let mut nonzero = 0;
        for i in 0..2000 {
            let ng = uniform_sphere(rng.vec2());
            let ns = (ng + 0.6 * uniform_sphere(rng.vec2())).normalize();
            let lobes = if i % 2 == 0 {
                Lobes::Diffuse {
                    albedo: Vec3A::new(0.7, 0.5, 0.2),
                }
            } else {
                Lobes::Glossy {
                    albedo: Vec3A::splat(0.3),
                    specular: Vec3A::splat(0.5),
                    alpha: 0.2,
                }
            };
            let wo = uniform_sphere(rng.vec2());
            let vp = point(Vec3A::ZERO, wo, lobes, ns, ng);
            let r = Receiver::new(7, &vp);
            assert_eq!(r.pixel(), 7);
            for _ in 0..8 {
                let wi = uniform_sphere(rng.vec2());
                let want = vp.bsdf.f(wo, wi);
                match r.f(wi) {
                    Some(f) => {
                        assert_eq!(
                            f.to_array().map(f32::to_bits),
                            want.to_array().map(f32::to_bits)
                        );
                        nonzero += usize::from(f != Vec3A::ZERO);
                    }
                    None => assert!(matches!(lobes, Lobes::Glossy { .. })),
                }
            }
        }
        assert!(nonzero > 1000, "{nonzero}");
    }
}
