//! A hashed uniform grid over the light vertices of one iteration, for merging: cells two
//! radii wide, so that the points within the radius of a query lie in the 2 x 2 x 2 cells
//! nearest it (as in SmallVCM's hash grid: 8 lookups instead of 27 for cells one radius wide).
//! Cells hash into a power-of-two table, the *order table*, at least as long as the vertex
//! list; each of its buckets is split in `2^SUB_BITS` *fine buckets* (the next bits of the same
//! hash), and the points are copied in fine-bucket order, so that a query reads each fine
//! bucket's points from one run of memory. The fine buckets spare a query the points of the
//! other cells its order bucket holds (with one point a cell on average, most of a bucket's);
//! the order table fixes the order in which a query reports what it finds: by order bucket, in
//! the order of the query's cells, and within an order bucket by point index (the fine buckets
//! of one order bucket that a query's cells share are read merged by index). The sums of the
//! merges, and so the image, are therefore bit for bit those of a grid of the order table alone.
//! Built by counting sort into arrays that are kept and reused from one iteration to the next.
//! Each camera path queries with its own radius: up to the one the grid was built for, the
//! 2 x 2 x 2 cells; above it (rare: the grid follows the largest radius of the last
//! iteration), every cell the query's ball overlaps, or every point if those are more than the
//! order table's buckets.

use glam::{DVec3, Vec3A};

/// log2 of the fine buckets an order bucket splits into.
const SUB_BITS: u32 = 2;

#[derive(Default)]
pub(super) struct Grid {
    min: DVec3,
    inv_cell: f64,
    /// The radius the cells are two of wide.
    radius: f32,
    /// log2 of the order table's length.
    bits: u32,
    /// `starts[h]..starts[h + 1]` are the positions in `items` and `points` of the points in
    /// fine bucket h (order bucket `h >> SUB_BITS`).
    starts: Vec<u32>,
    /// Each entry's index in the point list given to `build`.
    items: Vec<u32>,
    /// The points in fine-bucket order (`points[k]` is the point `items[k]`).
    points: Vec<Vec3A>,
    /// Each point's fine bucket (kept only to reuse its allocation).
    buckets: Vec<u32>,
}

/// `x.floor()` without a call to libm's `floor` (x86-64 without SSE4.1 has no rounding
/// instruction): exact up to the sign of zero (-0.0 gives +0.0, which no caller tells apart),
/// since every f64 of magnitude 2^52 or more (and infinity, NaN) is its own floor, and below
/// that the truncation to i64 is exact.
#[inline]
fn floor(x: f64) -> f64 {
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = x as i64 as f64;
        if t > x { t - 1.0 } else { t }
    } else {
        x
    }
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
        let fine = len << SUB_BITS;
        self.items.clear();
        self.items.resize(points.len(), 0);
        self.points.clear();
        self.points.resize(points.len(), Vec3A::ZERO);
        self.starts.clear();
        self.starts.resize(fine + 1, 0);
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
        self.starts.copy_within(..fine, 1);
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
        let q = self.scaled(p);
        [floor(q.x) as i64, floor(q.y) as i64, floor(q.z) as i64]
    }

    /// The fine bucket of cell `c`, from the products of its indices with the hash's primes.
    fn bucket(&self, c: [i64; 3]) -> u32 {
        self.bucket_of(
            c[0].wrapping_mul(PRIMES[0]),
            c[1].wrapping_mul(PRIMES[1]),
            c[2].wrapping_mul(PRIMES[2]),
        )
    }

    fn bucket_of(&self, x: i64, y: i64, z: i64) -> u32 {
        let h = x ^ y ^ z;
        // Fibonacci hashing: the high bits of the product mix every bit of `h`; the order
        // bucket is the top `bits` of them, the fine bucket `SUB_BITS` more.
        let mixed = (h as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        (mixed >> (64 - self.bits - SUB_BITS)) as u32
    }

    /// The points of fine bucket `b` within `sqrt(r2)` of `p`, in index order.
    #[inline(always)]
    fn visit(&self, b: u32, p: Vec3A, r2: f32, f: &mut impl FnMut(usize)) {
        self.visit_range(self.range(b), p, r2, f);
    }

    /// The positions in `items` and `points` of fine bucket `b`'s points.
    #[inline(always)]
    fn range(&self, b: u32) -> (usize, usize) {
        (
            self.starts[b as usize] as usize,
            self.starts[b as usize + 1] as usize,
        )
    }

    /// The points at positions `s..e` within `sqrt(r2)` of `p`, in index order.
    #[inline(always)]
    fn visit_range(&self, (s, e): (usize, usize), p: Vec3A, r2: f32, f: &mut impl FnMut(usize)) {
        for (&pt, &i) in self.points[s..e].iter().zip(&self.items[s..e]) {
            if (pt - p).length_squared() <= r2 {
                f(i as usize);
            }
        }
    }

    /// The points of several fine buckets (distinct, at most 8: a query's cells, or one order
    /// bucket's) within `sqrt(r2)` of `p`, merged in index order.
    fn visit_merged(&self, buckets: &[u32], p: Vec3A, r2: f32, f: &mut impl FnMut(usize)) {
        debug_assert!(buckets.len() <= 8, "{} buckets", buckets.len());
        let mut ranges = [(0usize, 0usize); 8];
        for (range, &b) in ranges.iter_mut().zip(buckets) {
            *range = self.range(b);
        }
        let ranges = &mut ranges[..buckets.len().min(8)];
        loop {
            let mut next: Option<(usize, u32)> = None;
            for (m, &(s, e)) in ranges.iter().enumerate() {
                if s < e && next.is_none_or(|(_, i)| self.items[s] < i) {
                    next = Some((m, self.items[s]));
                }
            }
            let Some((m, i)) = next else {
                return;
            };
            let s = ranges[m].0;
            ranges[m].0 += 1;
            if (self.points[s] - p).length_squared() <= r2 {
                f(i as usize);
            }
        }
    }

    /// The fine buckets of one order bucket (distinct), read merged by index.
    fn visit_fine(&self, fine: &[u32], p: Vec3A, r2: f32, f: &mut impl FnMut(usize)) {
        if let [b] = fine {
            self.visit(*b, p, r2, f);
        } else {
            self.visit_merged(fine, p, r2, f);
        }
    }

    /// Calls `f(index)` for every point within `r` of `p`, each once.
    pub(super) fn for_each_within(&self, p: Vec3A, r: f32, mut f: impl FnMut(usize)) {
        if self.points.is_empty() {
            return;
        }
        if r > self.radius {
            return self.for_each_within_wide(p, r, f);
        }
        let q = self.scaled(p);
        let c = DVec3::new(floor(q.x), floor(q.y), floor(q.z));
        // The neighbour on each axis is on the side of the cell's half that `p` lies in: a
        // ball of radius r (half a cell) around `p` reaches no further cell.
        let side = |x: f64, cx: f64| if x - cx >= 0.5 { 1 } else { -1 };
        let o = [side(q.x, c.x), side(q.y, c.y), side(q.z, c.z)];
        let c = [c.x as i64, c.y as i64, c.z as i64];
        // Each axis's two products with the hash's primes. Wrapping: a cell index saturated
        // at i64's end (a point ~10^19 cells away) still hashes, as the build's did.
        let axis = |a: usize| {
            [
                c[a].wrapping_mul(PRIMES[a]),
                c[a].wrapping_add(o[a]).wrapping_mul(PRIMES[a]),
            ]
        };
        let (hx, hy, hz) = (axis(0), axis(1), axis(2));
        let fine: [u32; 8] =
            std::array::from_fn(|k| self.bucket_of(hx[k & 1], hy[(k >> 1) & 1], hz[k >> 2]));
        let r2 = r * r;
        // Nearly always the 8 cells fall in 8 order buckets: their fine buckets are read in
        // the cells' order, their bounds loaded first (independent loads).
        let order = fine.map(|b| b >> SUB_BITS);
        let mut shared = false;
        for i in 0..8 {
            for j in i + 1..8 {
                shared |= order[i] == order[j];
            }
        }
        if !shared {
            for range in fine.map(|b| self.range(b)) {
                self.visit_range(range, p, r2, &mut f);
            }
            return;
        }
        for k in 0..8 {
            let order = fine[k] >> SUB_BITS;
            // An order bucket an earlier cell hashed to is read already.
            if fine[..k].iter().any(|&a| a >> SUB_BITS == order) {
                continue;
            }
            // This order bucket's fine buckets among this and the later cells, each once:
            // read merged by index where there are several.
            let mut shared = [0u32; 8];
            let mut n = 0;
            for &a in &fine[k..] {
                if a >> SUB_BITS == order && !shared[..n].contains(&a) {
                    shared[n] = a;
                    n += 1;
                }
            }
            self.visit_fine(&shared[..n], p, r2, &mut f);
        }
    }
}

/// The primes of the spatial hash (Teschner et al. 2003).
const PRIMES: [i64; 3] = [73_856_093, 19_349_663, 83_492_791];

impl Grid {
    /// `for_each_within` for a radius above the grid's: the fine buckets of every cell the
    /// ball's bounding box overlaps, each once, by order bucket; or every point where those
    /// cells outnumber the order table's buckets.
    fn for_each_within_wide(&self, p: Vec3A, r: f32, mut f: impl FnMut(usize)) {
        let q = self.scaled(p);
        let e = f64::from(r) * self.inv_cell;
        // Cell indices as `cell` gives them (saturated far away); their count in i128.
        let lo = (q - e).to_array().map(|x| floor(x) as i64);
        let hi = (q + e).to_array().map(|x| floor(x) as i64);
        let span = |a: i64, b: i64| i128::from(b) - i128::from(a) + 1;
        // `None` past i128 (an infinite radius, or one ~10^13 times the grid's): more cells than
        // any table's buckets.
        let cells = span(lo[0], hi[0])
            .checked_mul(span(lo[1], hi[1]))
            .and_then(|c| c.checked_mul(span(lo[2], hi[2])));
        let r2 = r * r;
        let n_order = (self.starts.len().saturating_sub(1)) >> SUB_BITS;
        let Some(cells) = cells.filter(|&c| c <= n_order as i128) else {
            let all: [u32; 1 << SUB_BITS] = std::array::from_fn(|k| k as u32);
            for order in 0..n_order as u32 {
                self.visit_fine(&all.map(|k| (order << SUB_BITS) + k), p, r2, &mut f);
            }
            return;
        };
        // Up to 4 x 4 x 4 cells (a radius up to 1.5 times the grid's) on the stack, more in
        // a buffer kept by the thread (no allocation a query).
        let mut each_bucket = |buckets: &mut [u32]| {
            let mut k = 0;
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        buckets[k] = self.bucket([x, y, z]);
                        k += 1;
                    }
                }
            }
            // Sorted, so a bucket that several cells hash to is read once, and the order
            // buckets come in order.
            buckets.sort_unstable();
            let mut j = 0;
            while j < buckets.len() {
                let order = buckets[j] >> SUB_BITS;
                let mut end = j + 1;
                while end < buckets.len() && buckets[end] >> SUB_BITS == order {
                    end += 1;
                }
                let mut fine = [0u32; 1 << SUB_BITS];
                let mut n = 0;
                for &b in &buckets[j..end] {
                    if n == 0 || fine[n - 1] != b {
                        fine[n] = b;
                        n += 1;
                    }
                }
                self.visit_fine(&fine[..n], p, r2, &mut f);
                j = end;
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

    /// A uniform point of the unit cube.
    fn unit_point(rng: &mut Rng) -> Vec3A {
        Vec3A::new(rng.f32(), rng.f32(), rng.f32())
    }

    /// The grid's `floor` is `f64::floor` (up to the sign of zero) at the edges of its
    /// branches: just below integers, around 2^52, beyond i64, infinities and NaN.
    #[test]
    fn floor_is_f64_floor() {
        let below_one = 1.0 - f64::EPSILON / 2.0;
        let big = 4_503_599_627_370_496.0; // 2^52
        let mut xs = vec![
            0.0,
            -0.0,
            -1e-300,
            1e-300,
            below_one,
            -below_one,
            -1.0,
            2.5,
            -2.5,
            big,
            -big,
            big - 0.5,
            -(big - 0.5),
            big + 1.0,
            9.3e18,
            -9.3e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
        ];
        let mut rng = Rng::new(21);
        xs.extend((0..10_000).map(|_| (f64::from(rng.f32()) - 0.5) * 1e6));
        for x in xs {
            let (a, b) = (floor(x), x.floor());
            assert!(a == b, "floor({x:e}) = {a:e}, f64::floor {b:e}");
        }
        assert!(floor(f64::NAN).is_nan());
    }

    /// A wide query whose ball spans more cells than i128 counts (an infinite radius) finds
    /// every point, as brute force does.
    #[test]
    fn a_query_of_infinite_radius_finds_every_point() {
        let points: Vec<Vec3A> = (0..50)
            .map(|k| Vec3A::new(k as f32, (k * 7 % 13) as f32, -(k as f32)))
            .collect();
        let mut grid = Grid::default();
        assert!(grid.build(&points, 0.5));
        for r in [f32::INFINITY, f32::MAX, 1e30] {
            let mut found = Vec::new();
            grid.for_each_within(Vec3A::ZERO, r, |i| found.push(i));
            found.sort_unstable();
            assert_eq!(found, (0..50).collect::<Vec<_>>(), "radius {r}");
        }
    }

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
            .map(|_| unit_point(&mut rng) * 4.0 - 1.0)
            .collect();
        let r = 0.2;
        let mut grid = Grid::default();
        assert!(grid.build(&points, r));
        for _ in 0..300 {
            let q = unit_point(&mut rng) * 5.0 - 1.5;
            assert_finds_what_brute_force_finds(&grid, &points, q, r);
            // Camera paths with radii smaller and larger than the grid's (up to the whole
            // point set, where the cells outnumber the buckets).
            for k in [0.3, 1.7, 4.0, 30.0] {
                assert_finds_what_brute_force_finds(&grid, &points, q, r * k);
            }
        }
    }

    /// The order a query of the old, unsplit table reported its points in: by order bucket
    /// (the 8 cells' in their order, a wide query's in increasing order, or every order bucket
    /// where its cells outnumber them), then by index.
    fn order_table_order(grid: &Grid, points: &[Vec3A], q: Vec3A, r: f32) -> Vec<usize> {
        let order = |c: [i64; 3]| grid.bucket(c) >> SUB_BITS;
        let s = grid.scaled(q);
        let mut buckets: Vec<u32> = if r <= grid.radius {
            let c = grid.cell(q);
            let side = |a: usize| if s[a] - s[a].floor() >= 0.5 { 1 } else { -1 };
            (0..8)
                .map(|k| {
                    order(std::array::from_fn(|a| {
                        c[a].wrapping_add(if k & (1 << a) != 0 { side(a) } else { 0 })
                    }))
                })
                .collect()
        } else {
            let e = f64::from(r) * grid.inv_cell;
            let (lo, hi) = ((s - e).floor().as_i64vec3(), (s + e).floor().as_i64vec3());
            let n_order = (grid.starts.len() - 1) >> SUB_BITS;
            let cells = (hi - lo + 1).as_dvec3().element_product();
            let mut b: Vec<u32> = if cells > n_order as f64 {
                (0..n_order as u32).collect()
            } else {
                let mut b = Vec::new();
                for z in lo.z..=hi.z {
                    for y in lo.y..=hi.y {
                        for x in lo.x..=hi.x {
                            b.push(order([x, y, z]));
                        }
                    }
                }
                b
            };
            b.sort_unstable();
            b
        };
        let mut seen = Vec::new();
        buckets.retain(|b| {
            let new = !seen.contains(b);
            seen.push(*b);
            new
        });
        buckets
            .iter()
            .flat_map(|&b| {
                (0..points.len()).filter(move |&i| {
                    order(grid.cell(points[i])) == b && (points[i] - q).length_squared() <= r * r
                })
            })
            .collect()
    }

    /// The fine buckets change nothing in the order a query reports its points in (so neither
    /// in a merge's sum): that of the order table alone, also where several of a query's cells
    /// share an order bucket (few points, so a short table) and for wide queries.
    #[test]
    fn queries_report_points_in_the_order_tables_order() {
        let mut rng = Rng::new(3);
        for n in [1, 2, 3, 5, 9, 40, 600] {
            let points: Vec<Vec3A> = (0..n).map(|_| unit_point(&mut rng) * 2.0).collect();
            let r = 0.3;
            let mut grid = Grid::default();
            assert!(grid.build(&points, r));
            for _ in 0..200 {
                let q = unit_point(&mut rng) * 2.4 - 0.2;
                for k in [1.0, 0.5, 1.3, 2.5, 20.0] {
                    let mut found = Vec::new();
                    grid.for_each_within(q, r * k, |i| found.push(i));
                    let expected = order_table_order(&grid, &points, q, r * k);
                    assert_eq!(found, expected, "{n} points, query {q}, radius {}", r * k);
                }
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
        points.extend((0..2000).map(|_| unit_point(&mut rng) * 0.05));
        let r = 0.002;
        let mut grid = Grid::default();
        assert!(grid.build(&points, r));
        for _ in 0..500 {
            let q = unit_point(&mut rng) * 0.05;
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
