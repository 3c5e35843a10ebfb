//! Binned SAH bounding volume hierarchy over shapes, flattened depth-first.
//! Shapes without finite bounds (infinite planes) are kept in a side list and tested always.

use std::sync::Mutex;

use arrayvec::ArrayVec;
use rayon::prelude::*;

use super::build::{Item, Parallelism, build};

use crate::geometry::{Aabb, Hit, Ray};
use crate::shapes::Shape;
use crate::shapes::primitive::{AnyShape, LazyHit};
use crate::shapes::quad::{Quad, QuadPacket};

/// Traversal stack size: one entry per interior node on the path from the root.
const STACK: usize = 64;
/// From this depth on, nodes split at the object median instead of by SAH, so that no tree is
/// deeper than `MEDIAN_DEPTH + log2(primitives)` (< `STACK` for fewer than 2^31 primitives). SAH
/// alone can peel a few primitives off per level (e.g. exponentially spaced sizes), and a
/// deeper tree would overflow the traversal stack.
const MEDIAN_DEPTH: usize = 32;

#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Aabb,
    /// Leaf: first primitive. Interior: index of the second child (the first follows).
    offset: u32,
    /// Primitives in a leaf; 0 for an interior node.
    count: u16,
    axis: u8,
    /// Leaf: how many of its primitives (the first ones) are quads tested in packets.
    quads: u8,
    /// Leaf: index of its first quad packet.
    packet: u32,
}

/// The accelerator: owns the shapes, each tagged with a caller id (e.g. a primitive index).
pub struct Bvh {
    nodes: Vec<Node>,
    shapes: Vec<AnyShape>,
    /// Each leaf's quads, four to a packet (the same quads are also in `shapes`).
    packets: Vec<QuadPacket>,
    ids: Vec<u32>,
    unbounded: Vec<(AnyShape, u32)>,
}

impl Bvh {
    pub fn new(shapes: Vec<(AnyShape, u32)>) -> Self {
        Self::with_median_depth(shapes, MEDIAN_DEPTH)
    }

    fn with_median_depth(shapes: Vec<(AnyShape, u32)>, median_depth: usize) -> Self {
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
        let mut items: Vec<Item> = boxes
            .par_iter()
            .enumerate()
            .map(|(index, b)| Item::new(b.padded(1e-6), index))
            .collect();
        let mut nodes: Vec<Node> = build(&mut items, median_depth, Parallelism::DEFAULT)
            .into_par_iter()
            .map(|b| Node {
                bounds: b.bounds,
                offset: b.offset,
                count: b.count as u16,
                axis: b.axis,
                quads: 0,
                packet: 0,
            })
            .collect();
        // Leaves with two quads or more list them first and test them four at a time.
        let is_quad = |it: &Item| matches!(bounded[it.index].0, AnyShape::Quad(_));
        // (Skipped without quads: a mesh's millions of leaves are not walked for nothing.)
        let any_quads = bounded
            .par_iter()
            .any(|(s, _)| matches!(s, AnyShape::Quad(_)));
        for node in nodes.iter_mut().filter(|n| any_quads && n.count > 0) {
            let leaf = &mut items[node.offset as usize..][..node.count as usize];
            let quads = leaf.iter().filter(|it| is_quad(it)).count();
            // (Leaves hold at most 8 shapes; the `u8` check only guards that.)
            if let Ok(q) = u8::try_from(quads)
                && q >= 2
            {
                leaf.sort_by_key(|it| !is_quad(it));
                node.quads = q;
            }
        }
        let mut packets = Vec::new();
        for node in nodes.iter_mut().filter(|n| any_quads && n.quads > 0) {
            node.packet = packets.len() as u32;
            let quads: Vec<Quad> = items[node.offset as usize..][..node.quads as usize]
                .iter()
                .filter_map(|it| match &bounded[it.index].0 {
                    AnyShape::Quad(q) => Some(*q),
                    _ => None,
                })
                .collect();
            packets.extend(quads.chunks(4).map(QuadPacket::new));
        }
        // Reorder the shapes into leaf order, in parallel (each slot is taken once, its lock
        // never waited for).
        let slots: Vec<Mutex<Option<(AnyShape, u32)>>> = bounded
            .into_par_iter()
            .map(|s| Mutex::new(Some(s)))
            .collect();
        let (shapes, ids) = items
            .par_iter()
            .map(|it| {
                let slot = slots[it.index].lock().ok().and_then(|mut s| s.take());
                slot.expect("each shape once")
            })
            .unzip();
        Self {
            nodes,
            shapes,
            packets,
            ids,
            unbounded,
        }
    }

    /// The quad packets of a leaf (empty for interior nodes and leaves without them).
    #[inline]
    fn leaf_packets(&self, node: &Node) -> &[QuadPacket] {
        let n = (node.quads as usize).div_ceil(4);
        &self.packets[node.packet as usize..][..n]
    }

    /// Bounds of the bounded shapes (infinite planes excluded).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds)
    }

    pub fn len(&self) -> usize {
        self.shapes.len() + self.unbounded.len()
    }

    /// Bytes held by the hierarchy: its nodes, shapes, quad packets and ids (what a scale
    /// benchmark reports per primitive; a boxed shape's own heap data is not followed).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.nodes.capacity() * size_of::<Node>()
            + self.shapes.capacity() * size_of::<AnyShape>()
            + self.packets.capacity() * size_of::<QuadPacket>()
            + self.ids.capacity() * size_of::<u32>()
            + self.unbounded.capacity() * size_of::<(AnyShape, u32)>()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Closest hit with `t_min < t < t_max`, and the hit shape's id. Candidates are tested
    /// for `t` only; the surface data is computed once, for the closest hit.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(Hit, u32)> {
        let (lazy, shape, id) = self.intersect_lazy(ray, t_min, t_max)?;
        Some((shape.hit_at(ray, lazy), lazy.part().unwrap_or(id)))
    }

    /// Closest hit as a [`LazyHit`], the shape hit and its id.
    #[inline]
    pub fn intersect_lazy(
        &self,
        ray: &Ray,
        t_min: f32,
        mut t_max: f32,
    ) -> Option<(LazyHit, &AnyShape, u32)> {
        let mut best: Option<(LazyHit, &AnyShape, u32)> = None;
        for (s, id) in &self.unbounded {
            if let Some(h) = s.intersect_lazy(ray, t_min, t_max) {
                t_max = h.t();
                best = Some((h, s, *id));
            }
        }
        if self.nodes.is_empty() {
            return best;
        }
        let inv_d = ray.d.recip();
        let neg = [inv_d.x < 0.0, inv_d.y < 0.0, inv_d.z < 0.0];
        // An ArrayVec: a fixed array would be zeroed on every call (a tenth of a short ray's
        // instructions).
        let mut stack = ArrayVec::<u32, STACK>::new();
        let mut cur = 0usize;
        // The closest bounded shape so far (`usize::MAX`: none; it then beats any unbounded
        // hit in `best`, whose `t` bounded the search), and its full hit if it is boxed.
        let mut closest = usize::MAX;
        let mut full: Option<Hit> = None;
        // The CSG part of `full`, if it came from a CSG tree (`u32::MAX`: none). Kept apart so
        // that the loop moves no more than it did before CSG existed.
        let mut part = u32::MAX;
        loop {
            let node = &self.nodes[cur];
            if node.bounds.hit(ray, inv_d, t_min, t_max).is_some() {
                if node.count > 0 {
                    let start = node.offset as usize;
                    let end = start + node.count as usize;
                    let quads = node.quads as usize;
                    for (p, packet) in self.leaf_packets(node).iter().enumerate() {
                        if let Some((lane, t)) = packet.hit_t(ray, t_min, t_max) {
                            t_max = t;
                            closest = start + 4 * p + lane;
                            full = None;
                        }
                    }
                    let rest = start + quads;
                    for (k, s) in self.shapes[rest..end].iter().enumerate() {
                        match s.analytic_t(ray, t_min, t_max) {
                            Ok(Some(t)) => {
                                t_max = t;
                                closest = rest + k;
                                full = None;
                            }
                            Ok(None) => {}
                            Err(()) => {
                                if let Some((h, p)) = s.intersect_full(ray, t_min, t_max) {
                                    t_max = h.t;
                                    part = p.unwrap_or(u32::MAX);
                                    closest = rest + k;
                                    full = Some(h);
                                }
                            }
                        }
                    }
                } else {
                    // Visit the near child first.
                    let (first, second) = if neg[node.axis as usize] {
                        (node.offset as usize, cur + 1)
                    } else {
                        (cur + 1, node.offset as usize)
                    };
                    stack.push(second as u32);
                    cur = first;
                    continue;
                }
            }
            match stack.pop() {
                Some(next) => cur = next as usize,
                None => break,
            }
        }
        if closest == usize::MAX {
            return best;
        }
        let lazy = match full {
            None => LazyHit::T(t_max),
            Some(h) if part != u32::MAX => LazyHit::Part(h, part),
            Some(h) => LazyHit::Full(h),
        };
        Some((lazy, &self.shapes[closest], self.ids[closest]))
    }

    /// Whether anything is hit with `t_min < t < t_max`.
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        if self
            .unbounded
            .iter()
            .any(|(s, _)| s.occluded(ray, t_min, t_max))
        {
            return true;
        }
        if self.nodes.is_empty() {
            return false;
        }
        let inv_d = ray.d.recip();
        // An ArrayVec: a fixed array would be zeroed on every call (a tenth of a short ray's
        // instructions).
        let mut stack = ArrayVec::<u32, STACK>::new();
        let mut cur = 0usize;
        loop {
            let node = &self.nodes[cur];
            if node.bounds.hit(ray, inv_d, t_min, t_max).is_some() {
                if node.count > 0 {
                    let start = node.offset as usize + node.quads as usize;
                    let end = node.offset as usize + node.count as usize;
                    if self
                        .leaf_packets(node)
                        .iter()
                        .any(|p| p.occluded(ray, t_min, t_max))
                        || self.shapes[start..end]
                            .iter()
                            .any(|s| s.occluded(ray, t_min, t_max))
                    {
                        return true;
                    }
                } else {
                    stack.push(node.offset);
                    cur += 1;
                    continue;
                }
            }
            match stack.pop() {
                Some(next) => cur = next as usize,
                None => return false,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::*;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::sphere::Sphere;

    /// Nodes on the longest root-to-leaf path.
    fn depth(bvh: &Bvh) -> usize {
        fn below(n: &[Node], i: usize) -> usize {
            if n[i].count > 0 {
                1
            } else {
                1 + below(n, i + 1).max(below(n, n[i].offset as usize))
            }
        }
        below(&bvh.nodes, 0)
    }

    fn spheres_bvh(spheres: &[Sphere], median_depth: usize) -> Bvh {
        let shapes = spheres
            .iter()
            .enumerate()
            .map(|(i, s)| (AnyShape::Sphere(*s), i as u32))
            .collect();
        Bvh::with_median_depth(shapes, median_depth)
    }

    fn assert_matches_brute_force(
        spheres: &[Sphere],
        bvh: &Bvh,
        rng: &mut Rng,
        ray_of: fn(&mut Rng) -> Ray,
    ) {
        let mut hits = 0;
        for _ in 0..500 {
            let ray = ray_of(rng);
            let brute = spheres
                .iter()
                .enumerate()
                .filter_map(|(i, s)| s.intersect(&ray, 0.0, f32::INFINITY).map(|h| (h.t, i)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let got = bvh
                .intersect(&ray, 0.0, f32::INFINITY)
                .map(|(h, i)| (h.t, i as usize));
            assert_eq!(brute, got);
            assert_eq!(brute.is_some(), bvh.occluded(&ray, 0.0, f32::INFINITY));
            hits += usize::from(brute.is_some());
        }
        assert!(hits > 100, "too few rays hit ({hits} of 500)");
    }

    /// `n` spheres of radius 0.1..0.6 centred in a random cube of side 10.
    fn sphere_cloud(rng: &mut Rng, n: usize) -> Vec<Sphere> {
        (0..n)
            .map(|_| {
                let c = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 10.0;
                Sphere::new(c, 0.1 + rng.f32() * 0.5).unwrap()
            })
            .collect()
    }

    /// Rays in a random cube of side 10.
    fn cloud_ray(rng: &mut Rng) -> Ray {
        let o = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 10.0;
        Ray::new(o, uniform_sphere(rng.vec2()))
    }

    /// Rays parallel to the x axis, within 0.05 of it, starting at x in 2^(0..100), running
    /// either way.
    fn chain_ray(rng: &mut Rng) -> Ray {
        let (y, z) = (0.1 * (rng.f32() - 0.5), 0.1 * (rng.f32() - 0.5));
        let o = Vec3A::new(2f32.powf(rng.f32() * 100.0), y, z);
        let side = if rng.f32() < 0.5 { -1.0 } else { 1.0 };
        Ray::new(o, Vec3A::new(side, 0.0, 0.0))
    }

    /// Below `median_depth` nodes split at the object median, which bounds the depth by
    /// `median_depth + log2(n)`: the traversal stack cannot overflow. Checked with the limit
    /// lowered so that median splits really happen, on spheres spaced exponentially along a
    /// line (SAH peels a few off per level there: 28 levels for 100 of them at ratio 2).
    #[test]
    fn median_splits_bound_the_depth_and_keep_hits() {
        let chain: Vec<Sphere> = (0..100)
            .map(|k| Sphere::new(Vec3A::new(2f32.powi(k), 0.0, 0.0), 0.1).unwrap())
            .collect();
        let sah = depth(&spheres_bvh(&chain, usize::MAX));
        assert!(sah > 20, "SAH alone builds a deep tree here ({sah})");
        assert!(
            depth(&Bvh::new(
                chain.iter().map(|s| (AnyShape::Sphere(*s), 0)).collect()
            )) <= STACK
        );
        let mut rng = Rng::new(3);
        let cloud = sphere_cloud(&mut rng, 300);
        for limit in [0, 3, 8] {
            for (spheres, ray_of) in [
                (&chain, chain_ray as fn(&mut Rng) -> Ray),
                (&cloud, cloud_ray),
            ] {
                let bvh = spheres_bvh(spheres, limit);
                let bound = limit + (spheres.len() as f32).log2().ceil() as usize + 1;
                let d = depth(&bvh);
                assert!(
                    d <= bound,
                    "depth {d} over {bound} with median splits from {limit}"
                );
                assert_matches_brute_force(spheres, &bvh, &mut rng, ray_of);
            }
        }
    }

    #[test]
    fn matches_brute_force() {
        let mut rng = Rng::new(7);
        let spheres = sphere_cloud(&mut rng, 200);
        let bvh = spheres_bvh(&spheres, MEDIAN_DEPTH);
        assert_matches_brute_force(&spheres, &bvh, &mut rng, cloud_ray);
    }

    /// Leaves that mix quads, spheres, triangles and disks: the quads are reordered to the
    /// front of the leaf and tested four at a time, the rest one by one. The nearest hit
    /// (its `t` bit for bit, and its id) and occlusion must be those of brute force over the
    /// shapes, including the Cornell box's single leaf of 6 quads and 2 spheres.
    #[test]
    fn leaves_of_mixed_shapes_match_brute_force() {
        use crate::shapes::disk::Disk;
        use crate::shapes::quad::Quad;
        use crate::shapes::triangle::Triangle;
        let mut rng = Rng::new(17);
        let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
        let (mut packed_leaves, mut two_packets) = (0, 0);
        for case in 0..300 {
            let n = 2 + case % 12;
            // Every tenth case is a closed box of 6 walls (random proportions) with 0-2 spheres
            // inside: often one leaf, whose 6 quads take two packets (as in the Cornell box).
            let walls = |rng: &mut Rng| {
                let (x, y, z) = (Vec3A::X, Vec3A::Y, Vec3A::Z);
                let s = Vec3A::ONE + v(rng).abs();
                let o = -s;
                let e = 2.0 * s;
                [
                    (o, e.x * x, e.z * z),
                    (o + e.y * y, e.x * x, e.z * z),
                    (o, e.x * x, e.y * y),
                    (o + e.z * z, e.x * x, e.y * y),
                    (o, e.z * z, e.y * y),
                    (o + e.x * x, e.z * z, e.y * y),
                ]
                .map(|(o, a, b)| AnyShape::Quad(Quad::new(o, a, b).unwrap()))
            };
            let shapes: Vec<AnyShape> = if case % 10 == 0 {
                let mut s = Vec::from(walls(&mut rng));
                for _ in 0..case % 3 {
                    s.push(AnyShape::Sphere(
                        Sphere::new(0.5 * v(&mut rng), 0.3).unwrap(),
                    ));
                }
                s
            } else {
                (0..n)
                    .map(|k| {
                        let c = 1.5 * v(&mut rng);
                        match (k + case) % 5 {
                            0 | 1 => {
                                AnyShape::Quad(Quad::new(c, v(&mut rng), v(&mut rng)).unwrap())
                            }
                            2 | 3 => {
                                AnyShape::Sphere(Sphere::new(c, 0.1 + 0.4 * rng.f32()).unwrap())
                            }
                            _ if k % 2 == 0 => AnyShape::Triangle(
                                Triangle::new([c, c + v(&mut rng), c + v(&mut rng)], None, None)
                                    .unwrap(),
                            ),
                            _ => AnyShape::Disk(Disk::new(c, v(&mut rng), 0.5).unwrap()),
                        }
                    })
                    .collect()
            };
            let bvh = Bvh::new(
                shapes
                    .iter()
                    .enumerate()
                    .map(|(i, s)| (copy_shape(s), 100 + i as u32))
                    .collect(),
            );
            packed_leaves += bvh.nodes.iter().filter(|n| n.quads > 0).count();
            two_packets += bvh.nodes.iter().filter(|n| n.quads > 4).count();
            for _ in 0..50 {
                let ray = Ray::new(2.0 * v(&mut rng), uniform_sphere(rng.vec2()));
                let t_max = if rng.f32() < 0.3 { 1.0 } else { f32::INFINITY };
                let mut brute: Option<(f32, u32)> = None;
                let mut limit = t_max;
                for (i, s) in shapes.iter().enumerate() {
                    if let Some(h) = s.intersect(&ray, 0.0, limit) {
                        limit = h.t;
                        brute = Some((h.t, 100 + i as u32));
                    }
                }
                let got = bvh.intersect(&ray, 0.0, t_max).map(|(h, id)| (h.t, id));
                assert_eq!(
                    got.map(|(t, id)| (t.to_bits(), id)),
                    brute.map(|(t, id)| (t.to_bits(), id)),
                    "case {case}"
                );
                assert_eq!(bvh.occluded(&ray, 0.0, t_max), brute.is_some());
            }
        }
        assert!(packed_leaves > 100, "{packed_leaves} leaves with packets");
        assert!(two_packets >= 10, "{two_packets} leaves with two packets");
    }

    fn copy_shape(s: &AnyShape) -> AnyShape {
        match s {
            AnyShape::Quad(q) => AnyShape::Quad(*q),
            AnyShape::Sphere(q) => AnyShape::Sphere(*q),
            AnyShape::Triangle(q) => AnyShape::Triangle(*q),
            AnyShape::Disk(q) => AnyShape::Disk(*q),
            _ => unreachable!("only the kinds this test builds"),
        }
    }
}
