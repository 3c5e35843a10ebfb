//! Building a [`PreparedScene`] from a plain `Scene`: its objects' shapes (instanced, baked
//! CSG, turned outward), its area lights, the BVH, the lights' distributions and the
//! per-material data shading reads.

use glam::Vec3A;
use rayon::prelude::*;

use super::shading::GlassAbsorption;
use super::shapes::{build_mesh, build_shapes};
use super::{
    NO_LIGHT, ObjectInfo, PreparedScene, Stop, SurfaceHit, color3, csg, emitters, instances,
    lights, orient, unless,
};
use crate::accel::{self, Bvh, Unbuilt};
use crate::camera::Camera;
use crate::diag::Diagnostic;
use crate::geometry::Hit;
use crate::lights::{AreaLight, GroundPhotons, Light};
use crate::materials::eval;
use crate::sampling::PiecewiseConstant1D;
use crate::scene::{self, Material, Scene};
use crate::shapes::Shape;
use crate::textures;

/// Shapes of one object from which they are moved into the scene's list in parallel.
const PARALLEL_SHAPES: usize = 4096;

/// How to mend a shape that cannot be built (the evaluator catches most of these first).
fn shape_help(shape: &scene::ShapeDecl) -> &'static str {
    use scene::ShapeDecl as S;
    match shape {
        S::Triangle { .. } => "give three points that do not lie on one line",
        S::Box { .. } => {
            "give two opposite corners that differ in x, y and z, e.g. `box { <-1, -1, -1>, <1, 1, 1> }`"
        }
        S::Mesh { .. } => {
            "the OBJ file needs faces (`f` lines) of three distinct vertices that span an area"
        }
        S::Revolve { .. } => "give the profile points away from the axis (a radius above 0)",
        S::Csg(_) => "check the sizes and transforms of the CSG's children",
        _ => "check the shape's sizes and its transform (scale, matrix) for zero or huge values",
    }
}

impl<'a> PreparedScene<'a> {
    pub fn new(scene: &'a Scene) -> Result<Self, Diagnostic> {
        Self::new_until(scene, &|| false)
    }

    /// [`PreparedScene::new`], stopping with [`Diagnostic::interrupted`] when `stop` says so
    /// (asked between phases, for every object, and inside the BVH build).
    pub fn new_until(scene: &'a Scene, stop: Stop) -> Result<Self, Diagnostic> {
        Self::new_sized(scene, scene.settings.resolution, stop)
    }

    /// [`PreparedScene::new_until`] for an image of `(width, height)` pixels (the render's
    /// resolution, which may override the scene's).
    pub(super) fn new_sized(
        scene: &'a Scene,
        (width, height): (u32, u32),
        stop: Stop,
    ) -> Result<Self, Diagnostic> {
        unless(stop)?;
        // From counts, before validation reads a CSG's meshes once per placement.
        csg::check_costs(scene)?;
        scene.validate()?;
        unless(stop)?;
        let camera = Camera::new(&scene.camera, scene.settings.handedness, width, height)?;
        let mut shapes = Vec::new();
        let mut isosurfaces = Vec::new();
        let mut meshes = Vec::new();
        let mut prim_object = Vec::new();
        let mut prim_light = Vec::new();
        let mut lights = Vec::new();
        let mut light_boxes = Vec::new();
        let mut objects = Vec::with_capacity(scene.objects.len());
        let mut instancer = instances::Instancer::new(scene);
        let mut orientation = orient::Orientation::default();
        // The parts of CSG objects, after the scene's objects.
        let mut csg_parts = Vec::new();
        for (oi, obj) in scene.objects.iter().enumerate() {
            // Each object can be a CSG tree's set-up or a mesh of millions of triangles.
            unless(stop)?;
            let err = |message: String| {
                Diagnostic::error(obj.span, format!("{}: {message}", obj.shape.kind()))
                    .with_help(shape_help(&obj.shape))
            };
            if obj.material.0 as usize >= scene.materials.len() {
                return Err(err("unknown material".into())
                    .with_help("refer to an entry of `Scene::materials`"));
            }
            objects.push(ObjectInfo::new(obj.material, &obj.transform));
            if let scene::ShapeDecl::Csg(_) = &obj.shape {
                // One primitive; its leaves have ids (and objects) of their own.
                let id = prim_object.len() as u32;
                let (shape, parts) = csg::build_csg(obj, id + 1, &mut isosurfaces).map_err(err)?;
                shapes.push((shape, id));
                prim_object.push(oi as u32);
                prim_light.push(NO_LIGHT);
                for part in parts {
                    if part.material.0 as usize >= scene.materials.len() {
                        return Err(err("unknown material".into())
                            .with_help("refer to an entry of `Scene::materials`"));
                    }
                    prim_object.push((scene.objects.len() + csg_parts.len()) as u32);
                    prim_light.push(NO_LIGHT);
                    csg_parts.push(ObjectInfo::new(part.material, &part.transform));
                }
                continue;
            }
            // Closed glass facing in is turned outward (`orient`).
            let faces_in = orientation.faces_in(scene, obj);
            let turned;
            let obj = match faces_in.then(|| orient::outward_revolve(obj)).flatten() {
                Some(t) => {
                    turned = t;
                    &turned
                }
                None => obj,
            };
            let placed = instancer.placement(obj, faces_in).map_err(err)?;
            let emission = obj
                .emission
                .filter(|e| e.radiance.is_finite() && e.radiance.max_element() > 0.0);
            if let Some(e) = obj.emission
                && !(e.radiance.is_finite() && e.radiance.min_element() >= 0.0)
            {
                return Err(err("emission must be finite and non-negative".into())
                    .with_help("give a radiance of finite numbers of at least 0"));
            }
            // A mesh that is neither instanced nor a light: one primitive, its triangles kept
            // in the BVH's compact form.
            if let (None, None, scene::ShapeDecl::Mesh { mesh }) = (&placed, emission, &obj.shape) {
                meshes.push((
                    build_mesh(obj, mesh, faces_in).map_err(err)?,
                    prim_object.len() as u32,
                ));
                prim_object.push(oi as u32);
                prim_light.push(NO_LIGHT);
                continue;
            }
            let list = match placed {
                Some(placed) => vec![placed],
                None => build_shapes(obj, &mut isosurfaces).map_err(err)?,
            };
            let light_shapes = if emission.is_some() {
                // The same shapes again, as lights: their isosurfaces are counted once.
                Some(build_shapes(obj, &mut Vec::new()).map_err(err)?)
            } else {
                None
            };
            if light_shapes.is_none() {
                // Not a light: a mesh's millions of shapes move in parallel; an object's few
                // do not (handing each of 100 000 spheres to the thread pool cost more CPU
                // than moving them).
                let (base, n) = (prim_object.len(), list.len());
                let tag =
                    |(k, s): (usize, crate::shapes::primitive::AnyShape)| (s, (base + k) as u32);
                if n >= PARALLEL_SHAPES {
                    shapes.par_extend(list.into_par_iter().enumerate().map(tag));
                } else {
                    shapes.extend(list.into_iter().enumerate().map(tag));
                }
                prim_object.resize(base + n, oi as u32);
                prim_light.resize(base + n, NO_LIGHT);
                continue;
            }
            let mut light_shapes = light_shapes.map(|l| l.into_iter());
            // One light per shape (an emissive mesh's millions): no doubling of the vector.
            lights.reserve(list.len());
            for s in list {
                let id = prim_object.len() as u32;
                let mut light = NO_LIGHT;
                if let (Some(e), Some(ls)) = (emission, light_shapes.as_mut()) {
                    let ls = ls.next().expect("same shapes twice");
                    let area = ls.area();
                    if !(area.is_finite() && area > 0.0) || ls.sample(glam::Vec2::ZERO).is_none() {
                        return Err(err(
                            "this emissive shape cannot be sampled as a light (infinite, or a \
                             transform other than translate/rotate/uniform scale)"
                                .into(),
                        )
                        .with_help(
                            "make the light a finite shape (a quad, disk, sphere, ...) under \
                             translate, rotate and uniform scale only",
                        ));
                    }
                    light = lights.len() as u32;
                    light_boxes.push(s.bounds());
                    lights.push(Light::Area(AreaLight {
                        shape: ls,
                        radiance: color3(e.radiance),
                        two_sided: e.two_sided,
                        area,
                        sampling: Default::default(),
                    }));
                }
                shapes.push((s, id));
                prim_object.push(oi as u32);
                prim_light.push(light);
            }
        }
        objects.extend(csg_parts);
        lights::push_scene_lights(scene, &mut lights)?;
        unless(stop)?;
        let bvh = Bvh::with_meshes_until(shapes, meshes, stop).map_err(|e| match e {
            Unbuilt::Stopped => Diagnostic::interrupted(),
            Unbuilt::TooLarge => Diagnostic::unplaced(e.to_string()),
        })?;
        unless(stop)?;
        let environment = lights::push_environment(scene, &bvh, &mut lights);
        unless(stop)?;
        let power: Vec<f64> = lights.iter().map(Light::power).collect();
        // Photons also leave the far parts of infinite planes under the environment light
        // (`GroundPhotons`), chosen after the lights.
        let ground_photons = lights::ground_photons(scene, &prim_object, &lights, environment);
        let mut photon_power = power.clone();
        if let Some(i) = environment {
            photon_power.extend(
                ground_photons
                    .iter()
                    .map(|_| GroundPhotons::SHARE * power[i]),
            );
        }
        let photon_distr = PiecewiseConstant1D::new(&photon_power);
        // Direct lighting leaves a uniform background to the BSDF sample, which draws it with
        // (nearly) no variance: by power it would take most light samples, its power counting
        // the whole disk around the scene rather than what reaches a point.
        let light_distr = match environment {
            Some(i) if lights[i].is_uniform_sky() => {
                let mut w = power;
                w[i] = 0.0;
                PiecewiseConstant1D::new(&w)
            }
            _ => PiecewiseConstant1D::new(&power),
        };
        let prim_material = prim_object
            .iter()
            .map(|&o| objects[o as usize].material as u32)
            .collect();
        let mut prepared = Self {
            scene,
            camera,
            bvh,
            prim_object,
            prim_light,
            light_bounds: lights::LightBounds::new(light_boxes),
            quad_emitters: Vec::new(),
            objects,
            lights,
            light_distr,
            photon_distr,
            ground_photons,
            environment,
            prim_material,
            const_lobes: Vec::new(),
            rough_parts: eval::non_specular_parts(scene),
            textured: scene.materials.iter().map(eval::has_texture).collect(),
            glass: scene
                .materials
                .iter()
                .zip(eval::glass_parts(scene))
                .map(|(m, g)| GlassAbsorption::of(m, g))
                .collect(),
            bump_scale: scene
                .materials
                .iter()
                .map(|m| match m {
                    Material::Bumped { normal, .. } => {
                        textures::bump::pattern_scale(normal, &scene.textures)
                    }
                    _ => 1.0,
                })
                .collect(),
            offset_floor: 0.0,
            absorbs: false,
            isosurfaces,
        };
        // The scene's extent: its finite objects and its camera (infinite planes have none).
        let b = prepared.bvh.bounds();
        let extent = [b.min.abs().max_element(), b.max.abs().max_element()]
            .into_iter()
            .filter(|e| e.is_finite())
            .fold(scene.camera.location.abs().max_element() as f32, f32::max);
        prepared.offset_floor = accel::offset_floor(extent);
        // A constant material gives the same lobes at every hit: the hit is not looked at.
        let dummy = SurfaceHit {
            hit: Hit {
                t: 0.0,
                p: Vec3A::ZERO,
                n: Vec3A::Z,
                ns: Vec3A::Z,
                uv: glam::Vec2::ZERO,
                dpdu: Vec3A::X,
            },
            prim: 0,
        };
        prepared.quad_emitters = prepared
            .lights
            .iter()
            .map(emitters::QuadEmitter::of)
            .collect();
        prepared.absorbs = prepared.glass.iter().any(|g| match g {
            GlassAbsorption::NotGlass => false,
            GlassAbsorption::Constant(sigma) => *sigma != Vec3A::ZERO,
            GlassAbsorption::Textured | GlassAbsorption::Blended => true,
        });
        prepared.const_lobes = scene
            .materials
            .iter()
            .map(|m| eval::is_constant(m).then(|| prepared.lobes(m, &dummy)))
            .collect();
        Ok(prepared)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{RenderOptions, prepare};
    use super::*;
    use crate::eval::{EvalOptions, load_source};

    /// The caller's cancel stops the prepare stage with [`Diagnostic::interrupted`]: raised
    /// before it, and asked midway through the objects and inside the BVH build (a stop that
    /// says yes from its n-th question on).
    #[test]
    fn a_cancel_stops_prepare_between_objects_and_inside_the_build() {
        use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
        let text = "light { <0, 10, 0> intensity rgb 1 }\n\
                    #for (I, 0, 19999) sphere { <mod(I, 100), floor(I / 100), 0>, 0.4 } #end\n";
        let loaded = load_source("many.scn", text, &EvalOptions::default());
        let scene = loaded.scene.expect("the scene loads");
        let cancel = crate::cancel::Cancel::new();
        let options = RenderOptions {
            cancel: cancel.clone(),
            ..RenderOptions::default()
        };
        assert!(prepare(&scene, &options).is_ok());
        cancel.cancel();
        let e = prepare(&scene, &options).err().expect("interrupted");
        assert!(e.interrupted && e.message == "interrupted", "{e:?}");
        // Every question a full prepare asks, then stops from a question on.
        let asked = AtomicUsize::new(0);
        let never = || {
            asked.fetch_add(1, Relaxed);
            false
        };
        assert!(PreparedScene::new_until(&scene, &never).is_ok());
        let full = asked.load(Relaxed);
        // One per object, a few between phases, a few dozen in the build of 20 000 boxes.
        assert!(full > 20_000 + 4, "{full}");
        for from in [10_000, 20_004, full - 2] {
            let asked = AtomicUsize::new(0);
            let stop = || asked.fetch_add(1, Relaxed) >= from;
            let e = PreparedScene::new_until(&scene, &stop)
                .err()
                .expect("interrupted");
            assert!(e.interrupted, "{e:?}");
            let n = asked.load(Relaxed);
            assert!(
                n > from && n < from + 50,
                "stopped from {from}: asked {n} times"
            );
        }
    }
}
