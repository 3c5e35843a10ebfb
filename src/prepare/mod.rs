//! The prepared scene: world-space shapes in a BVH, lights with a power distribution, and the
//! per-object data shading needs. Built once per render from a plain `Scene`.

use glam::{Affine3A, DVec3, Vec3A};
use rayon::prelude::*;

mod budget;
mod bump;
mod csg;
mod emitters;
mod instances;
mod lights;
mod method;
mod orient;
mod settings;
mod shapes;
mod sky;

use crate::accel::{self, Bvh};
use crate::camera::Camera;
use crate::diag::Diagnostic;
use crate::geometry::{Frame, Hit, Ray};
use crate::lights::{AreaLight, EnvironmentLight, GroundPhotons, Light, PhotonSample};
use crate::materials::{Bsdf, Lobes, eval};
use crate::sampling::PiecewiseConstant1D;
use crate::scene::{self, ColorParam, Material, Scene};
use crate::shapes::Shape;
use crate::textures::{self, TexCoord};
pub use budget::{
    BPT_VERTEX_BYTES, LT_VERTEX_BYTES, MemoryItem, VCM_GRID_BYTES, VCM_VERTEX_BYTES, check_memory,
    default_memory_limit, estimate as estimate_memory,
};
pub use csg::{MAX_CSG_RAY_COST, ray_cost as csg_ray_cost};
pub use method::{
    DEFAULT_ELSEWHERE, MethodChoice, MethodSource, default_method, method_choice, needs_a_lens,
};
pub use settings::{
    EffectiveSettings, GATHER_RADIUS_FACTOR, InitialRadius, MAX_ITERATIONS, MAX_PHOTONS,
    MAX_THREADS, RADIUS_FOOTPRINTS, RenderOptions, effective_settings,
};
use shapes::{build_mesh, build_shapes};

const NO_LIGHT: u32 = u32::MAX;

pub struct ObjectInfo {
    pub material: usize,
    /// World to object space (for texture lookups).
    pub to_object: Affine3A,
    pub normal_to_object: glam::Mat3A,
}

impl ObjectInfo {
    fn new(material: scene::MaterialId, to_world: &glam::DAffine3) -> Self {
        Self {
            material: material.0 as usize,
            to_object: to_world.inverse().as_affine3a(),
            normal_to_object: glam::Mat3A::from(to_world.matrix3.transpose().as_mat3()),
        }
    }
}

pub struct PreparedScene<'a> {
    pub scene: &'a Scene,
    /// The camera, validated, for the scene's resolution.
    pub camera: Camera,
    pub bvh: Bvh,
    /// Object of each primitive id (the parts of CSG objects, whose ids the BVH does not hold
    /// but their hits report, have objects after the scene's).
    pub prim_object: Vec<u32>,
    /// Area light of each primitive id, or `u32::MAX`.
    pub prim_light: Vec<u32>,
    /// Boxes around the area lights' primitives ([`Self::may_hit_light`]).
    light_bounds: lights::LightBounds,
    /// Per light: its photons' emitter where it is a rectangle ([`emitters::QuadEmitter`]).
    quad_emitters: Vec<Option<emitters::QuadEmitter>>,
    pub objects: Vec<ObjectInfo>,
    pub lights: Vec<Light>,
    /// How direct lighting chooses a light: by power, except a uniform background, which is
    /// left to the BSDF sample.
    pub light_distr: PiecewiseConstant1D,
    /// How a photon chooses the light it leaves from: by power, every light, then the
    /// `ground_photons` emitters (an index past the lights is one of those).
    pub photon_distr: PiecewiseConstant1D,
    /// Photons for the far parts of infinite planes under the environment light.
    pub ground_photons: Vec<GroundPhotons>,
    /// Index in `lights` of the environment light, if the background (a map or a colour) is
    /// not black.
    pub environment: Option<usize>,
    /// Material index of each primitive id (saves the object indirection per hit).
    prim_material: Vec<u32>,
    /// The lobes of each material whose parameters are all constants (no texture), computed
    /// once instead of at every hit.
    const_lobes: Vec<Option<Lobes>>,
    /// Per material: whether some point of it scatters other than specularly
    /// ([`Self::blend_stores_photons`]).
    rough_parts: Vec<bool>,
    /// Per material: whether any of its parameters is a texture (its lobes, or a glass's
    /// absorption), so that hits on it need their `uv`.
    textured: Vec<bool>,
    /// Per material: whether it is glass, and its absorption where that is a constant.
    glass: Vec<GlassAbsorption>,
    /// Whether any material may absorb inside (a glass whose absorption is not zero, or may
    /// not be): where none does, every path's medium is zero ([`Self::absorbs`]).
    absorbs: bool,
    /// Per material: for a bumped one, how far one object unit reaches in its height's
    /// pattern space ([`textures::bump::pattern_scale`], which sets the difference step);
    /// 1 otherwise.
    bump_scale: Vec<f32>,
    /// The floor of a spawned ray's offset, from the scene's extent ([`accel::offset_floor`]).
    offset_floor: f32,
    /// The isosurfaces, whose rays given up are reported after a render
    /// ([`PreparedScene::render_warnings`]).
    isosurfaces: shapes::Isosurfaces,
}

/// A surface hit with the primitive it belongs to.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceHit {
    pub hit: Hit,
    pub prim: u32,
}

/// A material's part in [`PreparedScene::glass_absorption`], decided once per material.
enum GlassAbsorption {
    NotGlass,
    /// A constant absorption (zero for clear glass), as [`PreparedScene::absorption`] gives it.
    Constant(Vec3A),
    /// An absorption from a texture: evaluated at each hit.
    Textured,
    /// A blend with a glass among its parts: the part chosen at each hit decides.
    Blended,
}

impl GlassAbsorption {
    fn of(m: &Material, has_glass: bool) -> Self {
        match m {
            Material::Blend { .. } | Material::Bumped { .. } if has_glass => Self::Blended,
            Material::Glass {
                absorb: ColorParam::Const(c),
                ..
            } => {
                let a = color3(*c).max(Vec3A::ZERO);
                Self::Constant(if a.is_finite() { a } else { Vec3A::ZERO })
            }
            Material::Glass { .. } => Self::Textured,
            _ => Self::NotGlass,
        }
    }
}

/// A ray the BVH can traverse: finite origin and direction (a caller's ray with an infinite or
/// NaN component meets nothing).
#[inline]
fn finite(ray: &Ray) -> bool {
    ray.o.is_finite() && ray.d.is_finite()
}

fn color3(c: DVec3) -> Vec3A {
    c.as_vec3a()
}

/// The prepare stage in one call: the settings with `options` applied, the memory estimate
/// against `options.memory_limit` (default: [`default_memory_limit`]), then the validated,
/// prepared scene. `check` and `render` both go through here, so they accept the same scenes.
///
/// Fails with [`Diagnostic::interrupted`] when `options.cancel` is raised: it is checked
/// between the phases, for every object and inside the BVH build.
pub fn prepare<'a>(
    scene: &'a Scene,
    options: &RenderOptions,
) -> Result<(EffectiveSettings, PreparedScene<'a>), Diagnostic> {
    prepare_until(scene, options, &|| options.cancel.is_cancelled())
}

/// [`prepare`], stopping when `stop` says so (the render also stops for its own cancel flag).
pub(crate) fn prepare_until<'a>(
    scene: &'a Scene,
    options: &RenderOptions,
    stop: Stop,
) -> Result<(EffectiveSettings, PreparedScene<'a>), Diagnostic> {
    unless(stop)?;
    // `PreparedScene::new` validates the scene (once); the estimate before it only counts.
    let settings = effective_settings(scene, options).map_err(|e| e.at(scene.settings.span))?;
    // The cost of each CSG first: a merge of many placements of a large mesh would otherwise
    // be refused for its memory, which tells less.
    csg::check_costs(scene)?;
    let limit = options.memory_limit.unwrap_or_else(default_memory_limit);
    check_memory(scene, &settings, limit, options.held_memory)
        .map_err(|e| e.at(scene.settings.span))?;
    let prepared = PreparedScene::new_sized(scene, settings.resolution, stop)?;
    Ok((settings, prepared))
}

/// Shapes of one object from which they are moved into the scene's list in parallel.
const PARALLEL_SHAPES: usize = 4096;

/// What the prepare stage asks to learn whether the caller cancelled.
pub type Stop<'s> = &'s (dyn Fn() -> bool + Sync);

/// [`Diagnostic::interrupted`] once `stop` says so.
fn unless(stop: Stop) -> Result<(), Diagnostic> {
    if stop() {
        Err(Diagnostic::interrupted())
    } else {
        Ok(())
    }
}

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
    /// What is legal but probably not what the author meant, as warnings: a scene with
    /// nothing that emits light, and a one-sided flat light that faces away from everything.
    pub fn warnings(&self) -> Vec<Diagnostic> {
        let mut out = lights::facing_away(self);
        if self.lights.is_empty() {
            out.push(
                Diagnostic::warning(
                    crate::span::Span::detached(),
                    "the scene has no light: no light source, no emitting object and a black \
                     background, so its objects render black",
                )
                .with_help(
                    "add a `light { <position> intensity <color> }`, an `area_light { ... }`, \
                     a `background rgb <...>` or an `environment { image \"sky.hdr\" }` (a \
                     `backdrop` is only seen, it lights nothing)",
                ),
            );
        }
        out
    }

    /// What went wrong in a render that still finished, since the last call: rays that gave
    /// up on an isosurface, their stretches exhausted, and were taken as misses (the image may
    /// show holes or specks there), one warning per isosurface at its object.
    pub fn render_warnings(&self) -> Vec<Diagnostic> {
        self.isosurfaces
            .iter()
            .filter_map(|(iso, span)| {
                let n = iso.take_exhausted();
                (n > 0).then(|| {
                    Diagnostic::warning(
                        *span,
                        format!(
                            "{n} ray{} gave up on this isosurface after {} stretches each and \
                             were taken as misses: the image may show holes or specks on it",
                            if n == 1 { "" } else { "s" },
                            crate::shapes::isosurface::MAX_VISITS
                        ),
                    )
                    .with_label("rays gave up here")
                    .with_help(
                        "give the isosurface a larger `accuracy` (each ray halves its stretches \
                         down to it), or simplify the function (its bounds over a stretch are \
                         tightest where each of x, y, z appears once): fewer stretches stay \
                         undecided",
                    )
                })
            })
            .collect()
    }

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
    fn new_sized(
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
        let bvh =
            Bvh::with_meshes_until(shapes, meshes, stop).ok_or_else(Diagnostic::interrupted)?;
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

    /// A ray leaving the surface point `p` (geometric normal `n`) in direction `dir`, its origin
    /// moved off the surface ([`accel::spawn_ray`]).
    #[inline]
    pub fn spawn_ray(&self, p: Vec3A, n: Vec3A, dir: Vec3A) -> Ray {
        accel::spawn_ray(p, n, dir, self.offset_floor)
    }

    /// A shadow ray from `p` to `target` (on a surface with normal `nt`), `t` up to the returned
    /// bound ([`accel::spawn_ray_to`]).
    #[inline]
    pub fn spawn_ray_to(&self, p: Vec3A, n: Vec3A, target: Vec3A, nt: Vec3A) -> (Ray, f32) {
        accel::spawn_ray_to(p, n, target, nt, self.offset_floor)
    }

    /// Inlined (always): each caller runs the choice of the query (a flat leaf, or the tree
    /// with AVX or without; each one out-of-line copy) and the tree's check of the ray, and the
    /// query writes its record into the caller's frame. (The traversal itself inlined into
    /// each caller ran fewer instructions but fewer photons/s: docs/measurements.md, "Tried and
    /// not kept".)
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        // A CSG tree names the part hit: its material and texture space are that part's. A ray
        // with a non-finite origin or direction hits nothing.
        let (hit, prim) = self
            .bvh
            .intersect_finite_uv(ray, 0.0, t_max, |prim| self.reads_uv(prim))?;
        Some(SurfaceHit { hit, prim })
    }

    /// Whether anything may read the `uv` of a hit on `prim`: only textures do (through
    /// [`Self::tex_coord`], for the lobes or a glass's absorption), so a primitive whose
    /// material has no texture gets hits without it (spheres, disks and cylinders then skip
    /// their trigonometry, revolves their arc length and angle; `uv` is NaN).
    #[inline]
    fn reads_uv(&self, prim: u32) -> bool {
        let m = self.prim_material[prim as usize] as usize;
        self.textured.get(m).copied().unwrap_or(true)
    }

    /// Whether the closest hit of `ray` may be on an area light: false only where the ray
    /// misses every (padded) box around the lights' primitives. A ray for which this is false
    /// ends on no light whatever [`Self::intersect`] finds (if anything).
    #[inline]
    pub fn may_hit_light(&self, ray: &Ray) -> bool {
        self.light_bounds.may_reach(ray)
    }

    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        finite(ray) && self.bvh.occluded(ray, 0.0, t_max)
    }

    /// The area light a primitive belongs to.
    #[inline]
    pub fn area_light(&self, prim: u32) -> Option<(usize, &AreaLight)> {
        let l = *self.prim_light.get(prim as usize)?;
        if l == NO_LIGHT {
            return None;
        }
        match &self.lights[l as usize] {
            Light::Area(a) => Some((l as usize, a)),
            _ => None,
        }
    }

    /// The material of primitive `prim` (`None` for a number no primitive has).
    #[inline]
    pub fn material(&self, prim: u32) -> Option<&Material> {
        let m = *self.prim_material.get(prim as usize)?;
        self.scene.materials.get(m as usize)
    }

    fn tex_coord(&self, sh: &SurfaceHit) -> TexCoord {
        let object = self
            .prim_object
            .get(sh.prim as usize)
            .and_then(|&o| self.objects.get(o as usize));
        match object {
            Some(o) => TexCoord {
                p: o.to_object.transform_point3a(sh.hit.p),
                n: (o.normal_to_object * sh.hit.ns).normalize_or_zero(),
                uv: sh.hit.uv,
            },
            // A hit made up by the caller, on no primitive: world space.
            None => TexCoord {
                p: sh.hit.p,
                n: sh.hit.ns,
                uv: sh.hit.uv,
            },
        }
    }

    /// The BSDF at a hit (black for a `SurfaceHit` whose `prim` no primitive has, which only
    /// a caller making one up can give).
    #[inline(always)]
    pub fn bsdf(&self, sh: &SurfaceHit) -> Bsdf {
        let m = self
            .prim_material
            .get(sh.prim as usize)
            .map_or(usize::MAX, |&m| m as usize);
        // A constant material (most of them) inline; textures and bumps are a call.
        if let Some(Some(l)) = self.const_lobes.get(m) {
            return Bsdf::new(*l, sh.hit.ns, sh.hit.dpdu, sh.hit.n);
        }
        self.varying_bsdf(sh, m)
    }

    /// [`Self::bsdf`] of material `m` when it is not constant.
    #[inline(never)]
    fn varying_bsdf(&self, sh: &SurfaceHit, m: usize) -> Bsdf {
        let Some(material) = self.scene.materials.get(m) else {
            let black = Lobes::Diffuse {
                albedo: Vec3A::ZERO,
            };
            return Bsdf::new(black, sh.hit.ns, sh.hit.dpdu, sh.hit.n);
        };
        // The texture coordinates, looked up once for the lobes and the bump alike.
        let cell = std::cell::OnceCell::new();
        let tc = || *cell.get_or_init(|| self.tex_coord(sh));
        let (lobes, normal) = eval::bumped_lobes(material, m, self.scene, tc);
        match normal {
            None => Bsdf::new(lobes, sh.hit.ns, sh.hit.dpdu, sh.hit.n),
            Some((normal, id)) => {
                let frame = Frame::from_normal_tangent(sh.hit.ns, sh.hit.dpdu);
                let scale = match id.and_then(|i| self.bump_scale.get(i)) {
                    Some(&s) => s,
                    None => textures::bump::pattern_scale(normal, &self.scene.textures),
                };
                let np = self.perturbed_normal(normal, scale, sh, &frame, &tc());
                Bsdf::bumped(lobes, frame, sh.hit.n, np)
            }
        }
    }

    /// The lobes of material `m` at a hit (texture lookups where the material has them).
    fn lobes(&self, m: &Material, sh: &SurfaceHit) -> Lobes {
        eval::lobes(m, self.scene, || self.tex_coord(sh))
    }

    /// Whether the hit is on a blend with a part that scatters other than specularly: photon
    /// mapping stores a photon arriving there even where the point shows a specular part, so
    /// that the density around a point showing the rough part counts all the light reaching
    /// the surface (SPPM deposits at every surface alike).
    #[inline]
    pub fn blend_stores_photons(&self, sh: &SurfaceHit) -> bool {
        let m = self
            .prim_material
            .get(sh.prim as usize)
            .map_or(usize::MAX, |&m| m as usize);
        matches!(self.scene.materials.get(m), Some(Material::Blend { .. }))
            && self.rough_parts.get(m) == Some(&true)
    }

    /// A photon from light `li` ([`Light::sample_photon`]), for `u1` and `u2` in [0,1)^2.
    /// A rectangle's photons come from its [`emitters::QuadEmitter`] (the same photons).
    #[inline]
    pub fn sample_photon(&self, li: usize, u1: glam::Vec2, u2: glam::Vec2) -> Option<PhotonSample> {
        match self.quad_emitters.get(li) {
            Some(Some(e)) => e.sample_photon(u1, u2),
            _ => self.lights.get(li)?.sample_photon(u1, u2),
        }
    }

    /// Whether some material may absorb light inside it (a glass with an absorption that is
    /// not a constant zero). Where this is false, a path's medium is zero everywhere: no
    /// absorption to track or apply.
    #[inline]
    pub fn absorbs(&self) -> bool {
        self.absorbs
    }

    /// For a hit on glass, its absorption coefficient (zero for clear glass); `None` for any
    /// other material.
    #[inline]
    pub fn glass_absorption(&self, sh: &SurfaceHit) -> Option<Vec3A> {
        self.glass_absorption_varying(sh).map(|(sigma, _)| sigma)
    }

    /// [`Self::glass_absorption`], and whether it comes from a texture (so that it differs
    /// from point to point of the glass): one material lookup for both.
    #[inline]
    pub fn glass_absorption_varying(&self, sh: &SurfaceHit) -> Option<(Vec3A, bool)> {
        let m = *self.prim_material.get(sh.prim as usize)?;
        match self.glass.get(m as usize)? {
            GlassAbsorption::NotGlass => None,
            GlassAbsorption::Constant(sigma) => Some((*sigma, false)),
            GlassAbsorption::Textured => Some((self.absorption(sh).unwrap_or(Vec3A::ZERO), true)),
            GlassAbsorption::Blended => {
                let m = eval::choose(self.material(sh.prim)?, self.scene, || self.tex_coord(sh));
                matches!(m, Material::Glass { .. })
                    .then(|| (self.absorption(sh).unwrap_or(Vec3A::ZERO), true))
            }
        }
    }

    /// Beer–Lambert absorption coefficient inside the material at this hit, if any.
    pub fn absorption(&self, sh: &SurfaceHit) -> Option<Vec3A> {
        let m = self.material(sh.prim)?;
        match eval::choose(m, self.scene, || self.tex_coord(sh)) {
            Material::Glass { absorb, .. } => {
                let a = eval::color(absorb, self.scene, || self.tex_coord(sh)).max(Vec3A::ZERO);
                (a != Vec3A::ZERO && a.is_finite()).then_some(a)
            }
            _ => None,
        }
    }

    /// The radiance a ray leaving the scene in direction `dir` sees: the environment light's (a
    /// map or a background colour), or black.
    #[inline]
    pub fn background_radiance(&self, dir: Vec3A) -> Vec3A {
        match self.environment_light() {
            Some((_, env)) => env.le(dir),
            None => Vec3A::ZERO,
        }
    }

    /// The environment light and its index in `lights`.
    #[inline]
    pub fn environment_light(&self) -> Option<(usize, &EnvironmentLight)> {
        let i = self.environment?;
        match &self.lights[i] {
            Light::Environment(e) => Some((i, e)),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::eval::{EvalOptions, load_file, load_source};
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::primitive::{AnyShape, LazyHit};

    /// A hit from [`PreparedScene::intersect`] is the full hit of the same shape, field for
    /// field and bit for bit, except that `uv` is NaN on spheres, disks, cylinders and revolves
    /// whose material reads no texture. Checked on the examples with textured and plain spheres,
    /// cylinders, disks, quads and revolves, and on glass whose absorption is textured, with
    /// camera rays and rays from random points in random directions (back faces, insides);
    /// fails if `uv` is left out where a texture could read it, or if leaving it out changed
    /// anything else.
    #[test]
    fn hits_leave_out_uv_only_where_no_texture_reads_it() {
        let root = crate::repo_root().join("examples");
        let (mut kept, mut left_out, mut absorbing_kept) = (0usize, 0usize, 0usize);
        // Revolve hits with `uv` kept and left out.
        let mut revolves = (0usize, 0usize);
        // Glass whose absorption is a uv-mapped texture reads `uv` too (its lobes do not).
        let absorbing = r#"
            camera { location <0, 1.2, -4>  look_at <0, 0.5, 0>  fov 60 }
            #declare Inked = material { glass absorb texture { checker rgb 3, rgb 0 map uv scale 0.1 } }
            #declare Clear = material { glass absorb rgb 0.5 }
            sphere { <-1.2, 0.5, 0>, 0.5  material { Inked } }
            cylinder { <0, 0, 0>, <0, 1, 0>, 0.4  material { Inked } }
            disk { <1.2, 0.5, 0>, <0, 0, -1>, 0.5  material { Inked } }
            sphere { <-1.2, 0.5, 1.5>, 0.5  material { Clear } }
            cylinder { <0, 0, 1.5>, <0, 1, 1.5>, 0.4  material { Clear } }
        "#;
        let examples = [
            "textures.scn",
            "room.scn",
            "crystal_tree.scn",
            "cornell.scn",
            "goblet.scn",
        ]
        .map(|name| {
            let loaded = load_file(&root.join(name), &EvalOptions::default()).unwrap();
            (name, loaded.scene.unwrap())
        });
        let inline = load_source("absorbing.scn", absorbing, &EvalOptions::default());
        for (name, scene) in examples
            .into_iter()
            .chain([("absorbing glass", inline.scene.unwrap())])
        {
            let prepared = PreparedScene::new(&scene).unwrap();
            let camera = Camera::new(&scene.camera, scene.settings.handedness, 64, 64).unwrap();
            let bounds = prepared.bvh.bounds();
            let mut rng = Rng::new(17);
            let mut rays: Vec<Ray> = (0..64 * 64)
                .map(|i| camera.ray(i % 64, i / 64, rng.vec2(), rng.vec2()))
                .collect();
            for _ in 0..4096 {
                let u = Vec3A::new(rng.f32(), rng.f32(), rng.f32());
                let o = bounds.min + u * (bounds.max - bounds.min);
                rays.push(Ray::new(o, uniform_sphere(rng.vec2())));
            }
            for ray in &rays {
                let full = prepared.bvh.intersect(ray, 0.0, f32::INFINITY);
                let got = prepared.intersect(ray, f32::INFINITY);
                let (Some((full, id)), Some(got)) = (full, got) else {
                    assert!(full.is_none() && got.is_none(), "{name}: {ray:?}");
                    continue;
                };
                assert_eq!(id, got.prim, "{name}");
                let bits = |h: &Hit| {
                    let v = [h.p, h.n, h.ns, h.dpdu].map(|v| v.to_array().map(f32::to_bits));
                    (h.t.to_bits(), v)
                };
                assert_eq!(bits(&full), bits(&got.hit), "{name}: {ray:?}");
                let lazy = prepared.bvh.intersect_lazy(ray, 0.0, f32::INFINITY);
                // A revolve's hit is deferred (its `uv` needs the arc length and an angle).
                let deferred = matches!(lazy, Some((LazyHit::Deferred(..), _, _)));
                let trig = deferred
                    || matches!(
                        lazy.and_then(|(_, s, _)| s.shape()),
                        Some(AnyShape::Sphere(_) | AnyShape::Disk(_) | AnyShape::Cylinder(_))
                    );
                if trig && !prepared.reads_uv(id) {
                    assert!(got.hit.uv.is_nan(), "{name}");
                    left_out += 1;
                    revolves.1 += usize::from(deferred);
                } else {
                    let uv_bits = |h: &Hit| h.uv.to_array().map(f32::to_bits);
                    assert_eq!(uv_bits(&full), uv_bits(&got.hit), "{name}: {ray:?}");
                    kept += usize::from(trig);
                    revolves.0 += usize::from(deferred);
                    if name == "absorbing glass" {
                        absorbing_kept += usize::from(trig);
                    }
                }
            }
        }
        println!(
            "uv kept on {kept} textured trig-shape hits ({absorbing_kept} on glass with textured \
             absorption), left out on {left_out}"
        );
        println!(
            "revolve hits: uv kept on {}, left out on {}",
            revolves.0, revolves.1
        );
        assert!(kept > 1000 && left_out > 1000, "{kept} {left_out}");
        assert!(revolves.0 > 300 && revolves.1 > 300, "{revolves:?}");
        assert!(absorbing_kept > 300, "{absorbing_kept}");
    }

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
