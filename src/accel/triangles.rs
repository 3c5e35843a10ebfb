//! Mesh triangles in the BVH's leaves: four to a packet, each as its first vertex and two edges
//! in SoA form, tested four at a time by Möller–Trumbore. A packet holds what the test needs and
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

    /// The lanes whose triangle the ray crosses with `t_min < t < t_max`, and each lane's `t`:
    /// the same operations in the same order as the scalar [`Triangle`] test, so the same bits.
    /// `None` when no lane can be hit, decided before the division (see [`certain_misses`]).
    ///
    /// [`Triangle`]: crate::shapes::triangle::Triangle
    #[inline(always)]
    fn hits(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(BVec4A, Vec4)> {
        let d = [ray.d.x, ray.d.y, ray.d.z].map(Vec4::splat);
        let o = [ray.o.x, ray.o.y, ray.o.z].map(Vec4::splat);
        let pv = cross4(&d, &self.e2);
        let det = dot4(&self.e1, &pv);
        let tv = [0, 1, 2].map(|a| o[a] - self.v0[a]);
        let n1 = dot4(&tv, &pv);
        let qv = cross4(&tv, &self.e1);
        let n2 = dot4(&d, &qv);
        let nt = dot4(&self.e2, &qv);
        if certain_misses(det, [n1, n2, nt], t_min, t_max).all() {
            return None;
        }
        let inv = Vec4::ONE / det;
        let (b1, b2, t) = (n1 * inv, n2 * inv, nt * inv);
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
        Some((mask, t))
    }

    /// The nearest hit with `t_min < t < t_max`: its triangle and `t` (on equal `t`, the lowest
    /// lane, as a scalar loop over the triangles in lane order would keep).
    #[inline]
    pub(crate) fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(u32, f32)> {
        let (mask, t) = self.hits(ray, t_min, t_max)?;
        if !mask.any() {
            return None;
        }
        let t = Vec4::select(mask, t, Vec4::INFINITY);
        let best = t.min_element();
        let lane = (t.cmpeq(Vec4::splat(best)) & mask)
            .bitmask()
            .trailing_zeros() as usize;
        Some((self.ids[lane], best))
    }

    /// Whether any triangle of the packet is hit with `t_min < t < t_max`.
    #[inline]
    pub(crate) fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.hits(ray, t_min, t_max)
            .is_some_and(|(mask, _)| mask.any())
    }
}

/// Bounds within which a lane's `|det|` lets [`certain_misses`] decide: `1/det` and the
/// products below are then normal numbers, each rounded with a relative error of at most
/// 2^-24.
const DET_RANGE: (f32, f32) = (1.0 / (1u64 << 60) as f32, (1u64 << 60) as f32);
/// Margins of [`certain_misses`]: 2^-40 (a quotient this far below zero stays below zero
/// after rounding) and 1 + 2^-20 (one this far above a bound stays above it).
const BELOW: f32 = 1.0 / (1u64 << 40) as f32;
const ABOVE: f32 = 1.0 + 1.0 / (1 << 20) as f32;

/// The lanes that the Möller–Trumbore test certainly rejects, told from `det` and the
/// numerators `[n1, n2, nt]` of `b1 = n1 / det`, `b2 = n2 / det` and `t = nt / det`, before the
/// division (lanes are left out when in doubt; the full test then decides them). With
/// `x = n * sign(det)` (exact) and `2^-60 <= |det| <= 2^60`, each rule below implies that the
/// rounded quotients `fl(n * fl(1 / det))` fail the test:
///
/// - `x1 < -2^-40 |det|` (or `x2`): the quotient is below `-2^-40 (1 - 2^-23)`, negative,
///   so `b1 < 0` (or `b2 < 0`); `xt` likewise gives `t < 0 <= t_min` when `t_min >= 0`.
/// - `xt > fl(|det| fl(t_max (1 + 2^-20)))` (with `t_max >= 2^-60`): `nt / det` exceeds
///   `t_max (1 + 2^-20)(1 - 2^-24)^2`, its product with `fl(1 / det)` exceeds `t_max`, and so
///   does its rounding (`t_max` is a float): `t >= t_max`.
/// - `fl(x1 + x2) > fl(|det| (1 + 2^-20))`: either `b1` or `b2` is negative (rejected), or
///   both are at least their quotient times `(1 - 2^-24)^2` less 2^-149, which sums to more
///   than `1 + 2^-22`: `fl(b1 + b2) > 1`.
///
/// A lane with `det == 0` (an empty lane) is rejected as the test rejects it; NaNs fail every
/// comparison, so they leave lanes in doubt.
#[inline(always)]
fn certain_misses(det: Vec4, [n1, n2, nt]: [Vec4; 3], t_min: f32, t_max: f32) -> BVec4A {
    let ad = det.abs();
    let s = Vec4::ONE.copysign(det);
    let (x1, x2, xt) = (n1 * s, n2 * s, nt * s);
    let decidable = ad.cmpge(Vec4::splat(DET_RANGE.0)) & ad.cmple(Vec4::splat(DET_RANGE.1));
    // (`min` returns one of its operands, so a lane below the bound meets its own rule.)
    let lowest = if t_min >= 0.0 {
        x1.min(x2).min(xt)
    } else {
        x1.min(x2)
    };
    let mut misses = lowest.cmplt(ad * -BELOW) | (x1 + x2).cmpgt(ad * ABOVE);
    if t_max >= DET_RANGE.0 {
        misses |= xt.cmpgt(ad * (t_max * ABOVE));
    }
    det.cmpeq(Vec4::ZERO) | (decidable & misses)
}

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

    /// Each lane gives the scalar triangle test's answer bit for bit (hit or not, and `t`),
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
            let (mask, t) = packet
                .hits(&ray, t_min, t_max)
                .unwrap_or((BVec4A::FALSE, Vec4::ZERO));
            // (Random triangles are never degenerate here: `Triangle::new` succeeds.)
            let scalar: Vec<Triangle> = tris
                .iter()
                .map(|(vs, _)| Triangle::new(*vs, None, None).unwrap())
                .collect();
            let best = packet_check::lanes(mask, t, count, (t_min, t_max), i, |k, lo, hi| {
                scalar[k].hit_t(&ray, lo, hi)
            })
            .map(|(lane, t)| (tris[lane].1, t));
            assert_eq!(packet.hit_t(&ray, t_min, t_max), best, "case {i}");
            assert_eq!(packet.occluded(&ray, t_min, t_max), best.is_some());
            hits += usize::from(best.is_some());
        }
        assert!(hits > 5000, "{hits} of 20000 cases hit");
    }

    /// The rejection before the division keeps the scalar test's answers where it is closest
    /// to being wrong: rays through an edge or vertex nudged by a few ulps to either side (a
    /// barycentric coordinate of either sign, down to ones whose quotient underflows to -0 and
    /// passes), `t_max` equal to the hit's `t` and one ulp either side of it, and triangles
    /// scaled by 2^-31..2^31 so that `det` is tiny, huge, or outside the range where the
    /// rejection decides.
    #[test]
    fn early_rejection_keeps_the_scalar_answers() {
        let mut rng = Rng::new(9);
        let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
        let (mut hits, mut rejected, mut cases, mut near_origin) = (0, 0, 0, 0);
        for i in 0..6000 {
            let scale = 2f32.powi([-31, -29, -20, 0, 0, 0, 20, 29, 31][i % 9]);
            let mut tris: Vec<([Vec3A; 3], u32)> = (0..4)
                .map(|k| {
                    (
                        [v(&mut rng), v(&mut rng), v(&mut rng)].map(|p| p * scale),
                        k,
                    )
                })
                .collect();
            if i % 10 == 9 {
                let t = &mut tris[i % 4].0;
                *t = [Vec3A::ZERO, t[1] - t[0], t[2] - t[0]];
            }
            let packet = TrianglePacket::new(&tris);
            // (A tiny triangle whose area underflows has no scalar test to compare with.)
            let Ok(scalar) = tris
                .iter()
                .map(|(vs, _)| Triangle::new(*vs, None, None))
                .collect::<Result<Vec<Triangle>, _>>()
            else {
                continue;
            };
            let p = tris[i % 4].0;
            // Every tenth ray starts a few subnormals away from a vertex at the coordinate
            // origin: its barycentric numerators are subnormal, and their quotients can
            // underflow to -0 (which `b >= 0` passes; with `t_min < 0` such rays hit).
            let tiny = |rng: &mut Rng| f32::from_bits(1 + (rng.f32() * 8.0) as u32);
            let sign = |rng: &mut Rng| if rng.f32() < 0.5 { -1.0 } else { 1.0 };
            let o = if i % 10 == 9 {
                let mut o = Vec3A::ZERO;
                for a in 0..3 {
                    o[a] = sign(&mut rng) * tiny(&mut rng);
                }
                o
            } else {
                2.0 * scale * v(&mut rng)
            };
            // A point on an edge or at a vertex, nudged by a few ulps.
            let mut target = match i % 3 {
                0 => p[1],
                1 => p[0] + 0.5 * (p[1] - p[0]),
                _ => p[2] + 0.25 * (p[0] - p[2]),
            };
            let ulps = (i / 3 % 7) as i32 - 3;
            for a in 0..3 {
                let bits = target[a].to_bits() as i32 + ulps * (1 + (i / 21 % 3) as i32);
                target[a] = f32::from_bits(bits as u32);
            }
            let ray = Ray::new(o, (target - o).normalize());
            let t_hit = scalar[i % 4].hit_t(&ray, 0.0, f32::INFINITY);
            let mut ranges = vec![(0.0, f32::INFINITY), (-1.0, f32::INFINITY)];
            if let Some(t) = t_hit {
                let up = f32::from_bits(t.to_bits() + 1);
                let down = f32::from_bits(t.to_bits() - 1);
                ranges.extend([(0.0, t), (0.0, up), (0.0, down), (down, f32::INFINITY)]);
            }
            for (t_min, t_max) in ranges {
                let got = packet.hits(&ray, t_min, t_max);
                rejected += usize::from(got.is_none());
                let (mask, t) = got.unwrap_or((BVec4A::FALSE, Vec4::ZERO));
                let best = packet_check::lanes(mask, t, 4, (t_min, t_max), i, |k, lo, hi| {
                    scalar[k].hit_t(&ray, lo, hi)
                });
                hits += usize::from(best.is_some());
                near_origin += usize::from(best.is_some() && i % 10 == 9);
                cases += 1;
            }
        }
        // Both outcomes are common: the cases test the rejection, and the hits near its edge.
        assert!(hits > cases / 5, "{hits} of {cases} cases hit");
        assert!(
            rejected > cases / 10,
            "{rejected} of {cases} cases rejected early"
        );
        assert!(
            near_origin > 100,
            "{near_origin} hits from next to the origin"
        );
    }
}
