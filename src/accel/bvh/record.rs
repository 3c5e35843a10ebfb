//! What a closest-hit traversal gives back: the lazy hit, and for [`Bvh::intersect_ng`] the
//! record Embree's `rtcIntersect1` returns (`t`, barycentric coordinates, triangle, geometry
//! id and unnormalised `Ng`), the normal taken from the triangle packet of the hit.

use glam::Vec3A;

use super::Bvh;
use crate::accel::leaf::Closest;
use crate::accel::triangles::PairTest;
#[cfg(target_arch = "x86_64")]
use crate::accel::wide::Avx;
use crate::accel::wide::{BoxTest, Halves};
use crate::geometry::Ray;
use crate::shapes::primitive::LazyHit;

use super::Surface;

/// A closest hit as [`Bvh::intersect_lazy`] gives it, and on a mesh triangle its unnormalised
/// geometric normal (zero on a shape). (Not an `Option`: with one, the caller's test of the
/// query's `None` became a 16-byte load of what the query had written in smaller stores, a
/// failed store forwarding on every query, 8 % of a camera ray's time at 10^5 triangles.)
pub type NgHit<'a> = (LazyHit, Surface<'a>, u32, Vec3A);

impl Bvh {
    /// [`Bvh::intersect_lazy`], and on a mesh triangle (zero on a shape) its unnormalised
    /// geometric normal: the bits of [`TriangleMesh::geometric_normal`], taken from the
    /// triangle packet the traversal found the hit in (just tested, so in the cache) where
    /// that leaf is referenced by its packets, else from the mesh's buffers. (From the
    /// buffers, an incoherent ray's hit waited on two dependent loads, the triangle's indices
    /// and then its positions, usually from memory in a large mesh.) The traversal is an
    /// instance of [`Bvh::intersect_lazy`]'s that also keeps the leaf of the hit (the other
    /// instances do not). The renderer asks for full records ([`Bvh::intersect`]); this is
    /// the record an embedder used to Embree's `rtcIntersect1` gets, and the scale bench's
    /// closest-hit query.
    ///
    /// [`TriangleMesh::geometric_normal`]: crate::shapes::mesh::TriangleMesh::geometric_normal
    #[inline]
    pub fn intersect_ng(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<NgHit<'_>> {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = self.avx {
            // SAFETY: an `Avx` value exists only where the CPU has AVX.
            return unsafe { self.intersect_ng_avx(avx, ray, t_min, t_max) };
        }
        self.intersect_ng_halves(ray, t_min, t_max)
    }

    /// [`Bvh::intersect_ng`] four boxes at a time, out of line as the other traversals of
    /// [`Halves`].
    #[inline(never)]
    fn intersect_ng_halves(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<NgHit<'_>> {
        self.ng_with(Halves, ray, t_min, t_max)
    }

    /// [`Bvh::intersect_ng`] with every operation allowed to use AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn intersect_ng_avx(&self, avx: Avx, ray: &Ray, t_min: f32, t_max: f32) -> Option<NgHit<'_>> {
        self.ng_with(avx, ray, t_min, t_max)
    }

    #[inline(always)]
    fn ng_with<B: BoxTest + PairTest>(
        &self,
        test: B,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> Option<NgHit<'_>> {
        let mut ng = None;
        let (lazy, surface, id) = self.closest_with::<B, true>(test, ray, t_min, t_max, &mut ng)?;
        Some((lazy, surface, id, ng.unwrap_or(Vec3A::ZERO)))
    }

    /// The result of a closest-hit traversal that ended with `c` and `t_max`.
    #[inline(always)]
    pub(super) fn closest_hit<'a>(
        &'a self,
        c: Closest,
        t_max: f32,
        best: Option<(LazyHit, Surface<'a>, u32)>,
    ) -> Option<(LazyHit, Surface<'a>, u32)> {
        if c.triangle != u32::MAX {
            let (mesh, k, id) = self.meshes.locate(c.triangle);
            return Some((
                LazyHit::T(t_max),
                Surface::MeshTriangle(mesh, k, c.bary),
                id,
            ));
        }
        if c.shape == usize::MAX {
            return best;
        }
        let lazy = c.boxed.unwrap_or(LazyHit::T(t_max));
        Some((
            lazy,
            Surface::Shape(&self.leaves.shapes[c.shape]),
            self.leaves.ids[c.shape],
        ))
    }

    /// The geometric normal of the triangle a traversal that kept its leaf ended on, if it
    /// ended on a triangle: from the packets of the leaf kept in `c`, else (a leaf with a
    /// record) from the mesh's buffers.
    #[inline(always)]
    pub(super) fn triangle_normal(&self, c: &Closest) -> Option<Vec3A> {
        if c.triangle == u32::MAX {
            return None;
        }
        self.leaves.packet_normal(c.leaf, c.triangle).or_else(|| {
            let (mesh, k, _) = self.meshes.locate(c.triangle);
            Some(mesh.geometric_normal(k))
        })
    }
}

#[cfg(test)]
mod tests {
    use glam::{DAffine3, DVec3, Vec3A};

    use crate::accel::Bvh;
    use crate::accel::bvh::Surface;
    use crate::geometry::Ray;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::scene::MeshData;
    use crate::shapes::mesh::TriangleMesh;
    use crate::shapes::primitive::AnyShape;
    use crate::shapes::sphere::Sphere;

    fn random_mesh(rng: &mut Rng, triangles: u32) -> TriangleMesh {
        let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
        let positions: Vec<DVec3> = (0..3 * triangles)
            .map(|k| {
                // Small triangles around random centres, so that the tree has many leaves.
                let c = v(rng);
                (if k % 3 == 0 { c } else { c * 0.05 }).as_dvec3()
            })
            .collect();
        let positions = positions
            .chunks(3)
            .flat_map(|p| [p[0], p[0] + p[1], p[0] + p[2]])
            .collect();
        let indices = (0..triangles)
            .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
            .collect();
        let data = MeshData {
            path: "random.obj".into(),
            positions,
            indices,
            normals: Vec::new(),
            uvs: Vec::new(),
        };
        TriangleMesh::new(&data, &DAffine3::IDENTITY).unwrap()
    }

    /// Every triangle of a mesh-only tree is found in the packets of exactly one leaf, with
    /// `TriangleMesh::geometric_normal`'s bits (so `intersect_ng` takes its normals from the
    /// packets there, not from the buffers); a leaf that does not hold a triangle, a leaf
    /// without packets and a reference naming packets past the end give none.
    #[test]
    fn every_triangle_has_its_normal_in_one_leafs_packets() {
        use crate::accel::leaf::PACKETS;
        use crate::accel::wide::LEAF;
        let mut rng = Rng::new(47);
        let bvh = Bvh::with_meshes(
            Vec::new(),
            vec![
                (random_mesh(&mut rng, 2000), 3),
                (random_mesh(&mut rng, 300), 5),
            ],
        )
        .unwrap();
        // The leaf references, from the root down.
        let (mut leaves, mut todo) = (Vec::new(), vec![0u32]);
        while let Some(r) = todo.pop() {
            for &c in &bvh.node(r).child {
                if c == u32::MAX {
                } else if c & LEAF != 0 {
                    leaves.push(c & !LEAF);
                } else {
                    todo.push(c);
                }
            }
        }
        let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
        let mut found = vec![0u32; 2300];
        for &leaf in &leaves {
            assert_ne!(
                leaf & PACKETS,
                0,
                "a mesh-only tree's leaves are referenced by packets"
            );
            for (g, n) in found.iter_mut().enumerate() {
                if let Some(ng) = bvh.leaves.packet_normal(leaf, g as u32) {
                    let (mesh, k, _) = bvh.meshes.locate(g as u32);
                    assert_eq!(bits(ng), bits(mesh.geometric_normal(k)), "triangle {g}");
                    *n += 1;
                }
            }
        }
        assert!(found.iter().all(|&n| n == 1), "{found:?}");
        assert!(leaves.len() > 100, "{} leaves", leaves.len());
        assert_eq!(bvh.leaves.packet_normal(0, 0), None);
        assert_eq!(bvh.leaves.packet_normal(leaves[0] & !PACKETS, 0), None);
        assert_eq!(bvh.leaves.packet_normal(PACKETS | (PACKETS - 1), 0), None);
    }

    /// `intersect_ng` gives `intersect_lazy`'s hit (the same `t`, barycentrics, triangle and
    /// id bit for bit) and, on a triangle, `TriangleMesh::geometric_normal`'s bits, with both
    /// box tests, on meshes alone (where the normal comes from the packets) and mixed with
    /// spheres (leaves with a record, where it comes from the buffers).
    #[test]
    fn the_normal_from_the_packets_is_the_meshs() {
        let mut rng = Rng::new(41);
        let meshes = || {
            let mut rng = Rng::new(43);
            vec![
                (random_mesh(&mut rng, 3000), 7),
                (random_mesh(&mut rng, 500), 9),
            ]
        };
        let mut spheres = Vec::new();
        for k in 0..200u32 {
            let c = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
            spheres.push((AnyShape::Sphere(Sphere::new(c, 0.02).unwrap()), 100 + k));
        }
        let alone = Bvh::with_meshes(Vec::new(), meshes()).unwrap();
        let mixed = Bvh::with_meshes(spheres, meshes()).unwrap();
        let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
        for (name, bvh) in [("alone", alone), ("mixed", mixed)] {
            let (mut triangles, mut shapes) = (0, 0);
            for i in 0..6000 {
                let o = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 3.0 - 1.5 * Vec3A::ONE;
                let ray = Ray::new(o, uniform_sphere(rng.vec2()));
                let t_max = if i % 4 == 0 { 0.5 } else { f32::INFINITY };
                let want = bvh.intersect_lazy(&ray, 0.0, t_max);
                let got = bvh.intersect_ng(&ray, 0.0, t_max);
                let halves = bvh.intersect_ng_halves(&ray, 0.0, t_max);
                for got in [got, halves] {
                    match (want, got) {
                        (None, None) => {}
                        (
                            Some((lw, Surface::MeshTriangle(mw, kw, bw), iw)),
                            Some((lg, Surface::MeshTriangle(mg, kg, bg), ig, ng)),
                        ) => {
                            assert!(std::ptr::eq(mw, mg), "{name}, ray {i}");
                            assert_eq!(
                                (lw.t().to_bits(), kw, bw.map(f32::to_bits), iw),
                                (lg.t().to_bits(), kg, bg.map(f32::to_bits), ig),
                                "{name}, ray {i}"
                            );
                            assert_eq!(bits(ng), bits(mw.geometric_normal(kw)), "{name}, ray {i}");
                        }
                        (
                            Some((lw, Surface::Shape(_), iw)),
                            Some((lg, Surface::Shape(_), ig, ng)),
                        ) => {
                            assert_eq!((lw.t().to_bits(), iw), (lg.t().to_bits(), ig));
                            assert_eq!(ng, Vec3A::ZERO);
                            shapes += 1;
                        }
                        _ => panic!("{name}, ray {i}: different hits"),
                    }
                }
                if let Some((_, Surface::MeshTriangle(..), _)) = want {
                    triangles += 1;
                }
            }
            assert!(triangles > 300, "{name}: {triangles} triangle hits");
            assert!(name == "alone" || shapes > 50, "{shapes} sphere hits");
        }
    }
}
