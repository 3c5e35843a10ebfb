//! Tests of the BVH against brute force, and of its build.

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
    Bvh::with_median_depth(shapes, Vec::new(), median_depth, &|| false).unwrap()
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
        depth(
            &Bvh::new(chain.iter().map(|s| (AnyShape::Sphere(*s), 0)).collect())
                .expect("a BVH of test size")
        ) <= STACK
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
                        0 | 1 => AnyShape::Quad(Quad::new(c, v(&mut rng), v(&mut rng)).unwrap()),
                        2 | 3 => AnyShape::Sphere(Sphere::new(c, 0.1 + 0.4 * rng.f32()).unwrap()),
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
        )
        .expect("a BVH of test size");
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

/// The leaves' packing and the collapse into wide nodes give the same arrays on 1, 2 and 4
/// threads, on a mesh large enough for both to work in parallel, with shapes in some leaves.
#[test]
fn packing_and_collapse_are_the_same_on_any_thread_count() {
    use crate::scene::MeshData;
    use glam::{DAffine3, DVec3};
    let mut rng = Rng::new(41);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for k in 0..30_000u32 {
        let c = DVec3::new(rng.f32() as f64, rng.f32() as f64, rng.f32() as f64) * 10.0;
        positions.extend([c, c + DVec3::X * 0.05, c + DVec3::Y * 0.05]);
        indices.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let data = MeshData {
        path: "cloud.obj".into(),
        positions,
        indices,
        normals: Vec::new(),
        uvs: Vec::new(),
    };
    let spheres = sphere_cloud(&mut rng, 300);
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mesh = TriangleMesh::new(&data, &DAffine3::IDENTITY).unwrap();
            Bvh::with_meshes(
                spheres.iter().map(|s| (AnyShape::Sphere(*s), 1)).collect(),
                vec![(mesh, 2)],
            )
            .expect("a BVH of test size")
        })
    };
    let one = build(1);
    assert!(one.nodes.len() > 1000);
    assert!(one.leaves.leaves.len() > 10, "leaves with shapes");
    for threads in [2, 4] {
        let other = build(threads);
        assert!(other.nodes == one.nodes, "nodes, {threads} threads");
        assert!(
            other.leaves.tri_packets == one.leaves.tri_packets,
            "packets, {threads} threads"
        );
        assert!(
            other.leaves.leaves == one.leaves.leaves,
            "leaves, {threads} threads"
        );
    }
}

/// A torus (a heavy primitive: a boxed shape under a transform) of scale `s`, turned by
/// `turn` (Euler angles) and moved to `at`.
fn heavy_torus(s: f32, turn: glam::Vec3, at: glam::Vec3) -> AnyShape {
    use crate::shapes::torus::Torus;
    use crate::shapes::transformed::Transformed;
    let xf = glam::Affine3A::from_scale_rotation_translation(
        glam::Vec3::splat(s),
        glam::Quat::from_euler(glam::EulerRot::XYZ, turn.x, turn.y, turn.z),
        at,
    );
    let torus: std::sync::Arc<dyn crate::shapes::Shape> =
        std::sync::Arc::new(Torus::new(1.0, 0.3).unwrap());
    AnyShape::Other(Box::new(Transformed::new(torus, xf).unwrap()))
}

/// Heavy primitives (each a leaf of its own) give the brute-force nearest `t`, bit for bit, and
/// the same occlusion, in the layouts that stress the build: identical boxes, an overlapping
/// row, boxes nested at exponentially growing scales, an exponentially spaced row, and a mix
/// with spheres and quads; with median splits from depths 0, 2 and 32. The primitive hit is
/// the brute force's except on identical boxes (exact ties).
#[test]
fn heavy_primitives_match_brute_force() {
    use crate::shapes::quad::Quad;
    use glam::Vec3;
    let mut rng = Rng::new(99);
    for layout in 0..5 {
        let mut hits = 0;
        for n in [2usize, 5, 9, 60] {
            for median_depth in [0, 2, MEDIAN_DEPTH] {
                let seed = u64::from(rng.f32().to_bits());
                let make = || {
                    let mut r = Rng::new(seed);
                    let mut v = move || Vec3::new(r.f32(), r.f32(), r.f32()) * 2.0 - Vec3::ONE;
                    (0..n)
                        .map(|i| {
                            let k = i as i32;
                            match layout {
                                0 => heavy_torus(1.0, Vec3::new(0.5, 0.3, 0.0), Vec3::ZERO),
                                1 => heavy_torus(0.5, Vec3::X, Vec3::X * (0.01 * i as f32)),
                                2 => heavy_torus(1.03f32.powi(k - n as i32 / 2), v(), Vec3::ZERO),
                                3 => heavy_torus(
                                    0.3 * 1.05f32.powi(k),
                                    Vec3::ZERO,
                                    Vec3::X * 1.05f32.powi(k),
                                ),
                                _ => match i % 4 {
                                    0 | 1 => heavy_torus(0.1 + v().x.abs(), 3.0 * v(), 3.0 * v()),
                                    2 => AnyShape::Sphere(
                                        Sphere::new((3.0 * v()).into(), 0.3).unwrap(),
                                    ),
                                    _ => AnyShape::Quad(
                                        Quad::new((3.0 * v()).into(), v().into(), v().into())
                                            .unwrap(),
                                    ),
                                },
                            }
                        })
                        .collect::<Vec<_>>()
                };
                let shapes = make();
                let bvh = Bvh::with_median_depth(
                    make().into_iter().zip(0u32..).collect(),
                    Vec::new(),
                    median_depth,
                    &|| false,
                )
                .unwrap();
                for _ in 0..200 {
                    // From a box around the shapes toward a point near the first ones.
                    let o = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 8.0 - Vec3A::splat(4.0);
                    let aim = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 3.0 - Vec3A::splat(1.5);
                    let d = (aim - o).normalize_or_zero();
                    let ray = Ray::new(o, if d == Vec3A::ZERO { Vec3A::X } else { d });
                    let t_max = if rng.f32() < 0.3 { 2.0 } else { f32::INFINITY };
                    let (mut brute, mut limit) = (None, t_max);
                    for (i, s) in shapes.iter().enumerate() {
                        if let Some(h) = s.intersect(&ray, 0.0, limit) {
                            limit = h.t;
                            brute = Some((h.t.to_bits(), i as u32));
                        }
                    }
                    let got = bvh
                        .intersect(&ray, 0.0, t_max)
                        .map(|(h, id)| (h.t.to_bits(), id));
                    let case = format!("layout {layout}, {n} shapes, median from {median_depth}");
                    assert_eq!(got.map(|g| g.0), brute.map(|b| b.0), "{case}");
                    if layout != 0 {
                        assert_eq!(got, brute, "{case}");
                    }
                    assert_eq!(bvh.occluded(&ray, 0.0, t_max), brute.is_some(), "{case}");
                    hits += usize::from(brute.is_some());
                }
            }
        }
        assert!(hits > 100, "layout {layout}: {hits} hits of 2400 rays");
    }
}

/// Rays a caller may pass by mistake or by rounding (a NaN or infinite direction or origin, a
/// zero direction) over a mesh and a sphere: no panic (a ray whose slab distances are NaN on
/// every axis entered the unused child slots and indexed past the packets), occlusion agrees
/// with the closest hit, and a hit lies in the range asked; a ray along an axis lying exactly
/// in the plane of a face of the mesh's bounds still finds what it crosses.
#[test]
fn degenerate_rays_are_answered_consistently() {
    use crate::scene::MeshData;
    use crate::shapes::mesh::TriangleMesh;
    use glam::DVec3;
    // A flat square of two triangles in z = 0 over [0, 1]^2, and one standing in x = 0.5.
    let mesh = MeshData {
        path: "flat.obj".into(),
        positions: vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.5, 0.0, -1.0),
            DVec3::new(0.5, 1.0, -1.0),
            DVec3::new(0.5, 0.5, 1.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]],
        normals: Vec::new(),
        uvs: Vec::new(),
    };
    let m = TriangleMesh::new(&mesh, &glam::DAffine3::IDENTITY).unwrap();
    let spheres = vec![(
        AnyShape::Sphere(Sphere::new(Vec3A::new(3.0, 0.0, 0.0), 0.5).unwrap()),
        9,
    )];
    let bvh = Bvh::with_meshes(spheres, vec![(m, 1)]).expect("a BVH of test size");
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let odd = [
        (Vec3A::new(0.2, 0.2, 1.0), Vec3A::new(nan, 0.0, -1.0)),
        (Vec3A::new(0.2, 0.2, 1.0), Vec3A::new(0.0, 0.0, -inf)),
        (Vec3A::new(0.2, 0.2, 1.0), Vec3A::new(inf, -inf, inf)),
        (Vec3A::new(0.2, 0.2, 1.0), Vec3A::ZERO),
        (Vec3A::new(nan, 0.2, 1.0), Vec3A::new(0.0, 0.0, -1.0)),
        (Vec3A::new(-inf, 0.2, 0.0), Vec3A::new(1.0, 0.0, 0.0)),
        (Vec3A::splat(nan), Vec3A::splat(nan)),
    ];
    for (o, d) in odd {
        let ray = Ray::new(o, d);
        for t_max in [1.0, f32::INFINITY, nan] {
            let hit = bvh.intersect(&ray, 0.0, t_max);
            assert_eq!(
                bvh.occluded(&ray, 0.0, t_max),
                hit.is_some(),
                "o {o}, d {d}, t_max {t_max}"
            );
            if let Some((h, _)) = hit {
                assert!(h.t > 0.0 && h.t < t_max, "o {o}, d {d}: t {}", h.t);
            }
        }
    }
    // In the plane z = 0 of the square (and of its box's face), along x: it crosses the
    // standing triangle at x = 0.5 and must find it.
    let ray = Ray::new(Vec3A::new(-1.0, 0.5, 0.0), Vec3A::X);
    let (h, id) = bvh
        .intersect(&ray, 0.0, f32::INFINITY)
        .expect("the standing triangle");
    assert_eq!(id, 1);
    assert!((h.t - 1.5).abs() < 1e-5, "t {}", h.t);
    assert!(bvh.occluded(&ray, 0.0, f32::INFINITY));
    // Along the bounds' face y = 1 from above the square: it crosses the square's edge.
    let ray = Ray::new(Vec3A::new(0.3, 1.0, 2.0), -Vec3A::Z);
    assert!(
        bvh.occluded(&ray, 0.0, f32::INFINITY) == bvh.intersect(&ray, 0.0, f32::INFINITY).is_some()
    );
}

/// The hit record made in the traversal's frame ([`Bvh::intersect_uv`]) is the one the lazy
/// result gives ([`Bvh::intersect_lazy`], then [`Surface::hit_at_uv`]): every field bit for bit
/// and the id, over a mesh with uvs, one without, spheres, quads and an infinite plane, with
/// `uv` asked for odd ids only (a sphere's `uv` is then NaN on even ones); and a mesh hit's
/// [`TriangleMesh::geometric_normal`], normalised, is the record's normal.
#[test]
fn the_hit_record_is_the_lazy_hits() {
    use crate::scene::MeshData;
    use crate::shapes::mesh::TriangleMesh;
    use crate::shapes::plane::Plane;
    use crate::shapes::quad::Quad;
    use glam::{DVec2, DVec3};
    let mut rng = Rng::new(23);
    let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
    let mesh = |rng: &mut Rng, uvs: bool| {
        let positions: Vec<DVec3> = (0..300).map(|_| v(rng).as_dvec3()).collect();
        let indices = (0..100).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let uvs = if uvs {
            (0..300)
                .map(|_| DVec2::new(rng.f32() as f64, rng.f32() as f64))
                .collect()
        } else {
            Vec::new()
        };
        let data = MeshData {
            path: "random.obj".into(),
            positions,
            indices,
            normals: Vec::new(),
            uvs,
        };
        TriangleMesh::new(&data, &glam::DAffine3::IDENTITY).unwrap()
    };
    let meshes = vec![(mesh(&mut rng, true), 2), (mesh(&mut rng, false), 3)];
    let mut shapes = vec![(AnyShape::Plane(Plane::new(Vec3A::Y, -1.5).unwrap()), 1)];
    for k in 0..20u32 {
        let c = v(&mut rng);
        let shape = if k % 2 == 0 {
            AnyShape::Sphere(Sphere::new(c, 0.1 + 0.2 * rng.f32()).unwrap())
        } else {
            AnyShape::Quad(Quad::new(c, 0.5 * v(&mut rng), 0.5 * v(&mut rng)).unwrap())
        };
        shapes.push((shape, 4 + k));
    }
    let bvh = Bvh::with_meshes(shapes, meshes).expect("a BVH of test size");
    let uv = |id: u32| id % 2 == 1;
    let bits = |h: &Hit| {
        let v = [h.p, h.n, h.ns, h.dpdu].map(|v| v.to_array().map(f32::to_bits));
        (h.t.to_bits(), v, h.uv.to_array().map(f32::to_bits))
    };
    let mut hits = [0usize; 5];
    for i in 0..8000 {
        let ray = Ray::new(2.0 * v(&mut rng), uniform_sphere(rng.vec2()));
        let t_max = if i % 3 == 0 { 1.0 } else { f32::INFINITY };
        let lazy = bvh.intersect_lazy(&ray, 0.0, t_max);
        let want = lazy.map(|(lazy, s, id)| {
            let id = lazy.part().unwrap_or(id);
            (s.hit_at_uv(&ray, lazy, uv(id)), id)
        });
        let got = bvh.intersect_uv(&ray, 0.0, t_max, uv);
        // A triangle's geometric normal, normalised, is its record's `n`.
        if let (Some((_, Surface::MeshTriangle(m, k, _), _)), Some((h, _))) = (lazy, got) {
            let c = m.geometric_normal(k);
            let n = c / crate::geometry::scaled_length(c);
            assert_eq!(
                n.to_array().map(f32::to_bits),
                h.n.to_array().map(f32::to_bits)
            );
        }
        assert_eq!(
            got.map(|(h, id)| (bits(&h), id)),
            want.map(|(h, id)| (bits(&h), id)),
            "ray {i}"
        );
        if let Some((h, id)) = got {
            let kind = match id {
                1..=3 => id as usize - 1,
                _ if h.uv.is_nan() => 3,
                _ => 4,
            };
            hits[kind] += 1;
        }
    }
    // Plane, mesh with uvs, mesh without, spheres without uv, other shapes.
    assert!(hits.iter().all(|&n| n > 40), "{hits:?}");
}

/// `intersect_finite_uv` answers a finite ray as `intersect_uv` does, and a ray with a NaN or
/// an infinity in its origin or direction with nothing, on a tree with an unbounded plane and
/// on a flat leaf.
#[test]
fn the_finite_query_drops_non_finite_rays_only() {
    use crate::shapes::plane::Plane;
    use crate::shapes::quad::Quad;
    let mut rng = Rng::new(31);
    let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
    // A tree: random quads and spheres and an unbounded plane.
    let mut shapes = vec![(AnyShape::Plane(Plane::new(Vec3A::Y, -1.5).unwrap()), 0)];
    for k in 1..7u32 {
        let c = v(&mut rng);
        shapes.push(if k % 3 == 0 {
            (
                AnyShape::Sphere(Sphere::new(c, 0.2 + 0.2 * rng.f32()).unwrap()),
                k,
            )
        } else {
            (
                AnyShape::Quad(Quad::new(c, v(&mut rng), v(&mut rng)).unwrap()),
                k,
            )
        });
    }
    let tree = Bvh::new(shapes).expect("a BVH of test size");
    // A flat leaf: the five walls of a box (as the Cornell box's) and two spheres in it.
    let walls = [
        (Vec3A::new(-1.0, -1.0, -1.0), Vec3A::X * 2.0, Vec3A::Z * 2.0),
        (Vec3A::new(-1.0, 1.0, -1.0), Vec3A::X * 2.0, Vec3A::Z * 2.0),
        (Vec3A::new(-1.0, -1.0, -1.0), Vec3A::X * 2.0, Vec3A::Y * 2.0),
        (Vec3A::new(-1.0, -1.0, -1.0), Vec3A::Z * 2.0, Vec3A::Y * 2.0),
        (Vec3A::new(1.0, -1.0, -1.0), Vec3A::Z * 2.0, Vec3A::Y * 2.0),
    ];
    let mut shapes: Vec<(AnyShape, u32)> = walls
        .iter()
        .zip(0..)
        .map(|(&(o, a, b), k)| (AnyShape::Quad(Quad::new(o, a, b).unwrap()), k))
        .collect();
    shapes.push((
        AnyShape::Sphere(Sphere::new(Vec3A::new(-0.4, -0.6, -0.3), 0.35).unwrap()),
        5,
    ));
    shapes.push((
        AnyShape::Sphere(Sphere::new(Vec3A::new(0.4, -0.6, 0.3), 0.35).unwrap()),
        6,
    ));
    let flat = Bvh::new(shapes).expect("a BVH of test size");
    assert!(!tree.is_flat(), "the tree");
    assert!(flat.is_flat(), "the box");
    let uv = |id: u32| id.is_multiple_of(2);
    let bits = |hit: Option<(Hit, u32)>| {
        hit.map(|(h, id)| {
            let v = [h.p, h.n, h.ns, h.dpdu].map(|v| v.to_array().map(f32::to_bits));
            (h.t.to_bits(), v, h.uv.to_array().map(f32::to_bits), id)
        })
    };
    let (mut hits, mut non_finite) = (0, 0);
    for i in 0..4000 {
        let mut ray = Ray::new(2.0 * v(&mut rng), uniform_sphere(rng.vec2()));
        let finite = i % 4 != 0;
        if !finite {
            let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][i % 3];
            match i % 8 {
                0 => ray.o.x = bad,
                _ => ray.d.z = bad,
            }
        }
        for bvh in [&tree, &flat] {
            let got = bvh.intersect_finite_uv(&ray, 0.0, f32::INFINITY, uv);
            if finite {
                assert_eq!(
                    bits(got),
                    bits(bvh.intersect_uv(&ray, 0.0, f32::INFINITY, uv)),
                    "ray {i}"
                );
                hits += usize::from(got.is_some());
            } else {
                assert!(got.is_none(), "ray {i}: {ray:?}");
                non_finite += 1;
            }
        }
    }
    assert!(
        hits > 1000 && non_finite > 1000,
        "{hits} hits, {non_finite} non-finite"
    );
}
