//! Mesh triangles in the BVH's leaves: four to a packet, each as its first vertex and two edges
//! in SoA form, tested four at a time by Möller–Trumbore (a leaf's two packets eight at a time
//! where the CPU has AVX). A packet holds what the test needs and
//! the triangles' numbers; the surface data of the closest hit comes from the mesh's shared
//! buffers ([`TriangleMesh::hit_at`]).

use glam::{BVec4A, Vec3A, Vec4};

use crate::geometry::Ray;
use crate::shapes::mesh::TriangleMesh;

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TrianglePacket {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
    /// Each lane's triangle (a number over all the BVH's meshes); `u32::MAX` in empty lanes.
    ids: [u32; 4],
}

#[inline(always)]
fn dot4(a: &[Vec4; 3], b: &[Vec4; 3]) -> Vec4 {
    (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]
}

#[inline(always)]
fn cross4(a: &[Vec4; 3], b: &[Vec4; 3]) -> [Vec4; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl TrianglePacket {
    /// The packet of up to four triangles, each given by its vertices and its number.
    pub(crate) fn new(tris: &[([Vec3A; 3], u32)]) -> Self {
        assert!(tris.len() <= 4, "a packet holds four triangles");
        let mut p = Self {
            v0: [Vec4::ZERO; 3],
            e1: [Vec4::ZERO; 3],
            e2: [Vec4::ZERO; 3],
            ids: [u32::MAX; 4],
        };
        for (lane, (v, id)) in tris.iter().enumerate() {
            let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
            for axis in 0..3 {
                p.v0[axis][lane] = v[0][axis];
                p.e1[axis][lane] = e1[axis];
                p.e2[axis][lane] = e2[axis];
            }
            p.ids[lane] = *id;
        }
        p
    }

    /// The lanes that hold triangle `g` (its number over all the BVH's meshes), as bits.
    #[inline(always)]
    pub(crate) fn lanes_of(&self, g: u32) -> u32 {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::*;
            // SAFETY: SSE2 is part of x86-64; `ids` is four `u32`s, read unaligned. (One
            // compare of the four: the compiler made four compares and their bits of it.)
            unsafe {
                let ids = _mm_loadu_si128(self.ids.as_ptr().cast());
                let eq = _mm_cmpeq_epi32(ids, _mm_set1_epi32(g as i32));
                _mm_movemask_ps(_mm_castsi128_ps(eq)) as u32
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        (0..4).fold(0, |m, l| m | (u32::from(self.ids[l] == g) << l))
    }

    /// The unnormalised geometric normal (`e1 x e2`) of the triangle in lane `lane % 4`: the
    /// operations of [`TriangleMesh::geometric_normal`] on the same edges (the packet's are
    /// `v1 - v0` and `v2 - v0` of the mesh's positions), so the same bits. (The lane picks
    /// addresses, not a branch: on a hit's random lane, a branch or jump table was
    /// mispredicted.)
    #[inline(always)]
    pub(crate) fn geometric_normal_at(&self, lane: usize) -> Vec3A {
        let l = lane % 4;
        let edge = |e: &[Vec4; 3]| {
            let at = |a: usize| AsRef::<[f32; 4]>::as_ref(&e[a])[l];
            Vec3A::new(at(0), at(1), at(2))
        };
        edge(&self.e1).cross(edge(&self.e2))
    }

    /// The lanes whose triangle the ray crosses with `t_min < t < t_max`, and each lane's `t`
    /// and barycentric coordinates: the same operations in the same order as the scalar
    /// [`Triangle`] test, so the same bits.
    ///
    /// [`Triangle`]: crate::shapes::triangle::Triangle
    #[inline(always)]
    fn hits(&self, ray: &Ray, t_min: f32, t_max: f32) -> (BVec4A, Vec4, [Vec4; 2]) {
        let d = [ray.d.x, ray.d.y, ray.d.z].map(Vec4::splat);
        let o = [ray.o.x, ray.o.y, ray.o.z].map(Vec4::splat);
        self.hits_with(&d, &o, t_min, t_max)
    }

    /// [`TrianglePacket::hits`] with the ray's direction `d` and origin `o` already broadcast.
    #[inline(always)]
    fn hits_with(
        &self,
        d: &[Vec4; 3],
        o: &[Vec4; 3],
        t_min: f32,
        t_max: f32,
    ) -> (BVec4A, Vec4, [Vec4; 2]) {
        let d = *d;
        let pv = cross4(&d, &self.e2);
        let det = dot4(&self.e1, &pv);
        let inv = Vec4::ONE / det;
        let tv = [0, 1, 2].map(|a| o[a] - self.v0[a]);
        let b1 = dot4(&tv, &pv) * inv;
        let qv = cross4(&tv, &self.e1);
        let b2 = dot4(&d, &qv) * inv;
        let t = dot4(&self.e2, &qv) * inv;
        let (zero, one) = (Vec4::ZERO, Vec4::ONE);
        let finite = det.abs().cmplt(Vec4::INFINITY);
        let mask = det.cmpne(zero)
            & finite
            & b1.cmpge(zero)
            & b1.cmple(one)
            & !b2.cmplt(zero)
            & !(b1 + b2).cmpgt(one)
            & t.cmpgt(Vec4::splat(t_min))
            & t.cmplt(Vec4::splat(t_max));
        (mask, t, [b1, b2])
    }

    /// The nearest hit with `t_min < t < t_max`: its triangle, `t` and barycentric coordinates
    /// (on equal `t`, the lowest lane, as a scalar loop over the triangles in lane order would
    /// keep).
    #[inline]
    pub(crate) fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(u32, f32, [f32; 2])> {
        self.nearest(self.hits(ray, t_min, t_max))
    }

    /// The nearest of the lanes `hits` returned (see [`TrianglePacket::hit_t`]).
    #[inline(always)]
    fn nearest(&self, (mask, t, b): (BVec4A, Vec4, [Vec4; 2])) -> Option<(u32, f32, [f32; 2])> {
        if !mask.any() {
            return None;
        }
        let t = Vec4::select(mask, t, Vec4::INFINITY);
        let best = t.min_element();
        let lane = (t.cmpeq(Vec4::splat(best)) & mask)
            .bitmask()
            .trailing_zeros() as usize;
        Some((self.ids[lane], best, [b[0][lane], b[1][lane]]))
    }

    /// Whether any triangle of the packet is hit with `t_min < t < t_max`.
    #[inline]
    pub(crate) fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.hits(ray, t_min, t_max).0.any()
    }
}

/// The triangle test of a leaf's two packets: [`Halves`] tests them one after the other,
/// [`Avx`] tests their eight lanes at once. Both give the scalar test's bits, and the same
/// nearest hit (on equal `t`, the first packet's lanes before the second's).
///
/// [`Halves`]: super::wide::Halves
/// [`Avx`]: super::wide::Avx
///
/// A traversal sets the ray up for the leaf tests once per query ([`PairTest::lanes`]), and
/// both tests, of one packet and of two, take their broadcasts of the ray from it: where the
/// CPU has AVX, the four-lane test reads the low halves of the eight-lane test's registers
/// (each set of broadcasts was otherwise made and spilled twice per query).
pub(crate) trait PairTest: Copy {
    /// The ray as the leaf tests take it.
    type Lanes;

    /// Sets `ray` up for the leaf tests, one set of broadcasts for both (the closest-hit
    /// traversal's set-up).
    fn lanes(self, ray: &Ray) -> Self::Lanes;

    /// Sets `ray` up for the leaf tests, leaving the compiler free to broadcast it again
    /// for each test (the any-hit traversal's set-up: its loop keeps the broadcasts in
    /// registers, and sharing them cost it about 1 % more instructions).
    fn plain_lanes(self, ray: &Ray) -> Self::Lanes;

    /// [`TrianglePacket::hit_t`], the same bits.
    fn packet_hit_t(
        self,
        lanes: &Self::Lanes,
        packet: &TrianglePacket,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(u32, f32, [f32; 2])>;

    /// [`TrianglePacket::occluded`].
    fn packet_occluded(
        self,
        lanes: &Self::Lanes,
        packet: &TrianglePacket,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool;

    /// The nearest hit in `pair` with `t_min < t < t_max`, as [`TrianglePacket::hit_t`].
    fn pair_hit_t(
        self,
        lanes: &Self::Lanes,
        pair: &[TrianglePacket; 2],
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(u32, f32, [f32; 2])>;

    /// Whether any triangle of `pair` is hit with `t_min < t < t_max`.
    fn pair_occluded(
        self,
        lanes: &Self::Lanes,
        pair: &[TrianglePacket; 2],
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool;
}

impl PairTest for super::wide::Halves {
    type Lanes = ();

    #[inline(always)]
    fn lanes(self, _: &Ray) {}

    #[inline(always)]
    fn plain_lanes(self, _: &Ray) {}

    #[inline(always)]
    fn packet_hit_t(
        self,
        _: &(),
        packet: &TrianglePacket,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(u32, f32, [f32; 2])> {
        packet.hit_t(ray, t_min, t_max)
    }

    #[inline(always)]
    fn packet_occluded(
        self,
        _: &(),
        packet: &TrianglePacket,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        packet.occluded(ray, t_min, t_max)
    }

    #[inline(always)]
    fn pair_hit_t(
        self,
        _: &(),
        pair: &[TrianglePacket; 2],
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(u32, f32, [f32; 2])> {
        let first = pair[0].hit_t(ray, t_min, t_max);
        let limit = first.map_or(t_max, |h| h.1);
        pair[1].hit_t(ray, t_min, limit).or(first)
    }

    #[inline(always)]
    fn pair_occluded(
        self,
        _: &(),
        pair: &[TrianglePacket; 2],
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        pair.iter().any(|p| p.occluded(ray, t_min, t_max))
    }
}

/// The ray as the AVX leaf tests take it.
#[cfg(target_arch = "x86_64")]
type AvxLanes = avx::Lanes;
#[cfg(not(target_arch = "x86_64"))]
type AvxLanes = ();

impl PairTest for super::wide::Avx {
    type Lanes = AvxLanes;

    #[inline(always)]
    fn lanes(self, ray: &Ray) -> AvxLanes {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: an `Avx` value is made only after AVX was detected.
            unsafe { avx::lanes(ray) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = ray;
    }

    #[inline(always)]
    fn plain_lanes(self, ray: &Ray) -> AvxLanes {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: as above.
            unsafe { avx::plain_lanes(ray) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = ray;
    }

    #[inline(always)]
    fn packet_hit_t(
        self,
        lanes: &AvxLanes,
        packet: &TrianglePacket,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(u32, f32, [f32; 2])> {
        #[cfg(target_arch = "x86_64")]
        {
            let _ = ray;
            // SAFETY: as above.
            packet.nearest(unsafe { avx::packet_hits(lanes, packet, t_min, t_max) })
        }
        #[cfg(not(target_arch = "x86_64"))]
        super::wide::Halves.packet_hit_t(lanes, packet, ray, t_min, t_max)
    }

    #[inline(always)]
    fn packet_occluded(
        self,
        lanes: &AvxLanes,
        packet: &TrianglePacket,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            let _ = ray;
            // SAFETY: as above.
            unsafe { avx::packet_hits(lanes, packet, t_min, t_max) }
                .0
                .any()
        }
        #[cfg(not(target_arch = "x86_64"))]
        super::wide::Halves.packet_occluded(lanes, packet, ray, t_min, t_max)
    }

    #[inline(always)]
    fn pair_hit_t(
        self,
        lanes: &AvxLanes,
        pair: &[TrianglePacket; 2],
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<(u32, f32, [f32; 2])> {
        #[cfg(target_arch = "x86_64")]
        {
            let _ = ray;
            // SAFETY: as above.
            unsafe { avx::hit_t(lanes, pair, t_min, t_max) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        super::wide::Halves.pair_hit_t(lanes, pair, ray, t_min, t_max)
    }

    #[inline(always)]
    fn pair_occluded(
        self,
        lanes: &AvxLanes,
        pair: &[TrianglePacket; 2],
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            let _ = ray;
            // SAFETY: as above.
            unsafe { avx::hits(lanes, pair, t_min, t_max).0 != 0 }
        }
        #[cfg(not(target_arch = "x86_64"))]
        super::wide::Halves.pair_occluded(lanes, pair, ray, t_min, t_max)
    }
}

#[cfg(target_arch = "x86_64")]
mod avx;

/// The BVH's meshes, each with its caller id, and the first global triangle number of each.
#[derive(Default)]
pub(crate) struct Meshes {
    meshes: Vec<(TriangleMesh, u32)>,
    starts: Vec<u32>,
}

impl Meshes {
    pub(crate) fn new(meshes: Vec<(TriangleMesh, u32)>) -> Self {
        let mut starts = Vec::with_capacity(meshes.len());
        let mut n = 0u32;
        for (m, _) in &meshes {
            starts.push(n);
            n = n.saturating_add(u32::try_from(m.len()).unwrap_or(u32::MAX));
        }
        Self { meshes, starts }
    }

    /// Triangles over all meshes.
    pub(crate) fn triangles(&self) -> usize {
        self.meshes.iter().map(|(m, _)| m.len()).sum()
    }

    /// Every triangle as (global number, mesh, triangle within it).
    pub(crate) fn iter(&self) -> impl Iterator<Item = (u32, &TriangleMesh, usize)> {
        self.meshes
            .iter()
            .zip(&self.starts)
            .flat_map(|((m, _), &s)| (0..m.len()).map(move |k| (s + k as u32, m, k)))
    }

    /// The mesh, triangle within it and caller id of global triangle `g`.
    #[inline]
    pub(crate) fn locate(&self, g: u32) -> (&TriangleMesh, usize, u32) {
        let m = self.starts.partition_point(|&s| s <= g) - 1;
        let (mesh, id) = &self.meshes[m];
        (mesh, (g - self.starts[m]) as usize, *id)
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        self.meshes
            .iter()
            .map(|(m, _)| m.memory_bytes())
            .sum::<usize>()
            + self.meshes.capacity() * std::mem::size_of::<(TriangleMesh, u32)>()
            + self.starts.capacity() * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::SplitShape;
    use crate::shapes::quad::packet_check;
    use crate::shapes::triangle::Triangle;

    /// Each lane gives the scalar triangle test's answer bit for bit (hit or not, `t`, and the
    /// nearest hit's barycentric coordinates),
    /// including rays through vertices and along edges, and the packet's nearest is the
    /// scalar loop's nearest.
    #[test]
    fn packets_match_the_scalar_test() {
        let mut rng = Rng::new(5);
        let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
        let mut hits = 0;
        for i in 0..20000 {
            let count = 1 + i % 4;
            let tris: Vec<([Vec3A; 3], u32)> = (0..count)
                .map(|k| ([v(&mut rng), v(&mut rng), v(&mut rng)], 10 + k as u32))
                .collect();
            let packet = TrianglePacket::new(&tris);
            let mut o = 2.0 * v(&mut rng);
            let mut d = uniform_sphere(rng.vec2());
            let p = tris[i % count].0;
            match i % 10 {
                0 => d = (p[1] - o).normalize(), // through a vertex
                1 => d = (p[0] + 0.5 * (p[1] - p[0]) - o).normalize(), // through an edge
                2 => o = p[0] + 0.3 * (p[1] - p[0]), // from an edge
                3..=6 => {
                    let (a, b) = (1.2 * rng.f32() - 0.1, 1.2 * rng.f32() - 0.1);
                    d = (p[0] + a * (p[1] - p[0]) + b * (p[2] - p[0]) - o).normalize();
                }
                _ => {}
            }
            let ray = Ray::new(o, d);
            let (t_min, t_max) = packet_check::t_range(i);
            let (mask, t, _) = packet.hits(&ray, t_min, t_max);
            // (Random triangles are never degenerate here: `Triangle::new` succeeds.)
            let scalar: Vec<Triangle> = tris
                .iter()
                .map(|(vs, _)| Triangle::new(*vs, None, None).unwrap())
                .collect();
            let best = packet_check::lanes(mask, t, count, (t_min, t_max), i, |k, lo, hi| {
                scalar[k].hit_t(&ray, lo, hi)
            })
            .map(|(lane, t)| {
                // The barycentric coordinates of the scalar test, bit for bit.
                let (_, b1, b2) = scalar[lane].solve(&ray).expect("a hit lane solves");
                (tris[lane].1, t, [b1, b2])
            });
            let bits = |h: Option<(u32, f32, [f32; 2])>| {
                h.map(|(g, t, b)| (g, t.to_bits(), b.map(f32::to_bits)))
            };
            assert_eq!(
                bits(packet.hit_t(&ray, t_min, t_max)),
                bits(best),
                "case {i}"
            );
            assert_eq!(packet.occluded(&ray, t_min, t_max), best.is_some());
            hits += usize::from(best.is_some());
        }
        assert!(hits > 5000, "{hits} of 20000 cases hit");
    }

    /// Two packets tested as eight AVX lanes give the nearest hit (triangle, `t` and
    /// barycentric coordinates, bit for bit) and the occlusion of the two tested one after the
    /// other, including rays through vertices and edges and ties between the packets.
    #[test]
    fn pairs_match_two_packets() {
        use super::super::wide::{Avx, Halves};
        let Some(avx) = Avx::detect() else { return };
        let mut rng = Rng::new(9);
        let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
        let (mut hits, mut single) = (0, 0);
        for i in 0..20000 {
            let count = 5 + i % 4;
            let mut tris: Vec<([Vec3A; 3], u32)> = (0..count)
                .map(|k| ([v(&mut rng), v(&mut rng), v(&mut rng)], 10 + k as u32))
                .collect();
            if i % 7 == 0 {
                // The same triangle in both packets: a tie the first packet wins.
                tris[4].0 = tris[1].0;
            }
            let pair = [
                TrianglePacket::new(&tris[..4]),
                TrianglePacket::new(&tris[4..]),
            ];
            let mut o = 2.0 * v(&mut rng);
            let mut d = uniform_sphere(rng.vec2());
            let p = tris[i % count].0;
            match i % 10 {
                0 => d = (p[1] - o).normalize(),
                1 => d = (p[0] + 0.5 * (p[1] - p[0]) - o).normalize(),
                2 => o = p[0] + 0.3 * (p[1] - p[0]),
                3..=6 => {
                    let (a, b) = (1.2 * rng.f32() - 0.1, 1.2 * rng.f32() - 0.1);
                    d = (p[0] + a * (p[1] - p[0]) + b * (p[2] - p[0]) - o).normalize();
                }
                _ => {}
            }
            let ray = Ray::new(o, d);
            let (t_min, t_max) = packet_check::t_range(i);
            let bits = |h: Option<(u32, f32, [f32; 2])>| {
                h.map(|(g, t, b)| (g, t.to_bits(), b.map(f32::to_bits)))
            };
            let lanes = avx.lanes(&ray);
            let want = Halves.pair_hit_t(&(), &pair, &ray, t_min, t_max);
            assert_eq!(
                bits(avx.pair_hit_t(&lanes, &pair, &ray, t_min, t_max)),
                bits(want),
                "case {i}"
            );
            assert_eq!(
                avx.pair_occluded(&lanes, &pair, &ray, t_min, t_max),
                want.is_some()
            );
            assert_eq!(
                Halves.pair_occluded(&(), &pair, &ray, t_min, t_max),
                want.is_some()
            );
            // Each packet alone through the AVX set-up (the low halves of the pair's
            // broadcasts): the four-lane test's bits.
            for packet in &pair {
                let want = packet.hit_t(&ray, t_min, t_max);
                assert_eq!(
                    bits(avx.packet_hit_t(&lanes, packet, &ray, t_min, t_max)),
                    bits(want),
                    "case {i}"
                );
                assert_eq!(
                    avx.packet_occluded(&lanes, packet, &ray, t_min, t_max),
                    want.is_some(),
                    "case {i}"
                );
                single += usize::from(want.is_some());
            }
            hits += usize::from(want.is_some());
        }
        assert!(hits > 5000, "{hits} of 20000 cases hit");
        assert!(single > 5000, "{single} packets hit");
    }
}
