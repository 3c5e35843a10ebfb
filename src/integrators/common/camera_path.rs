//! The eye path of one pixel sample: through specular bounces to the first non-specular
//! surface (its visible point), adding the emitted light it meets and the direct light there.
//! SPPM, PPM, photon mapping and Whitted ray tracing all start from it.

use glam::{Vec2, Vec3A};

use super::direct::direct_lighting;
use super::{attenuate_inside, medium_after};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::materials::{Bsdf, TransportMode};
use crate::prepare::{EffectiveSettings, PreparedScene};
use crate::sampling::Rng;

/// Where an eye path reached its first non-specular surface.
#[derive(Clone, Copy)]
pub(crate) struct VisiblePoint {
    pub(crate) p: Vec3A,
    pub(crate) wo: Vec3A,
    pub(crate) bsdf: Bsdf,
    /// The path's throughput up to the point.
    pub(crate) beta: Vec3A,
    /// The length of the camera path to the point (through specular bounces).
    pub(crate) distance: f32,
    /// The absorption of the glass the point is inside (zero: none).
    pub(crate) medium: Vec3A,
}

/// A jittered eye path for pixel (x, y) (pixel position and lens position from `rng`): returns
/// emitted + direct light and the visible point, if the path reached one.
pub(crate) fn camera_path(
    scene: &PreparedScene,
    camera: &Camera,
    settings: &EffectiveSettings,
    x: u32,
    y: u32,
    rng: &mut Rng,
) -> (Vec3A, Option<VisiblePoint>) {
    let jitter = rng.vec2();
    let lens = rng.vec2();
    follow_eye_ray(scene, camera.ray(x, y, jitter, lens), settings, rng, |_| {})
}

/// The eye path through `jitter` (in [0,1)^2) in pixel (x, y), the lens position from `rng`,
/// with the path's signature: a hash of the sequence of objects it met (two paths that met
/// the same objects in the same order have the same signature).
pub(crate) fn signed_camera_path(
    scene: &PreparedScene,
    camera: &Camera,
    settings: &EffectiveSettings,
    (x, y, jitter): (u32, u32, Vec2),
    rng: &mut Rng,
) -> (Vec3A, Option<VisiblePoint>, u64) {
    let lens = rng.vec2();
    // FNV-1a over the objects' indices.
    let mut signature = 0xcbf2_9ce4_8422_2325u64;
    let (l, vp) = follow_eye_ray(scene, camera.ray(x, y, jitter, lens), settings, rng, |o| {
        signature = (signature ^ u64::from(o)).wrapping_mul(0x100_0000_01b3);
    });
    (l, vp, signature)
}

/// The eye path for pixel (x, y) through the pixel center and the lens center. It draws (and
/// ignores) the two samples [`camera_path`] uses for the jitter and the lens, so that the rest
/// of the stream is laid out as in a jittered path.
pub(crate) fn fixed_camera_path(
    scene: &PreparedScene,
    camera: &Camera,
    settings: &EffectiveSettings,
    x: u32,
    y: u32,
    rng: &mut Rng,
) -> (Vec3A, Option<VisiblePoint>) {
    let _jitter = rng.vec2();
    let _lens = rng.vec2();
    let center = Vec2::splat(0.5);
    follow_eye_ray(
        scene,
        camera.ray(x, y, center, center),
        settings,
        rng,
        |_| {},
    )
}

/// Follows `ray` through specular bounces (at most `max_depth` surfaces) to the first
/// non-specular surface; `on_hit(object)` runs at every surface it meets.
#[inline]
fn follow_eye_ray(
    scene: &PreparedScene,
    ray: Ray,
    settings: &EffectiveSettings,
    rng: &mut Rng,
    on_hit: impl FnMut(u32),
) -> (Vec3A, Option<VisiblePoint>) {
    let start = PathStart {
        beta: Vec3A::ONE,
        distance: 0.0,
        gather: false,
        medium: Vec3A::ZERO,
    };
    follow(scene, ray, settings, rng, start, on_hit)
}

/// The final-gather path from visible point `vp`: one BSDF sample there, then through
/// specular and glossy bounces to the next non-specular surface (the gather point), adding the
/// direct light of every non-specular surface it meets. Light that reaches `vp` from an emitter
/// through specular bounces only is left out: the caustic photons at `vp` carry it (see
/// `docs/integrators.md`). Returns that light (weighted by the path's throughput from the
/// camera) and the gather point.
pub(crate) fn gather_path(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    vp: &VisiblePoint,
    rng: &mut Rng,
) -> (Vec3A, Option<VisiblePoint>) {
    let Some(s) = vp
        .bsdf
        .sample(vp.wo, rng.f32(), rng.vec2(), TransportMode::Radiance)
    else {
        return (Vec3A::ZERO, None);
    };
    let beta = vp.beta * s.weight;
    if beta.max_element().is_nan() || beta.max_element() <= 0.0 {
        return (Vec3A::ZERO, None);
    }
    let start = PathStart {
        beta,
        distance: vp.distance,
        gather: true,
        medium: vp.medium,
    };
    let ray = scene.spawn_ray(vp.p, vp.bsdf.ng, s.wi);
    follow(scene, ray, settings, rng, start, |_| {})
}

/// Where [`follow`] starts: the throughput and length of the path so far, and whether it is a
/// gather path (which starts after a BSDF sample at a visible point, not at the camera).
struct PathStart {
    beta: Vec3A,
    distance: f32,
    gather: bool,
    medium: Vec3A,
}

/// Follows `ray` through specular and glossy bounces (at most `max_depth` surfaces) to the
/// first other surface; `on_hit(object)` runs at every surface it meets.
#[inline]
fn follow(
    scene: &PreparedScene,
    mut ray: Ray,
    settings: &EffectiveSettings,
    rng: &mut Rng,
    start: PathStart,
    mut on_hit: impl FnMut(u32),
) -> (Vec3A, Option<VisiblePoint>) {
    let mut beta = start.beta;
    let mut l = Vec3A::ZERO;
    let mut distance = start.distance;
    let mut medium = start.medium;
    // After a glossy bounce, direct_lighting's BSDF sample already counted emission and the
    // background the next segment meets. A gather path starts after such a sample too, and
    // the light it meets through specular bounces alone is the caustic photons' share: it
    // counts emission only once it has passed a glossy surface.
    let mut after_specular = !start.gather;
    let mut counts_emission = !start.gather;
    // A camera path through specular bounces alone still sees the backdrop.
    let mut camera_chain = !start.gather;
    for depth in 0..settings.max_depth {
        let Some(sh) = scene.intersect(&ray, f32::INFINITY) else {
            if after_specular && counts_emission {
                l += beta * scene.escaped_radiance(ray.d, camera_chain);
            }
            break;
        };
        let wo = -ray.d;
        on_hit(scene.prim_object[sh.prim as usize]);
        distance += sh.hit.t * ray.d.length();
        attenuate_inside(scene, &sh, &ray, medium, &mut beta);
        if after_specular
            && counts_emission
            && let Some((_, al)) = scene.area_light(sh.prim)
        {
            l += beta * al.le(sh.hit.n, wo);
        }
        let bsdf = scene.bsdf(&sh);
        if !bsdf.is_specular() {
            l += beta * direct_lighting(scene, &sh, &bsdf, wo, medium, rng);
            counts_emission = true;
        }
        if !bsdf.is_specular() && (!bsdf.is_glossy() || depth + 1 == settings.max_depth) {
            let vp = VisiblePoint {
                p: sh.hit.p,
                wo,
                bsdf,
                beta,
                distance,
                medium,
            };
            return (l, Some(vp));
        }
        let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2(), TransportMode::Radiance) else {
            break;
        };
        medium = medium_after(scene, &sh, wo, s.wi, medium);
        after_specular = s.specular;
        camera_chain &= s.specular;
        beta *= s.weight;
        if beta.max_element() <= 0.0 {
            break;
        }
        ray = scene.spawn_ray(sh.hit.p, sh.hit.n, s.wi);
    }
    (l, None)
}
