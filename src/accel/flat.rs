//! A BVH whose whole tree is one leaf of quads and spheres (a small scene such as the Cornell
//! box: five walls, a light and two spheres, eight shapes the build keeps in one leaf) is
//! queried without the tree: no wide node's box test around the leaf, no traversal stack or
//! closest-hit record set up per ray, the quads in one eight-lane test where the CPU has AVX,
//! the spheres without the shape enum's dispatch, and the nearest hit's record built from its
//! shape's own type. Every ray of such a scene tested all of the leaf's shapes anyway. The
//! tests keep the leaf's order (its quads by lane, then its other shapes), so a ray gets the
//! hit the tree gives, ties included.

use super::leaf::{Leaf, Leaves};
use super::wide::Avx;
use crate::geometry::{Hit, Ray};
use crate::shapes::primitive::AnyShape;
use crate::shapes::quad::{Quad, QuadOctet};
use crate::shapes::sphere::Sphere;
use crate::shapes::{Shape, SplitShape};

/// The one leaf of a BVH that is nothing else, when that leaf holds quads and spheres only.
pub(super) struct Flat {
    leaf: Leaf,
    /// The leaf's quads (at most eight: a leaf holds at most eight shapes), lane by lane.
    octet: QuadOctet,
    /// The same quads, in the leaf's order, for the hit's record.
    quads: Vec<Quad>,
    /// The leaf's shapes after its quads (all spheres), in the leaf's order.
    spheres: Vec<Sphere>,
}

/// The quads' test: the octet's where the CPU has AVX, else the leaf's packets of four.
trait Quads: Copy {
    fn nearest(
        self,
        flat: &Flat,
        leaves: &Leaves,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(usize, f32)>;
    fn any(self, flat: &Flat, leaves: &Leaves, ray: &Ray, t_min: f32, t_max: f32) -> bool;
}

#[derive(Clone, Copy)]
struct Packets;

impl Quads for Packets {
    #[inline(always)]
    fn nearest(
        self,
        flat: &Flat,
        leaves: &Leaves,
        ray: &Ray,
        t_min: f32,
        mut t_max: f32,
    ) -> Option<(usize, f32)> {
        let mut best = None;
        for (p, packet) in leaves.quad_packets(&flat.leaf).iter().enumerate() {
            if let Some((lane, t)) = packet.hit_t(ray, t_min, t_max) {
                t_max = t;
                best = Some((4 * p + lane, t));
            }
        }
        best
    }

    #[inline(always)]
    fn any(self, flat: &Flat, leaves: &Leaves, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        leaves
            .quad_packets(&flat.leaf)
            .iter()
            .any(|p| p.occluded(ray, t_min, t_max))
    }
}

#[cfg(target_arch = "x86_64")]
impl Quads for Avx {
    #[inline(always)]
    fn nearest(
        self,
        flat: &Flat,
        _: &Leaves,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(usize, f32)> {
        // SAFETY: an `Avx` value exists only where the CPU has AVX.
        unsafe { flat.octet.hit_t(ray, t_min, t_max) }
    }

    #[inline(always)]
    fn any(self, flat: &Flat, _: &Leaves, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        // SAFETY: an `Avx` value exists only where the CPU has AVX.
        unsafe { flat.octet.occluded(ray, t_min, t_max) }
    }
}

impl Flat {
    /// The flat form of a tree that is the single leaf `leaf` (a leaf reference of `leaves`),
    /// if that leaf holds no mesh triangles and only quads and spheres.
    pub(super) fn of(leaves: &Leaves, leaf: u32) -> Option<Self> {
        let leaf = *leaves.leaves.get(usize::try_from(leaf).ok()?)?;
        if leaf.tris != 0 {
            return None;
        }
        let start = leaf.shapes as usize;
        let shapes = leaves.shapes.get(start..start + leaf.count as usize)?;
        let (quads, rest) = shapes.split_at_checked(leaf.quads as usize)?;
        let quads = quads
            .iter()
            .map(|s| match s {
                AnyShape::Quad(q) => Some(*q),
                _ => None,
            })
            .collect::<Option<Vec<Quad>>>()?;
        let spheres = rest
            .iter()
            .map(|s| match s {
                AnyShape::Sphere(s) => Some(*s),
                _ => None,
            })
            .collect::<Option<Vec<Sphere>>>()?;
        Some(Self {
            leaf,
            octet: QuadOctet::new(&quads)?,
            quads,
            spheres,
        })
    }

    /// [`super::Bvh::intersect_uv`]: the closest hit's full record and its shape's id (the
    /// record [`AnyShape::hit_at_uv`] gives). The test itself is out of line, as the tree's
    /// traversal (this only chooses it).
    #[inline]
    pub(super) fn intersect(
        &self,
        leaves: &Leaves,
        avx: Option<Avx>,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = avx {
            // SAFETY: an `Avx` value exists only where the CPU has AVX.
            return unsafe { self.intersect_avx(avx, leaves, ray, t_min, t_max, uv) };
        }
        let _ = avx;
        self.intersect_packets(leaves, ray, t_min, t_max, uv)
    }

    #[inline(never)]
    fn intersect_packets(
        &self,
        leaves: &Leaves,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        self.intersect_with(Packets, leaves, ray, t_min, t_max, uv)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn intersect_avx(
        &self,
        avx: Avx,
        leaves: &Leaves,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        self.intersect_with(avx, leaves, ray, t_min, t_max, uv)
    }

    /// Whether anything is hit with `t_min < t < t_max` ([`super::Bvh::occluded`]).
    #[inline]
    pub(super) fn occluded(
        &self,
        leaves: &Leaves,
        avx: Option<Avx>,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = avx {
            // SAFETY: an `Avx` value exists only where the CPU has AVX.
            return unsafe { self.occluded_avx(avx, leaves, ray, t_min, t_max) };
        }
        let _ = avx;
        self.occluded_packets(leaves, ray, t_min, t_max)
    }

    #[inline(never)]
    fn occluded_packets(&self, leaves: &Leaves, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.occluded_with(Packets, leaves, ray, t_min, t_max)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn occluded_avx(&self, avx: Avx, leaves: &Leaves, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.occluded_with(avx, leaves, ray, t_min, t_max)
    }

    #[inline(always)]
    fn intersect_with<Q: Quads>(
        &self,
        quads: Q,
        leaves: &Leaves,
        ray: &Ray,
        t_min: f32,
        mut t_max: f32,
        uv: impl Fn(u32) -> bool,
    ) -> Option<(Hit, u32)> {
        // As the tree's box test, which no ray with a non-finite origin or direction passes.
        if !super::wide::BoxRay::usable(ray) {
            return None;
        }
        let start = self.leaf.shapes as usize;
        let mut best = quads
            .nearest(self, leaves, ray, t_min, t_max)
            .map(|(lane, t)| {
                t_max = t;
                lane
            });
        let rest = self.leaf.quads as usize;
        for (k, s) in self.spheres.iter().enumerate() {
            if let Some(t) = s.hit_t(ray, t_min, t_max) {
                t_max = t;
                best = Some(rest + k);
            }
        }
        let k = best?;
        let (id, t) = (leaves.ids[start + k], t_max);
        // Each branch writes its record into the result itself (merged, the record was built
        // in a temporary and copied), with `uv` and `t` in one store (`Hit::from_parts`).
        match k.checked_sub(rest) {
            Some(k) => Some((self.spheres[k].hit_at_uv(ray, t, uv(id)), id)),
            None => Some((self.quads[k].hit_at(ray, t), id)),
        }
    }

    #[inline(always)]
    fn occluded_with<Q: Quads>(
        &self,
        quads: Q,
        leaves: &Leaves,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        super::wide::BoxRay::usable(ray)
            && (quads.any(self, leaves, ray, t_min, t_max)
                || self.spheres.iter().any(|s| s.occluded(ray, t_min, t_max)))
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::super::Bvh;
    use crate::geometry::{Hit, Ray};
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::primitive::AnyShape;
    use crate::shapes::quad::Quad;
    use crate::shapes::sphere::Sphere;

    fn random_vec(rng: &mut Rng) -> Vec3A {
        Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE
    }

    /// A scene of up to eight shapes: the walls of a box (quads sharing edges and corners, as
    /// the Cornell box's), random quads and spheres, in a random order.
    fn scene(rng: &mut Rng, case: usize) -> Vec<AnyShape> {
        let box_walls = [
            (Vec3A::new(-1.0, 0.0, -1.0), Vec3A::X * 2.0, Vec3A::Z * 2.0),
            (Vec3A::new(-1.0, 2.0, -1.0), Vec3A::X * 2.0, Vec3A::Z * 2.0),
            (Vec3A::new(-1.0, 0.0, -1.0), Vec3A::X * 2.0, Vec3A::Y * 2.0),
            (Vec3A::new(-1.0, 0.0, -1.0), Vec3A::Z * 2.0, Vec3A::Y * 2.0),
            (Vec3A::new(1.0, 0.0, -1.0), Vec3A::Z * 2.0, Vec3A::Y * 2.0),
        ];
        let count = 2 + case % 7;
        (0..count)
            .map(|k| {
                let pick = rng.f32();
                if k < box_walls.len() && case.is_multiple_of(2) {
                    let (o, u, v) = box_walls[k];
                    AnyShape::Quad(Quad::new(o, u, v).unwrap())
                } else if pick < 0.6 {
                    let o = random_vec(rng) + Vec3A::Y;
                    AnyShape::Quad(Quad::new(o, random_vec(rng), random_vec(rng)).unwrap())
                } else {
                    let c = random_vec(rng) * 0.6 + Vec3A::Y;
                    AnyShape::Sphere(Sphere::new(c, 0.05 + 0.4 * rng.f32()).unwrap())
                }
            })
            .collect()
    }

    /// A hit's `t`, vectors, `uv` and id, as bits.
    type Bits = (u32, [[u32; 3]; 4], [u32; 2], u32);

    fn bits(hit: Option<(Hit, u32)>) -> Option<Bits> {
        hit.map(|(h, id)| {
            let v = [h.p, h.n, h.ns, h.dpdu].map(|v| v.to_array().map(f32::to_bits));
            (h.t.to_bits(), v, h.uv.to_array().map(f32::to_bits), id)
        })
    }

    /// A BVH that is one leaf of quads and spheres answers without its tree exactly as through
    /// it, with AVX and without: the same shape, the same record bit for bit, and the same
    /// occlusion, for rays from inside and outside, toward shared edges and corners (equal `t`
    /// on two quads), and with non-finite origins or directions.
    #[test]
    fn the_flat_query_gives_the_tree_s_answers() {
        let mut rng = Rng::new(21);
        let (mut flat, mut hits, mut edges, mut ties) = (0, 0, 0, 0);
        for case in 0..600 {
            let seed = 1000 + case as u64;
            let build = |rng: &mut Rng| {
                let shapes = scene(rng, case);
                Bvh::new(shapes.into_iter().zip(0..).collect()).expect("a BVH of test size")
            };
            let bvh = build(&mut Rng::new(seed));
            let tree = build(&mut Rng::new(seed)).without_flat();
            let packets = build(&mut Rng::new(seed)).without_avx();
            flat += usize::from(bvh.is_flat());
            for i in 0..200 {
                let o = if i % 2 == 0 {
                    random_vec(&mut rng) * 0.9 + Vec3A::Y
                } else {
                    random_vec(&mut rng) * 4.0
                };
                let d = match i % 7 {
                    // Toward an edge or a corner of the box.
                    0 | 1 => {
                        let mut c = Vec3A::new(rng.f32() * 2.0 - 1.0, 2.0 * rng.f32(), -1.0);
                        if i % 7 == 1 {
                            c.y = 0.0;
                            c.x = if rng.f32() < 0.5 { -1.0 } else { 1.0 };
                        }
                        (c - o).normalize()
                    }
                    // From the plane `y - 1 = z` toward the floor and back wall's shared edge,
                    // which it meets at the same `t` on both.
                    2 => Vec3A::new(rng.f32() * 0.6 - 0.3, -1.0, -1.0).normalize(),
                    _ if i % 50 == 3 => Vec3A::new(f32::NAN, 0.0, 1.0),
                    _ => uniform_sphere(rng.vec2()),
                };
                let o = match (i % 7, i % 50) {
                    (2, _) => Vec3A::new(rng.f32() * 1.6 - 0.8, 1.0, 0.0),
                    (_, 5) => Vec3A::INFINITY,
                    _ => o,
                };
                let ray = Ray::new(o, d);
                let t_max = if i % 3 == 0 {
                    2.0 * rng.f32()
                } else {
                    f32::INFINITY
                };
                let got = bvh.intersect(&ray, 0.0, t_max);
                assert_eq!(
                    bits(got),
                    bits(tree.intersect(&ray, 0.0, t_max)),
                    "case {case}, ray {i}"
                );
                assert_eq!(
                    bvh.occluded(&ray, 0.0, t_max),
                    tree.occluded(&ray, 0.0, t_max)
                );
                assert_eq!(got.is_some(), bvh.occluded(&ray, 0.0, t_max));
                // Without AVX: the leaf's packets of four.
                assert_eq!(bits(packets.intersect(&ray, 0.0, t_max)), bits(got));
                assert_eq!(packets.occluded(&ray, 0.0, t_max), got.is_some());
                if bvh.is_flat() {
                    hits += usize::from(got.is_some());
                    edges += usize::from(got.is_some() && i % 7 < 3);
                    ties += usize::from(got.is_some() && i % 7 == 2 && case.is_multiple_of(2));
                }
            }
        }
        assert!(flat > 200, "{flat} of 600 scenes flat");
        assert!(
            hits > 8_000 && edges > 4_000 && ties > 500,
            "{hits} hits, {edges} toward edges, {ties} toward the tie"
        );
    }
}
