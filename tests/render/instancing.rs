//! A mesh placed many times is stored once (a two-level BVH): the placements intersect exactly
//! as the same triangles baked into world space, and a mesh of ~1000 triangles placed 50 000
//! times renders in bounded memory instead of asking for tens of gigabytes.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::AtomicBool;

use glam::Vec3A;
use sppm_lang::EvalOptions;
use sppm_lang::internals::eval::load_file;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::prepare::{
    PreparedScene, RenderOptions, effective_settings, estimate_memory,
};
use sppm_lang::internals::render::render;
use sppm_lang::internals::scene::Scene;

/// A UV sphere of radius 1 as OBJ text: `rings * segments * 2` triangles (minus the poles').
fn sphere_obj(rings: u32, segments: u32) -> String {
    let mut s = String::new();
    for i in 0..=rings {
        let th = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let ph = std::f64::consts::TAU * j as f64 / segments as f64;
            // A little bumpiness so that neighbouring placements are not all alike.
            let r = 1.0 + 0.05 * (3.0 * ph).sin() * th.sin();
            let _ = writeln!(
                s,
                "v {:.6} {:.6} {:.6}",
                r * th.sin() * ph.cos(),
                r * th.cos(),
                r * th.sin() * ph.sin()
            );
        }
    }
    let idx = |i: u32, j: u32| i * segments + (j % segments) + 1;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (idx(i, j), idx(i, j + 1), idx(i + 1, j), idx(i + 1, j + 1));
            if i > 0 {
                let _ = writeln!(s, "f {a} {b} {c}");
            }
            if i + 1 < rings {
                let _ = writeln!(s, "f {b} {d} {c}");
            }
        }
    }
    s
}

fn load(dir: &Path, text: &str) -> Scene {
    let path = dir.join("scene.scn");
    std::fs::write(&path, text).unwrap();
    let loaded = load_file(&path, &EvalOptions::default()).unwrap();
    let errors: Vec<_> = loaded
        .diagnostics
        .iter()
        .map(|d| d.message.clone())
        .collect();
    loaded.scene.unwrap_or_else(|| panic!("{errors:?}"))
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("sppm-instancing-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Placements of `file` at the given transforms, as scene text.
fn placements(file: &str, transforms: &[&str]) -> String {
    transforms
        .iter()
        .map(|t| format!("mesh {{ \"{file}\" {t} }}\n"))
        .collect()
}

#[test]
fn instanced_placements_hit_like_baked_triangles() {
    let dir = temp_dir("exact");
    let obj = sphere_obj(12, 16);
    // The same triangles in two files: loaded twice, so each placement of `b*.obj` is baked,
    // while the placements of `a.obj` share one BVH.
    std::fs::write(dir.join("a.obj"), &obj).unwrap();
    let transforms = [
        "translate <-2, 0, 0>",
        "scale <1, 0.5, 2> rotate <0, 30, 0> translate <1.5, 0.3, 0>",
        "rotate <40, 10, 0> scale 0.7 translate <0, 2, 1>",
        "scale <-1, 1, 1> translate <0, -2, 0.5>",
    ];
    let mut baked = String::new();
    for (i, t) in transforms.iter().enumerate() {
        let name = format!("b{i}.obj");
        std::fs::write(dir.join(&name), &obj).unwrap();
        baked += &placements(&name, &[t]);
    }
    let head = "camera { location <0, 0, -8> look_at <0, 0, 0> }\n";
    let instanced = load(&dir, &format!("{head}{}", placements("a.obj", &transforms)));
    let baked = load(&dir, &format!("{head}{baked}"));
    let pi = PreparedScene::new(&instanced).unwrap();
    let pb = PreparedScene::new(&baked).unwrap();
    assert_eq!(
        pi.bvh.len(),
        transforms.len(),
        "one primitive per placement"
    );
    assert!(
        pb.bvh.len() > 100 * transforms.len(),
        "baked into triangles"
    );

    let mut state = 0x9e3779b97f4a7c15u64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let (mut hits, mut agree) = (0, 0);
    for _ in 0..20_000 {
        let o = Vec3A::new(rnd() * 8.0 - 4.0, rnd() * 8.0 - 4.0, -6.0);
        let target = Vec3A::new(rnd() * 6.0 - 3.0, rnd() * 6.0 - 3.0, rnd() * 2.0 - 1.0);
        let ray = Ray::new(o, (target - o).normalize());
        let a = pi.intersect(&ray, f32::INFINITY);
        let b = pb.intersect(&ray, f32::INFINITY);
        match (a, b) {
            (None, None) => agree += 1,
            (Some(a), Some(b)) => {
                hits += 1;
                let close = (a.hit.t - b.hit.t).abs() <= 1e-4 * b.hit.t.max(1.0);
                let same_object =
                    pi.prim_object[a.prim as usize] == pb.prim_object[b.prim as usize];
                let normal = a.hit.n.dot(b.hit.n) > 0.9999;
                if close && same_object && normal {
                    agree += 1;
                }
            }
            _ => {}
        }
    }
    assert!(hits > 5_000, "too few hits to say anything: {hits}");
    // A ray through a shared edge may hit either triangle at the same point, and one grazing
    // an edge may miss in one and hit in the other by an ulp: allow a handful.
    assert!(agree >= 20_000 - 10, "{agree} of 20000 rays agree");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_mesh_placed_50000_times_renders_in_bounded_memory() {
    let dir = temp_dir("many");
    let obj = sphere_obj(24, 22);
    assert!(
        obj.len() > 30_000,
        "an OBJ of the size users bring: {} bytes",
        obj.len()
    );
    std::fs::write(dir.join("ball.obj"), &obj).unwrap();
    let scene = load(
        &dir,
        "settings { resolution <24, 16> photons 2000 iterations 1 }\n\
         camera { location <0, 300, -400> look_at <0, 0, 0> }\n\
         light { <0, 500, -200> intensity rgb 1e6 }\n\
         #for (i, 0, 49999)\n\
           mesh { \"ball.obj\" translate <mod(i, 250) * 3 - 375, 0, floor(i / 250) * 3 - 300> }\n\
         #end\n",
    );
    assert_eq!(scene.objects.len(), 50_000);
    let triangles = 24 * 22 * 2 - 2 * 22;
    let options = RenderOptions {
        memory_limit: Some(1 << 30),
        ..RenderOptions::default()
    };
    let settings = effective_settings(&scene, &options).unwrap();
    let total: u64 = estimate_memory(&scene, &settings)
        .iter()
        .map(|i| i.bytes)
        .sum();
    // Baked, it would be 50 000 x ~1000 triangles at ~200 bytes each (~10 GB).
    assert!(
        total < 256 << 20,
        "estimate {} MiB for {} triangles placed 50000 times",
        total >> 20,
        triangles
    );
    let out = render(&scene, &options, &AtomicBool::new(false), &mut |_| {}).unwrap();
    assert_eq!(out.iterations_done, 1);
    let lit = out
        .image
        .pixels
        .iter()
        .filter(|p| p.iter().any(|&c| c > 0.0))
        .count();
    assert!(lit > out.image.pixels.len() / 4, "{lit} pixels lit");
    std::fs::remove_dir_all(&dir).ok();
}
