//! Tests of the memory estimate and its limit.

use super::*;
use crate::prepare::{RenderOptions, effective_settings};

fn settings_of(scene: &Scene) -> EffectiveSettings {
    effective_settings(scene, &RenderOptions::default()).unwrap()
}

fn scene(text: &str) -> Scene {
    let l = crate::eval::load_source("budget.scn", text, &Default::default());
    l.scene.expect("a valid scene")
}

#[test]
fn a_huge_film_is_refused_and_a_small_one_is_not() {
    let mut scene = scene("sphere { <0,0,0> 1 }");
    scene.settings.resolution = (16384, 8192);
    let e = check_memory(&scene, &settings_of(&scene), 2 << 30, None).unwrap_err();
    assert!(
        e.message.contains("film and per-pixel state"),
        "{}",
        e.message
    );
    assert!(
        e.help
            .as_ref()
            .is_some_and(|h| h.contains("--memory-limit")),
        "{e:?}"
    );
    scene.settings.resolution = (512, 512);
    check_memory(&scene, &settings_of(&scene), 2 << 30, None).unwrap();
}

/// What the caller holds beside the render (a live view's images) is part of the estimate.
#[test]
fn memory_held_by_the_caller_is_counted() {
    let mut scene = scene("sphere { <0,0,0> 1 }");
    scene.settings.resolution = (512, 512);
    let settings = settings_of(&scene);
    let limit = 512 << 20;
    check_memory(&scene, &settings, limit, None).unwrap();
    let held = MemoryItem {
        what: "live view",
        bytes: limit,
    };
    let e = check_memory(&scene, &settings, limit, Some(held)).unwrap_err();
    assert!(e.message.contains("live view 512"), "{}", e.message);
}

#[test]
fn photon_mapping_counts_its_photons_and_sppm_does_not() {
    let mut scene = scene("sphere { <0,0,0> 1 }");
    scene.settings.resolution = (64, 64);
    scene.settings.photons = Some(10_000_000_000);
    scene.settings.integrator = Some(Integrator::Sppm);
    check_memory(&scene, &settings_of(&scene), 2 << 30, None).unwrap();
    scene.settings.integrator = Some(Integrator::PhotonMap);
    let e = check_memory(&scene, &settings_of(&scene), 2 << 30, None).unwrap_err();
    assert!(
        e.message.contains("photons of one iteration"),
        "{}",
        e.message
    );
}

/// A mesh of `n` x `n` quads (two triangles each) on a wavy sheet, or, `scattered`, the
/// same number of small triangles at random places (leaves of one or two triangles: the
/// worst filled packets); normals and texture coordinates when `attributes`.
fn mesh(n: usize, scattered: bool, attributes: bool) -> MeshData {
    use glam::{DVec2, DVec3};
    let mut rng = crate::sampling::Rng::new(n as u64);
    let mut m = MeshData::default();
    if scattered {
        for k in 0..2 * n * n {
            let c = DVec3::new(rng.f32() as f64, rng.f32() as f64, rng.f32() as f64) * 100.0;
            let d = 0.01;
            m.positions.extend([c, c + DVec3::X * d, c + DVec3::Y * d]);
            m.indices.push([0, 1, 2].map(|i| (3 * k + i) as u32));
        }
    } else {
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                m.positions
                    .push(DVec3::new(x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos()));
            }
        }
        let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                m.indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                m.indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    if attributes {
        m.normals = m
            .positions
            .iter()
            .map(|p| (*p + DVec3::Z).normalize())
            .collect();
        m.uvs = m.positions.iter().map(|p| DVec2::new(p.x, p.y)).collect();
    }
    m
}

/// The estimate of a compact mesh is at least what its buffers and BVH hold once built
/// (`Bvh::memory_bytes`, mesh buffers included) on sheets of 2 to 500 000 triangles, with
/// and without normals and texture coordinates, and on scattered triangles; from 1000
/// triangles on (where the fixed cost per mesh no longer counts) at most twice that: a
/// budget is fooled neither by an under- nor by a wild overestimate.
#[test]
fn a_compact_mesh_estimate_follows_what_it_holds() {
    use crate::accel::Bvh;
    use crate::shapes::mesh::TriangleMesh;
    for (n, scattered, attributes) in [
        (1, false, false),
        (8, false, true),
        (40, false, false),
        (120, true, false),
        (200, false, true),
        (500, false, false),
    ] {
        let m = mesh(n, scattered, attributes);
        let tris = TriangleMesh::new(&m, &glam::DAffine3::IDENTITY).unwrap();
        assert_eq!(tris.len(), m.indices.len());
        let bvh = Bvh::with_meshes(Vec::new(), vec![(tris, 0)]).expect("a BVH of test size");
        let measured = bvh.memory_bytes() as f64;
        let estimate = compact_mesh_bytes(&m) as f64;
        let t = m.indices.len() as f64;
        println!(
            "{} triangles{}{}: measured {:.1} B/triangle, estimate {:.1} ({:.2}x); {:?}",
            m.indices.len(),
            if scattered { " scattered" } else { "" },
            if attributes { " with normals, uvs" } else { "" },
            measured / t,
            estimate / t,
            estimate / measured,
            bvh.memory_parts()
                .map(|(w, b)| format!("{w} {:.1}", b as f64 / t))
        );
        assert!(
            estimate >= measured,
            "{n} {scattered}: {estimate} < {measured}"
        );
        if m.indices.len() >= 1000 {
            assert!(
                estimate <= 2.0 * measured,
                "{n} {scattered}: {estimate} vs {measured}"
            );
        }
    }
}

/// A mesh placed 1000 times counts its triangles once; placed once it counts them once
/// too, in compact form; emissive, it is built twice as shapes of their own.
#[test]
fn meshes_are_counted_as_they_are_built() {
    let m = std::sync::Arc::new(mesh(40, false, false));
    let mut once = scene("sphere { <0,0,0> 1 }");
    once.objects[0].shape = ShapeDecl::Mesh { mesh: m.clone() };
    let primitives_of = |s: &Scene| {
        estimate(s, &settings_of(s))
            .into_iter()
            .find(|i| i.what == "primitives and their BVH")
            .unwrap()
            .bytes
    };
    let one = primitives_of(&once);
    assert!(one >= compact_mesh_bytes(&m) && one < compact_mesh_bytes(&m) + 4096);
    let mut many = once.clone();
    many.objects = vec![once.objects[0].clone(); 1000];
    let placed = primitives_of(&many);
    assert!(
        placed > one && placed < one + 1000 * 1024,
        "{placed} vs {one}"
    );
    let mut lit = once.clone();
    lit.objects[0].emission = Some(crate::scene::Emission {
        radiance: glam::DVec3::ONE,
        two_sided: false,
    });
    assert!(
        primitives_of(&lit) > 4 * one,
        "{} vs {one}",
        primitives_of(&lit)
    );
}

/// A revolve counts one primitive per segment (and one for a partial sweep's caps), as it
/// is built, each with its share of the lathe: three segments cost at least three times
/// a sphere's primitive plus the lathe's tables.
#[test]
fn revolves_are_counted_by_their_segments() {
    let profile = "profile bezier { <0, 0>, <1, 0>, <1, 1>, <1, 2>, <1, 3>, <0.5, 3.5>, \
                   <0.2, 3.8>, <0.1, 3.9>, <0.05, 3.95>, <0, 4> }";
    for (sweep, parts) in [("", 3), ("angle 0, 90", 4)] {
        let s = scene(&format!("revolve {{ {profile} {sweep} }}"));
        let built = super::super::shapes::build_shapes(&s.objects[0], &mut Vec::new()).unwrap();
        assert_eq!(built.len(), parts, "{sweep}");
        assert_eq!(primitives(&s.objects[0].shape), parts as u64, "{sweep}");
        assert!(built.iter().all(|p| p.is_heavy()));
    }
    let bytes = |text: &str| {
        let s = scene(text);
        estimate(&s, &settings_of(&s))
            .into_iter()
            .find(|i| i.what == "primitives and their BVH")
            .unwrap()
            .bytes
    };
    let sphere = bytes("sphere { <0,0,0> 1 }");
    let revolve = bytes(&format!("revolve {{ {profile} }}"));
    assert!(
        revolve >= 3 * (sphere + Lathe::bytes_per_segment() as u64),
        "{revolve} vs {sphere}"
    );
}

#[test]
fn the_default_limit_is_at_most_two_gib() {
    let l = default_memory_limit();
    assert!(l > 0 && l <= 2 << 30, "{l}");
}
