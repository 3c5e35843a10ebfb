//! Constructive solid geometry: a tree of operations over closed shapes, intersected as one
//! primitive by classifying the hits of its shapes along the ray.
//!
//! Every leaf is a closed shape (one or more world-space surfaces, e.g. a box's six quads)
//! whose normals point out of its volume. Along a ray, the hit of a leaf whose normal faces the
//! ray enters that leaf and a hit whose normal faces away leaves it; so the state of each leaf
//! at the ray's origin is known from its first hit (leaving: the origin is inside; no hit: the
//! origin is outside, except for a plane's half-space, tested directly). The hits of all leaves
//! are then visited in order, each leaf's next hit fetched only once its current one is used,
//! and a hit is kept when POV-Ray's rules keep it (checked from the leaf up to the root, with
//! the states of the other leaves at that point). Each operation counts the children the
//! current point is inside, updated as a leaf's state changes, so a hit is classified with one
//! test per level rather than a visit to every leaf, and a large tree's waiting hits are in a
//! heap: a ray costs a test of each leaf whose bounds it meets, then a logarithmic step per
//! hit it visits. The rules:
//!
//! - `union`: every child's hits;
//! - `merge`: a child's hits outside every other child;
//! - `intersection`: a child's hits inside every other child;
//! - `difference`: the first child's hits outside the others, and the others' hits inside the
//!   first and outside the rest, turned inside out;
//! - `inverse`: its child's hits, turned inside out.
//!
//! The normal of a kept hit is the leaf's outward normal, reversed once for every difference
//! (as a subtracted child) and inverse above the leaf: it points out of the CSG solid, so a
//! dielectric knows whether the ray enters or leaves. Without `union` nodes, the kept hits are
//! exactly the points where the ray enters or leaves the tree's solid.

use arrayvec::ArrayVec;
use glam::{Vec2, Vec3A};

mod queue;

use super::primitive::{AnyShape, LazyHit};
use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::CsgOp;
use queue::{Heap, Key, LeafHit, NO_HIT, Queue};

/// Most hits one ray may visit in one tree before it is given up as a miss (a bound on the
/// work of a hostile tree; a ray meets far fewer surfaces in any real scene).
pub const MAX_STEPS: usize = 1 << 16;

/// Leaves whose per-ray state lives on the stack; larger trees use the heap.
const INLINE_LEAVES: usize = 16;
/// Nodes (leaves and operations) whose per-ray state lives on the stack.
const INLINE_NODES: usize = 64;

/// The input form of a tree.
pub enum CsgNode {
    Leaf(CsgLeaf),
    Op(CsgOp, Vec<CsgNode>),
}

/// A closed shape in world space.
pub struct CsgLeaf {
    pub shapes: Vec<AnyShape>,
    /// The shapes' normals point into the volume: reverse them.
    pub flip: bool,
    /// Reported with the hits of this leaf (the prepared scene's primitive id).
    pub id: u32,
}

struct Leaf {
    shapes: Vec<AnyShape>,
    flip: bool,
    id: u32,
    bounds: Aabb,
    /// Node of this leaf.
    node: u32,
    /// The leaf's solid counts negated in the tree's (a subtracted child of a difference, or
    /// under `inverse`, an odd number of times): see [`Csg::walk`] on hits at the same distance.
    negated: bool,
}

struct Node {
    /// `None`: a leaf (its index in `first`).
    op: Option<CsgOp>,
    /// Leaf: the leaf index. Operation: index of its first child in `children`.
    first: u32,
    count: u32,
    parent: u32,
}

const NO_PARENT: u32 = u32::MAX;

/// A prepared CSG tree: one primitive for the BVH.
pub struct Csg {
    nodes: Vec<Node>,
    /// Child node indices of the operations, each operation's children contiguous.
    children: Vec<u32>,
    leaves: Vec<Leaf>,
    /// Where kept hits can lie.
    surface: Aabb,
}

/// Per node, during one ray: whether the current point is inside its solid, and (an
/// operation) how many of its children it is inside of. Kept up to date leaf by leaf, so that a
/// hit is classified with one test per level of the tree, not by visiting every leaf again.
#[derive(Clone, Copy, Default)]
struct NodeState {
    inside: bool,
    count: u32,
}

fn everything() -> Aabb {
    Aabb::new(Vec3A::splat(f32::NEG_INFINITY), Vec3A::splat(f32::INFINITY))
}

fn meet(a: Aabb, b: Aabb) -> Aabb {
    let m = Aabb {
        min: a.min.max(b.min),
        max: a.max.min(b.max),
    };
    if m.is_empty() { Aabb::EMPTY } else { m }
}

impl Csg {
    pub fn new(root: CsgNode) -> Result<Self, String> {
        let mut csg = Csg {
            nodes: Vec::new(),
            children: Vec::new(),
            leaves: Vec::new(),
            surface: Aabb::EMPTY,
        };
        let (surface, _) = csg.add(root, NO_PARENT)?;
        csg.surface = surface;
        for i in 0..csg.leaves.len() {
            csg.leaves[i].negated = csg.negated(csg.leaves[i].node);
        }
        Ok(csg)
    }

    /// Whether node `c`'s solid counts negated in the whole tree's.
    fn negated(&self, mut c: u32) -> bool {
        let mut negated = false;
        loop {
            let a = self.nodes[c as usize].parent;
            if a == NO_PARENT {
                return negated;
            }
            let node = &self.nodes[a as usize];
            match node.op {
                Some(CsgOp::Difference) if self.kids(node)[0] != c => negated = !negated,
                Some(CsgOp::Inverse) => negated = !negated,
                _ => {}
            }
            c = a;
        }
    }

    /// Adds a subtree; returns its surface bounds (where its kept hits lie) and volume bounds
    /// (where its inside lies).
    fn add(&mut self, node: CsgNode, parent: u32) -> Result<(Aabb, Aabb), String> {
        let index = self.nodes.len() as u32;
        match node {
            CsgNode::Leaf(leaf) => {
                if leaf.shapes.is_empty() {
                    return Err("a CSG shape has no surface".into());
                }
                let bounds = leaf
                    .shapes
                    .iter()
                    .fold(Aabb::EMPTY, |b, s| b.union(s.bounds()));
                self.nodes.push(Node {
                    op: None,
                    first: self.leaves.len() as u32,
                    count: 0,
                    parent,
                });
                self.leaves.push(Leaf {
                    shapes: leaf.shapes,
                    flip: leaf.flip,
                    id: leaf.id,
                    bounds,
                    node: index,
                    negated: false,
                });
                Ok((bounds, bounds))
            }
            CsgNode::Op(op, kids) => {
                if op == CsgOp::Inverse && kids.len() != 1 {
                    return Err("inverse takes exactly one object".into());
                }
                let first = self.children.len() as u32;
                self.nodes.push(Node {
                    op: Some(op),
                    first,
                    count: kids.len() as u32,
                    parent,
                });
                // Reserve the contiguous slots first: the children add their own below.
                self.children.extend(std::iter::repeat_n(0, kids.len()));
                let mut bounds = Vec::with_capacity(kids.len());
                for (k, kid) in kids.into_iter().enumerate() {
                    self.children[first as usize + k] = self.nodes.len() as u32;
                    bounds.push(self.add(kid, index)?);
                }
                let surfaces = bounds.iter().fold(Aabb::EMPTY, |b, (s, _)| b.union(*s));
                Ok(match op {
                    CsgOp::Union | CsgOp::Merge => (
                        surfaces,
                        bounds.iter().fold(Aabb::EMPTY, |b, (_, v)| b.union(*v)),
                    ),
                    CsgOp::Intersection => {
                        let volume = bounds.iter().fold(everything(), |b, (_, v)| meet(b, *v));
                        (meet(surfaces, volume), volume)
                    }
                    CsgOp::Difference => {
                        let volume = bounds.first().map_or(Aabb::EMPTY, |(_, v)| *v);
                        (meet(surfaces, volume), volume)
                    }
                    CsgOp::Inverse => (surfaces, everything()),
                })
            }
        }
    }

    fn kids(&self, node: &Node) -> &[u32] {
        &self.children[node.first as usize..][..node.count as usize]
    }

    /// Whether operation `n` is inside its solid, from its count of children inside.
    fn op_inside(&self, n: usize, states: &[NodeState]) -> bool {
        let node = &self.nodes[n];
        let count = states[n].count;
        match node.op {
            None => states[n].inside,
            Some(CsgOp::Union | CsgOp::Merge) => count > 0,
            Some(CsgOp::Intersection) => count == node.count,
            // Inside the first child, and it is the only child inside.
            Some(CsgOp::Difference) => self
                .kids(node)
                .first()
                .is_some_and(|&b| states[b as usize].inside && count == 1),
            Some(CsgOp::Inverse) => count == 0,
        }
    }

    /// Fills in every operation's count and state from its leaves' (children have higher
    /// indices than their parent, so a reverse sweep sees them first).
    fn settle(&self, states: &mut [NodeState]) {
        for n in (0..self.nodes.len()).rev() {
            let node = &self.nodes[n];
            if node.op.is_none() {
                continue;
            }
            states[n].count = self
                .kids(node)
                .iter()
                .map(|&k| u32::from(states[k as usize].inside))
                .sum();
            states[n].inside = self.op_inside(n, states);
        }
    }

    /// Sets leaf `i`'s state and carries the change up as far as it changes anything: at most
    /// one step per level of the tree.
    fn set_leaf(&self, i: usize, inside: bool, states: &mut [NodeState]) {
        let mut c = self.leaves[i].node as usize;
        if states[c].inside == inside {
            return;
        }
        states[c].inside = inside;
        loop {
            let a = self.nodes[c].parent;
            if a == NO_PARENT {
                return;
            }
            let a = a as usize;
            if states[c].inside {
                states[a].count += 1;
            } else {
                states[a].count -= 1;
            }
            let now = self.op_inside(a, states);
            if now == states[a].inside {
                return;
            }
            states[a].inside = now;
            c = a;
        }
    }

    /// Whether a hit on `leaf` is kept, and if so whether its normal is reversed: one test per
    /// level, from the counts.
    fn keep(&self, leaf: usize, states: &[NodeState]) -> Option<bool> {
        let mut flip = false;
        let mut c = self.leaves[leaf].node;
        loop {
            let a = self.nodes[c as usize].parent;
            if a == NO_PARENT {
                return Some(flip);
            }
            let node = &self.nodes[a as usize];
            // Children of `a` other than `c` that are inside.
            let others = states[a as usize].count - u32::from(states[c as usize].inside);
            match node.op {
                Some(CsgOp::Union) | None => {}
                Some(CsgOp::Merge) => {
                    if others > 0 {
                        return None;
                    }
                }
                Some(CsgOp::Intersection) => {
                    if others + 1 != node.count {
                        return None;
                    }
                }
                Some(CsgOp::Difference) => {
                    let base = self.kids(node)[0];
                    if c != base {
                        // Inside the first child and no other subtracted one.
                        if !states[base as usize].inside || others != 1 {
                            return None;
                        }
                        flip = !flip;
                    } else if others > 0 {
                        return None;
                    }
                }
                Some(CsgOp::Inverse) => flip = !flip,
            }
            c = a;
        }
    }

    /// The nearest hit of leaf `i` after `t0`, its normals pointing out of the leaf's volume;
    /// an analytic shape's without its `uv` ([`Csg::complete`] fills it in).
    fn leaf_hit(&self, i: usize, ray: &Ray, inv_d: Vec3A, t0: f32) -> Option<LeafHit> {
        let leaf = &self.leaves[i];
        let bounded = leaf.bounds.min.is_finite() && leaf.bounds.max.is_finite();
        if bounded
            && leaf
                .bounds
                .padded(1e-6)
                .hit(ray, inv_d, t0, f32::INFINITY)
                .is_none()
        {
            return None;
        }
        // The nearest `t` of an analytic shape (and which), or a boxed shape's full hit.
        let mut best: Option<(f32, usize, Option<Hit>)> = None;
        for (k, s) in leaf.shapes.iter().enumerate() {
            let t1 = best.map_or(f32::INFINITY, |(t, _, _)| t);
            match s.analytic_t(ray, t0, t1) {
                Ok(Some(t)) => best = Some((t, k, None)),
                Ok(None) => {}
                Err(()) => {
                    if let Some(h) = s.intersect(ray, t0, t1) {
                        best = Some((h.t, k, Some(h)));
                    }
                }
            }
        }
        let (hit, shape) = match best? {
            (_, _, Some(h)) => (h, u32::MAX),
            (t, k, None) => (
                leaf.shapes[k].hit_at_uv(ray, LazyHit::T(t), false),
                k as u32,
            ),
        };
        Some(LeafHit {
            hit: self.outward(i, hit),
            shape,
        })
    }

    /// A hit of leaf `i` with its normals pointing out of the leaf's volume.
    fn outward(&self, i: usize, mut h: Hit) -> Hit {
        if self.leaves[i].flip {
            h.n = -h.n;
            h.ns = -h.ns;
        }
        h
    }

    /// The full hit of a kept [`LeafHit`] of leaf `i`: what the shape's own intersection gives.
    fn complete(&self, i: usize, ray: &Ray, h: LeafHit) -> Hit {
        match self.leaves[i].shapes.get(h.shape as usize) {
            Some(s) => self.outward(i, s.hit_at(ray, LazyHit::T(h.hit.t))),
            None => h.hit,
        }
    }

    /// Whether the origin of a ray that meets leaf `i` nowhere ahead is inside it: only a
    /// plane's half-space reaches past every hit.
    fn inside_without_hit(&self, i: usize, o: Vec3A) -> bool {
        let leaf = &self.leaves[i];
        match leaf.shapes.as_slice() {
            [AnyShape::Plane(p)] => p.contains(o) != leaf.flip,
            _ => false,
        }
    }

    /// Where a hit of leaf `i` waits to be visited.
    ///
    /// Hits at the same distance (coincident faces: a cutter flush with the surface it cuts,
    /// two merged boxes sharing a face) are visited as if every leaf were a hair larger, and a
    /// negated one (a cutter) larger still: hits that enter a leaf before hits that leave one,
    /// a cutter entered first and left last. So a flush cutter opens its hole, a cutter the
    /// same as the solid leaves nothing, and merged neighbours show no face between them,
    /// which is what such a scene means (in POV-Ray they render as speckles). Ties beyond that
    /// go to the leaf that comes first in the tree.
    fn pending(&self, i: usize, hit: &Hit, ray: &Ray) -> Key {
        let enters = hit.n.dot(ray.d) < 0.0;
        let order = match (enters, self.leaves[i].negated) {
            (true, true) => 0u8,
            (true, false) => 1,
            (false, false) => 2,
            (false, true) => 3,
        };
        Key {
            t: hit.t,
            order,
            leaf: i as u32,
        }
    }

    /// Each leaf's state at the ray's origin (settled up the tree) and its first hit after
    /// `t_min`, queued.
    fn start(
        &self,
        ray: &Ray,
        inv_d: Vec3A,
        t_min: f32,
        states: &mut [NodeState],
        queue: &mut impl Queue,
    ) {
        for i in 0..self.leaves.len() {
            let next = self.leaf_hit(i, ray, inv_d, t_min);
            let inside = match next {
                Some(h) => h.hit.n.dot(ray.d) > 0.0,
                None => self.inside_without_hit(i, ray.o),
            };
            states[self.leaves[i].node as usize].inside = inside;
            if let Some(h) = next {
                queue.push(self.pending(i, &h.hit, ray), h);
            }
        }
        self.settle(states);
    }

    /// The nearest kept hit with `t_min < t < t_max` and the id of the leaf it is on.
    pub fn intersect_part(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(Hit, u32)> {
        let inv_d = ray.d.recip();
        let fresh = std::iter::repeat_n(NodeState::default(), self.nodes.len());
        if self.leaves.len() <= INLINE_LEAVES && self.nodes.len() <= INLINE_NODES {
            let mut states: ArrayVec<NodeState, INLINE_NODES> = fresh.collect();
            let mut queue = ArrayVec::<(Key, LeafHit), INLINE_LEAVES>::new();
            self.start(ray, inv_d, t_min, &mut states, &mut queue);
            self.walk(ray, inv_d, t_max, &mut states, &mut queue)
        } else {
            let mut states: Vec<NodeState> = fresh.collect();
            let mut queue = Heap {
                keys: std::collections::BinaryHeap::new(),
                hits: vec![NO_HIT; self.leaves.len()],
            };
            self.start(ray, inv_d, t_min, &mut states, &mut queue);
            self.walk(ray, inv_d, t_max, &mut states, &mut queue)
        }
    }

    /// Visits the hits in order (see [`Csg::pending`]) until one is kept.
    fn walk(
        &self,
        ray: &Ray,
        inv_d: Vec3A,
        t_max: f32,
        states: &mut [NodeState],
        queue: &mut impl Queue,
    ) -> Option<(Hit, u32)> {
        for _ in 0..MAX_STEPS {
            let (Key { leaf, .. }, lh) = queue.pop()?;
            let i = leaf as usize;
            let h = lh.hit;
            if h.t >= t_max {
                return None;
            }
            if let Some(flip) = self.keep(i, states) {
                let mut h = self.complete(i, ray, lh);
                if flip {
                    h.n = -h.n;
                    h.ns = -h.ns;
                }
                return Some((h, self.leaves[i].id));
            }
            self.set_leaf(i, h.n.dot(ray.d) < 0.0, states);
            if let Some(next) = self.leaf_hit(i, ray, inv_d, h.t) {
                queue.push(self.pending(i, &next.hit, ray), next);
            }
        }
        None
    }

    /// Number of closed shapes in the tree.
    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }
}

impl Shape for Csg {
    fn bounds(&self) -> Aabb {
        self.surface
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        self.intersect_part(ray, t_min, t_max).map(|(h, _)| h)
    }

    /// A CSG surface is not sampled as a light (emissive children are refused).
    fn area(&self) -> f32 {
        0.0
    }

    fn sample(&self, _u: Vec2) -> Option<AreaSample> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::shapes::sphere::Sphere;

    impl Csg {
        /// Whether node `n` is inside, from its leaves' states by the definitions alone.
        fn inside_by_definition(&self, n: u32, states: &[NodeState]) -> bool {
            let node = &self.nodes[n as usize];
            let kids = self.kids(node);
            let inside = |k: &u32| self.inside_by_definition(*k, states);
            match node.op {
                None => states[n as usize].inside,
                Some(CsgOp::Union | CsgOp::Merge) => kids.iter().any(inside),
                Some(CsgOp::Intersection) => kids.iter().all(inside),
                Some(CsgOp::Difference) => match kids.split_first() {
                    Some((a, rest)) => inside(a) && !rest.iter().any(inside),
                    None => false,
                },
                Some(CsgOp::Inverse) => !inside(&kids[0]),
            }
        }

        /// POV-Ray's rules for keeping a hit on `leaf`, each ancestor's other children
        /// evaluated by definition.
        fn keep_by_definition(&self, leaf: usize, states: &[NodeState]) -> Option<bool> {
            let mut flip = false;
            let mut c = self.leaves[leaf].node;
            loop {
                let a = self.nodes[c as usize].parent;
                if a == NO_PARENT {
                    return Some(flip);
                }
                let node = &self.nodes[a as usize];
                let kids = self.kids(node);
                let others = || kids.iter().copied().filter(|&k| k != c);
                let inside = |k: u32| self.inside_by_definition(k, states);
                match node.op {
                    Some(CsgOp::Union) | None => {}
                    Some(CsgOp::Merge) => {
                        if others().any(inside) {
                            return None;
                        }
                    }
                    Some(CsgOp::Intersection) => {
                        if !others().all(inside) {
                            return None;
                        }
                    }
                    Some(CsgOp::Difference) => {
                        let base = kids[0];
                        if c != base {
                            if !inside(base) {
                                return None;
                            }
                            flip = !flip;
                        }
                        if others().any(|k| k != base && inside(k)) {
                            return None;
                        }
                    }
                    Some(CsgOp::Inverse) => flip = !flip,
                }
                c = a;
            }
        }
    }

    fn random_tree(rng: &mut Rng, depth: u32, next_id: &mut u32) -> CsgNode {
        if depth == 0 || rng.f32() < 0.3 {
            *next_id += 1;
            let c = Vec3A::new(rng.f32(), rng.f32(), rng.f32());
            return CsgNode::Leaf(CsgLeaf {
                shapes: vec![AnyShape::Sphere(Sphere::new(c, 0.5).unwrap())],
                flip: false,
                id: *next_id,
            });
        }
        let ops = [
            CsgOp::Union,
            CsgOp::Merge,
            CsgOp::Intersection,
            CsgOp::Difference,
            CsgOp::Inverse,
        ];
        let op = ops[(rng.f32() * 5.0) as usize % 5];
        let n = if op == CsgOp::Inverse {
            1
        } else {
            1 + (rng.f32() * 4.0) as usize
        };
        let kids = (0..n)
            .map(|_| random_tree(rng, depth - 1, next_id))
            .collect();
        CsgNode::Op(op, kids)
    }

    /// The counts kept leaf by leaf give every node's state and every hit's fate exactly as
    /// the definitions do (which visit every leaf below): on 300 random trees of every
    /// operation, after each of 200 random changes of a leaf's state.
    #[test]
    fn counted_states_agree_with_the_definitions() {
        let mut rng = Rng::new(5);
        let mut checked = 0;
        for _ in 0..300 {
            let csg = Csg::new(random_tree(&mut rng, 4, &mut 0)).unwrap();
            let mut states = vec![NodeState::default(); csg.nodes.len()];
            for leaf in &csg.leaves {
                states[leaf.node as usize].inside = rng.f32() < 0.5;
            }
            csg.settle(&mut states);
            for _ in 0..200 {
                for n in 0..csg.nodes.len() as u32 {
                    assert_eq!(
                        states[n as usize].inside,
                        csg.inside_by_definition(n, &states)
                    );
                }
                for i in 0..csg.leaves.len() {
                    assert_eq!(csg.keep(i, &states), csg.keep_by_definition(i, &states));
                    checked += 1;
                }
                let i = (rng.f32() * csg.leaves.len() as f32) as usize % csg.leaves.len();
                csg.set_leaf(i, rng.f32() < 0.5, &mut states);
            }
        }
        assert!(checked > 100_000, "{checked}");
    }

    /// A tree of more than [`INLINE_LEAVES`] leaves (its waiting hits in a heap) keeps the
    /// right hit: 4 096 concentric spheres in an intersection are the innermost one, and in a
    /// merge the outermost one, seen from outside and from the centre.
    #[test]
    fn large_trees_keep_the_right_hit() {
        for (op, want) in [(CsgOp::Intersection, 0.001f32), (CsgOp::Merge, 4.096)] {
            let kids = (1..=4096u32)
                .map(|k| {
                    CsgNode::Leaf(CsgLeaf {
                        shapes: vec![AnyShape::Sphere(
                            Sphere::new(Vec3A::ZERO, k as f32 * 0.001).unwrap(),
                        )],
                        flip: false,
                        id: k,
                    })
                })
                .collect();
            let csg = Csg::new(CsgNode::Op(op, kids)).unwrap();
            let ray = Ray::new(Vec3A::new(0.0, 0.0, -10.0), Vec3A::Z);
            let (h, id) = csg.intersect_part(&ray, 0.0, f32::INFINITY).unwrap();
            assert!((10.0 - h.t - want).abs() < 1e-4, "{op:?}: {}", h.t);
            assert!(h.n.z < 0.0, "{op:?}");
            assert_eq!(id, (want * 1000.0).round() as u32, "{op:?}");
            // From the centre, the ray leaves through the same sphere.
            let inner = Ray::new(Vec3A::ZERO, Vec3A::Z);
            let (h, _) = csg.intersect_part(&inner, 0.0, f32::INFINITY).unwrap();
            assert!((h.t - want).abs() < 1e-4 && h.n.z > 0.0, "{op:?}: {}", h.t);
        }
    }
}
