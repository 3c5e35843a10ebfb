//! The library's render options are range-checked by the render itself, not only by the command
//! line: a caller passing absurd overrides gets an error, never a panic, a hang or a huge
//! allocation.

use crate::common;

use std::sync::atomic::AtomicBool;

use common::{add_material, add_object, furnace_emitting};
use glam::{DVec2, DVec3};
use sppm_lang::Span;
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::scene::{
    ColorParam, IntersectMethod, LightDecl, Material, Profile, ScalarParam, Scene, ShapeDecl,
    TextureId,
};

#[test]
fn absurd_overrides_are_errors() {
    let scene = furnace_emitting(4);
    let cases = [
        (
            "iterations",
            RenderOptions {
                iterations: Some(0),
                ..Default::default()
            },
        ),
        (
            "iterations",
            RenderOptions {
                iterations: Some(u32::MAX),
                ..Default::default()
            },
        ),
        (
            "photons",
            RenderOptions {
                photons: Some(u64::MAX),
                ..Default::default()
            },
        ),
        (
            "threads",
            RenderOptions {
                threads: Some(0),
                ..Default::default()
            },
        ),
        (
            "threads",
            RenderOptions {
                threads: Some(usize::MAX),
                ..Default::default()
            },
        ),
        (
            "time limit",
            RenderOptions {
                time_limit: Some(f64::NAN),
                ..Default::default()
            },
        ),
        (
            "time limit",
            RenderOptions {
                time_limit: Some(-1.0),
                ..Default::default()
            },
        ),
    ];
    for (what, opts) in cases {
        let err = render(&scene, &opts, &AtomicBool::new(false), &mut |_| {})
            .err()
            .unwrap_or_else(|| panic!("{opts:?} was accepted"));
        assert!(err.to_string().contains(what), "{opts:?}: {err}");
    }
    // In range, the same overrides render.
    let ok = RenderOptions {
        iterations: Some(1),
        photons: Some(1000),
        threads: Some(1),
        ..Default::default()
    };
    let out = render(&scene, &ok, &AtomicBool::new(false), &mut |_| {}).unwrap();
    assert_eq!(out.iterations_done, 1);
}

/// The error `render` gives for `scene` with default options (panics if it renders).
fn refused(scene: &Scene) -> String {
    match render(
        scene,
        &RenderOptions::default(),
        &AtomicBool::new(false),
        &mut |_| {},
    ) {
        Ok(_) => panic!("accepted"),
        Err(e) => {
            assert!(e.help.is_some(), "{e}: no help");
            e.to_string()
        }
    }
}

/// A scene built by hand holds any count: its own settings are checked like the options (the
/// language refuses the same numbers). Before, `iterations: u32::MAX` or `photons: u64::MAX`
/// rendered for ever and `iterations: 0` rendered nothing without a word.
#[test]
fn absurd_settings_of_a_hand_built_scene_are_errors() {
    type Breaks = fn(&mut Scene);
    let cases: [(&str, Breaks); 6] = [
        ("iterations", |s| s.settings.iterations = u32::MAX),
        ("iterations", |s| s.settings.iterations = 0),
        ("photons", |s| s.settings.photons = Some(u64::MAX)),
        ("radius scale", |s| s.settings.radius_scale = f64::NAN),
        ("radius scale", |s| s.settings.radius_scale = 0.0),
        ("radius scale", |s| s.settings.radius_scale = f64::INFINITY),
    ];
    for (what, break_it) in cases {
        let mut scene = furnace_emitting(4);
        break_it(&mut scene);
        let err = refused(&scene);
        assert!(err.contains(what), "{what}: {err}");
    }
    // With a time limit to end it, the scene's iteration count may be as large as it likes.
    let mut scene = furnace_emitting(4);
    scene.settings.iterations = u32::MAX;
    scene.settings.time_limit = Some(0.2);
    scene.settings.photons = Some(1000);
    render(
        &scene,
        &RenderOptions::default(),
        &AtomicBool::new(false),
        &mut |_| {},
    )
    .unwrap();
}

/// A material may name a texture the scene does not have (it panicked on an index out of
/// bounds), and a curved shape may ask Newton's method for 2^32 iterations from 2^32 starts
/// per ray (it never finished); both are refused before rendering.
#[test]
fn a_missing_texture_or_an_endless_newton_method_is_an_error() {
    let textures: [fn(TextureId) -> Material; 3] = [
        |t| Material::Diffuse {
            albedo: ColorParam::Texture(t),
        },
        |t| Material::Glass {
            ior: 1.5,
            absorb: ColorParam::Texture(t),
            tint: DVec3::ONE,
            roughness: ScalarParam::Const(0.0),
        },
        |t| Material::Glossy {
            albedo: ColorParam::Const(DVec3::splat(0.5)),
            specular: ColorParam::Const(DVec3::splat(0.5)),
            roughness: ScalarParam::Texture(t),
        },
    ];
    for material in textures {
        let mut scene = furnace_emitting(4);
        scene.materials.push(material(TextureId(5)));
        let err = refused(&scene);
        assert!(err.contains("texture 5"), "{err}");
    }
    let newton = IntersectMethod::Newton {
        iterations: u32::MAX,
        starts: u32::MAX,
    };
    let shapes = [
        ShapeDecl::Revolve {
            profile: Profile {
                segments: vec![vec![DVec2::new(0.5, -0.5), DVec2::new(0.5, 0.5)]],
            },
            sweep: None,
            method: newton,
        },
        ShapeDecl::BezierPatch {
            points: Box::new(std::array::from_fn(|i| {
                DVec3::new((i / 4) as f64 * 0.2, (i % 4) as f64 * 0.2, 0.5)
            })),
            method: newton,
        },
    ];
    for shape in shapes {
        let mut scene = furnace_emitting(4);
        let m = add_material(
            &mut scene,
            Material::Diffuse {
                albedo: ColorParam::Const(DVec3::splat(0.5)),
            },
        );
        add_object(&mut scene, shape, m, None);
        let err = refused(&scene);
        assert!(err.contains("Newton"), "{err}");
    }
}

/// A spot light's angles as the language bounds them: a cone of 200 degrees (more than all
/// directions) or a falloff outside the cone rendered without a word; a NaN intensity is
/// refused with a fix.
#[test]
fn a_spot_light_out_of_the_language_s_bounds_is_an_error() {
    let aimed =
        |direction: DVec3, cone_angle: f64, falloff_angle: f64, intensity: f64| LightDecl::Spot {
            position: DVec3::new(0.0, 0.5, 0.0),
            direction,
            intensity: DVec3::splat(intensity),
            cone_angle,
            falloff_angle,
            span: Span::detached(),
        };
    let spot = |cone_angle, falloff_angle, intensity| {
        aimed(DVec3::NEG_Y, cone_angle, falloff_angle, intensity)
    };
    for light in [
        spot(200.0, 100.0, 1.0),
        spot(0.0, 0.0, 1.0),
        spot(30.0, 40.0, 1.0),
        spot(30.0, -1.0, 1.0),
        spot(30.0, 20.0, f64::NAN),
    ] {
        let mut scene = furnace_emitting(4);
        scene.lights.push(light);
        let err = refused(&scene);
        assert!(err.contains("spot light"), "{err}");
    }
    let mut scene = furnace_emitting(4);
    scene.lights.push(spot(90.0, 90.0, 1.0));
    let ok = RenderOptions {
        iterations: Some(1),
        photons: Some(1000),
        ..Default::default()
    };
    render(&scene, &ok, &AtomicBool::new(false), &mut |_| {}).unwrap();
    // A direction too short for f32 (or to square) is still a direction: the light shines
    // down, as the unit one does (it was zero in f32, and the light's direction NaN).
    let mean = |direction: DVec3| {
        let mut scene = furnace_emitting(4);
        scene.lights.push(aimed(direction, 60.0, 30.0, 1.0));
        let out = render(&scene, &ok, &AtomicBool::new(false), &mut |_| {}).unwrap();
        out.image.mean()
    };
    assert_eq!(mean(DVec3::NEG_Y * 1e-200), mean(DVec3::NEG_Y));
    let mut scene = furnace_emitting(4);
    scene.lights.push(aimed(DVec3::ZERO, 60.0, 30.0, 1.0));
    assert!(refused(&scene).contains("spot light"));
}

/// The prepared scene's queries take any ray and any primitive number a caller gives: a ray
/// with an infinite or NaN component meets nothing (it panicked in the BVH's leaf), and a
/// primitive number no primitive has has no material (it panicked on the index).
#[test]
fn queries_with_non_finite_rays_or_unknown_primitives_do_not_panic() {
    use glam::Vec3A;
    use sppm_lang::internals::geometry::Ray;
    use sppm_lang::internals::prepare::PreparedScene;
    let l = sppm_lang::internals::eval::load_source(
        "q.scn",
        "triangle { <0,0,0>, <1,0,0>, <0,1,0> }\nsphere { <3, 0, 0>, 1 }\n",
        &sppm_lang::EvalOptions::default(),
    );
    let scene = l.scene.expect("the scene loads");
    let prepared = PreparedScene::new(&scene).expect("it prepares");
    let o = Vec3A::new(0.2, 0.2, -5.0);
    // The ray that works, then every kind of non-finite component in origin and direction.
    let good = Ray::new(o, Vec3A::Z);
    let hit = prepared
        .intersect(&good, f32::INFINITY)
        .expect("the triangle is hit");
    assert!(prepared.occluded(&good, f32::INFINITY));
    assert!(prepared.material(hit.prim).is_some());
    for bad in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
        for (i, k) in [0, 1, 2].into_iter().enumerate() {
            let mut d = Vec3A::Z.to_array();
            d[k] = bad;
            let mut p = o.to_array();
            p[(k + i) % 3] = bad;
            for ray in [
                Ray::new(o, Vec3A::from_array(d)),
                Ray::new(Vec3A::from_array(p), Vec3A::Z),
                Ray::new(o, Vec3A::splat(bad)),
            ] {
                assert!(prepared.intersect(&ray, f32::INFINITY).is_none(), "{ray:?}");
                assert!(!prepared.occluded(&ray, f32::INFINITY), "{ray:?}");
            }
        }
    }
    // A primitive number no primitive has.
    assert!(prepared.material(u32::MAX).is_none());
    let made_up = sppm_lang::internals::prepare::SurfaceHit {
        prim: u32::MAX,
        ..hit
    };
    let _ = prepared.bsdf(&made_up);
    assert!(prepared.absorption(&made_up).is_none());
}

/// Materials, emission, lights, textures and the background of a hand-built scene get the
/// language's ranges: a glass of index 0 or NaN, a NaN albedo, a radiance of 1e308 (it
/// rendered black: its power overflowed), an empty colour map (it panicked) or a noise of
/// 2^32 octaves (it never finished a texture lookup) are refused, each naming what is wrong.
#[test]
fn appearance_values_outside_the_language_s_ranges_are_errors() {
    use sppm_lang::internals::scene::{Background, ColorMap, Mapping, Pattern, Texture};
    let c = |x: f64| ColorParam::Const(DVec3::splat(x));
    let glass = |ior: f64, absorb: f64, tint: f64| Material::Glass {
        ior,
        absorb: c(absorb),
        tint: DVec3::splat(tint),
        roughness: ScalarParam::Const(0.0),
    };
    let glossy = |specular: f64, roughness: f64| Material::Glossy {
        albedo: c(0.5),
        specular: c(specular),
        roughness: ScalarParam::Const(roughness),
    };
    let materials = [
        ("ior", glass(0.0, 0.0, 1.0)),
        ("ior", glass(f64::NAN, 0.0, 1.0)),
        ("ior", glass(1e6, 0.0, 1.0)),
        ("absorb", glass(1.5, -1.0, 1.0)),
        ("tint", glass(1.5, 0.0, f64::NAN)),
        (
            "albedo",
            Material::Diffuse {
                albedo: c(f64::NAN),
            },
        ),
        ("albedo", Material::Diffuse { albedo: c(-0.5) }),
        (
            "tint",
            Material::Mirror {
                tint: c(f64::INFINITY),
            },
        ),
        ("specular", glossy(f64::NAN, 0.2)),
        ("roughness", glossy(0.04, 0.0)),
        ("roughness", glossy(0.04, f64::NAN)),
        ("roughness", glossy(0.04, 2.0)),
        (
            "roughness",
            Material::Glass {
                ior: 1.5,
                absorb: c(0.0),
                tint: DVec3::ONE,
                roughness: ScalarParam::Const(f64::NAN),
            },
        ),
        (
            "roughness",
            Material::Glass {
                ior: 1.5,
                absorb: c(0.0),
                tint: DVec3::ONE,
                roughness: ScalarParam::Const(-0.1),
            },
        ),
        (
            "ior",
            Material::ThinGlass {
                ior: 0.5,
                tint: DVec3::ONE,
            },
        ),
        (
            "tint",
            Material::ThinGlass {
                ior: 1.5,
                tint: DVec3::splat(f64::NAN),
            },
        ),
    ];
    for (what, material) in materials {
        let mut scene = furnace_emitting(4);
        scene.materials[0] = material.clone();
        let err = refused(&scene);
        assert!(err.contains(what), "{material:?}: {err}");
    }
    for radiance in [1e308, f64::NAN, -1.0] {
        let mut scene = furnace_emitting(4);
        scene.objects[0].emission.as_mut().unwrap().radiance = DVec3::new(1.0, radiance, 1.0);
        let err = refused(&scene);
        assert!(err.contains("radiance"), "{radiance}: {err}");
    }
    let mut scene = furnace_emitting(4);
    scene.lights.push(LightDecl::Point {
        position: DVec3::ZERO,
        intensity: DVec3::splat(1e308),
        span: Span::detached(),
    });
    assert!(refused(&scene).contains("intensity"));
    for bg in [f64::NAN, -1.0, 1e300] {
        let mut scene = furnace_emitting(4);
        scene.background = Background::Color(DVec3::splat(bg));
        let err = refused(&scene);
        assert!(err.contains("background"), "{bg}: {err}");
    }
    let map = |entries: &[(f64, f64)]| {
        ColorMap(entries.iter().map(|&(p, v)| (p, DVec3::splat(v))).collect())
    };
    let good = || map(&[(0.0, 0.0), (1.0, 1.0)]);
    let patterns = [
        (
            "color map",
            Pattern::Noise {
                map: map(&[]),
                octaves: 6,
            },
        ),
        (
            "color map",
            Pattern::Noise {
                map: map(&[(f64::NAN, 0.5), (1.0, 1.0)]),
                octaves: 6,
            },
        ),
        (
            "color map",
            Pattern::Noise {
                map: map(&[(0.0, f64::NAN), (1.0, 1.0)]),
                octaves: 6,
            },
        ),
        (
            "color map",
            Pattern::Noise {
                map: map(&[(1.0, 0.0), (0.0, 1.0)]),
                octaves: 6,
            },
        ),
        (
            "octaves",
            Pattern::Noise {
                map: good(),
                octaves: u32::MAX,
            },
        ),
        (
            "octaves",
            Pattern::Wood {
                map: good(),
                turbulence: 1.0,
                octaves: 0,
            },
        ),
        (
            "turbulence",
            Pattern::Marble {
                map: good(),
                turbulence: f64::NAN,
                octaves: 6,
            },
        ),
        (
            "turbulence",
            Pattern::Marble {
                map: good(),
                turbulence: -1.0,
                octaves: 6,
            },
        ),
        (
            "color",
            Pattern::Checker {
                a: DVec3::splat(f64::NAN),
                b: DVec3::ONE,
            },
        ),
        (
            "color",
            Pattern::Stripes {
                a: DVec3::ONE,
                b: DVec3::splat(-1.0),
            },
        ),
        (
            "gradient",
            Pattern::Gradient {
                direction: DVec3::ZERO,
                map: good(),
            },
        ),
        (
            "brick",
            Pattern::Brick {
                brick: DVec3::ONE,
                mortar: DVec3::ZERO,
                size: DVec3::new(0.2, 0.0, 0.1),
                mortar_width: 0.01,
            },
        ),
        (
            "mortar",
            Pattern::Brick {
                brick: DVec3::ONE,
                mortar: DVec3::ZERO,
                size: DVec3::new(0.2, 0.075, 0.1),
                mortar_width: f64::NAN,
            },
        ),
    ];
    let texture = |pattern: Pattern| Texture {
        pattern,
        mapping: Mapping::Solid,
        transform: glam::DAffine3::IDENTITY,
        span: Span::detached(),
    };
    for (what, pattern) in patterns {
        let mut scene = furnace_emitting(4);
        scene.textures.push(texture(pattern.clone()));
        scene.materials[0] = Material::Diffuse {
            albedo: ColorParam::Texture(TextureId(0)),
        };
        let err = refused(&scene);
        assert!(err.contains(what), "{pattern:?}: {err}");
    }
    let mut scene = furnace_emitting(4);
    let mut t = texture(Pattern::Noise {
        map: good(),
        octaves: 6,
    });
    t.transform.translation.x = f64::NAN;
    scene.textures.push(t);
    assert!(refused(&scene).contains("transform"));
    // The same textures in range render.
    let mut scene = furnace_emitting(4);
    scene.textures.push(texture(Pattern::Marble {
        map: good(),
        turbulence: 2.0,
        octaves: 16,
    }));
    scene.materials[0] = Material::Diffuse {
        albedo: ColorParam::Texture(TextureId(0)),
    };
    let ok = RenderOptions {
        iterations: Some(1),
        photons: Some(1000),
        ..Default::default()
    };
    render(&scene, &ok, &AtomicBool::new(false), &mut |_| {}).unwrap();
}

/// A bezier patch whose control points all lie at one point or on one line draws nothing: it
/// is refused as a zero-area quad is (it rendered nothing without a word).
#[test]
fn a_bezier_patch_without_area_is_an_error() {
    let flat_line = |i: usize| DVec3::new(i as f64 * 0.1, 0.0, 0.5);
    for points in [
        [DVec3::new(0.0, 0.0, 0.5); 16],
        std::array::from_fn(flat_line),
    ] {
        let mut scene = furnace_emitting(4);
        let m = add_material(
            &mut scene,
            Material::Diffuse {
                albedo: ColorParam::Const(DVec3::splat(0.5)),
            },
        );
        let shape = ShapeDecl::BezierPatch {
            points: Box::new(points),
            method: IntersectMethod::Robust,
        };
        add_object(&mut scene, shape, m, None);
        let err = refused(&scene);
        assert!(err.contains("no area"), "{err}");
    }
}

/// A PNG of one colour, `w` by `h` pixels, made in memory.
fn png_of(rgb: [u8; 3]) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(2, 2, image::Rgb(rgb));
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .unwrap();
    bytes
}

/// A scene whose include and floor image exist only in memory: the include sets the resolution
/// and the light, the image colours the floor that fills the view.
fn memory_world(floor: [u8; 3]) -> sppm_lang::MemoryWorld {
    let scene = r#"
        #include "parts/setup.scn"
        settings { resolution <W, H>  iterations 2  photons 5000  seed 3 }
        camera { location <0, 3, 0.01>  look_at <0, 0, 0>  fov 40 }
        quad { <-4, 0, -4>, <8, 0, 0>, <0, 0, 8>
               material { diffuse texture { image "maps/floor.png" } } }
    "#;
    let setup = r#"
        #declare W = 20;
        #declare H = 14;
        area_light { quad { <-1, 4, -1>, <2, 0, 0>, <0, 0, 2> }  radiance rgb <6, 6, 6> }
    "#;
    sppm_lang::MemoryWorld::new()
        .with("memory-only/scene.scn", scene)
        .with("memory-only/parts/setup.scn", setup)
        .with("memory-only/maps/floor.png", png_of(floor))
}

fn mean(image: &sppm_lang::Image) -> [f64; 3] {
    let n = image.pixels.len() as f64;
    image
        .pixels
        .iter()
        .fold([0.0; 3], |m, p| [m[0] + p[0], m[1] + p[1], m[2] + p[2]])
        .map(|c| c / n)
}

#[test]
fn a_scene_its_include_and_its_image_load_and_render_from_memory() {
    let main = std::path::Path::new("memory-only/scene.scn");
    assert!(!main.exists(), "the test needs files that are not on disk");
    let render = |floor: [u8; 3], options: &sppm_lang::RenderOptions| {
        let load_options = sppm_lang::EvalOptions {
            world: sppm_lang::SharedWorld::new(memory_world(floor)),
            ..Default::default()
        };
        let document = sppm_lang::load(main, &load_options).unwrap_or_else(|f| panic!("{f}"));
        for dep in ["memory-only/parts/setup.scn", "memory-only/maps/floor.png"] {
            assert!(
                document
                    .dependencies
                    .iter()
                    .any(|d| d.ends_with(dep) || d == std::path::Path::new(dep)),
                "{dep} not read: {:?}",
                document.dependencies
            );
            assert!(!std::path::Path::new(dep).exists());
        }
        let prepared = sppm_lang::prepare(&document, options).unwrap_or_else(|f| panic!("{f}"));
        let rendered = sppm_lang::render(&prepared).unwrap_or_else(|f| panic!("{f}"));
        assert_eq!(options.cancel.progress(), (2, 2));
        rendered
    };
    // The include's resolution is used; the image's colour reaches the picture.
    let red = render([230, 20, 20], &Default::default());
    assert_eq!((red.image.width, red.image.height), (20, 14));
    let [r, g, b] = mean(&red.image);
    assert!(r > 4.0 * g && r > 4.0 * b, "red floor gave {r} {g} {b}");
    let green = render([20, 230, 20], &Default::default());
    let [r, g, b] = mean(&green.image);
    assert!(g > 4.0 * r && g > 4.0 * b, "green floor gave {r} {g} {b}");
    // The options override the scene's settings without editing it.
    let options = sppm_lang::RenderOptions {
        resolution: Some((8, 6)),
        integrator: Some(sppm_lang::Integrator::Path),
        ..Default::default()
    };
    let small = render([230, 20, 20], &options);
    assert_eq!((small.image.width, small.image.height), (8, 6));
}

#[test]
fn a_file_missing_from_memory_is_a_diagnostic_at_its_include() {
    let world = sppm_lang::MemoryWorld::new().with("main.scn", "#include \"gone.scn\"\n");
    let load_options = sppm_lang::EvalOptions {
        world: sppm_lang::SharedWorld::new(world),
        ..Default::default()
    };
    let failure = sppm_lang::load(std::path::Path::new("main.scn"), &load_options).unwrap_err();
    let e = &failure.diagnostics[0];
    assert!(
        e.message.contains("cannot read included file `gone.scn`"),
        "{}",
        e.message
    );
    assert_eq!(failure.sources.snippet(e.span), "\"gone.scn\"");
    let missing = sppm_lang::load(std::path::Path::new("other.scn"), &load_options).unwrap_err();
    assert!(missing.to_string().contains("other.scn"), "{missing}");
}

/// The three calls report in one type, `Diagnostic`: a warning of the prepared scene comes back
/// in `Prepared::warnings` as a warning (not an error), a refused override as an error at the
/// `settings` block that the option overrides, a missing scene file as an error at no place, and
/// the caller's cancel as the one diagnostic `interrupted` with its flag set.
#[test]
fn the_three_calls_report_in_one_type() {
    use sppm_lang::SharedWorld;
    use sppm_lang::{Cancel, EvalOptions, MemoryWorld, Severity};
    use std::path::Path;
    // No light: legal, but it renders black (a warning at no place).
    let text = "settings { resolution 8, 8 }\ncamera { location <0, 0, 3> look_at <0, 0, 0> }\n\
                sphere { <0, 0, 0>, 1 material { diffuse rgb <0.5, 0.5, 0.5> } }\n";
    let options = EvalOptions {
        world: SharedWorld::new(MemoryWorld::new().with("dark.scn", text)),
        ..EvalOptions::default()
    };
    let document = sppm_lang::load(Path::new("dark.scn"), &options).expect("loads");
    let prepared = sppm_lang::prepare(&document, &RenderOptions::default()).expect("prepares");
    let no_light: Vec<_> = prepared
        .warnings
        .iter()
        .filter(|w| w.message.contains("no light"))
        .collect();
    assert_eq!(no_light.len(), 1, "{:?}", prepared.warnings);
    assert_eq!(no_light[0].severity, Severity::Warning);
    assert!(!no_light[0].is_placed());

    let too_many = RenderOptions {
        iterations: Some(0),
        ..Default::default()
    };
    let failure = sppm_lang::prepare(&document, &too_many)
        .err()
        .expect("0 iterations are refused");
    assert!(!failure.interrupted);
    let [e] = failure.diagnostics.as_slice() else {
        panic!("{:?}", failure.diagnostics)
    };
    assert_eq!(e.severity, Severity::Error);
    assert!(e.message.contains("iterations"), "{}", e.message);
    assert_eq!(e.span, document.settings().span);
    assert!(e.is_placed());

    let missing = sppm_lang::load(Path::new("missing.scn"), &options)
        .expect_err("a missing file is an error");
    let [e] = missing.diagnostics.as_slice() else {
        panic!("{:?}", missing.diagnostics)
    };
    assert!(e.is_error() && !e.is_placed(), "{e:?}");
    assert!(e.message.contains("missing.scn"), "{}", e.message);

    let cancel = Cancel::new();
    cancel.cancel();
    let stopped = RenderOptions {
        cancel,
        ..Default::default()
    };
    let failure = sppm_lang::prepare(&document, &stopped)
        .err()
        .expect("a cancelled prepare stops");
    assert!(failure.interrupted);
    assert_eq!(failure.diagnostics.len(), 1);
    assert!(failure.diagnostics[0].interrupted);
    assert_eq!(failure.diagnostics[0].message, "interrupted");
}
