//! Unidirectional path tracing with next-event estimation: at every non-specular vertex the
//! shared [`direct_lighting`] combines one light sample and one BSDF sample with the power
//! heuristic (MIS); the path then continues with a fresh BSDF sample and counts emission it hits
//! only after specular bounces (direct lighting already accounted for the rest). Russian
//! roulette from the fourth vertex on. One sample per pixel per iteration, seeded from
//! (seed, iteration, pixel): unbiased, the reference the photon methods are checked against.

use crate::integrators::Job;

use glam::Vec3A;

use super::common::direct::direct_lighting;
use super::common::progressive;
use super::common::{attenuate_inside, camera_roulette, medium_after, refraction_scale};
use super::{Integrator, RenderOutput};
use crate::camera::Camera;
use crate::materials::TransportMode;
use crate::prepare::PreparedScene;
use crate::sampling::Rng;

/// Path tracing with next-event estimation.
#[derive(Debug, Clone, Copy, Default)]
pub struct PathTracer;

impl Integrator for PathTracer {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput {
        let (scene, settings, _cancel) = (job.scene, job.settings, job.cancel);
        progressive::render(
            job,
            |_| ((), 0),
            |_, camera, x, y, rng| radiance(scene, camera, settings.max_depth, x, y, rng),
        )
    }
}

/// One path-traced radiance sample for pixel (x, y).
fn radiance(
    scene: &PreparedScene,
    camera: &Camera,
    max_depth: u32,
    x: u32,
    y: u32,
    rng: &mut Rng,
) -> Vec3A {
    let jitter = rng.vec2();
    let lens = rng.vec2();
    let mut ray = camera.ray(x, y, jitter, lens);
    let mut beta = Vec3A::ONE;
    let mut l = Vec3A::ZERO;
    let mut specular_bounce = true;
    // Every bounce so far specular: the path still sees the backdrop.
    let mut camera_chain = true;
    // The absorption of the glass the path is inside (zero: none).
    let mut medium = Vec3A::ZERO;
    // The product of the bounces' refraction scales: the roulette judges `beta` without
    // the `1 / eta^2` of the glass the path is in.
    let mut eta_scale = 1.0;
    for depth in 0..max_depth {
        let Some(sh) = scene.intersect(&ray, f32::INFINITY) else {
            // After a non-specular bounce the escaped direction was already counted by
            // direct_lighting's BSDF sample.
            if specular_bounce {
                l += beta * scene.escaped_radiance(ray.d, camera_chain);
            }
            break;
        };
        let wo = -ray.d;
        attenuate_inside(scene, &sh, &ray, medium, &mut beta);
        if specular_bounce && let Some((_, al)) = scene.area_light(sh.prim) {
            l += beta * al.le(sh.hit.n, wo);
        }
        let bsdf = scene.bsdf(&sh);
        if !bsdf.is_specular() {
            l += beta * direct_lighting(scene, &sh, &bsdf, wo, medium, rng);
        }
        let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2(), TransportMode::Radiance) else {
            break;
        };
        medium = medium_after(scene, &sh, wo, s.wi, medium);
        specular_bounce = s.specular;
        camera_chain &= s.specular;
        beta *= s.weight;
        eta_scale *= refraction_scale(&bsdf, wo, s.wi);
        if !camera_roulette(&mut beta, eta_scale, depth + 1, rng) {
            break;
        }
        ray = scene.spawn_ray(sh.hit.p, sh.hit.n, s.wi);
    }
    l
}
