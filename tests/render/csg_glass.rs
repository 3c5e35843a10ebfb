//! A glass `merge` refracts as one solid: its inner surfaces are never seen, by camera rays or
//! photons.

use std::sync::atomic::AtomicBool;

use glam::{DVec3, Vec3A};
use sppm_lang::EvalOptions;
use sppm_lang::internals::eval::load_source;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::render::{PreparedScene, RenderOptions, render};
use sppm_lang::internals::scene::Scene;

fn scene(objects: &str) -> Scene {
    let text = format!(
        r#"
        settings {{ resolution <48, 48> }}
        camera {{ location <0, 1.2, -3> look_at <0, 0.5, 0> fov 45 }}
        area_light {{ quad {{ <-0.3, 2.5, -0.3>, <0.6, 0, 0>, <0, 0, 0.6> }} radiance rgb 20 }}
        plane {{ <0, 1, 0>, 0 material {{ diffuse rgb 0.7 }} }}
        #declare Glass = material {{ glass ior 1.5 absorb rgb <0.2, 0.1, 0> }}
        {objects}
        "#
    );
    let l = load_source("glass.scn", &text, &EvalOptions::default());
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
    l.scene.unwrap()
}

fn pixels(scene: &Scene) -> Vec<[u64; 3]> {
    let opts = RenderOptions {
        iterations: Some(3),
        photons: Some(20_000),
        seed: Some(5),
        threads: Some(2),
        ..Default::default()
    };
    let out = render(scene, &opts, &AtomicBool::new(false), &mut |_| {}).unwrap();
    out.image
        .pixels
        .iter()
        .map(|p| p.map(f64::to_bits))
        .collect()
}

/// A merge of a ball with a smaller ball inside it, or with a copy of itself, renders the very
/// image of the ball alone (bit for bit: every path meets the same surfaces at the same points,
/// photons and camera rays alike); a union of the same balls keeps the inner surfaces and does
/// not.
#[test]
fn glass_merge_of_nested_or_equal_balls_is_the_ball() {
    let ball = "sphere { <0, 0.6, 0>, 0.6 material { Glass } }";
    let alone = pixels(&scene(ball));
    let nested = pixels(&scene(&format!(
        "merge {{ {ball} sphere {{ <0.1, 0.5, 0.1>, 0.3 }} material {{ Glass }} }}"
    )));
    let twice = pixels(&scene(&format!("merge {{ {ball} {ball} }}")));
    assert!(
        alone == nested,
        "a merge with a ball inside differs from the ball"
    );
    let mean = alone.iter().map(|p| f64::from_bits(p[1])).sum::<f64>() / alone.len() as f64;
    assert!(mean > 0.01, "the scene is dark: mean {mean}");
    assert!(
        alone == twice,
        "a merge of a ball with itself differs from the ball"
    );
    let union = pixels(&scene(&format!(
        "union {{ {ball} sphere {{ <0.1, 0.5, 0.1>, 0.3 }} material {{ Glass }} }}"
    )));
    assert!(alone != union, "the inner ball of a union should show");
}

/// Along any line through a glass merge of two overlapping balls, the hits alternate between
/// entering and leaving (normal against, then along the ray), and none lies inside either ball:
/// a ray never meets the inner surfaces. The same test fails for the two balls as separate
/// objects.
#[test]
fn rays_through_a_merge_alternate_and_never_meet_inner_surfaces() {
    let balls = "sphere { <-0.3, 0.6, 0>, 0.5 } sphere { <0.3, 0.6, 0.1>, 0.45 }";
    let check = |objects: &str| -> usize {
        let s = scene(objects);
        let prepared = PreparedScene::new(&s).unwrap();
        let centers = [
            (DVec3::new(-0.3, 0.6, 0.0), 0.5),
            (DVec3::new(0.3, 0.6, 0.1), 0.45),
        ];
        let mut bad = 0;
        let mut rng = sppm_lang::internals::sampling::Rng::new(0x1234_5678);
        let mut f = || f64::from(rng.f32()) * 2.0 - 1.0;
        for _ in 0..4000 {
            let o = DVec3::new(f() * 2.0, 0.6 + f() * 1.5, -2.0 + f() * 0.2);
            let target = DVec3::new(f() * 0.8, 0.6 + f() * 0.5, f() * 0.5);
            let d = (target - o).normalize();
            let mut ray = Ray::new(o.as_vec3a(), d.as_vec3a());
            let mut expect_enter = true;
            for _ in 0..8 {
                let Some(h) = prepared.intersect(&ray, f32::INFINITY) else {
                    break;
                };
                let p = DVec3::from(h.hit.p.to_array().map(f64::from));
                if p.y < 1e-3 {
                    break; // the floor
                }
                let enter = h.hit.n.dot(ray.d) < 0.0;
                let inside_other = centers.iter().any(|(c, r)| (p - *c).length() < r - 1e-4);
                if enter != expect_enter || inside_other {
                    bad += 1;
                    break;
                }
                expect_enter = !expect_enter;
                let off = h.hit.p + ray.d * 1e-4;
                ray = Ray::new(off, ray.d);
            }
            assert!(expect_enter || ray.d != Vec3A::ZERO);
        }
        bad
    };
    let merged = check(&format!("merge {{ {balls} material {{ Glass }} }}"));
    assert_eq!(merged, 0, "{merged} rays met an inner surface of the merge");
    let separate = check(&format!("union {{ {balls} material {{ Glass }} }}"));
    assert!(
        separate > 100,
        "only {separate} rays met inner surfaces of two separate balls"
    );
}

/// A closed glass surface whose normals point in (a mesh wound inward, a revolve profile drawn
/// from the top down) renders as the same surface facing out, bit for bit, whether placed once
/// or several times (a shared mesh); before, such glass rendered inside out.
#[test]
fn closed_glass_facing_in_renders_as_facing_out() {
    let dir = std::env::temp_dir().join(format!("sppm-inward-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let v = "v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 1 -0.5\nv -0.5 1 -0.5\n\
             v -0.5 0 0.5\nv 0.5 0 0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n";
    // Counter-clockwise seen from outside.
    let faces = [
        [1, 4, 3],
        [1, 3, 2],
        [5, 6, 7],
        [5, 7, 8],
        [1, 2, 6],
        [1, 6, 5],
        [4, 8, 7],
        [4, 7, 3],
        [1, 5, 8],
        [1, 8, 4],
        [2, 3, 7],
        [2, 7, 6],
    ];
    let obj = |inward: bool| {
        let f: String = faces
            .iter()
            .map(|t| match inward {
                false => format!("f {} {} {}\n", t[0], t[1], t[2]),
                true => format!("f {} {} {}\n", t[0], t[2], t[1]),
            })
            .collect();
        format!("{v}{f}")
    };
    let (out_path, in_path) = (dir.join("out.obj"), dir.join("in.obj"));
    std::fs::write(&out_path, obj(false)).unwrap();
    std::fs::write(&in_path, obj(true)).unwrap();
    let cube = |p: &std::path::Path, at: &str| {
        format!(
            "mesh {{ \"{}\" scale 0.7 translate {at} material {{ Glass }} }}",
            p.display()
        )
    };
    let once = |p: &std::path::Path| pixels(&scene(&cube(p, "<0, 0, 0>")));
    let twice = |p: &std::path::Path| {
        pixels(&scene(&format!(
            "{} {}",
            cube(p, "<-0.5, 0, 0>"),
            cube(p, "<0.5, 0, 0.5>")
        )))
    };
    assert!(
        once(&out_path) == once(&in_path),
        "a glass cube wound inward differs"
    );
    assert!(
        twice(&out_path) == twice(&in_path),
        "shared glass cubes wound inward differ"
    );
    let revolve = |points: &str| {
        pixels(&scene(&format!(
            "revolve {{ profile bezier {{ degree 1 {points} }} corner material {{ Glass }} }}"
        )))
    };
    let up = revolve("<0, 0>, <0.5, 0>, <0.5, 1>, <0, 1>");
    let down = revolve("<0, 1>, <0.5, 1>, <0.5, 0>, <0, 0>");
    assert!(
        up == down,
        "a glass revolve drawn from the top down differs"
    );
    std::fs::remove_dir_all(&dir).ok();
}
