//! A hashed uniform grid over the light vertices of one iteration, for merging: cells one
//! radius wide, so that the points within the radius of a query lie in the 27 cells around it;
//! cells hash into a table as long as the vertex list. Built by counting sort into arrays that
//! are kept and reused from one iteration to the next.

use glam::Vec3A;

#[derive(Default)]
pub(super) struct Grid {
    min: Vec3A,
    inv_cell: f32,
    /// `starts[h]..starts[h + 1]` are the positions in `items` of the points in hash bucket h.
    starts: Vec<u32>,
    items: Vec<u32>,
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
        self.min = min;
        self.inv_cell = 1.0 / r;
        self.items.clear();
        self.items.resize(points.len(), 0);
        self.starts.clear();
        self.starts.resize(points.len() + 1, 0);
        let mut buckets = std::mem::take(&mut self.buckets);
        buckets.clear();
        buckets.extend(points.iter().map(|p| self.bucket_of(*p)));
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
            *cursor += 1;
        }
        self.starts.copy_within(..points.len(), 1);
        self.starts[0] = 0;
        self.buckets = buckets;
        true
    }

    fn cell(&self, p: Vec3A) -> [i64; 3] {
        let c = ((p - self.min) * self.inv_cell).floor();
        [c.x as i64, c.y as i64, c.z as i64]
    }

    fn bucket(&self, c: [i64; 3]) -> u32 {
        let h = (c[0].wrapping_mul(73_856_093))
            ^ (c[1].wrapping_mul(19_349_663))
            ^ (c[2].wrapping_mul(83_492_791));
        (h as u64 % self.items.len() as u64) as u32
    }

    fn bucket_of(&self, p: Vec3A) -> u32 {
        self.bucket(self.cell(p))
    }

    /// Calls `f(index)` for every point within `r` of `p` (the grid's radius), each once.
    pub(super) fn for_each_within(
        &self,
        points: &[Vec3A],
        p: Vec3A,
        r: f32,
        mut f: impl FnMut(usize),
    ) {
        let c = self.cell(p);
        let r2 = r * r;
        // Cells hashing into the same bucket are visited once: the buckets of the 27 cells,
        // deduplicated (a small list).
        let mut seen = [u32::MAX; 27];
        let mut n = 0;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let b = self.bucket([c[0] + dx, c[1] + dy, c[2] + dz]);
                    if seen[..n].contains(&b) {
                        continue;
                    }
                    seen[n] = b;
                    n += 1;
                    let (s, e) = (self.starts[b as usize], self.starts[b as usize + 1]);
                    for &i in &self.items[s as usize..e as usize] {
                        if (points[i as usize] - p).length_squared() <= r2 {
                            f(i as usize);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

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
            let mut found = Vec::new();
            grid.for_each_within(&points, q, r, |i| found.push(i));
            found.sort_unstable();
            let expected: Vec<usize> = (0..points.len())
                .filter(|&i| (points[i] - q).length_squared() <= r * r)
                .collect();
            assert_eq!(found, expected);
        }
    }
}
