//! Good scenes: the evaluated `Scene` holds what the text says.

use glam::{DAffine3, DVec2, DVec3};
use sppm_lang::internals::eval::{Loaded, load_file, load_source};
use sppm_lang::internals::scene::*;
use sppm_lang::{EvalOptions, Severity};

fn load(text: &str) -> Loaded {
    let l = load_source("test.scn", text, &EvalOptions::default());
    assert!(
        !l.has_errors(),
        "{}",
        sppm_lang::render_plain(&l.sources, &l.diagnostics, 100)
    );
    l
}

fn scene(text: &str) -> Scene {
    load(text).scene.expect("scene")
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).abs().max_element() < 1e-9
}

#[test]
fn examples_all_check() {
    for name in ["cornell", "crystal_tree", "furnace", "smallppm"] {
        let path = format!("examples/{name}.scn");
        let l = load_file(path.as_ref(), &EvalOptions::default()).expect("readable");
        assert!(!l.has_errors(), "{name}: {:?}", l.diagnostics);
        assert!(
            l.diagnostics.is_empty(),
            "{name} has warnings: {:?}",
            l.diagnostics
        );
    }
}

#[test]
fn cornell_matches_reference_description() {
    let l = load_file("examples/cornell.scn".as_ref(), &EvalOptions::default()).unwrap();
    let s = l.scene.unwrap();
    assert_eq!(s.objects.len(), 8);
    assert_eq!(s.settings.resolution, (256, 256));
    assert!(close(s.camera.location, DVec3::new(0.0, 1.0, 3.9)));
    assert_eq!(s.camera.fov, 40.0);
    let light: Vec<&Object> = s.objects.iter().filter(|o| o.emission.is_some()).collect();
    assert_eq!(light.len(), 1);
    let e = light[0].emission.unwrap();
    assert_eq!(e.radiance, DVec3::new(17.0, 12.0, 4.0));
    assert!(!e.two_sided);
    let ShapeDecl::Quad {
        origin,
        edge_u,
        edge_v,
    } = light[0].shape
    else {
        panic!()
    };
    assert!(close(origin, DVec3::new(-0.25, 1.98, -0.25)));
    assert!(edge_u.cross(edge_v).y < 0.0, "light must face down");
    assert_eq!(
        *s.material(light[0].material),
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::ZERO)
        }
    );
    let glass = s
        .objects
        .iter()
        .find(|o| matches!(s.material(o.material), Material::Glass { .. }))
        .unwrap();
    assert!(matches!(s.material(glass.material), Material::Glass { ior, .. } if *ior == 1.5));
    let mirror = s
        .objects
        .iter()
        .find(|o| matches!(s.material(o.material), Material::Mirror { .. }))
        .unwrap();
    assert_eq!(
        *s.material(mirror.material),
        Material::Mirror {
            tint: ColorParam::Const(DVec3::ONE)
        }
    );
}

#[test]
fn defaults_are_explicit() {
    let s = scene("sphere { <0, 0, 0>, 1 }");
    assert_eq!(s.settings, Settings::default());
    assert_eq!(s.camera, Camera::default());
    assert_eq!(s.objects[0].transform, DAffine3::IDENTITY);
    assert_eq!(
        *s.material(s.objects[0].material),
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::splat(0.5))
        }
    );
    assert!(s.textures.is_empty() && s.lights.is_empty());
    assert!(matches!(s.background, Background::Color(c) if c == DVec3::ZERO));
}

#[test]
fn transforms_apply_in_order() {
    let s = scene("sphere { <0, 0, 0>, 1 translate <1, 0, 0> rotate <0, 0, 90> scale 2 }");
    let t = s.objects[0].transform;
    // (1,0,0) translated, then rotated 90° about z to (0,1,0), then scaled to (0,2,0).
    assert!(close(
        t.transform_point3(DVec3::ZERO),
        DVec3::new(0.0, 2.0, 0.0)
    ));
    let s = scene("sphere { <0,0,0>, 1 rotate <90, 90, 0> }");
    // x first: y -> z; then y: z -> x.
    assert!(close(
        s.objects[0].transform.transform_vector3(DVec3::Y),
        DVec3::X
    ));
    let s = scene("sphere { <0,0,0>, 1 matrix <1,0,0, 0,1,0, 0,0,1, 4,5,6> }");
    assert!(close(
        s.objects[0].transform.translation,
        DVec3::new(4.0, 5.0, 6.0)
    ));
}

#[test]
fn unions_compose_and_declared_objects_instantiate() {
    let s = scene(
        "#declare Ball = sphere { <0, 0, 0>, 1 translate <1, 0, 0> }
         union { Ball object { Ball translate <0, 1, 0> } translate <0, 0, 5> material { mirror } }
         Ball",
    );
    assert_eq!(s.objects.len(), 3);
    let p: Vec<DVec3> = s
        .objects
        .iter()
        .map(|o| o.transform.transform_point3(DVec3::ZERO))
        .collect();
    assert!(close(p[0], DVec3::new(1.0, 0.0, 5.0)));
    assert!(close(p[1], DVec3::new(1.0, 1.0, 5.0)));
    assert!(close(p[2], DVec3::new(1.0, 0.0, 0.0)));
    assert!(matches!(
        s.material(s.objects[0].material),
        Material::Mirror { .. }
    ));
    assert!(matches!(
        s.material(s.objects[2].material),
        Material::Diffuse { .. }
    ));
}

#[test]
fn materials_are_deduplicated_by_declaration() {
    let s = scene(
        "#declare W = material { diffuse rgb <0.7, 0.7, 0.7> }
         #for (I, 0, 9) sphere { <I, 0, 0>, 0.4 material { W } } #end
         sphere { <0, 3, 0>, 1 material { diffuse rgb <0.7, 0.7, 0.7> } }",
    );
    assert_eq!(s.objects.len(), 11);
    assert_eq!(s.materials.len(), 2, "{:?}", s.materials);
    assert!(
        s.objects[..10]
            .iter()
            .all(|o| o.material == s.objects[0].material)
    );
}

/// An override of a declared material keeps what it does not write, for every kind: a
/// glossy material given a new roughness kept no colour (it came out grey), and a mirror
/// override dropped its tint.
#[test]
fn overrides_of_declared_materials_keep_the_rest() {
    let s = scene(
        "#declare G = material { glossy rgb <1, 0, 0> specular rgb 0.1 roughness 0.3 }
         #declare M = material { mirror rgb <0.9, 0.5, 0.2> }
         #declare Q = material { glass ior 1.7 tint rgb <0.9, 0.9, 1> }
         sphere { <0, 0, 0>, 1 material { G roughness 0.31 } }
         sphere { <3, 0, 0>, 1 material { G glossy rgb <0, 1, 0> } }
         sphere { <6, 0, 0>, 1 material { M glass ior 1.5 } }
         sphere { <9, 0, 0>, 1 material { Q ior 1.6 } }
         sphere { <12, 0, 0>, 1 material { M mirror } }
         sphere { <15, 0, 0>, 1 material { mirror tint texture { checker rgb 1, rgb 0.5 } } }",
    );
    let m = |i: usize| &s.materials[s.objects[i].material.0 as usize];
    let c = |x: f64, y: f64, z: f64| ColorParam::Const(DVec3::new(x, y, z));
    assert_eq!(
        m(0),
        &Material::Glossy {
            albedo: c(1.0, 0.0, 0.0),
            specular: c(0.1, 0.1, 0.1),
            roughness: ScalarParam::Const(0.31),
        }
    );
    assert_eq!(
        m(1),
        &Material::Glossy {
            albedo: c(0.0, 1.0, 0.0),
            specular: c(0.1, 0.1, 0.1),
            roughness: ScalarParam::Const(0.3),
        }
    );
    assert!(matches!(m(2), Material::Glass { ior, .. } if *ior == 1.5));
    assert!(
        matches!(m(3), Material::Glass { ior, tint, .. } if *ior == 1.6 && close(*tint, DVec3::new(0.9, 0.9, 1.0)))
    );
    assert_eq!(
        m(4),
        &Material::Mirror {
            tint: c(0.9, 0.5, 0.2)
        }
    );
    // `mirror tint <texture>` is `mirror <texture>` (the tint was refused as "expected a color").
    assert!(matches!(
        m(5),
        Material::Mirror {
            tint: ColorParam::Texture(_)
        }
    ));
}

#[test]
fn macros_recurse_and_count() {
    let s = scene(
        "#macro Branch(P, Dir, Len, Depth)
           cylinder { P, P + Dir*Len, Len*0.08 }
           #if (Depth > 0)
             Branch(P + Dir*Len, vrotate(Dir, <0, 0, 25>), Len*0.618, Depth - 1)
             Branch(P + Dir*Len, vrotate(Dir, <0, 0, -25>), Len*0.618, Depth - 1)
           #end
         #end
         Branch(<0, 0, 0>, <0, 1, 0>, 0.5, 6)",
    );
    assert_eq!(s.objects.len(), 127);
    let ShapeDecl::Cylinder { cap, radius, .. } = s.objects[0].shape else {
        panic!()
    };
    assert!(close(cap, DVec3::new(0.0, 0.5, 0.0)));
    assert!((radius - 0.04).abs() < 1e-12);
}

/// POV-Ray's `cone`: base point and radius, cap point and radius, either radius 0, `open`.
#[test]
fn cones_as_in_pov_ray() {
    let s = scene(
        "cone { <0, 0, 0>, 1, <0, 2, 0>, 0 }
         cone { <1, 0, 0>, 0.25, <1, 1, 0>, 0.5 open }",
    );
    let ShapeDecl::Cone {
        base,
        base_radius,
        cap,
        cap_radius,
        open,
    } = s.objects[0].shape
    else {
        panic!()
    };
    assert_eq!(
        (base, base_radius, cap, cap_radius, open),
        (DVec3::ZERO, 1.0, DVec3::new(0.0, 2.0, 0.0), 0.0, false)
    );
    assert!(
        matches!(s.objects[1].shape, ShapeDecl::Cone { open: true, cap_radius, .. } if cap_radius == 0.5)
    );
    assert_eq!(s.objects[1].shape.kind(), "cone");
}

/// POV-Ray's `torus { major, minor }` about the y axis.
#[test]
fn a_torus_as_in_pov_ray() {
    let s = scene("torus { 1, 0.25 translate <0, 0.25, 0> }");
    assert!(
        matches!(s.objects[0].shape, ShapeDecl::Torus { major, minor } if major == 1.0 && minor == 0.25)
    );
}

#[test]
fn expressions_and_builtins() {
    let s = scene(
        "#declare A = 1 + 2 * 3 - 4 / 2;          // 5
         #declare B = <1, 2, 3> * 2 + <1, 1, 1>;  // <3, 5, 7>
         #declare C = max(1, 7, 3) + clamp(5, 0, 2) + abs(-1) + floor(2.7);  // 7+2+1+2
         #declare D = vcross(x, y).z + vdot(<1,2,3>, <1,1,1>) + vlength(<3, 4, 0>);  // 1+6+5
         #declare E = [1, 2, 3][1] + B.y + degrees(pi);  // 2+5+180
         #declare F = 0;
         #if (A == 5 && !(C < 12) || false) #declare F = 1; #elif (1) #declare F = 2; #end
         sphere { <A, C, D>, E/1000 + F }",
    );
    let ShapeDecl::Sphere { center, radius } = s.objects[0].shape else {
        panic!()
    };
    assert_eq!(center, DVec3::new(5.0, 12.0, 12.0));
    assert!((radius - (0.187 + 1.0)).abs() < 1e-12);
}

#[test]
fn loops_and_locals() {
    let s = scene(
        "#declare I = 0;
         #while (I < 4) sphere { <I, 0, 0>, 0.1 } #declare I = I + 1; #end
         #for (J, 10, 0, -5) sphere { <J, 1, 0>, 0.1 } #end",
    );
    assert_eq!(s.objects.len(), 7);
    let ShapeDecl::Sphere { center, .. } = s.objects[6].shape else {
        panic!()
    };
    assert_eq!(center, DVec3::new(0.0, 1.0, 0.0));
}

#[test]
fn settings_camera_lights_background() {
    let s = scene(
        "settings { resolution <640, 480> iterations 8 photons 1000 radius 0.02 alpha 0.5
                    max_depth 5 seed 9 integrator path exposure 2 time_limit 30 }
         camera { location <1, 2, 3> look_at <0, 0, 0> fov 50 aperture 0.1 focus_distance 3 }
         light { <0, 5, 0> intensity rgb <10, 10, 10> }
         spotlight { <0, 5, 0> point_at <0, 0, 0> intensity 5 angle 40 falloff 30 }
         background rgb <0.1, 0.2, 0.3>",
    );
    let st = &s.settings;
    assert_eq!(st.resolution, (640, 480));
    assert_eq!(
        (st.iterations, st.photons, st.max_depth, st.seed),
        (8, Some(1000), 5, 9)
    );
    assert_eq!(
        (st.radius, st.alpha, st.exposure, st.time_limit),
        (Some(0.02), 0.5, 2.0, Some(30.0))
    );
    assert_eq!(st.integrator, Some(Integrator::Path));
    assert_eq!(s.camera.aperture, 0.1);
    assert_eq!(s.camera.focus_distance, Some(3.0));
    assert_eq!(s.lights.len(), 2);
    let LightDecl::Spot {
        direction,
        cone_angle,
        falloff_angle,
        intensity,
        ..
    } = &s.lights[1]
    else {
        panic!()
    };
    assert!(close(*direction, -DVec3::Y));
    assert_eq!((*cone_angle, *falloff_angle), (40.0, 30.0));
    assert_eq!(*intensity, DVec3::splat(5.0));
    assert!(matches!(s.background, Background::Color(c) if close(c, DVec3::new(0.1, 0.2, 0.3))));
}

#[test]
fn textures_store_inverse_transform_and_unused_are_not_loaded() {
    let l = load(
        "#declare Unused = texture { image \"does_not_exist.png\" }
         #declare T = texture { checker rgb <1, 1, 1>, rgb <0.1, 0.2, 0.6> scale 0.1 }
         sphere { <0, 0, 0>, 1 material { diffuse T } }
         sphere { <0, 3, 0>, 1 material { glossy texture { marble color_map { [0, rgb 0] [1, rgb 1] } turbulence 2 } roughness 0.3 } }",
    );
    let s = l.scene.as_ref().unwrap();
    assert_eq!(s.textures.len(), 2);
    assert!(matches!(s.textures[0].pattern, Pattern::Checker { a, .. } if a == DVec3::ONE));
    assert_eq!(s.textures[0].mapping, Mapping::Solid);
    assert!(close(
        s.textures[0].transform.transform_point3(DVec3::ONE),
        DVec3::splat(10.0)
    ));
    assert!(
        matches!(&s.textures[1].pattern, Pattern::Marble { turbulence, octaves: 6, .. } if *turbulence == 2.0)
    );
    assert_eq!(l.diagnostics.len(), 1, "{:?}", l.diagnostics);
    assert!(l.diagnostics[0].message.contains("unused texture `Unused`"));
}

#[test]
fn revolve_and_patches() {
    let s = scene(
        "revolve { profile bezier { <0, 0>, <0.35, 0>, <0.4, 0.3>, <0.15, 0.6> }
                   axis <1, 0, 0> angle 0, 270 method newton iterations 10 starts 4 }
         revolve { profile bezier { degree 1 <0, 0>, <1, 0>, <1, 1> } corner }
         bezier_patch { #for (I, 0, 3) #for (J, 0, 3) <I, 0, J>, #end #end }
         bezier_mesh { #for (K, 1, 32) <K, 0, 0> #end }",
    );
    assert_eq!(s.objects.len(), 5);
    let ShapeDecl::Revolve {
        profile,
        sweep,
        method,
    } = &s.objects[0].shape
    else {
        panic!()
    };
    assert_eq!(
        profile.segments,
        vec![vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(0.35, 0.0),
            DVec2::new(0.4, 0.3),
            DVec2::new(0.15, 0.6)
        ]]
    );
    assert_eq!(*sweep, Some((0.0, 270.0)));
    assert_eq!(
        *method,
        IntersectMethod::Newton {
            iterations: 10,
            starts: 4
        }
    );
    // The axis maps object y onto world x.
    assert!(close(
        s.objects[0].transform.transform_vector3(DVec3::Y),
        DVec3::X
    ));
    let ShapeDecl::Revolve { profile, .. } = &s.objects[1].shape else {
        panic!()
    };
    assert_eq!(profile.segments.len(), 2);
    let ShapeDecl::BezierPatch { points, .. } = &s.objects[2].shape else {
        panic!()
    };
    assert_eq!(points[4 + 2], DVec3::new(1.0, 0.0, 2.0));
}

#[test]
fn includes_resolve_relative_to_the_including_file() {
    let l = load_file("tests/good/inc_main.scn".as_ref(), &EvalOptions::default()).unwrap();
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
    assert_eq!(l.dependencies.len(), 2);
    let s = l.scene.unwrap();
    let ShapeDecl::Sphere { radius, .. } = s.objects[0].shape else {
        panic!()
    };
    assert_eq!(radius, 0.25);
}

/// An included file's top-level `#local`s are its own (they do not overwrite the scene's
/// globals and are gone when it ends; its macros see them while it runs), and what it declares
/// but the scene does not use is not reported unused.
#[test]
fn an_included_file_keeps_its_locals_and_its_spare_declarations_quietly() {
    let l = load_file("tests/good/inc_local.scn".as_ref(), &EvalOptions::default()).unwrap();
    assert!(
        l.diagnostics.is_empty(),
        "{}",
        sppm_lang::render_plain(&l.sources, &l.diagnostics, 100)
    );
    let radii: Vec<f64> = l
        .scene
        .unwrap()
        .objects
        .iter()
        .map(|o| match o.shape {
            ShapeDecl::Sphere { radius, .. } => radius,
            _ => panic!("a sphere"),
        })
        .collect();
    // The library's `LibSphere(2)` (its `Step`), `Count` (the scene's 3, not the library's
    // 100), `LibReady / 100` (the library's `Count`); no `Step` after the include.
    assert_eq!(radii, [0.5, 3.0, 1.0]);
}

#[test]
fn area_light_over_disk_and_sphere() {
    let s = scene(
        "area_light { disk { <0, 2, 0>, <0, -1, 0>, 0.3 } radiance rgb <5, 5, 5> two_sided }
         area_light { sphere { <0, 1, 0>, 0.1 } radiance 3 material { mirror } }",
    );
    assert_eq!(s.objects.len(), 2);
    assert!(s.objects[0].emission.unwrap().two_sided);
    assert_eq!(s.objects[1].emission.unwrap().radiance, DVec3::splat(3.0));
    assert!(matches!(
        s.material(s.objects[1].material),
        Material::Mirror { .. }
    ));
}

#[path = "../../benches/support/big_scene.rs"]
mod big_scene;

/// The benchmark's generated scene evaluates to exactly the objects it writes (kinds counted).
#[test]
fn generated_100k_scene_has_100k_objects() {
    let s = scene(&big_scene::big_scene(100_000));
    assert_eq!(s.objects.len(), 100_000);
    let count = |k: &str| s.objects.iter().filter(|o| o.shape.kind() == k).count();
    assert_eq!(count("sphere"), 40_000);
    assert_eq!(count("box"), 20_000);
    assert_eq!(count("cylinder"), 20_000);
    assert_eq!(count("disk"), 20_000);
    assert_eq!(s.materials.len(), 3);
}

/// The x coordinates of the sphere centres, in scene order.
fn sphere_xs(s: &Scene) -> Vec<f64> {
    s.objects
        .iter()
        .map(|o| match o.shape {
            ShapeDecl::Sphere { center, .. } => o.transform.transform_point3(center).x,
            _ => panic!("not a sphere: {:?}", o.shape),
        })
        .collect()
}

/// `#switch`: `#case` by equality, `#range` inclusive at both ends; from the first match on,
/// every following clause and `#else` run untested until a `#break` (POV-Ray 3.7's
/// fall-through, checked against `povray` itself); `#else` also when nothing matched.
#[test]
fn switch_case_range_break_else() {
    let run = |v: &str| {
        sphere_xs(&scene(&format!(
            "#declare V = {v};
             #switch (V)
               #case (1) sphere {{ <1,0,0>, 1 }} #break
               #case (2) sphere {{ <2,0,0>, 1 }}
               #range (2, 3) sphere {{ <3,0,0>, 1 }}
                 #if (V == 3) #break #end
               #case (3) sphere {{ <4,0,0>, 1 }}
               #else sphere {{ <9,0,0>, 1 }}
             #end"
        )))
    };
    assert_eq!(run("1"), [1.0]);
    // Falls through from `#case (2)` into every later body, `#else` included.
    assert_eq!(run("2"), [2.0, 3.0, 4.0, 9.0]);
    // `#range` is inclusive; the `#break` inside an `#if` leaves the switch.
    assert_eq!(run("3"), [3.0]);
    assert_eq!(run("2.5"), [3.0, 4.0, 9.0]);
    assert_eq!(run("0.1 + 0.2 + 0.7"), [1.0], "equal within 1e-10");
    assert_eq!(run("7"), [9.0]);
    // A matching clause without `#break` falls into `#else` as well.
    let s = scene(
        "#switch (1) #case (1) sphere { <1,0,0>, 1 } #else sphere { <9,0,0>, 1 } #end
         #switch (5) #else sphere { <5,0,0>, 1 } #end",
    );
    assert_eq!(sphere_xs(&s), [1.0, 9.0, 5.0]);
}

/// `#break` leaves the innermost loop; inside a block or a macro body it refers to that body.
#[test]
fn break_leaves_loops() {
    let s = scene(
        "#for (I, 0, 10) #if (I > 2) #break #end sphere { <I,0,0>, 1 } #end
         #declare J = 10;
         #while (true) #declare J = J + 1; #if (J > 12) #break #end sphere { <J,0,0>, 1 } #end
         #for (K, 0, 1) union { #for (L, 0, 5) #if (L > 0) #break #end sphere { <20+K,0,0>, 1 } #end } #end",
    );
    assert_eq!(sphere_xs(&s), [0.0, 1.0, 2.0, 11.0, 12.0, 20.0, 21.0]);
}

/// `#ifdef`, `#ifndef` and `#undef`, with locals of a macro and globals.
#[test]
fn ifdef_ifndef_undef() {
    let s = scene(
        "#declare A = 1;
         #ifdef (A) sphere { <1,0,0>, 1 } #else sphere { <9,0,0>, 1 } #end
         #ifndef (B) sphere { <2,0,0>, 1 } #end
         #undef A
         #ifdef (A) sphere { <9,0,0>, 1 } #else sphere { <3,0,0>, 1 } #end
         #macro M(P) #ifdef (P) sphere { <P,0,0>, 1 } #end #undef P #ifndef (P) sphere { <5,0,0>, 1 } #end #end
         M(4)
         #ifdef (pi) sphere { <6,0,0>, 1 } #end",
    );
    assert_eq!(sphere_xs(&s), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
}

/// `#debug` and `#warning` reach the caller as diagnostics at the directive, in order, the
/// scene still loads; numbers are shown as written.
#[test]
fn debug_and_warning_messages() {
    let l = load(
        "#declare S = 0.1 + 0.2;
         #for (I, 1, 2) #debug \"step \" + str(I) #end
         #warning \"check this\"
         #debug <S, 1, 2>
         sphere { <0,0,0>, 1 }",
    );
    assert!(l.scene.is_some());
    let shown: Vec<(Severity, &str)> = l
        .diagnostics
        .iter()
        .map(|d| (d.severity, d.message.as_str()))
        .collect();
    assert_eq!(
        shown,
        [
            (Severity::Note, "step 1"),
            (Severity::Note, "step 2"),
            (Severity::Warning, "check this"),
            (Severity::Note, "<0.3, 1, 2>"),
        ]
    );
    let text = &l.sources.get(l.diagnostics[2].span.file).unwrap().text;
    let d = &l.diagnostics[2];
    assert_eq!(
        &text[d.span.start as usize..d.span.end as usize],
        "#warning \"check this\""
    );
}

/// `==` and `!=` take numbers within 1e-10 to be equal, as `#case` and POV-Ray do (a sum of
/// tenths reaches 1, a loop until it does ends); `str` shows a number as `#debug` does.
#[test]
fn equality_within_rounding_and_str_as_written() {
    let l = load(
        "#declare A = 0.1 + 0.2;
         #if (A == 0.3) #debug \"equal\" #end
         #if (A != 0.3) #debug \"not equal\" #end
         #if (A == 0.3000001) #debug \"too far\" #end
         #declare T = 0; #declare N = 0;
         #while (T != 1) #declare T = T + 0.1; #declare N = N + 1; #end
         #debug \"steps \" + str(N)
         #if (<A, 0, 1> == <0.3, 0, 1>) #debug \"vectors equal\" #end
         #debug str(A) + \" \" + str(-0.0) + \" \" + str(-1 * 0)
         sphere { <0,0,0>, 1 }",
    );
    let shown: Vec<&str> = l.diagnostics.iter().map(|d| d.message.as_str()).collect();
    assert_eq!(
        shown,
        ["equal", "steps 10", "vectors equal", "0.3 0 0"],
        "{}",
        sppm_lang::render_plain(&l.sources, &l.diagnostics, 100)
    );
}

/// A loop of `#debug` or `#warning` keeps the first messages and says the rest were left out:
/// bounded.
#[test]
fn debug_messages_are_bounded() {
    for kind in ["#debug", "#warning"] {
        let l = load(&format!(
            "#for (I, 1, 5000) {kind} str(I) #end sphere {{ <0,0,0>, 1 }}"
        ));
        assert_eq!(
            l.diagnostics.len(),
            sppm_lang::internals::eval::MAX_MESSAGES + 1
        );
        assert!(l.diagnostics.last().unwrap().message.contains("not shown"));
    }
}

/// The standard library is built in: its colours and materials are the documented values, and
/// its unused declarations give no warnings.
#[test]
fn standard_library_colors_and_materials() {
    let l = load(
        "#include \"std/colors.scn\"
         #include \"std/materials.scn\"
         sphere { <0,0,0>, 1 material { diffuse Orange } }
         sphere { <1,0,0>, 1 material { Glass_Crown } }
         sphere { <2,0,0>, 1 material { Metal_Gold } }
         sphere { <3,0,0>, 1 material { Diffuse_FreshSnow } }
         background Gray50",
    );
    assert!(l.diagnostics.is_empty(), "{:?}", l.diagnostics);
    let s = l.scene.unwrap();
    let m = |i: usize| s.material(s.objects[i].material).clone();
    assert_eq!(
        m(0),
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::new(1.0, 0.5, 0.0))
        }
    );
    assert!(matches!(m(1), Material::Glass { ior, .. } if ior == 1.5168));
    assert_eq!(
        m(2),
        Material::Mirror {
            tint: ColorParam::Const(DVec3::new(1.0, 0.766, 0.336))
        }
    );
    assert_eq!(
        m(3),
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::splat(0.8))
        }
    );
    assert!(matches!(s.background, Background::Color(c) if c == DVec3::splat(0.5)));
    // Only what is placed is stored: 4 materials, not the whole library.
    assert_eq!(s.materials.len(), 4);
    assert!(
        l.dependencies
            .iter()
            .all(|p| !p.to_string_lossy().contains("std/"))
    );
}

/// `mirror` is also a material keyword: `wrap mirror` was read as `wrap` with no value ("`wrap`
/// needs `repeat`, `clamp` or `mirror`"), though it is one of the three words it names.
#[test]
fn every_wrap_word_is_read_even_one_that_is_a_keyword() {
    for (word, want) in [
        ("repeat", Wrap::Repeat),
        ("clamp", Wrap::Clamp),
        ("mirror", Wrap::Mirror),
    ] {
        let s = scene(&format!(
            "sphere {{ <0, 0, 0>, 1 material {{ diffuse texture {{ \
             image \"examples/textures/world.png\" wrap {word} map spherical }} }} }}"
        ));
        match &s.textures[0].pattern {
            Pattern::Image { wrap, .. } => assert_eq!(*wrap, want, "wrap {word}"),
            p => panic!("wrap {word}: {p:?}"),
        }
        assert_eq!(s.textures[0].mapping, Mapping::Spherical, "wrap {word}");
    }
}

/// Directions of vectors far from unit length come out unit length: `vnormalize` and the
/// normals of planes and disks scale by the largest component before squaring (the squared
/// length of `<1e160, 0, 0>` overflows and that of `<1e-160, 0, 0>` underflows).
#[test]
fn directions_of_huge_and_tiny_vectors_are_unit() {
    let s = scene(
        "#declare A = vnormalize(<1e160, 1e160, 1e160>);\n\
         #declare B = vnormalize(<3e-162, 4e-162, 0>);\n\
         sphere { A, 1 }\n\
         sphere { B, 1 }\n\
         plane { <1e200, 0, 0>, 0 }\n\
         disk { <0, 0, 0>, <1e-200, 1e-200, 0>, 1 }\n",
    );
    let third = 1.0 / 3f64.sqrt();
    let mut found = 0;
    for o in &s.objects {
        match o.shape {
            ShapeDecl::Sphere { center, .. } => {
                let want = [DVec3::splat(third), DVec3::new(0.6, 0.8, 0.0)][found];
                assert!(close(center, want), "{center} != {want}");
                found += 1;
            }
            ShapeDecl::Plane { normal, .. } => assert!(close(normal, DVec3::X), "{normal}"),
            ShapeDecl::Disk { normal, .. } => {
                let h = 0.5f64.sqrt();
                assert!(close(normal, DVec3::new(h, h, 0.0)), "{normal}");
            }
            _ => {}
        }
    }
    assert_eq!(found, 2);
}

/// Small things a POV-Ray file does: lengths of tiny vectors (`vlength` scales as `vnormalize`
/// does: `<1e-200, 1e-200, 0>` once had length 0), a form feed between statements (whitespace,
/// as in POV-Ray), and `#debug` lines ending in `\n` (the message is that line, without an
/// empty one after it).
#[test]
fn tiny_lengths_form_feeds_and_debug_lines() {
    let l = load(
        "#declare L = vlength(<3e-200, 4e-200, 0>) * 1e200;\n\u{0C}\
         #debug \"L = \" + str(L) + \"\\n\"\n\
         sphere { <0, 0, 0>, L }\n",
    );
    let s = l.scene.unwrap_or_else(|| panic!("{:?}", l.diagnostics));
    match s.objects[0].shape {
        ShapeDecl::Sphere { radius, .. } => assert!((radius - 5.0).abs() < 1e-12, "{radius}"),
        ref other => panic!("{other:?}"),
    }
    assert_eq!(l.diagnostics[0].message, "L = 5");
}

/// A string literal longer than the strings a scene may build is refused at the literal (with
/// a memory limit that lets a file of its size be parsed).
#[test]
fn string_literals_beyond_the_string_limit_are_errors() {
    let text = format!(
        "#declare S = \"{}\";\nsphere {{ <0, 0, 0>, 1 }}\n",
        "a".repeat(sppm_lang::internals::eval::MAX_STRING_BYTES + 1)
    );
    let options = sppm_lang::EvalOptions {
        memory_limit: Some(4 << 30),
        ..Default::default()
    };
    let l = sppm_lang::internals::eval::load_source("test.scn", &text, &options);
    let e = l
        .diagnostics
        .iter()
        .find(|d| d.is_error())
        .expect("an error");
    assert!(e.message.contains("more than the limit"), "{}", e.message);
    assert_eq!(e.span.start as usize, "#declare S = ".len());
}

/// POV-Ray's `&` and `|` are `&&` and `||`, and its conditional `c ? a : b` groups to the right
/// and evaluates only the branch it takes; a chain too long to evaluate is refused like any
/// long expression.
#[test]
fn povray_logic_operators_and_the_conditional() {
    let l = load(
        "#declare A = true;\n#declare B = false;\n\
         #declare C = A & !B ? 2 : 3;\n\
         #declare D = B | false ? 10 : B ? 20 : 30;\n\
         #declare E = A ? 1 : 1 / 0;\n\
         sphere { <C, D, E>, (A | B ? 1 : 2) }\n",
    );
    let s = l.scene.unwrap_or_else(|| panic!("{:?}", l.diagnostics));
    match s.objects[0].shape {
        ShapeDecl::Sphere { center, radius } => {
            assert_eq!(center, DVec3::new(2.0, 30.0, 1.0));
            assert_eq!(radius, 1.0);
        }
        ref other => panic!("{other:?}"),
    }
    let chain = format!("#declare X = {}1;\n", "0 ? 1 : ".repeat(50_000));
    let l = load_source("chain.scn", &chain, &EvalOptions::default());
    let e: Vec<_> = l.diagnostics.iter().filter(|d| d.is_error()).collect();
    assert_eq!(e.len(), 1);
    assert!(
        e[0].message.contains("expression too long"),
        "{}",
        e[0].message
    );
}

/// A declared camera named inside a camera block, as POV-Ray writes it, is the block's start:
/// the properties after it change it.
#[test]
fn a_declared_camera_inside_a_camera_block_starts_it() {
    let s = scene(
        "#declare Cam = camera { location <1, 2, -3> look_at <0, 1, 0> fov 30 }\n\
         camera { Cam fov 50 }\n\
         sphere { <0, 0, 0>, 1 }\n",
    );
    assert_eq!(s.camera.location, DVec3::new(1.0, 2.0, -3.0));
    assert_eq!(s.camera.look_at, DVec3::new(0.0, 1.0, 0.0));
    assert_eq!(s.camera.fov, 50.0);
    // A declared camera starts from the defaults, not from the scene's camera so far (whose
    // depth of field it took, and whose look_at made this one look at its own location).
    let s = scene(
        "camera { location <0, 0, -10> look_at <0, 0, -5> aperture 0.5 focus_distance 2 }\n\
         #declare Side = camera { location <0, 0, -5> }\n\
         camera { Side }\n\
         sphere { <0, 0, 0>, 1 }\n",
    );
    assert_eq!(s.camera.look_at, DVec3::ZERO);
    assert_eq!(s.camera.aperture, 0.0);
    assert_eq!(s.camera.focus_distance, None);
    // After a property or another camera it would drop them: an error at it.
    for body in ["fov 50 Cam", "Cam Cam"] {
        let l = load_source(
            "t.scn",
            &format!("#declare Cam = camera {{ fov 30 }}\ncamera {{ {body} }}\n"),
            &EvalOptions::default(),
        );
        let e = l.diagnostics.iter().find(|d| d.is_error()).expect(body);
        assert!(e.message.contains("comes first"), "{body}: {}", e.message);
    }
}

/// A spotlight whose `point_at` is very close to it still has that direction (the difference
/// is scaled before it is normalised; its squared length underflowed to zero and the render
/// refused the light with a catch-all message).
#[test]
fn a_spotlight_aimed_at_a_very_close_point_has_that_direction() {
    let s = scene(
        "spotlight { <0, 0, 0> point_at <0, -1e-300, 0> intensity 10 }\n\
         plane { <0, 1, 0>, -2 }\n",
    );
    match &s.lights[0] {
        sppm_lang::internals::scene::LightDecl::Spot { direction, .. } => {
            assert_eq!(*direction, DVec3::NEG_Y)
        }
        other => panic!("{other:?}"),
    }
}

/// A conductor takes its index from a named metal (symbol or English name), from `eta` and
/// `extinction`, or from `reflectance` and `edge_tint` (mapped so that the normal-incidence
/// reflectance is the one written); roughness 0 is allowed (a polished metal) and an override
/// keeps the declared metal.
#[test]
fn conductors_take_a_metal_an_index_or_artist_colours() {
    let s = scene(
        "#declare Gold = material { conductor \"Au\" roughness 0.2 }
         sphere { <0, 0, 0>, 1 material { Gold } }
         sphere { <3, 0, 0>, 1 material { conductor \"copper\" } }
         sphere { <6, 0, 0>, 1 material { conductor eta rgb <0.2, 0.5, 1.4> extinction rgb <3, 2.4, 1.8> } }
         sphere { <9, 0, 0>, 1 material { conductor reflectance rgb <0.9, 0.6, 0.5> edge_tint rgb 1 roughness 0.5 } }
         sphere { <12, 0, 0>, 1 material { Gold roughness 0 } }",
    );
    let m = |i: usize| &s.materials[s.objects[i].material.0 as usize];
    let au = metals::metal("Au").unwrap();
    let cu = metals::metal("Cu").unwrap();
    let Material::Conductor { eta, k, roughness } = m(0) else {
        panic!("{:?}", m(0))
    };
    assert_eq!((*eta, *k, *roughness), (au.eta.into(), au.k.into(), 0.2));
    assert!(matches!(m(1), Material::Conductor { eta, roughness, .. }
        if *eta == DVec3::from(cu.eta) && *roughness == 0.0));
    assert!(matches!(m(2), Material::Conductor { eta, k, .. }
        if close(*eta, DVec3::new(0.2, 0.5, 1.4)) && close(*k, DVec3::new(3.0, 2.4, 1.8))));
    let Material::Conductor { eta, k, roughness } = m(3) else {
        panic!("{:?}", m(3))
    };
    let f0 = (*eta - 1.0) * (*eta - 1.0) + *k * *k;
    let f0 = f0 / ((*eta + 1.0) * (*eta + 1.0) + *k * *k);
    assert!(close(f0, DVec3::new(0.9, 0.6, 0.5)), "{f0}");
    assert_eq!(*roughness, 0.5);
    assert!(matches!(m(4), Material::Conductor { eta, roughness, .. }
        if *eta == DVec3::from(au.eta) && *roughness == 0.0));
}

/// `coated` gives a coated material: smooth without `roughness` (zero), the ior and roughness
/// as written; an override of a declared coated material keeps what it does not write.
#[test]
fn coated_materials_hold_their_parameters() {
    let s = scene(
        "#declare Varnish = material { coated rgb <0.6, 0.3, 0.1> ior 1.4 }
         sphere { <0, 0, 0>, 1 material { Varnish } }
         sphere { <3, 0, 0>, 1 material { Varnish roughness 0.2 } }
         sphere { <6, 0, 0>, 1 material { coated rgb <0.8, 0.1, 0.1> ior 1.5 roughness 0.1 } }",
    );
    let coats: Vec<_> = s
        .materials
        .iter()
        .filter_map(|m| match m {
            Material::Coated {
                albedo: ColorParam::Const(a),
                ior,
                roughness: ScalarParam::Const(r),
            } => Some((*a, *ior, *r)),
            _ => None,
        })
        .collect();
    assert_eq!(coats.len(), 3, "{:?}", s.materials);
    assert!(close(coats[0].0, DVec3::new(0.6, 0.3, 0.1)));
    assert_eq!((coats[0].1, coats[0].2), (1.4, 0.0));
    assert!(close(coats[1].0, DVec3::new(0.6, 0.3, 0.1)));
    assert_eq!((coats[1].1, coats[1].2), (1.4, 0.2));
    assert!(close(coats[2].0, DVec3::new(0.8, 0.1, 0.1)));
    assert_eq!((coats[2].1, coats[2].2), (1.5, 0.1));
}

/// The animation names read the frame the caller sets (`EvalOptions::frame`), as POV-Ray's do:
/// the clock runs from the initial to the final clock over the frames, one `clock_delta` per
/// frame; a still reads 0 everywhere and `clock_on` false.
#[test]
fn animation_names_read_the_frame_being_evaluated() {
    let text = "#declare Values = [clock, clock_delta, frame_number, initial_clock, \
                final_clock, initial_frame, final_frame, (clock_on ? 1 : 0)];\n\
                sphere { <clock * 4, 0, 0>, 1 }\n\
                settings { resolution <8, 8> frames 10, 14 clock_range 2, 4 }\n";
    let at = |frame: Option<Frame>| {
        let options = EvalOptions {
            frame,
            ..EvalOptions::default()
        };
        let l = load_source("anim.scn", text, &options);
        assert!(!l.has_errors(), "{:?}", l.diagnostics);
        assert!(l.animated, "the scene reads `clock`");
        let s = l.scene.unwrap();
        let ShapeDecl::Sphere { center, .. } = s.objects[0].shape else {
            panic!("{:?}", s.objects[0].shape)
        };
        (center.x / 4.0, s)
    };
    let (still_clock, still) = at(None);
    assert_eq!(still_clock, 0.0);
    let range = sppm_lang::internals::eval::frame_range(&still.settings, &Default::default())
        .unwrap()
        .expect("the scene declares frames");
    assert_eq!((range.first, range.last), (10, 14));
    assert_eq!((range.initial_clock, range.final_clock), (2.0, 4.0));
    let clocks: Vec<f64> = range.frames().map(|k| at(range.frame(k)).0).collect();
    assert_eq!(clocks, [2.0, 2.5, 3.0, 3.5, 4.0]);
    // Every value, through `#debug`-free reading of the declared array via a second scene.
    let probe = |frame: Option<Frame>| -> Vec<f64> {
        let options = EvalOptions {
            frame,
            ..EvalOptions::default()
        };
        let l = load_source(
            "probe.scn",
            &format!(
                "{text}#declare I = 0;\n#while (I < 8) sphere {{ <Values[I], 0, 0>, 1 }} \
                 #declare I = I + 1; #end\n"
            ),
            &options,
        );
        let s = l.scene.expect("scene");
        s.objects[1..]
            .iter()
            .map(|o| match o.shape {
                ShapeDecl::Sphere { center, .. } => center.x,
                _ => f64::NAN,
            })
            .collect()
    };
    assert_eq!(probe(None), [0.0; 8]);
    assert_eq!(
        probe(range.frame(11)),
        [2.5, 0.5, 11.0, 2.0, 4.0, 10.0, 14.0, 1.0]
    );
}

/// A scene that reads no animation name is the same in every frame (`load_frame` reuses the
/// still); one whose frame range depends on the clock is refused at its settings.
#[test]
fn a_frame_reloads_only_what_the_clock_changes() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let over = sppm_lang::internals::eval::RangeOverride::default();
    let options = EvalOptions::default();
    let fixed = write(
        "fixed.scn",
        "sphere { <0, 0, 0>, 1 } settings { frames 0, 3 }\n",
    );
    let still = load_file(&fixed, &options).unwrap();
    assert!(!still.animated);
    let range =
        sppm_lang::internals::eval::frame_range(&still.scene.as_ref().unwrap().settings, &over)
            .unwrap()
            .unwrap();
    let frame =
        sppm_lang::internals::eval::load_frame(&fixed, &options, &still, &over, &range, 2).unwrap();
    assert_eq!(format!("{:?}", frame.scene), format!("{:?}", still.scene));
    let moving = write(
        "moving.scn",
        "sphere { <0, 0, 0>, 1 } settings { frames 0, 3 + (clock > 0 ? 1 : 0) }\n",
    );
    let still = load_file(&moving, &options).unwrap();
    assert!(still.animated);
    let range =
        sppm_lang::internals::eval::frame_range(&still.scene.as_ref().unwrap().settings, &over)
            .unwrap()
            .unwrap();
    assert_eq!(range.last, 3);
    // Frame 0 has clock 0, as the still: the same range, accepted.
    let first = sppm_lang::internals::eval::load_frame(&moving, &options, &still, &over, &range, 0)
        .unwrap();
    assert!(!first.has_errors(), "{:?}", first.diagnostics);
    let later = sppm_lang::internals::eval::load_frame(&moving, &options, &still, &over, &range, 2)
        .unwrap();
    assert!(later.scene.is_none());
    let text = sppm_lang::render_plain(&later.sources, &later.diagnostics, 100);
    assert!(
        text.contains("the frame range changes with the frame"),
        "{text}"
    );
}
