//! Photon emission and tracing: a light chosen by power emits a photon, which bounces through
//! the scene by BSDF sampling (importance transport) with Russian roulette. SPPM, PPM and photon
//! mapping decide what to keep at each surface.

use glam::Vec3A;

use super::{attenuate_inside, medium_after};
use crate::geometry::Ray;
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
    let Some(ps) = scene.lights[li].sample_photon(u1, u2) else {
        return;
    };
    let mut beta = ps.beta / pl;
    let mut ray = if ps.n == Vec3A::ZERO {
        Ray::new(ps.p, ps.dir)
    } else {
        scene.spawn_ray(ps.p, ps.n, ps.dir)
    };
    let mut all_specular = true;
    // The absorption of the glass the photon is inside (zero: none; a light inside a glass
    // starts outside of it as far as this knows, and its first segment is absorbed only where
    // it ends on that glass).
    let mut medium = Vec3A::ZERO;
    for depth in 0..max_depth {
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
        let bnew = beta * s.weight;
        // Russian roulette keeps the photon's power roughly constant.
        let q = (1.0 - bnew.max_element() / beta.max_element()).max(0.0);
        if rng.f32() < q {
            return;
        }
        beta = bnew / (1.0 - q);
        if !beta.is_finite() || beta.max_element() <= 0.0 {
            return;
        }
        ray = scene.spawn_ray(sh.hit.p, sh.hit.n, s.wi);
    }
}
