//! A small static 3-d tree for k-nearest-neighbour photon lookups. Points are stored in an
//! implicit balanced tree: the median of a range sits in its middle, its split axis (the
//! widest extent of the range) in `axes`.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::Vec3A;

pub struct KdTree<T> {
    items: Vec<(Vec3A, T)>,
    axes: Vec<u8>,
}

#[derive(PartialEq)]
struct Candidate(f32, usize);

impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

impl<T> KdTree<T> {
    /// Builds the tree; points that are not finite are dropped.
    pub fn new(mut items: Vec<(Vec3A, T)>) -> Self {
        items.retain(|(p, _)| p.is_finite());
        let mut axes = vec![0u8; items.len()];
        build(&mut items, &mut axes);
        Self { items, axes }
    }

    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The `k` items nearest to `p` (any order) and the squared distance of the farthest.
    pub fn nearest(&self, p: Vec3A, k: usize, out: &mut Vec<usize>) -> f32 {
        out.clear();
        if k == 0 || self.items.is_empty() {
            return 0.0;
        }
        let mut heap = BinaryHeap::with_capacity(k + 1);
        self.search(0, self.items.len(), p, k, &mut heap);
        let r2 = heap.peek().map_or(0.0, |c: &Candidate| c.0);
        out.extend(heap.into_iter().map(|c| c.1));
        r2
    }

    pub fn item(&self, i: usize) -> &(Vec3A, T) {
        &self.items[i]
    }

    fn search(&self, lo: usize, hi: usize, p: Vec3A, k: usize, heap: &mut BinaryHeap<Candidate>) {
        if lo >= hi {
            return;
        }
        let mid = (lo + hi) / 2;
        let (q, _) = &self.items[mid];
        let axis = self.axes[mid] as usize;
        let d = p[axis] - q[axis];
        let (near, far) = if d < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1, p, k, heap);
        let d2 = (p - *q).length_squared();
        if heap.len() < k {
            heap.push(Candidate(d2, mid));
        } else if d2 < heap.peek().map_or(f32::INFINITY, |c| c.0) {
            heap.pop();
            heap.push(Candidate(d2, mid));
        }
        if heap.len() < k || d * d < heap.peek().map_or(f32::INFINITY, |c| c.0) {
            self.search(far.0, far.1, p, k, heap);
        }
    }
}

fn build<T>(items: &mut [(Vec3A, T)], axes: &mut [u8]) {
    if items.len() <= 1 {
        return;
    }
    let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    for (p, _) in items.iter() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let ext = hi - lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    axes[mid] = axis as u8;
    let (left, rest) = items.split_at_mut(mid);
    let (al, arest) = axes.split_at_mut(mid);
    build(left, al);
    build(&mut rest[1..], &mut arest[1..]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn nearest_matches_brute_force() {
        let mut rng = Rng::new(3);
        let pts: Vec<(Vec3A, usize)> = (0..2000)
            .map(|i| {
                let a = rng.vec2();
                (Vec3A::new(a.x, a.y, rng.f32()), i)
            })
            .collect();
        let tree = KdTree::new(pts.clone());
        let mut out = Vec::new();
        for _ in 0..50 {
            let a = rng.vec2();
            let q = Vec3A::new(a.x, a.y, rng.f32());
            let r2 = tree.nearest(q, 10, &mut out);
            let mut found: Vec<usize> = out.iter().map(|&i| tree.item(i).1).collect();
            found.sort();
            let mut brute: Vec<(f32, usize)> = pts
                .iter()
                .map(|(p, i)| ((*p - q).length_squared(), *i))
                .collect();
            brute.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut expect: Vec<usize> = brute[..10].iter().map(|b| b.1).collect();
            expect.sort();
            assert_eq!(found, expect);
            assert_eq!(r2, brute[9].0);
        }
    }
}
