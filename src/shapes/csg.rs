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
//! the states of the other leaves at that point):
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

use super::primitive::AnyShape;
use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::CsgOp;

/// Most hits one ray may visit in one tree before it is given up as a miss (a bound on the
/// work of a hostile tree; a ray meets far fewer surfaces in any real scene).
pub const MAX_STEPS: usize = 1 << 16;

/// Leaves whose per-ray state lives on the stack; larger trees use the heap.
const INLINE_LEAVES: usize = 16;

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

/// Per leaf, during one ray: whether the current point is inside, and its next hit.
#[derive(Clone, Copy)]
struct Slot {
    inside: bool,
    next: Option<Hit>,
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

    /// Whether the points the states describe are inside node `n`'s solid.
    fn inside(&self, n: u32, slots: &[Slot]) -> bool {
        let node = &self.nodes[n as usize];
        let kids = self.kids(node);
        match node.op {
            None => slots[node.first as usize].inside,
            Some(CsgOp::Union | CsgOp::Merge) => kids.iter().any(|&k| self.inside(k, slots)),
            Some(CsgOp::Intersection) => kids.iter().all(|&k| self.inside(k, slots)),
            Some(CsgOp::Difference) => match kids.split_first() {
                Some((&a, rest)) => {
                    self.inside(a, slots) && !rest.iter().any(|&k| self.inside(k, slots))
                }
                None => false,
            },
            Some(CsgOp::Inverse) => !self.inside(kids[0], slots),
        }
    }

    /// Whether a hit on `leaf` is kept, and if so whether its normal is reversed.
    fn keep(&self, leaf: usize, slots: &[Slot]) -> Option<bool> {
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
            match node.op {
                Some(CsgOp::Union) | None => {}
                Some(CsgOp::Merge) => {
                    if others().any(|k| self.inside(k, slots)) {
                        return None;
                    }
                }
                Some(CsgOp::Intersection) => {
                    if !others().all(|k| self.inside(k, slots)) {
                        return None;
                    }
                }
                Some(CsgOp::Difference) => {
                    let base = kids[0];
                    if c != base {
                        if !self.inside(base, slots) {
                            return None;
                        }
                        flip = !flip;
                    }
                    if others().any(|k| k != base && self.inside(k, slots)) {
                        return None;
                    }
                }
                Some(CsgOp::Inverse) => flip = !flip,
            }
            c = a;
        }
    }

    /// The nearest hit of leaf `i` after `t0`, its normals pointing out of the leaf's volume.
    fn leaf_hit(&self, i: usize, ray: &Ray, inv_d: Vec3A, t0: f32) -> Option<Hit> {
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
        let mut best: Option<Hit> = None;
        for s in &leaf.shapes {
            let t1 = best.map_or(f32::INFINITY, |h| h.t);
            if let Some(h) = s.intersect(ray, t0, t1) {
                best = Some(h);
            }
        }
        best.map(|mut h| {
            if leaf.flip {
                h.n = -h.n;
                h.ns = -h.ns;
            }
            h
        })
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

    /// Each leaf's state at the ray's origin and its first hit after `t_min`.
    fn start<'a>(
        &'a self,
        ray: &'a Ray,
        inv_d: Vec3A,
        t_min: f32,
    ) -> impl Iterator<Item = Slot> + 'a {
        (0..self.leaves.len()).map(move |i| {
            let next = self.leaf_hit(i, ray, inv_d, t_min);
            let inside = match next {
                Some(h) => h.n.dot(ray.d) > 0.0,
                None => self.inside_without_hit(i, ray.o),
            };
            Slot { inside, next }
        })
    }

    /// The nearest kept hit with `t_min < t < t_max` and the id of the leaf it is on.
    pub fn intersect_part(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(Hit, u32)> {
        let inv_d = ray.d.recip();
        if self.leaves.len() <= INLINE_LEAVES {
            let mut slots = ArrayVec::<Slot, INLINE_LEAVES>::new();
            slots.extend(self.start(ray, inv_d, t_min));
            self.walk(ray, inv_d, t_max, &mut slots)
        } else {
            let mut slots: Vec<Slot> = self.start(ray, inv_d, t_min).collect();
            self.walk(ray, inv_d, t_max, &mut slots)
        }
    }

    /// Visits the hits in order until one is kept.
    ///
    /// Hits at the same distance (coincident faces: a cutter flush with the surface it cuts,
    /// two merged boxes sharing a face) are visited as if every leaf were a hair larger, and a
    /// negated one (a cutter) larger still: hits that enter a leaf before hits that leave one,
    /// a cutter entered first and left last. So a flush cutter opens its hole, a cutter the
    /// same as the solid leaves nothing, and merged neighbours show no face between them,
    /// which is what such a scene means (in POV-Ray they render as speckles).
    fn walk(&self, ray: &Ray, inv_d: Vec3A, t_max: f32, slots: &mut [Slot]) -> Option<(Hit, u32)> {
        let order = |i: usize, h: &Hit| {
            let enters = h.n.dot(ray.d) < 0.0;
            let negated = self.leaves[i].negated;
            match (enters, negated) {
                (true, true) => 0u8,
                (true, false) => 1,
                (false, false) => 2,
                (false, true) => 3,
            }
        };
        for _ in 0..MAX_STEPS {
            let (i, h) = slots
                .iter()
                .enumerate()
                .filter_map(|(i, s)| s.next.map(|h| (i, h)))
                .min_by(|a, b| {
                    a.1.t
                        .total_cmp(&b.1.t)
                        .then_with(|| order(a.0, &a.1).cmp(&order(b.0, &b.1)))
                })?;
            if h.t >= t_max {
                return None;
            }
            if let Some(flip) = self.keep(i, slots) {
                let mut h = h;
                if flip {
                    h.n = -h.n;
                    h.ns = -h.ns;
                }
                return Some((h, self.leaves[i].id));
            }
            slots[i].inside = h.n.dot(ray.d) < 0.0;
            slots[i].next = self.leaf_hit(i, ray, inv_d, h.t);
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
