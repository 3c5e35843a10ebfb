use glam::{DAffine3, DVec2, DVec3};

use super::super::Bvh;
use super::super::bvh::Node as BinaryNode;
use super::{Avx, BoxRay, BoxTest, Halves, LEAF, NODE_STEP, NODE_UNIT, WideNode, fits};
use crate::geometry::{Aabb, Ray};
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

/// The AVX box test gives the mask and entry distances of the test four at a time, bit for
/// bit, on random boxes and rays, including rays parallel to an axis, rays in a box's
/// plane, flat boxes and unused slots.
#[test]
fn avx_box_test_matches_the_halves() {
    if let Some(avx) = Avx::detect() {
        let mut rng = Rng::new(23);
        let v = |rng: &mut Rng| {
            glam::Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - glam::Vec3A::ONE
        };
        let mut hits = 0;
        for i in 0..5000 {
            let kids = 1 + i % 8;
            let nodes: Vec<BinaryNode> = (0..kids)
                .map(|k| {
                    let (a, mut b) = (v(&mut rng), v(&mut rng));
                    if k == 1 {
                        b.y = a.y; // flat
                    }
                    BinaryNode {
                        bounds: Aabb::new(a, b),
                        offset: 0,
                        count: 1,
                        axis: 0,
                    }
                })
                .collect();
            let slots: Vec<usize> = (0..kids).collect();
            let refs = vec![0; kids];
            let node = WideNode::from_children(&nodes, &slots, &refs);
            let mut o = 2.0 * v(&mut rng);
            let mut d = uniform_sphere(rng.vec2());
            match i % 6 {
                0 => d = glam::Vec3A::new(d.x, 0.0, d.z).normalize(),
                1 => d = glam::Vec3A::new(0.0, 0.0, if d.z < 0.0 { -1.0 } else { 1.0 }),
                2 => o.x = nodes[0].bounds.min.x,
                3 => o.y = nodes[kids - 1].bounds.max.y,
                _ => d = (nodes[i % kids].bounds.centroid() - o).normalize(),
            }
            let ray = BoxRay::new(&Ray::new(o, d));
            let t_max = if i % 3 == 0 { 0.5 } else { f32::INFINITY };
            let halves = Halves.hit(&node, &ray, 0.0, t_max);
            let got = avx.hit(&node, &ray, 0.0, t_max);
            assert_eq!(halves.0, got.0, "case {i}");
            assert_eq!(halves.0 >> kids, 0, "case {i}: an unused slot is hit");
            assert_eq!(
                halves.1.map(f32::to_bits),
                got.1.map(f32::to_bits),
                "case {i}"
            );
            hits += halves.0.count_ones();
        }
        assert!(hits > 1000, "{hits} boxes hit");
    }
}

/// The largest node count `fits` takes is the one whose last node's offset is the
/// largest multiple of the node's size below the `LEAF` bit; one node more would reach
/// the bit. (Arithmetic in u64: a tree of 76 million nodes is too large to build here.)
#[test]
fn the_node_limit_is_the_last_offset_below_the_leaf_bit() {
    assert_eq!(NODE_STEP * NODE_UNIT, std::mem::size_of::<WideNode>());
    assert_eq!(NODE_STEP, 28);
    let max = (u64::from(LEAF) - 1) / NODE_STEP as u64 + 1;
    assert!(fits(max as usize));
    assert!(!fits(max as usize + 1));
    let last = (max - 1) * NODE_STEP as u64;
    assert!(last < u64::from(LEAF) && last + NODE_STEP as u64 >= u64::from(LEAF));
    assert_eq!(max, 76_695_845);
    assert!(fits(0) && fits(1));
}

/// A random binary tree of up to `2^depth` leaves, flattened depth-first (leaf `offset`s
/// are the leaves' node indices).
fn random_tree(rng: &mut Rng, out: &mut Vec<BinaryNode>, depth: usize) -> Aabb {
    let i = out.len();
    let v = |rng: &mut Rng| glam::Vec3A::new(rng.f32(), rng.f32(), rng.f32());
    out.push(BinaryNode {
        bounds: Aabb::EMPTY,
        offset: i as u32,
        count: 1,
        axis: 0,
    });
    let bounds = if depth == 0 || (depth < 10 && rng.f32() < 0.15) {
        Aabb::new(v(rng), v(rng))
    } else {
        let a = random_tree(rng, out, depth - 1);
        out[i].offset = out.len() as u32;
        out[i].count = 0;
        a.union(random_tree(rng, out, depth - 1))
    };
    out[i].bounds = bounds;
    bounds
}

/// The collapse of a large tree, its top levels in parallel, gives the nodes of the serial
/// depth-first collapse, on 1, 2 and 4 threads.
#[test]
fn parallel_collapse_matches_the_serial_one() {
    let mut nodes = Vec::new();
    random_tree(&mut Rng::new(31), &mut nodes, 16);
    assert!(
        nodes.len() >= super::PARALLEL_NODES,
        "{} nodes",
        nodes.len()
    );
    let mut serial = Vec::new();
    let plan = super::plan::plan(&nodes, usize::MAX);
    super::collapse_at(&nodes, &plan, 0, &mut serial);
    assert!(serial.len() > 1000);
    for threads in [1, 2, 4] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let parallel = pool.install(|| super::collapse(&nodes)).expect("fits");
        assert_eq!(parallel.len(), serial.len());
        for (k, (p, s)) in parallel.iter().zip(&serial).enumerate() {
            assert_eq!(p.planes, s.planes, "node {k}, {threads} threads");
            // The collapse's interior references are the serial one's indices as offsets.
            let offset = |c: u32| {
                if c & LEAF == 0 {
                    c * NODE_STEP as u32
                } else {
                    c
                }
            };
            assert_eq!(p.child, s.child.map(offset), "node {k}, {threads} threads");
        }
    }
}

/// One past the last node of node `i`'s subtree (flattened depth-first).
fn subtree_end(nodes: &[BinaryNode], i: usize) -> usize {
    if nodes[i].count > 0 {
        i + 1
    } else {
        subtree_end(nodes, nodes[i].offset as usize)
    }
}

/// The binary nodes that become wide nodes in the collapse of `nodes` (the root first), each
/// with its children; checks that each has two to eight, all in its subtree below it, and that
/// every binary leaf is in the slots once.
fn wide_roots(nodes: &[BinaryNode], kids: impl Fn(usize) -> Vec<usize>) -> Vec<usize> {
    let mut roots = vec![0];
    let mut seen = vec![false; nodes.len()];
    let mut k = 0;
    while k < roots.len() {
        let children = kids(roots[k]);
        assert!(
            (2..=8).contains(&children.len()),
            "{} children",
            children.len()
        );
        let (r, end) = (roots[k], subtree_end(nodes, roots[k]));
        for c in children {
            assert!(r < c && c < end, "node {c} is not below node {r}");
            assert!(!seen[c], "node {c} in two slots");
            seen[c] = true;
            if nodes[c].count == 0 {
                roots.push(c);
            }
        }
        k += 1;
    }
    for (i, n) in nodes.iter().enumerate() {
        assert!(n.count == 0 || seen[i], "leaf {i} in no slot");
    }
    roots
}

/// The summed surface area of the wide nodes made from `roots`.
fn area(nodes: &[BinaryNode], roots: &[usize]) -> f64 {
    roots
        .iter()
        .map(|&r| f64::from(nodes[r].bounds.surface_area()))
        .sum()
}

/// The children of the wide node made from interior node `i` by the greedy collapse: its two
/// children, then the interior child of largest area opened, until eight.
fn greedy(nodes: &[BinaryNode], i: usize) -> Vec<usize> {
    let mut kids = vec![i + 1, nodes[i].offset as usize];
    while kids.len() < 8 {
        let widest = (0..kids.len())
            .filter(|&j| nodes[kids[j]].count == 0)
            .max_by(|&a, &b| {
                let area = |j: usize| nodes[kids[j]].bounds.surface_area();
                area(a).total_cmp(&area(b))
            });
        let Some(j) = widest else { break };
        let k = kids.remove(j);
        kids.insert(j, nodes[k].offset as usize);
        kids.insert(j, k + 1);
    }
    kids
}

/// The plan's collapse of a random tree of at most 16 leaves against every collapse of it
/// (every set of interior nodes made wide nodes whose nodes have at most eight children):
/// none has a smaller summed area of wide nodes.
#[test]
fn the_plan_has_the_least_summed_area_of_any_collapse() {
    let mut rng = Rng::new(7);
    let (mut tried, mut worse) = (0, 0);
    while tried < 300 {
        let mut nodes = Vec::new();
        random_tree(&mut rng, &mut nodes, 5);
        let interior: Vec<usize> = (1..nodes.len()).filter(|&i| nodes[i].count == 0).collect();
        if nodes[0].count > 0 || interior.len() > 14 {
            continue;
        }
        tried += 1;
        let plan = super::plan::plan(&nodes, usize::MAX);
        let got = area(
            &nodes,
            &wide_roots(&nodes, |i| super::kids_of(&nodes, &plan, i).to_vec()),
        );
        let mut best = f64::INFINITY;
        for set in 0u32..1 << interior.len() {
            let wide = |i: usize| {
                i == 0
                    || interior
                        .iter()
                        .position(|&k| k == i)
                        .is_some_and(|p| set >> p & 1 != 0)
            };
            // A wide node's slots: its children, each opened (its children in its place)
            // unless it is a leaf or a wide node itself.
            fn slots(nodes: &[BinaryNode], wide: &dyn Fn(usize) -> bool, c: usize) -> usize {
                if nodes[c].count > 0 || wide(c) {
                    1
                } else {
                    slots(nodes, wide, c + 1) + slots(nodes, wide, nodes[c].offset as usize)
                }
            }
            let mut total = 0.0;
            let mut fits = true;
            for w in (0..nodes.len()).filter(|&i| nodes[i].count == 0 && wide(i)) {
                let n =
                    slots(&nodes, &wide, w + 1) + slots(&nodes, &wide, nodes[w].offset as usize);
                fits &= n <= 8;
                total += f64::from(nodes[w].bounds.surface_area());
            }
            if fits {
                best = best.min(total);
            }
        }
        // (Not below the least either: that would be a collapse the search does not count as
        // one. The plan chose in f32, hence the tolerance above.)
        assert!(got <= best * (1.0 + 1e-6), "plan {got}, best {best}");
        assert!(
            got >= best * (1.0 - 1e-12),
            "plan {got} below every collapse's {best}"
        );
        let theirs = area(&nodes, &wide_roots(&nodes, |i| greedy(&nodes, i)));
        worse += usize::from(theirs > best * (1.0 + 1e-6));
    }
    // (The search can tell: the greedy collapse is above the least on some of these trees.)
    assert!(
        worse > 0,
        "the greedy collapse was the least on all {tried} trees"
    );
    println!("the greedy collapse above the least on {worse} of {tried} trees");
}

/// On large random trees the plan's collapse has a smaller summed area of wide nodes than
/// the greedy one (open the interior child of largest area until eight), and fewer nodes.
#[test]
fn the_plan_beats_the_greedy_collapse() {
    for seed in 0..4 {
        let mut nodes = Vec::new();
        random_tree(&mut Rng::new(100 + seed), &mut nodes, 12);
        let plan = super::plan::plan(&nodes, usize::MAX);
        let ours = wide_roots(&nodes, |i| super::kids_of(&nodes, &plan, i).to_vec());
        let theirs = wide_roots(&nodes, |i| greedy(&nodes, i));
        let (a, b) = (area(&nodes, &ours), area(&nodes, &theirs));
        assert!(a < b, "seed {seed}: plan {a}, greedy {b}");
        assert!(
            ours.len() < theirs.len(),
            "seed {seed}: {} against {} nodes",
            ours.len(),
            theirs.len()
        );
        println!(
            "seed {seed}: area {a:.1} against {b:.1}, {} against {} nodes",
            ours.len(),
            theirs.len()
        );
    }
}

/// Boxes whose area is NaN (flat, spanning more than `f32`'s range on another axis) or
/// infinite leave a valid collapse: every leaf in one slot, two to eight children a node.
#[test]
fn boxes_of_nan_or_infinite_area_leave_a_valid_collapse() {
    let mut rng = Rng::new(5);
    for seed in 0..8 {
        let mut nodes = Vec::new();
        random_tree(&mut Rng::new(200 + seed), &mut nodes, 9);
        if nodes[0].count > 0 {
            continue;
        }
        for n in nodes.iter_mut() {
            let u = rng.f32();
            if u < 0.1 {
                // x spans 4e38 (infinite in f32), y is flat: area inf * 0 = NaN.
                n.bounds = Aabb::new(
                    glam::Vec3A::new(-2e38, 0.5, 0.0),
                    glam::Vec3A::new(2e38, 0.5, 1.0),
                );
                assert!(n.bounds.surface_area().is_nan());
            } else if u < 0.2 {
                n.bounds = Aabb::new(glam::Vec3A::splat(-3e38), glam::Vec3A::splat(3e38));
                assert!(n.bounds.surface_area().is_infinite());
            }
        }
        let plan = super::plan::plan(&nodes, usize::MAX);
        let roots = wide_roots(&nodes, |i| super::kids_of(&nodes, &plan, i).to_vec());
        let wide = super::collapse(&nodes).expect("fits");
        assert_eq!(wide.len(), roots.len(), "seed {seed}");
    }
}

/// Two meshes (one with normals and uvs, one mirrored without) and a few spheres in one
/// 8-wide BVH: the closest hit (every field of it, bit for bit, and its id) and occlusion
/// are those of brute force over the meshes expanded into stand-alone triangles.
#[test]
fn meshes_and_shapes_match_brute_force() {
    let mut rng = Rng::new(11);
    let mirror = DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0));
    for case in 0..6 {
        let n = [1, 3, 40, 200, 700, 2000][case];
        let a = TriangleMesh::new(&random_mesh(&mut rng, n, true), &DAffine3::IDENTITY).unwrap();
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
        )
        .expect("a BVH of test size");
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
