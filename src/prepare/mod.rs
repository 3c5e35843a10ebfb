//! The prepared scene: world-space shapes in a BVH, lights with a power distribution, and the
//! per-object data shading needs. Built once per render from a plain `Scene`.

use glam::{Affine3A, DVec3, Vec3A};

mod budget;
mod build;
mod bump;
mod csg;
mod emitters;
mod instances;
mod lights;
mod method;
mod orient;
mod rays;
mod settings;
mod shading;
mod shapes;
mod sky;

use crate::accel::Bvh;
use crate::camera::Camera;
use crate::diag::Diagnostic;
use crate::geometry::{Hit, Ray};
use crate::lights::{GroundPhotons, Light};
use crate::materials::Lobes;
use crate::sampling::PiecewiseConstant1D;
use crate::scene::{self, Scene};
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
use shading::GlassAbsorption;

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
    /// pattern space ([`crate::textures::bump::pattern_scale`], which sets the difference step);
    /// 1 otherwise.
    bump_scale: Vec<f32>,
    /// The floor of a spawned ray's offset, from the scene's extent
    /// ([`crate::accel::offset_floor`]).
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
                            iso.max_visits()
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
}
