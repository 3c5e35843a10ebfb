//! Scenes built directly in Rust for the renderer tests and the benchmark.
#![allow(dead_code)]

use glam::{DAffine3, DVec3, Vec3A};
use std::sync::atomic::AtomicBool;

use sppm_lang::Image;
use sppm_lang::Span;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::sampling::{Rng, uniform_sphere};
use sppm_lang::internals::scene::{
    Background, Camera, ColorParam, Emission, LightDecl, Material, MaterialId, Object, ScalarParam,
    Scene, Settings, ShapeDecl,
};

pub fn empty_scene(res: (u32, u32)) -> Scene {
    Scene {
        settings: Settings {
            resolution: res,
            ..Settings::default()
        },
        camera: Camera::default(),
        objects: Vec::new(),
        lights: Vec::new(),
        materials: Vec::new(),
        textures: Vec::new(),
        background: Background::Color(DVec3::ZERO),
        backdrop: None,
    }
}

pub fn add_material(s: &mut Scene, m: Material) -> MaterialId {
    s.materials.push(m);
    MaterialId(s.materials.len() as u32 - 1)
}

pub fn diffuse(s: &mut Scene, albedo: f64) -> MaterialId {
    add_material(
        s,
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::splat(albedo)),
        },
    )
}

pub fn add_object(
    s: &mut Scene,
    shape: ShapeDecl,
    material: MaterialId,
    emission: Option<Emission>,
) {
    s.objects.push(Object {
        shape,
        transform: DAffine3::IDENTITY,
        material,
        emission,
        span: Span::detached(),
    });
}

pub fn sphere(center: DVec3, radius: f64) -> ShapeDecl {
    ShapeDecl::Sphere { center, radius }
}

/// A clear glass of index 1.5 and a white mirror, both lossless.
pub fn glass_and_mirror(s: &mut Scene) -> (MaterialId, MaterialId) {
    let glass = add_material(
        s,
        Material::Glass {
            ior: 1.5,
            absorb: ColorParam::Const(DVec3::ZERO),
            tint: DVec3::ONE,
            roughness: ScalarParam::Const(0.0),
        },
    );
    let mirror = add_material(
        s,
        Material::Mirror {
            tint: ColorParam::Const(DVec3::ONE),
        },
    );
    (glass, mirror)
}

/// Camera at the center of a unit sphere, looking along +z.
pub fn inside_camera() -> Camera {
    Camera {
        location: DVec3::ZERO,
        look_at: DVec3::Z,
        up: DVec3::Y,
        fov: 90.0,
        orthographic: false,
        aperture: 0.0,
        focus_distance: None,
        right: None,
        span: sppm_lang::Span::detached(),
    }
}

/// Furnace (a): a unit sphere, diffuse albedo 0.5 inside, emitting radiance 0.5.
pub fn furnace_emitting(res: u32) -> Scene {
    let mut s = empty_scene((res, res));
    let m = diffuse(&mut s, 0.5);
    add_object(
        &mut s,
        sphere(DVec3::ZERO, 1.0),
        m,
        Some(Emission {
            radiance: DVec3::splat(0.5),
            two_sided: true,
        }),
    );
    s.camera = inside_camera();
    s
}

/// Furnace (b): the same sphere, not emitting, a point light of intensity pi at the center.
pub fn furnace_point(res: u32) -> Scene {
    let mut s = empty_scene((res, res));
    let m = diffuse(&mut s, 0.5);
    add_object(&mut s, sphere(DVec3::ZERO, 1.0), m, None);
    s.lights.push(LightDecl::Point {
        position: DVec3::ZERO,
        intensity: DVec3::splat(std::f64::consts::PI),
        span: Span::detached(),
    });
    s.camera = inside_camera();
    s
}

/// Furnace (c): a diffuse sphere of albedo `a` inside a black enclosure emitting radiance 1.
pub fn furnace_enclosure(res: u32, a: f64) -> Scene {
    let mut s = empty_scene((res, res));
    let black = diffuse(&mut s, 0.0);
    let grey = diffuse(&mut s, a);
    add_object(
        &mut s,
        sphere(DVec3::ZERO, 10.0),
        black,
        Some(Emission {
            radiance: DVec3::ONE,
            two_sided: true,
        }),
    );
    add_object(&mut s, sphere(DVec3::ZERO, 1.0), grey, None);
    s.camera = Camera {
        location: DVec3::new(0.0, 0.0, -5.0),
        look_at: DVec3::ZERO,
        up: DVec3::Y,
        fov: 30.0,
        orthographic: false,
        aperture: 0.0,
        focus_distance: None,
        right: None,
        span: sppm_lang::Span::detached(),
    };
    s
}

fn quad(origin: DVec3, edge_u: DVec3, edge_v: DVec3) -> ShapeDecl {
    ShapeDecl::Quad {
        origin,
        edge_u,
        edge_v,
    }
}

/// The Cornell box with a glass and a mirror sphere, exactly as
/// the independent reference in `../shared/reference/cornell-glass/` describes it (the same scene
/// as `examples/cornell.scn`).
/// `n` seeded rays from random points inside the Cornell box of [`cornell_glass`] in uniformly
/// random directions (the benchmarks' fixed ray set).
pub fn cornell_rays(n: usize) -> Vec<Ray> {
    let mut rng = Rng::new(12345);
    (0..n)
        .map(|_| {
            let o = Vec3A::new(
                rng.f32() * 1.8 - 0.9,
                rng.f32() * 1.9 + 0.05,
                rng.f32() * 1.8 - 0.9,
            );
            Ray::new(o, uniform_sphere(rng.vec2()))
        })
        .collect()
}

pub fn cornell_glass(res: u32) -> Scene {
    let mut s = empty_scene((res, res));
    let white = add_material(
        &mut s,
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::new(0.725, 0.71, 0.68)),
        },
    );
    let red = add_material(
        &mut s,
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::new(0.63, 0.065, 0.05)),
        },
    );
    let green = add_material(
        &mut s,
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::new(0.14, 0.45, 0.091)),
        },
    );
    let black = diffuse(&mut s, 0.0);
    let (glass, mirror) = glass_and_mirror(&mut s);
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    // Floor, ceiling, back wall, left, right (two-sided diffuse).
    add_object(
        &mut s,
        quad(DVec3::new(-1.0, 0.0, -1.0), 2.0 * z, 2.0 * x),
        white,
        None,
    );
    add_object(
        &mut s,
        quad(DVec3::new(-1.0, 2.0, -1.0), 2.0 * x, 2.0 * z),
        white,
        None,
    );
    add_object(
        &mut s,
        quad(DVec3::new(-1.0, 0.0, -1.0), 2.0 * x, 2.0 * y),
        white,
        None,
    );
    add_object(
        &mut s,
        quad(DVec3::new(-1.0, 0.0, -1.0), 2.0 * y, 2.0 * z),
        red,
        None,
    );
    add_object(
        &mut s,
        quad(DVec3::new(1.0, 0.0, -1.0), 2.0 * z, 2.0 * y),
        green,
        None,
    );
    // Light: normal edge_u x edge_v = x' x z' ... choose edges so the normal is -y.
    add_object(
        &mut s,
        quad(DVec3::new(-0.25, 1.98, -0.25), 0.5 * x, 0.5 * z),
        black,
        Some(Emission {
            radiance: DVec3::new(17.0, 12.0, 4.0),
            two_sided: false,
        }),
    );
    add_object(
        &mut s,
        sphere(DVec3::new(0.42, 0.35, 0.25), 0.35),
        glass,
        None,
    );
    add_object(
        &mut s,
        sphere(DVec3::new(-0.45, 0.35, -0.4), 0.35),
        mirror,
        None,
    );
    s.camera = Camera {
        location: DVec3::new(0.0, 1.0, 3.9),
        look_at: DVec3::new(0.0, 1.0, 0.0),
        up: DVec3::Y,
        fov: 40.0,
        orthographic: false,
        aperture: 0.0,
        focus_distance: None,
        right: None,
        span: sppm_lang::Span::detached(),
    };
    s.settings.max_depth = 16;
    s
}

/// A diffuse floor (y = 0, x in [0, 2]) meeting a mirror wall at x = 0 under a point light,
/// seen from above: near the wall the density estimate's disc reaches past the floor. Returns
/// the scene and, per pixel, the analytic radiance (averaged over 4x4 positions in the pixel:
/// floor albedo / pi * I cos / d^2 from the light and its mirror image) and the floor x of the
/// pixel center.
pub fn corner_scene(res: u32) -> (Scene, impl Fn(u32, u32) -> (f64, f64)) {
    let mut s = empty_scene((res, res));
    let floor_m = diffuse(&mut s, 0.5);
    let mirror = add_material(
        &mut s,
        Material::Mirror {
            tint: ColorParam::Const(DVec3::ONE),
        },
    );
    add_object(
        &mut s,
        ShapeDecl::Quad {
            origin: DVec3::new(0.0, 0.0, -1.0),
            edge_u: DVec3::Z * 2.0,
            edge_v: DVec3::X * 2.0,
        },
        floor_m,
        None,
    );
    add_object(
        &mut s,
        ShapeDecl::Quad {
            origin: DVec3::new(0.0, 0.0, -1.0),
            edge_u: DVec3::Y * 2.0,
            edge_v: DVec3::Z * 2.0,
        },
        mirror,
        None,
    );
    let intensity = 4.0;
    s.lights.push(LightDecl::Point {
        position: DVec3::new(1.0, 1.0, 0.0),
        intensity: DVec3::splat(intensity),
        span: Span::detached(),
    });
    s.camera = sppm_lang::internals::scene::Camera {
        location: DVec3::new(0.3, 3.0, 0.0),
        look_at: DVec3::new(0.3, 0.0, 0.0),
        up: DVec3::X,
        fov: 11.4,
        orthographic: false,
        aperture: 0.0,
        focus_distance: None,
        right: None,
        span: sppm_lang::Span::detached(),
    };
    s.settings.max_depth = 2;
    let cam = sppm_lang::internals::camera::Camera::new(&s.camera, s.settings.handedness, res, res)
        .unwrap();
    let analytic = move |p: glam::Vec3A| -> f64 {
        let p = p.as_dvec3();
        let term = |l: DVec3| {
            let d = l - p;
            let d2 = d.length_squared();
            intensity * (d.y / d2.sqrt()) / d2
        };
        0.5 / std::f64::consts::PI
            * (term(DVec3::new(1.0, 1.0, 0.0)) + term(DVec3::new(-1.0, 1.0, 0.0)))
    };
    let expected = move |x: u32, y: u32| -> (f64, f64) {
        let floor_point = |u: f32, v: f32| {
            let r = cam.ray(x, y, glam::Vec2::new(u, v), glam::Vec2::ZERO);
            r.at(-r.o.y / r.d.y)
        };
        let mut sum = 0.0;
        for i in 0..4 {
            for j in 0..4 {
                sum += analytic(floor_point((i as f32 + 0.5) / 4.0, (j as f32 + 0.5) / 4.0));
            }
        }
        (sum / 16.0, floor_point(0.5, 0.5).x as f64)
    };
    (s, expected)
}

/// Renders `scene` (iterations and photons per iteration given, seed 1); every iteration must
/// finish.
pub fn run(scene: &Scene, iterations: u32, photons: u64) -> Image {
    let opts = RenderOptions {
        iterations: Some(iterations),
        photons: Some(photons),
        seed: Some(1),
        ..Default::default()
    };
    let out = render(scene, &opts, &AtomicBool::new(false), &mut |_| {}).unwrap();
    assert_eq!(out.iterations_done, iterations);
    out.image
}

/// `text` loaded as a scene file, with no errors (they are printed otherwise).
pub fn load(text: &str) -> sppm_lang::internals::eval::Loaded {
    let l = sppm_lang::internals::eval::load_source(
        "test.scn",
        text,
        &sppm_lang::EvalOptions::default(),
    );
    assert!(
        !l.has_errors(),
        "{}",
        sppm_lang::render_plain(&l.sources, &l.diagnostics, 100)
    );
    l
}

/// `text` loaded (with no errors) and rendered with `opts` over the scene's own settings.
pub fn render_text(text: &str, opts: &RenderOptions) -> sppm_lang::internals::render::RenderOutput {
    let scene = load(text).scene.expect("a scene");
    render(&scene, opts, &AtomicBool::new(false), &mut |_| {}).unwrap()
}

/// The `#debug` messages of a load, in order.
pub fn debug(l: &sppm_lang::internals::eval::Loaded) -> Vec<String> {
    l.diagnostics
        .iter()
        .filter(|d| d.severity == sppm_lang::Severity::Note)
        .map(|d| d.message.clone())
        .collect()
}
