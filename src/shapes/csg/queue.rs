//! The hits of a CSG's leaves waiting to be visited along one ray, nearest first.

use std::collections::BinaryHeap;

use arrayvec::ArrayVec;
use glam::{Vec2, Vec3A};

use crate::geometry::Hit;

/// Where a leaf's next hit waits to be visited: ordered by distance, then by the order
/// [`super::Csg::pending`] gives hits at the same distance, then by leaf.
#[derive(Clone, Copy)]
pub(super) struct Key {
    pub t: f32,
    pub order: u8,
    pub leaf: u32,
}

impl Key {
    fn nearer(&self, other: &Self) -> std::cmp::Ordering {
        self.t
            .total_cmp(&other.t)
            .then(self.order.cmp(&other.order))
            .then(self.leaf.cmp(&other.leaf))
    }
}

impl PartialEq for Key {
    fn eq(&self, other: &Self) -> bool {
        self.nearer(other).is_eq()
    }
}

impl Eq for Key {}

impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

/// Reversed: the standard heap pops its greatest, the walk wants the nearest.
impl Ord for Key {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        other.nearer(self)
    }
}

/// A leaf's hit as the walk sees it: `uv` left out (NaN) where the shape can fill it in later
/// ([`LeafHit::shape`]), since most hits are never kept.
#[derive(Clone, Copy)]
pub(super) struct LeafHit {
    pub hit: Hit,
    /// The leaf's shape hit, to complete the hit if it is kept; `u32::MAX`: it is complete.
    pub shape: u32,
}

/// A placeholder in [`Heap::hits`] for a leaf with no hit waiting.
pub(super) const NO_HIT: LeafHit = LeafHit {
    hit: Hit {
        t: f32::INFINITY,
        p: Vec3A::ZERO,
        n: Vec3A::Z,
        ns: Vec3A::Z,
        uv: Vec2::ZERO,
        dpdu: Vec3A::X,
    },
    shape: u32::MAX,
};

/// The hits waiting to be visited, at most one per leaf: a short list scanned whole in a small
/// tree, a heap of small keys in a large one (a merge of thousands of shapes visits each hit
/// in log time, without moving the hits themselves).
pub(super) trait Queue {
    fn push(&mut self, key: Key, hit: LeafHit);
    /// The nearest waiting hit.
    fn pop(&mut self) -> Option<(Key, LeafHit)>;
}

impl<const N: usize> Queue for ArrayVec<(Key, LeafHit), N> {
    fn push(&mut self, key: Key, hit: LeafHit) {
        ArrayVec::push(self, (key, hit));
    }

    fn pop(&mut self) -> Option<(Key, LeafHit)> {
        let i = (0..self.len()).max_by(|&a, &b| self[a].0.cmp(&self[b].0))?;
        Some(self.swap_remove(i))
    }
}

/// The heap of keys, and each leaf's waiting hit by leaf index.
pub(super) struct Heap {
    pub keys: BinaryHeap<Key>,
    pub hits: Vec<LeafHit>,
}

impl Queue for Heap {
    fn push(&mut self, key: Key, hit: LeafHit) {
        self.hits[key.leaf as usize] = hit;
        self.keys.push(key);
    }

    fn pop(&mut self) -> Option<(Key, LeafHit)> {
        let key = self.keys.pop()?;
        Some((key, self.hits[key.leaf as usize]))
    }
}
