//! A hashed uniform grid over the light vertices of one iteration, for merging: cells two
//! radii wide, so that the points within the radius of a query lie in the 2 x 2 x 2 cells
//! nearest it (as in SmallVCM's hash grid: 8 lookups instead of 27 for cells one radius wide);
//! cells hash into a power-of-two table at least as long as the vertex list. The points are
//! copied in bucket order, so a query reads each bucket's points from one run of memory. Built
//! by counting sort into arrays that are kept and reused from one iteration to the next.
//! Each camera path queries with its own radius: up to the one the grid was built for, the
//! 2 x 2 x 2 cells; above it (rare: the grid follows the largest radius of the last
//! iteration), every cell the query's ball overlaps, or every point if those are more than the
//! table's buckets.

use glam::{DVec3, Vec3A};

#[derive(Default)]
pub(super) struct Grid {
    min: DVec3,
    inv_cell: f64,
    /// The radius the cells are two of wide.
    radius: f32,
    /// log2 of the table's length.
    bits: u32,
    /// `starts[h]..starts[h + 1]` are the positions in `items` and `points` of the points in
    /// hash bucket h.
    starts: Vec<u32>,
    /// Each entry's index in the point list given to `build`.
    items: Vec<u32>,
    /// The points in bucket order (`points[k]` is the point `items[k]`).
    points: Vec<Vec3A>,
    /// Each point's bucket (kept only to reuse its allocation).
    buckets: Vec<u32>,
}

impl Grid {
    /// Rebuilds the grid over `points` for queries of radius `r`, reusing its arrays; `false`
    /// (and nothing to query) with no points or no usable radius.
    pub(super) fn build(&mut self, points: &[Vec3A], r: f32) -> bool {
        if points.is_empty() || !(r > 0.0 && r.is_finite()) {
            return false;
        }
        let (min, max) = points.iter().fold(
            (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        if !(min.is_finite() && max.is_finite()) {
            return false;
        }
        self.min = min.as_dvec3();
        self.inv_cell = 0.5 / f64::from(r);
        self.radius = r;
        let len = points.len().next_power_of_two();
        self.bits = len.trailing_zeros();
        self.items.clear();
        self.items.resize(points.len(), 0);
        self.points.clear();
        self.points.resize(points.len(), Vec3A::ZERO);
        self.starts.clear();
        self.starts.resize(len + 1, 0);
        let mut buckets = std::mem::take(&mut self.buckets);
        buckets.clear();
        buckets.extend(points.iter().map(|p| self.bucket(self.cell(*p))));
        for &b in &buckets {
            self.starts[b as usize + 1] += 1;
        }
        for i in 1..self.starts.len() {
            self.starts[i] += self.starts[i - 1];
        }
        // Fill the buckets in point order, each bucket's start serving as its cursor; the
        // cursors end at the next bucket's start, so the starts shift back by one after.
        for (i, &b) in buckets.iter().enumerate() {
            let cursor = &mut self.starts[b as usize];
            self.items[*cursor as usize] = i as u32;
            self.points[*cursor as usize] = points[i];
            *cursor += 1;
        }
        self.starts.copy_within(..len, 1);
        self.starts[0] = 0;
        self.buckets = buckets;
        true
    }

    /// The cell of `p`, in cell units (the integer part is the cell, the rest the position in
    /// it); in f64, whose 53 bits keep the position within a cell exact enough for the choice of
    /// neighbours in a scene 10^7 radii wide, where f32's 24 would not.
    fn scaled(&self, p: Vec3A) -> DVec3 {
        (p.as_dvec3() - self.min) * self.inv_cell
    }

    fn cell(&self, p: Vec3A) -> [i64; 3] {
        let c = self.scaled(p).floor();
        [c.x as i64, c.y as i64, c.z as i64]
    }

    fn bucket(&self, c: [i64; 3]) -> u32 {
        let h = (c[0].wrapping_mul(73_856_093))
            ^ (c[1].wrapping_mul(19_349_663))
            ^ (c[2].wrapping_mul(83_492_791));
        // Fibonacci hashing: the high bits of the product mix every bit of `h`.
        let mixed = (h as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        mixed.checked_shr(64 - self.bits).unwrap_or(0) as u32
    }

    /// Calls `f(index)` for every point within `r` of `p`, each once.
    pub(super) fn for_each_within(&self, p: Vec3A, r: f32, mut f: impl FnMut(usize)) {
        if r > self.radius {
            return self.for_each_within_wide(p, r, f);
        }
        let q = self.scaled(p);
        let c = q.floor();
        // The neighbour on each axis is on the side of the cell's half that `p` lies in: a
        // ball of radius r (half a cell) around `p` reaches no further cell.
        let side = |x: f64, cx: f64| if x - cx >= 0.5 { 1 } else { -1 };
        let o = [side(q.x, c.x), side(q.y, c.y), side(q.z, c.z)];
        let c = [c.x as i64, c.y as i64, c.z as i64];
        let r2 = r * r;
        // Cells hashing into the same bucket are visited once.
        let mut seen = [u32::MAX; 8];
        for k in 0..8 {
            let cell = [
                // Wrapping: a cell index saturated at i64's end (a point ~10^19 cells away)
                // still hashes, as the build's did.
                c[0].wrapping_add(if k & 1 != 0 { o[0] } else { 0 }),
                c[1].wrapping_add(if k & 2 != 0 { o[1] } else { 0 }),
                c[2].wrapping_add(if k & 4 != 0 { o[2] } else { 0 }),
            ];
            let b = self.bucket(cell);
            if seen[..k].contains(&b) {
                continue;
            }
            seen[k] = b;
            let (s, e) = (
                self.starts[b as usize] as usize,
                self.starts[b as usize + 1] as usize,
            );
            for (&pt, &i) in self.points[s..e].iter().zip(&self.items[s..e]) {
                if (pt - p).length_squared() <= r2 {
                    f(i as usize);
                }
            }
        }
    }
}

impl Grid {
    /// `for_each_within` for a radius above the grid's: the buckets of every cell the ball's
    /// bounding box overlaps, each once, in bucket order; or every point where those cells
    /// outnumber the buckets.
    fn for_each_within_wide(&self, p: Vec3A, r: f32, mut f: impl FnMut(usize)) {
        let q = self.scaled(p);
        let e = f64::from(r) * self.inv_cell;
        // Cell indices as `cell` gives them (saturated far away); their count in i128.
        let (lo, hi) = ((q - e).floor().as_i64vec3(), (q + e).floor().as_i64vec3());
        let span = |a: i64, b: i64| i128::from(b) - i128::from(a) + 1;
        let cells = span(lo.x, hi.x) * span(lo.y, hi.y) * span(lo.z, hi.z);
        let r2 = r * r;
        let n_buckets = self.starts.len().saturating_sub(1);
        let mut visit = |s: usize, e: usize| {
            for (&pt, &i) in self.points[s..e].iter().zip(&self.items[s..e]) {
                if (pt - p).length_squared() <= r2 {
                    f(i as usize);
                }
            }
        };
        if cells > n_buckets as i128 {
            return visit(0, self.points.len());
        }
        // Up to 4 x 4 x 4 cells (a radius up to 1.5 times the grid's) on the stack, more in
        // a buffer kept by the thread (no allocation a query).
        let mut each_bucket = |buckets: &mut [u32]| {
            let mut k = 0;
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        buckets[k] = self.bucket([x, y, z]);
                        k += 1;
                    }
                }
            }
            // Sorted, so a bucket that several cells hash to is read once.
            buckets.sort_unstable();
            for (j, &b) in buckets.iter().enumerate() {
                if j == 0 || buckets[j - 1] != b {
                    let b = b as usize;
                    visit(self.starts[b] as usize, self.starts[b + 1] as usize);
                }
            }
        };
        if cells <= 64 {
            each_bucket(&mut [0u32; 64][..cells as usize]);
        } else {
            WIDE_BUCKETS.with_borrow_mut(|buckets| {
                buckets.clear();
                buckets.resize(cells as usize, 0);
                each_bucket(buckets);
            });
        }
    }
}

thread_local! {
    /// The bucket list of a wide query over more than 64 cells, reused by the thread.
    static WIDE_BUCKETS: std::cell::RefCell<Vec<u32>> = const { std::cell::RefCell::new(Vec::new()) };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// The points the grid finds within `r` of `q` are exactly a brute-force scan's, each once.
    fn assert_finds_what_brute_force_finds(grid: &Grid, points: &[Vec3A], q: Vec3A, r: f32) {
        let mut found = Vec::new();
        grid.for_each_within(q, r, |i| found.push(i));
        found.sort_unstable();
        let expected: Vec<usize> = (0..points.len())
            .filter(|&i| (points[i] - q).length_squared() <= r * r)
            .collect();
        assert_eq!(found, expected, "query {q}");
    }

    /// The grid finds exactly the points a brute-force scan finds, each once.
    #[test]
    fn grid_finds_what_brute_force_finds() {
        let mut rng = Rng::new(11);
        let points: Vec<Vec3A> = (0..3000)
            .map(|_| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 4.0 - 1.0)
            .collect();
        let r = 0.2;
        let mut grid = Grid::default();
        assert!(grid.build(&points, r));
        for _ in 0..300 {
            let q = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 5.0 - 1.5;
            assert_finds_what_brute_force_finds(&grid, &points, q, r);
            // Camera paths with radii smaller and larger than the grid's (up to the whole
            // point set, where the cells outnumber the buckets).
            for k in [0.3, 1.7, 4.0, 30.0] {
                assert_finds_what_brute_force_finds(&grid, &points, q, r * k);
            }
        }
    }

    /// A scene 10^7 radii wide (one vertex far off, the rest in a small cluster): every point
    /// within the radius is still found, each once. In f32, `p - min` alone would round the
    /// cluster's positions to whole cells.
    #[test]
    fn a_wide_scene_loses_no_neighbour() {
        let mut rng = Rng::new(5);
        let mut points = vec![Vec3A::splat(-1.0e5)];
        points.extend((0..2000).map(|_| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 0.05));
        let r = 0.002;
        let mut grid = Grid::default();
        assert!(grid.build(&points, r));
        for _ in 0..500 {
            let q = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 0.05;
            assert_finds_what_brute_force_finds(&grid, &points, q, r);
        }
        // A query far from every cell (its index saturates) finds nothing and does not panic.
        let mut none = true;
        grid.for_each_within(Vec3A::splat(3.0e38), r, |_| none = false);
        grid.for_each_within(Vec3A::splat(-3.0e38), r, |_| none = false);
        // So with a radius above the grid's.
        grid.for_each_within(Vec3A::splat(3.0e38), r * 3.0, |_| none = false);
        grid.for_each_within(Vec3A::splat(-3.0e38), r * 3.0, |_| none = false);
        assert!(none);
    }
}
