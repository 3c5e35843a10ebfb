//! Photon emission and tracing: a light chosen by power emits a photon, which bounces through
//! the scene by BSDF sampling (importance transport) with Russian roulette. SPPM, PPM and photon
//! mapping decide what to keep at each surface.

use glam::{Vec2, Vec3A};

use super::{attenuate_inside, medium_after};
use crate::geometry::Ray;
use crate::lights::{GroundPhotons, Light};
use crate::materials::TransportMode;
use crate::prepare::{PreparedScene, SurfaceHit};
use crate::sampling::Rng;

/// One photon path from a light chosen by power. `at_hit(depth, hit, wi, beta)` runs at every
/// surface the photon reaches, `beta` being the photon's flux there (before the surface's BSDF).
pub(crate) fn trace_photon(
    scene: &PreparedScene,
    max_depth: u32,
    rng: &mut Rng,
    mut at_hit: impl FnMut(u32, &SurfaceHit, Vec3A, Vec3A),
) {
    trace_classified_photon(scene, max_depth, rng, |depth, sh, wi, beta, _| {
        at_hit(depth, sh, wi, beta)
    });
}

/// [`trace_photon`], telling `at_hit` also whether every bounce before this surface was a
/// specular one (true at the first surface): the photon is then a caustic photon.
pub(crate) fn trace_classified_photon(
    scene: &PreparedScene,
    max_depth: u32,
    rng: &mut Rng,
    mut at_hit: impl FnMut(u32, &SurfaceHit, Vec3A, Vec3A, bool),
) {
    let Some((li, pl)) = scene.photon_distr.sample(rng.f32()) else {
        return;
    };
    let (u1, u2) = (rng.vec2(), rng.vec2());
    let (mut ray, mut beta, mut all_specular, first) = if li < scene.lights.len() {
        let Some(ps) = scene.sample_photon(li, u1, u2) else {
            return;
        };
        // An environment photon starts on a disk just outside the finite shapes, not at
        // infinity: an infinite plane may lie between the sky and that disk (the sky below a
        // ground's horizon cannot light what stands on it). Only infinite shapes can.
        if scene.environment == Some(li)
            && scene.bvh.unbounded_len() > 0
            && scene.occluded(&Ray::new(ps.p, -ps.dir), f32::INFINITY)
        {
            return;
        }
        let ray = if ps.n == Vec3A::ZERO {
            Ray::new(ps.p, ps.dir)
        } else {
            scene.spawn_ray(ps.p, ps.n, ps.dir)
        };
        (ray, ps.beta / pl, true, 0)
    } else {
        let Some(g) = scene.ground_photons.get(li - scene.lights.len()) else {
            return;
        };
        if max_depth == 0 {
            return;
        }
        // The photon's first surface is the plane: it continues from there at depth 1.
        let Some((ray, beta)) = ground_start(scene, g, pl, u1, u2, rng, &mut at_hit) else {
            return;
        };
        (ray, beta, false, 1)
    };
    // The absorption of the glass the photon is inside (zero: none; a light inside a glass
    // starts outside of it as far as this knows, and its first segment is absorbed only where
    // it ends on that glass).
    let mut medium = Vec3A::ZERO;
    for depth in first..max_depth {
        let Some(sh) = scene.intersect(&ray, f32::INFINITY) else {
            return;
        };
        attenuate_inside(scene, &sh, &ray, medium, &mut beta);
        let wi = -ray.d;
        at_hit(depth, &sh, wi, beta, all_specular);
        let bsdf = scene.bsdf(&sh);
        let Some(s) = bsdf.sample(wi, rng.f32(), rng.vec2(), TransportMode::Importance) else {
            return;
        };
        medium = medium_after(scene, &sh, wi, s.wi, medium);
        all_specular &= s.specular;
        if !roulette(&mut beta, s.weight, rng) {
            return;
        }
        ray = scene.spawn_ray(sh.hit.p, sh.hit.n, s.wi);
    }
}

/// Russian roulette after a bounce that multiplies the photon's power `beta` by `weight`:
/// keeps the power roughly constant. Returns whether the photon goes on (`beta` then its new
/// power).
pub(crate) fn roulette(beta: &mut Vec3A, weight: Vec3A, rng: &mut Rng) -> bool {
    let next = *beta * weight;
    let q = (1.0 - next.max_element() / beta.max_element()).max(0.0);
    if rng.f32() < q {
        return false;
    }
    *beta = next / (1.0 - q);
    beta.is_finite() && beta.max_element() > 0.0
}

/// A photon of the far part of an infinite plane ([`GroundPhotons`]): a point of the plane and
/// a sky direction the environment light's disk does not cover, reported to `at_hit` as the
/// photon's first surface (depth 0), and its bounce: the ray leaving the plane and the power
/// it carries.
fn ground_start(
    scene: &PreparedScene,
    g: &GroundPhotons,
    pl: f32,
    u1: Vec2,
    u2: Vec2,
    rng: &mut Rng,
    at_hit: &mut impl FnMut(u32, &SurfaceHit, Vec3A, Vec3A, bool),
) -> Option<(Ray, Vec3A)> {
    let (p, pdf_area) = g.sample_point(u1);
    let Light::Environment(env) = scene.lights.get(g.env)? else {
        return None;
    };
    let sky = env.sample_li(p, u2)?;
    let w = sky.wi;
    let cos = w.dot(g.normal);
    if !(cos > 0.0 && pdf_area > 0.0) || g.covered_by_disk(p, w) {
        return None;
    }
    // From a point just above the plane along the sky direction: the plane must be the first
    // surface below it, and nothing may hide the sky above it.
    let lift = 1e-4 * g.scale.max((p - g.origin).length() * 1e-3);
    let q = p + w * (lift / cos);
    let sh = scene.intersect(&Ray::new(q, -w), f32::INFINITY)?;
    if sh.prim != g.prim || scene.occluded(&Ray::new(q, w), f32::INFINITY) {
        return None;
    }
    let beta = sky.li * (cos / (sky.pdf * pdf_area * pl));
    if !beta.is_finite() {
        return None;
    }
    at_hit(0, &sh, w, beta, true);
    // The bounce goes toward the objects (the bounding sphere of the finite shapes): what the
    // far plane sends elsewhere leaves the scene or reaches another plane's far part (not
    // covered). A specular plane reflects into one direction, which this cannot choose.
    let bsdf = scene.bsdf(&sh);
    if bsdf.is_specular() {
        return None;
    }
    let (d, pdf) = g.sample_toward_objects(sh.hit.p, rng.vec2())?;
    let weight = bsdf.f(d, w) * (d.dot(sh.hit.ns).abs() / pdf);
    // No roulette here: the power before this bounce is that of the whole far plane's light
    // (its density is low), and most of it does not leave toward the objects; the bounce's
    // weight brings it down to a photon's usual power.
    let beta = beta * weight;
    (beta.is_finite() && beta.max_element() > 0.0)
        .then(|| (scene.spawn_ray(sh.hit.p, sh.hit.n, d), beta))
}
