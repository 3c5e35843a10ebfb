//! The BVH as traversed: 4-wide nodes collapsed from the binary SAH tree, each holding its
//! children's boxes in SoA form so that one ray tests all four at once, visiting the hit
//! children nearest first.

use arrayvec::ArrayVec;
use glam::{Vec3A, Vec4};

use super::bvh::Node as BinaryNode;
use crate::geometry::{Aabb, Ray};

/// A child reference with this bit set names a leaf (the rest is its index in the leaf list).
pub(super) const LEAF: u32 = 1 << 31;
/// An unused child slot.
pub(super) const EMPTY: u32 = u32::MAX;
/// Far bounds are scaled up by 1 + 2*gamma(3) (pbrt) so that rounding never culls a hit, as
/// in [`Aabb::hit`].
const FAR_SCALE: f32 = 1.000_000_4;

#[derive(Debug, Clone, Copy)]
pub(super) struct WideNode {
    min: [Vec4; 3],
    max: [Vec4; 3],
    /// Interior child: its node index; leaf: `LEAF | leaf index`; unused: `EMPTY`.
    pub child: [u32; 4],
}

/// A ray set up for box tests.
pub(super) struct BoxRay {
    o: [Vec4; 3],
    inv_d: [Vec4; 3],
    /// Per axis: whether the ray runs toward decreasing coordinates (it then enters a box
    /// through its `max` plane).
    neg: [bool; 3],
}

impl BoxRay {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Self {
        let inv_d: Vec3A = ray.d.recip();
        Self {
            o: [ray.o.x, ray.o.y, ray.o.z].map(Vec4::splat),
            inv_d: [inv_d.x, inv_d.y, inv_d.z].map(Vec4::splat),
            neg: [inv_d.x < 0.0, inv_d.y < 0.0, inv_d.z < 0.0],
        }
    }
}

impl WideNode {
    /// The children whose box the ray enters with `t_min <= t <= t_max` (conservatively, as
    /// [`Aabb::hit`]), as a bit mask, and the entry distances. The entry and exit planes are
    /// chosen by the ray's signs; a NaN slab distance (a ray in a slab's plane, parallel to
    /// it) is ignored. Unused slots may be in the mask.
    #[inline(always)]
    pub(super) fn hit(&self, ray: &BoxRay, t_min: f32, t_max: f32) -> (u32, Vec4) {
        let mut near = Vec4::splat(t_min);
        let mut far = Vec4::splat(t_max);
        for a in 0..3 {
            let (lo, hi) = if ray.neg[a] {
                (self.max[a], self.min[a])
            } else {
                (self.min[a], self.max[a])
            };
            // `x.max(acc)` keeps `acc` where `x` is NaN (SSE `maxps` returns its second
            // operand when either is NaN), as `Aabb::hit` does.
            near = ((lo - ray.o[a]) * ray.inv_d[a]).max(near);
            far = ((hi - ray.o[a]) * ray.inv_d[a]).min(far);
        }
        (near.cmple(far * FAR_SCALE).bitmask(), near)
    }
}

/// Whether a child entered at `near` may still hold a hit closer than `t_max` (the test of
/// [`WideNode::hit`] against a shrunk `t_max`).
#[inline(always)]
pub(super) fn still_near(near: f32, t_max: f32) -> bool {
    near <= t_max * FAR_SCALE
}

/// Collapses the binary tree (flattened depth-first: an interior node's first child follows
/// it, `offset` names the second; a leaf's `offset` is its leaf index) into 4-wide nodes: each
/// node takes its two children, then repeatedly replaces the interior child of largest surface
/// area by that child's two children, up to four. The root is node 0.
pub(super) fn collapse(nodes: &[BinaryNode]) -> Vec<WideNode> {
    let mut out = Vec::with_capacity(nodes.len() / 3 + 1);
    if nodes.is_empty() {
        return out;
    }
    if nodes[0].count > 0 {
        // A single leaf: one node with one child.
        out.push(WideNode::from_children(
            nodes,
            &[0],
            &[LEAF | nodes[0].offset],
        ));
        return out;
    }
    collapse_at(nodes, 0, &mut out);
    out.shrink_to_fit();
    out
}

fn collapse_at(nodes: &[BinaryNode], i: usize, out: &mut Vec<WideNode>) -> u32 {
    let idx = out.len();
    out.push(WideNode::from_children(nodes, &[], &[]));
    let mut kids: ArrayVec<usize, 4> = ArrayVec::new();
    kids.push(i + 1);
    kids.push(nodes[i].offset as usize);
    while !kids.is_full() {
        let widest = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| nodes[**k].count == 0)
            .max_by(|a, b| {
                let area = |k: usize| nodes[k].bounds.surface_area();
                area(*a.1).total_cmp(&area(*b.1))
            })
            .map(|(j, _)| j);
        let Some(j) = widest else { break };
        let k = kids.remove(j);
        kids.insert(j, nodes[k].offset as usize);
        kids.insert(j, k + 1);
    }
    let refs: ArrayVec<u32, 4> = kids
        .iter()
        .map(|&k| {
            if nodes[k].count > 0 {
                LEAF | nodes[k].offset
            } else {
                collapse_at(nodes, k, out)
            }
        })
        .collect();
    out[idx] = WideNode::from_children(nodes, &kids, &refs);
    idx as u32
}

impl WideNode {
    fn from_children(nodes: &[BinaryNode], kids: &[usize], refs: &[u32]) -> Self {
        // Unused slots get NaN boxes; traversal also skips them by their `EMPTY` reference.
        let mut n = Self {
            min: [Vec4::NAN; 3],
            max: [Vec4::NAN; 3],
            child: [EMPTY; 4],
        };
        for (slot, (&k, &r)) in kids.iter().zip(refs).enumerate() {
            let b: Aabb = nodes[k].bounds;
            for a in 0..3 {
                n.min[a][slot] = b.min[a];
                n.max[a][slot] = b.max[a];
            }
            n.child[slot] = r;
        }
        n
    }
}

/// The hit children of a node (mask and entry distances from [`WideNode::hit`]), unused
/// slots left out, ordered far to near in `out`; returns how many. (Fixed arrays and an
/// insertion sort: an `ArrayVec` insert here was a `memmove` call per child.)
#[inline(always)]
pub(super) fn far_to_near(
    node: &WideNode,
    mask: u32,
    near: Vec4,
    out: &mut [(u32, f32); 4],
) -> usize {
    let near = near.to_array();
    let mut n = 0;
    let mut bits = mask;
    while bits != 0 {
        let slot = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let c = node.child[slot];
        if c == EMPTY {
            continue;
        }
        let d = near[slot];
        let mut at = n;
        while at > 0 && out[at - 1].1 < d {
            out[at] = out[at - 1];
            at -= 1;
        }
        out[at] = (c, d);
        n += 1;
    }
    n
}

#[cfg(test)]
mod tests {
    use glam::{DAffine3, DVec2, DVec3};

    use super::super::Bvh;
    use crate::geometry::Ray;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::scene::MeshData;
    use crate::shapes::Shape;
    use crate::shapes::mesh::TriangleMesh;
    use crate::shapes::primitive::AnyShape;
    use crate::shapes::sphere::Sphere;

    /// A mesh of `n` random small triangles in the cube [-1, 1]^3 (shared vertices: each
    /// triangle reuses one of the previous triangle's), with normals and uvs when asked.
    fn random_mesh(rng: &mut Rng, n: usize, attributes: bool) -> MeshData {
        let v = |rng: &mut Rng| {
            DVec3::new(rng.f32() as f64, rng.f32() as f64, rng.f32() as f64) * 2.0 - DVec3::ONE
        };
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for k in 0..n {
            let c = v(rng);
            let base = positions.len() as u32;
            positions.push(c);
            positions.push(c + 0.3 * v(rng));
            positions.push(c + 0.3 * v(rng));
            let first = if k > 0 { base - 1 } else { base };
            indices.push([first, base + 1, base + 2]);
        }
        let count = positions.len();
        MeshData {
            path: "random.obj".into(),
            normals: if attributes {
                (0..count).map(|_| v(rng)).collect()
            } else {
                Vec::new()
            },
            uvs: if attributes {
                (0..count)
                    .map(|_| DVec2::new(rng.f32() as f64, rng.f32() as f64))
                    .collect()
            } else {
                Vec::new()
            },
            positions,
            indices,
        }
    }

    /// Two meshes (one with normals and uvs, one mirrored without) and a few spheres in one
    /// 4-wide BVH: the closest hit (every field of it, bit for bit, and its id) and occlusion
    /// are those of brute force over the meshes expanded into stand-alone triangles.
    #[test]
    fn meshes_and_shapes_match_brute_force() {
        let mut rng = Rng::new(11);
        let mirror = DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0));
        for case in 0..6 {
            let n = [1, 3, 40, 200, 700, 2000][case];
            let a =
                TriangleMesh::new(&random_mesh(&mut rng, n, true), &DAffine3::IDENTITY).unwrap();
            let b = TriangleMesh::new(&random_mesh(&mut rng, n / 2 + 1, false), &mirror).unwrap();
            let spheres: Vec<Sphere> = (0..case * 3)
                .map(|k| {
                    let c = glam::Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
                    Sphere::new(c, 0.05 + 0.02 * k as f32).unwrap()
                })
                .collect();
            let mut brute: Vec<(AnyShape, u32)> = Vec::new();
            for (mesh, id) in [(&a, 7), (&b, 8)] {
                brute.extend(
                    mesh.triangles()
                        .into_iter()
                        .map(|t| (AnyShape::Triangle(t), id)),
                );
            }
            brute.extend(spheres.iter().map(|s| (AnyShape::Sphere(*s), 20)));
            let bvh = Bvh::with_meshes(
                spheres.iter().map(|s| (AnyShape::Sphere(*s), 20)).collect(),
                vec![(a, 7), (b, 8)],
            );
            assert_eq!(bvh.len(), brute.len());
            let mut hits = 0;
            for i in 0..2000 {
                let o = glam::Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 3.0 - 1.5;
                let ray = Ray::new(o, uniform_sphere(rng.vec2()));
                let t_max = if i % 4 == 0 { 0.7 } else { f32::INFINITY };
                let mut want = None;
                let mut limit = t_max;
                for (s, id) in &brute {
                    if let Some(h) = s.intersect(&ray, 0.0, limit) {
                        limit = h.t;
                        want = Some((h, *id));
                    }
                }
                let got = bvh.intersect(&ray, 0.0, t_max);
                let bits = |h: &crate::geometry::Hit| {
                    let v = [h.p, h.n, h.ns, h.dpdu].map(|v| v.to_array().map(f32::to_bits));
                    (h.t.to_bits(), v, h.uv.to_array().map(f32::to_bits))
                };
                assert_eq!(
                    got.map(|(h, id)| (bits(&h), id)),
                    want.map(|(h, id)| (bits(&h), id)),
                    "case {case}, ray {i}"
                );
                assert_eq!(bvh.occluded(&ray, 0.0, t_max), want.is_some());
                hits += usize::from(want.is_some());
            }
            assert!(hits > 100 || n < 40, "case {case}: {hits} hits");
        }
    }
}
