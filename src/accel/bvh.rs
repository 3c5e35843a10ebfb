//! Binned SAH bounding volume hierarchy over shapes and mesh triangles, flattened depth-first.
//! Shapes without finite bounds (infinite planes) are kept in a side list and tested always.
//! What the leaves hold is packed after the build ([`super::leaf`]).

use arrayvec::ArrayVec;
use rayon::prelude::*;

use super::build::{Item, Parallelism, build};
use super::leaf::{Closest, Content, Leaves};
use super::triangles::Meshes;
use super::wide::{BoxRay, EMPTY, LEAF, WideNode, collapse, far_to_near, still_near};
use crate::geometry::{Aabb, Hit, Ray};
use crate::shapes::Shape;
use crate::shapes::mesh::TriangleMesh;
use crate::shapes::primitive::{AnyShape, LazyHit};

/// Traversal stack size: up to three entries per level of the 4-wide tree, which is no deeper
/// than the binary tree (< 64 levels, see `MEDIAN_DEPTH`).
const STACK: usize = 192;
/// From this depth on, nodes split at the object median instead of by SAH, so that no tree is
/// deeper than `MEDIAN_DEPTH + log2(primitives)` (< `STACK` for fewer than 2^31 primitives). SAH
/// alone can peel a few primitives off per level (e.g. exponentially spaced sizes), and a
/// deeper tree would overflow the traversal stack.
const MEDIAN_DEPTH: usize = 32;

/// A node of the binary tree the build makes (collapsed into [`WideNode`]s afterwards).
#[derive(Debug, Clone, Copy)]
pub(super) struct Node {
    pub bounds: Aabb,
    /// Leaf: first item (after packing: its index in the leaf list). Interior: index of the
    /// second child (the first follows).
    pub offset: u32,
    /// Items in a leaf; 0 for an interior node.
    pub count: u16,
}

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
}

/// What a closest hit is on: a shape, or triangle `k` of a mesh.
#[derive(Clone, Copy)]
pub enum Surface<'a> {
    Shape(&'a AnyShape),
    MeshTriangle(&'a TriangleMesh, usize),
}

impl<'a> Surface<'a> {
    /// The full hit for a [`LazyHit`] returned for `ray` (see [`AnyShape::hit_at_uv`]).
    #[inline]
    pub fn hit_at_uv(&self, ray: &Ray, lazy: LazyHit, uv: bool) -> Hit {
        match self {
            Surface::Shape(s) => s.hit_at_uv(ray, lazy, uv),
            Surface::MeshTriangle(m, k) => match lazy {
                LazyHit::T(t) => m.hit_at(*k, ray, t),
                LazyHit::Full(h) | LazyHit::Part(h, _) => h,
            },
        }
    }

    /// The shape hit, unless it is a mesh triangle.
    pub fn shape(self) -> Option<&'a AnyShape> {
        match self {
            Surface::Shape(s) => Some(s),
            Surface::MeshTriangle(..) => None,
        }
    }
}

impl Bvh {
    pub fn new(shapes: Vec<(AnyShape, u32)>) -> Self {
        Self::with_meshes(shapes, Vec::new())
    }

    /// A BVH over `shapes` and the triangles of `meshes` (each mesh with the id its hits get).
    pub fn with_meshes(shapes: Vec<(AnyShape, u32)>, meshes: Vec<(TriangleMesh, u32)>) -> Self {
        Self::with_median_depth(shapes, meshes, MEDIAN_DEPTH)
    }

    fn with_median_depth(
        shapes: Vec<(AnyShape, u32)>,
        meshes: Vec<(TriangleMesh, u32)>,
        median_depth: usize,
    ) -> Self {
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
            .map(|(index, b)| Item::new(b.padded(1e-6), index))
            .chain(
                triangles
                    .par_iter()
                    .map(|&(g, m, k)| Item::triangle(m.bounds(k).padded(1e-6), nb + g as usize)),
            )
            .collect();
        drop(triangles);
        let mut nodes: Vec<Node> = build(&mut items, median_depth, Parallelism::DEFAULT)
            .into_par_iter()
            .map(|b| Node {
                bounds: b.bounds,
                offset: b.offset,
                count: b.count as u16,
            })
            .collect();
        nodes.shrink_to_fit();
        // Pack each leaf's contents; its node then names the leaf.
        let mut slots: Vec<Option<(AnyShape, u32)>> = bounded.into_iter().map(Some).collect();
        let mut leaves = Leaves::default();
        let mut contents = Vec::new();
        for node in nodes.iter_mut().filter(|n| n.count > 0) {
            contents.clear();
            contents.extend(
                items[node.offset as usize..][..node.count as usize]
                    .iter()
                    .map(|it| match it.index.checked_sub(nb) {
                        Some(g) => Content::Triangle(g as u32),
                        None => Content::Shape(it.index),
                    }),
            );
            node.offset = leaves.push(&contents, &mut slots, &meshes);
        }
        leaves.shrink_to_fit();
        #[cfg(test)]
        fn below(n: &[Node], i: usize) -> usize {
            if n[i].count > 0 {
                1
            } else {
                1 + below(n, i + 1).max(below(n, n[i].offset as usize))
            }
        }
        Self {
            #[cfg(test)]
            binary_depth: if nodes.is_empty() {
                0
            } else {
                below(&nodes, 0)
            },
            bounds: nodes.first().map_or(Aabb::EMPTY, |n| n.bounds),
            nodes: collapse(&nodes),
            leaves,
            meshes,
            unbounded,
        }
    }

    /// Bounds of the bounded shapes (infinite planes excluded).
    pub fn bounds(&self) -> Aabb {
        self.bounds
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
    /// for `t` only; the surface data is computed once, for the closest hit.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(Hit, u32)> {
        let (lazy, surface, id) = self.intersect_lazy(ray, t_min, t_max)?;
        Some((
            surface.hit_at_uv(ray, lazy, true),
            lazy.part().unwrap_or(id),
        ))
    }

    /// Closest hit as a [`LazyHit`], the surface hit and its id.
    #[inline]
    pub fn intersect_lazy(
        &self,
        ray: &Ray,
        t_min: f32,
        mut t_max: f32,
    ) -> Option<(LazyHit, Surface<'_>, u32)> {
        let mut best: Option<(LazyHit, Surface<'_>, u32)> = None;
        for (s, id) in &self.unbounded {
            if let Some(h) = s.intersect_lazy(ray, t_min, t_max) {
                t_max = h.t();
                best = Some((h, Surface::Shape(s), *id));
            }
        }
        if self.nodes.is_empty() {
            return best;
        }
        let boxes = BoxRay::new(ray);
        // Children still to visit, with their entry distances. An ArrayVec: a fixed array
        // would be zeroed on every call (a tenth of a short ray's instructions).
        let mut stack = ArrayVec::<(u32, f32), STACK>::new();
        let mut c = Closest::NONE;
        let mut cur = 0u32;
        loop {
            if cur & LEAF != 0 {
                self.leaves
                    .closest(cur & !LEAF, ray, t_min, &mut t_max, &mut c);
            } else {
                let node = &self.nodes[cur as usize];
                let (mask, near) = node.hit(&boxes, t_min, t_max);
                let mut hits = [(0, 0.0); 4];
                let n = far_to_near(node, mask, near, &mut hits);
                if n > 0 {
                    // (At most 3 per level of a tree no deeper than `STACK / 3`.)
                    for &h in &hits[..n - 1] {
                        stack.push(h);
                    }
                    cur = hits[n - 1].0;
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
                    None => return self.closest_hit(c, t_max, best),
                }
            }
        }
    }

    /// The result of a closest-hit traversal that ended with `c` and `t_max`.
    #[inline(always)]
    fn closest_hit<'a>(
        &'a self,
        c: Closest,
        t_max: f32,
        best: Option<(LazyHit, Surface<'a>, u32)>,
    ) -> Option<(LazyHit, Surface<'a>, u32)> {
        if c.triangle != u32::MAX {
            let (mesh, k, id) = self.meshes.locate(c.triangle);
            return Some((LazyHit::T(t_max), Surface::MeshTriangle(mesh, k), id));
        }
        if c.shape == usize::MAX {
            return best;
        }
        let lazy = match c.full {
            None => LazyHit::T(t_max),
            Some(h) if c.part != u32::MAX => LazyHit::Part(h, c.part),
            Some(h) => LazyHit::Full(h),
        };
        Some((
            lazy,
            Surface::Shape(&self.leaves.shapes[c.shape]),
            self.leaves.ids[c.shape],
        ))
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
        let boxes = BoxRay::new(ray);
        let mut stack = ArrayVec::<u32, STACK>::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF != 0 {
                if self.leaves.occluded(cur & !LEAF, ray, t_min, t_max) {
                    return true;
                }
            } else {
                let node = &self.nodes[cur as usize];
                let (mask, _) = node.hit(&boxes, t_min, t_max);
                let mut bits = mask;
                while bits != 0 {
                    let slot = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    if node.child[slot] != EMPTY {
                        stack.push(node.child[slot]);
                    }
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
mod tests {
    use glam::Vec3A;

    use super::*;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::sphere::Sphere;

    /// Nodes on the longest root-to-leaf path of the binary tree.
    fn depth(bvh: &Bvh) -> usize {
        bvh.binary_depth
    }

    fn spheres_bvh(spheres: &[Sphere], median_depth: usize) -> Bvh {
        let shapes = spheres
            .iter()
            .enumerate()
            .map(|(i, s)| (AnyShape::Sphere(*s), i as u32))
            .collect();
        Bvh::with_median_depth(shapes, Vec::new(), median_depth)
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
            packed_leaves += bvh.leaves.leaves.iter().filter(|l| l.quads > 0).count();
            two_packets += bvh.leaves.leaves.iter().filter(|l| l.quads > 4).count();
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
