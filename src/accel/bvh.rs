//! Binned SAH bounding volume hierarchy over shapes and mesh triangles, flattened depth-first.
//! Shapes without finite bounds (infinite planes) are kept in a side list and tested always.
//! What the leaves hold is packed after the build ([`super::leaf`]).

use rayon::prelude::*;

use super::build::{Item, Parallelism, Stop, build_until};
use super::flat::Flat;
use super::leaf::{Closest, Leaves};
use super::stack::{Stack, push_far_to_near};
use super::triangles::{Meshes, PairTest};
use super::unbuilt::{self, Unbuilt};
use super::wide::{Avx, BoxRay, BoxTest, Halves, LEAF, NODE_UNIT, WideNode, collapse, still_near};
use crate::geometry::{Aabb, Hit, Ray};
use crate::shapes::Shape;
use crate::shapes::mesh::TriangleMesh;
use crate::shapes::primitive::{AnyShape, LazyHit};

/// Traversal stack size: up to seven entries per level of the 8-wide tree (eight for a moment
/// while a node's children are sorted on it), which is no deeper than the binary tree (< 64
/// levels, see `MEDIAN_DEPTH`).
const STACK: usize = 7 * 64;
/// From this depth on, nodes split at the object median instead of by SAH, so that no tree is
/// deeper than `MEDIAN_DEPTH + log2(primitives)` (< `STACK` for fewer than 2^31 primitives). SAH
/// alone can peel a few primitives off per level (e.g. exponentially spaced sizes), and a
/// deeper tree would overflow the traversal stack.
const MEDIAN_DEPTH: usize = 32;

/// A node of the binary tree the build makes (collapsed into [`WideNode`]s afterwards), used as
/// built (no copy: the tree is the largest thing the build holds). After packing, a leaf's
/// `offset` is its leaf reference (see [`super::leaf::PACKETS`]).
pub(super) use super::build::BuildNode as Node;

mod record;
mod surface;
pub use record::NgHit;
pub use surface::Surface;

/// The accelerator: owns the shapes and meshes, each tagged with a caller id (e.g. a
/// primitive index).
pub struct Bvh {
    nodes: Vec<WideNode>,
    /// Nodes on the longest root-to-leaf path of the binary tree.
    #[cfg(test)]
    binary_depth: usize,
    bounds: Aabb,
    leaves: Leaves,
    meshes: Meshes,
    unbounded: Vec<(AnyShape, u32)>,
    /// The tree's one leaf, when the tree is nothing else and that leaf holds only quads and
    /// spheres (and there are no unbounded shapes): queried without the tree.
    flat: Option<Flat>,
    /// The AVX tests, where the CPU has them: detected once here, not on every query.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx: Option<Avx>,
}

impl Bvh {
    /// A BVH over `shapes` ([`Bvh::with_meshes`] without meshes).
    pub fn new(shapes: Vec<(AnyShape, u32)>) -> Result<Self, Unbuilt> {
        Self::with_meshes(shapes, Vec::new())
    }

    /// A BVH over `shapes` and the triangles of `meshes` (each mesh with the id its hits get);
    /// [`Unbuilt::TooLarge`] when its tree would have more nodes than it can address.
    pub fn with_meshes(
        shapes: Vec<(AnyShape, u32)>,
        meshes: Vec<(TriangleMesh, u32)>,
    ) -> Result<Self, Unbuilt> {
        Self::with_median_depth(shapes, meshes, MEDIAN_DEPTH, &|| false)
    }

    /// [`Bvh::with_meshes`], asking `stop` between the build's phases and inside the tree's
    /// build at a coarse grain (a subtree of a few thousand items): [`Unbuilt::Stopped`] once
    /// it said yes.
    pub fn with_meshes_until(
        shapes: Vec<(AnyShape, u32)>,
        meshes: Vec<(TriangleMesh, u32)>,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<Self, Unbuilt> {
        Self::with_median_depth(shapes, meshes, MEDIAN_DEPTH, stop)
    }

    fn with_median_depth(
        shapes: Vec<(AnyShape, u32)>,
        meshes: Vec<(TriangleMesh, u32)>,
        median_depth: usize,
        stop: Stop,
    ) -> Result<Self, Unbuilt> {
        if unbuilt::too_many(shapes.len(), meshes.iter().map(|(m, _)| m.len())) {
            return Err(Unbuilt::TooLarge);
        }
        // Boxes in parallel; most scenes (every mesh) have only bounded shapes.
        let boxes: Vec<Aabb> = shapes.par_iter().map(|(s, _)| s.bounds()).collect();
        let finite = |b: &Aabb| !b.is_empty() && b.min.is_finite() && b.max.is_finite();
        let (bounded, boxes, unbounded) = if boxes.par_iter().all(finite) {
            (shapes, boxes, Vec::new())
        } else {
            let (mut bounded, mut kept, mut unbounded) = (Vec::new(), Vec::new(), Vec::new());
            for (shape, b) in shapes.into_iter().zip(boxes) {
                if finite(&b) {
                    bounded.push(shape);
                    kept.push(b);
                } else if !b.is_empty() {
                    unbounded.push(shape);
                }
            }
            (bounded, kept, unbounded)
        };
        let meshes = Meshes::new(meshes);
        let nb = bounded.len();
        let triangles: Vec<(u32, &TriangleMesh, usize)> = meshes.iter().collect();
        let mut items: Vec<Item> = boxes
            .par_iter()
            .enumerate()
            .map(|(index, b)| Item {
                heavy: bounded[index].0.is_heavy(),
                ..Item::new(b.padded(1e-6), index)
            })
            .chain(
                triangles
                    .par_iter()
                    .map(|&(g, m, k)| Item::triangle(m.bounds(k).padded(1e-6), nb + g as usize)),
            )
            .collect();
        drop(triangles);
        if stop() {
            return Err(Unbuilt::Stopped);
        }
        let mut nodes: Vec<Node> =
            build_until(&mut items, median_depth, Parallelism::DEFAULT, stop)
                .ok_or(Unbuilt::Stopped)?;
        nodes.shrink_to_fit();
        if stop() {
            return Err(Unbuilt::Stopped);
        }
        // Pack each leaf's contents; its node then names the leaf.
        let mut slots: Vec<Option<(AnyShape, u32)>> = bounded.into_iter().map(Some).collect();
        let mut leaves = Leaves::default();
        let ranges: Vec<(u32, u16)> = nodes
            .par_iter()
            .filter(|n| n.count > 0)
            .map(|n| (n.offset, n.count as u16))
            .collect();
        let refs = leaves.pack(&items, &ranges, nb, &mut slots, &meshes);
        for (node, r) in nodes.iter_mut().filter(|n| n.count > 0).zip(refs) {
            node.offset = r;
        }
        leaves.shrink_to_fit();
        if stop() {
            return Err(Unbuilt::Stopped);
        }
        let flat = match nodes.as_slice() {
            [root] if root.count > 0 && unbounded.is_empty() => Flat::of(&leaves, root.offset),
            _ => None,
        };
        #[cfg(test)]
        fn below(n: &[Node], i: usize) -> usize {
            if n[i].count > 0 {
                1
            } else {
                1 + below(n, i + 1).max(below(n, n[i].offset as usize))
            }
        }
        let wide = collapse(&nodes).ok_or(Unbuilt::TooLarge)?;
        Ok(Self {
            #[cfg(test)]
            binary_depth: if nodes.is_empty() {
                0
            } else {
                below(&nodes, 0)
            },
            bounds: nodes.first().map_or(Aabb::EMPTY, |n| n.bounds),
            nodes: wide,
            leaves,
            meshes,
            unbounded,
            flat,
            avx: Avx::detect(),
        })
    }

    /// Whether queries skip the tree ([`Flat`]).
    #[cfg(test)]
    pub(super) fn is_flat(&self) -> bool {
        self.flat.is_some()
    }

    /// The same BVH queried through its tree even where it could skip it.
    #[cfg(test)]
    pub(super) fn without_flat(mut self) -> Self {
        self.flat = None;
        self
    }

    /// The same BVH queried as on a CPU without AVX.
    #[cfg(test)]
    pub(super) fn without_avx(mut self) -> Self {
        self.avx = None;
        self
    }

    /// Bounds of the bounded shapes (infinite planes excluded).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// How many shapes have no finite bounds (infinite planes), outside [`Bvh::bounds`].
    pub fn unbounded_len(&self) -> usize {
        self.unbounded.len()
    }

    /// Shapes and mesh triangles.
    pub fn len(&self) -> usize {
        self.leaves.shapes.len() + self.unbounded.len() + self.meshes.triangles()
    }

    /// Bytes held by the hierarchy: its nodes, leaves, shapes, packets, ids and meshes (what a
    /// scale benchmark reports per primitive; a boxed shape's own heap data is not followed).
    pub fn memory_bytes(&self) -> usize {
        self.memory_parts().iter().map(|p| p.1).sum()
    }

    /// [`Bvh::memory_bytes`] by part: nodes, leaf records, triangle packets, other leaf
    /// contents (shapes, their ids, quad packets), meshes' buffers, unbounded shapes.
    pub fn memory_parts(&self) -> [(&'static str, usize); 6] {
        use std::mem::size_of;
        let l = &self.leaves;
        [
            ("nodes", self.nodes.capacity() * size_of::<WideNode>()),
            (
                "leaves",
                l.leaves.capacity() * size_of::<super::leaf::Leaf>(),
            ),
            (
                "triangle packets",
                l.tri_packets.capacity() * size_of::<super::triangles::TrianglePacket>(),
            ),
            (
                "shapes",
                l.memory_bytes()
                    - l.leaves.capacity() * size_of::<super::leaf::Leaf>()
                    - l.tri_packets.capacity() * size_of::<super::triangles::TrianglePacket>(),
            ),
            ("mesh buffers", self.meshes.memory_bytes()),
            (
                "unbounded",
                self.unbounded.capacity() * size_of::<(AnyShape, u32)>(),
            ),
        ]
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Closest hit with `t_min < t < t_max`, and the hit shape's id. Candidates are tested
    /// for `t` only; the surface data is computed once, for the closest hit. A ray with a NaN
    /// in its origin or a non-finite direction hits none of the bounded shapes. The record
    /// (with its `uv`) is completed in the traversal's frame, as [`Bvh::intersect_uv`] does:
    /// taking the [`LazyHit`] out of [`Bvh::intersect_lazy`] and completing it here cost 20-35
    /// instructions a query more (a second frame and the lazy result copied out).
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(Hit, u32)> {
        self.intersect_uv(ray, t_min, t_max, |_| true)
    }

    /// [`Bvh::intersect`], where `uv(id)` says whether a hit on the shape of id `id` (a CSG
    /// tree's: the part's) needs its `uv` (see [`AnyShape::hit_at_uv`]): the renderer's query.
    /// The record is completed in the traversal's own frame, so the [`LazyHit`] is not passed
    /// on through another, and the CPU's features are looked at once. (The traversal itself is
    /// [`Bvh::intersect_lazy`]'s: a version that kept only its parts and built the record
    /// from them changed the loop's code, and the scale bench's bounce rays lost 2-7 %.)
    #[inline]
    pub fn intersect_uv(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        if let Some(flat) = &self.flat {
            return flat.intersect(&self.leaves, self.avx, ray, t_min, t_max, uv);
        }
        self.tree_uv(ray, t_min, t_max, uv)
    }

    /// [`Bvh::intersect_uv`] for rays with a finite origin and direction: any other ray gets
    /// `None`, the unbounded shapes' hits included. The flat query checks the ray itself (as
    /// the tree's box test rejects such rays), so a caller that needs the check does not make
    /// it twice.
    #[inline(always)]
    pub fn intersect_finite_uv(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        if self.flat.is_none() && !super::wide::BoxRay::usable(ray) {
            return None;
        }
        self.intersect_uv(ray, t_min, t_max, uv)
    }

    /// [`Bvh::intersect_uv`] through the tree, at the CPU's feature level.
    #[inline(always)]
    fn tree_uv(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = self.avx {
            // SAFETY: an `Avx` value exists only where the CPU has AVX.
            return unsafe { self.intersect_full_avx(avx, ray, t_min, t_max, uv) };
        }
        self.intersect_full_halves(ray, t_min, t_max, uv)
    }

    /// [`Bvh::intersect_uv`] four boxes at a time, out of line as [`Bvh::intersect_halves`].
    #[inline(never)]
    fn intersect_full_halves(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        self.full_with(Halves, ray, t_min, t_max, uv)
    }

    /// [`Bvh::intersect_uv`] with every operation allowed to use AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn intersect_full_avx(
        &self,
        avx: Avx,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        self.full_with(avx, ray, t_min, t_max, uv)
    }

    /// The closest hit's full record, completed where the traversal ran (inlined into each
    /// of the two feature levels above).
    #[inline(always)]
    fn full_with<B: BoxTest + PairTest>(
        &self,
        test: B,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        let (lazy, surface, id) =
            self.closest_with::<B, false>(test, ray, t_min, t_max, &mut None)?;
        let id = lazy.part().unwrap_or(id);
        Some((surface.hit_at_uv(ray, lazy, uv(id)), id))
    }

    /// Closest hit as a [`LazyHit`], the surface hit and its id. The traversal is compiled
    /// twice, with the box test of [`Avx`] (taken where the CPU has it) and of [`Halves`];
    /// both give the same bits, so the same hit.
    #[inline]
    pub fn intersect_lazy(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(LazyHit, Surface<'_>, u32)> {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = self.avx {
            // SAFETY: an `Avx` value exists only where the CPU has AVX.
            return unsafe { self.intersect_avx(avx, ray, t_min, t_max) };
        }
        self.intersect_halves(ray, t_min, t_max)
    }

    /// [`Bvh::intersect_lazy`] four boxes at a time, out of line: a CPU with AVX never runs
    /// it, and its frame stays out of every query's.
    #[inline(never)]
    fn intersect_halves(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(LazyHit, Surface<'_>, u32)> {
        self.closest_with::<_, false>(Halves, ray, t_min, t_max, &mut None)
    }

    /// [`Bvh::intersect_lazy`] with every operation allowed to use AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn intersect_avx(
        &self,
        avx: Avx,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(LazyHit, Surface<'_>, u32)> {
        self.closest_with::<_, false>(avx, ray, t_min, t_max, &mut None)
    }

    /// The closest-hit traversal; with `NG`, also the hit triangle's geometric normal in `ng`
    /// ([`Bvh::intersect_ng`]: an instance of its own, so that keeping the hit's leaf costs
    /// the other queries nothing).
    #[inline(always)]
    fn closest_with<B: BoxTest + PairTest, const NG: bool>(
        &self,
        test: B,
        ray: &Ray,
        t_min: f32,
        mut t_max: f32,
        ng: &mut Option<glam::Vec3A>,
    ) -> Option<(LazyHit, Surface<'_>, u32)> {
        let mut best: Option<(LazyHit, Surface<'_>, u32)> = None;
        for (s, id) in &self.unbounded {
            if let Some(h) = s.intersect_lazy(ray, t_min, t_max) {
                t_max = h.t();
                best = Some((h, Surface::Shape(s), *id));
            }
        }
        if self.nodes.is_empty() || !BoxRay::usable(ray) {
            return best;
        }
        let boxes = BoxRay::new(ray);
        let lanes = test.lanes(ray);
        // Children still to visit, with their entry distances.
        let mut stack = Stack::<(u32, f32), STACK>::new();
        let mut c = Closest::NONE;
        let mut cur = 0u32;
        loop {
            if cur & LEAF != 0 {
                self.leaves.closest::<B, NG>(
                    test,
                    &lanes,
                    cur & !LEAF,
                    ray,
                    t_min,
                    &mut t_max,
                    &mut c,
                );
            } else {
                let node = self.node(cur);
                let (mask, near) = test.hit(node, &boxes, t_min, t_max);
                // Visit the nearest hit child next and stack the others; one or two hit
                // children (most nodes) take no sort. (At most 7 pushes per level of a tree no
                // deeper than `STACK / 7`.)
                if mask != 0 {
                    let a = mask.trailing_zeros() as usize;
                    let rest = mask & (mask - 1);
                    if rest == 0 {
                        cur = node.child[a];
                    } else if rest & (rest - 1) == 0 {
                        let b = rest.trailing_zeros() as usize;
                        // As `push_far_to_near` orders them: on equal distances, `b` first.
                        let (first, second) = if near[a] < near[b] { (a, b) } else { (b, a) };
                        stack.push((node.child[second], near[second]));
                        cur = node.child[first];
                    } else {
                        push_far_to_near(node, mask, &near, &mut stack);
                        // (Never empty: three children or more were pushed.)
                        cur = stack.pop().map_or(cur, |h| h.0);
                    }
                    continue;
                }
            }
            loop {
                match stack.pop() {
                    Some((next, near)) if still_near(near, t_max) => {
                        cur = next;
                        break;
                    }
                    Some(_) => {}
                    None => {
                        if NG {
                            *ng = self.triangle_normal(&c);
                        }
                        return self.closest_hit(c, t_max, best);
                    }
                }
            }
        }
    }

    /// The interior node of child reference `r` (without the [`LEAF`] bit; 0, the root): the
    /// node `r * NODE_UNIT` bytes from the first.
    #[inline(always)]
    fn node(&self, r: u32) -> &WideNode {
        let at = r as usize * NODE_UNIT;
        debug_assert!(at.is_multiple_of(size_of::<WideNode>()));
        debug_assert!(at / size_of::<WideNode>() < self.nodes.len());
        // SAFETY: the traversals start at the root, 0, only when there are nodes, and go on
        // only to references read from the nodes' `child` arrays without the `LEAF` bit: the
        // collapse writes those as the offsets (in `NODE_UNIT`s) of nodes it made, whole
        // nodes from the first (`collapse` turning the indices of `collapse_at` and
        // `collapse_run` into offsets, after checking the last one fits below `LEAF`).
        // (Unchecked, and a byte offset rather than an index: the bounds check was a compare
        // and branch per node visited, the index a multiply by the node's size on the way
        // from a popped reference to its node's loads.)
        unsafe { &*self.nodes.as_ptr().cast::<u8>().add(at).cast::<WideNode>() }
    }

    /// Whether anything is hit with `t_min < t < t_max` (with AVX where the CPU has it, as
    /// [`Bvh::intersect_lazy`]).
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        if let Some(flat) = &self.flat {
            return flat.occluded(&self.leaves, self.avx, ray, t_min, t_max);
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = self.avx {
            // SAFETY: an `Avx` value exists only where the CPU has AVX.
            return unsafe { self.occluded_avx(avx, ray, t_min, t_max) };
        }
        self.occluded_halves(ray, t_min, t_max)
    }

    /// [`Bvh::occluded`] four boxes at a time, out of line as [`Bvh::intersect_halves`].
    #[inline(never)]
    fn occluded_halves(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.occluded_with(Halves, ray, t_min, t_max)
    }

    /// [`Bvh::occluded`] with every operation allowed to use AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn occluded_avx(&self, avx: Avx, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.occluded_with(avx, ray, t_min, t_max)
    }

    #[inline(always)]
    fn occluded_with<B: BoxTest + PairTest>(
        &self,
        test: B,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        if self
            .unbounded
            .iter()
            .any(|(s, _)| s.occluded(ray, t_min, t_max))
        {
            return true;
        }
        if self.nodes.is_empty() || !BoxRay::usable(ray) {
            return false;
        }
        let boxes = BoxRay::new(ray);
        let lanes = test.plain_lanes(ray);
        let mut stack = Stack::<u32, STACK>::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF != 0 {
                if self
                    .leaves
                    .occluded(test, &lanes, cur & !LEAF, ray, t_min, t_max)
                {
                    return true;
                }
            } else {
                let node = self.node(cur);
                let (mask, _) = test.hit(node, &boxes, t_min, t_max);
                if mask != 0 {
                    // Go on to the highest hit slot (the one the stack would give back first)
                    // and stack the others: no push and pop for the child visited next.
                    let last = 31 - mask.leading_zeros() as usize;
                    stack.push_children(node, mask & !(1 << last));
                    cur = node.child[last];
                    continue;
                }
            }
            match stack.pop() {
                Some(next) => cur = next,
                None => return false,
            }
        }
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod unbounded_tests;
