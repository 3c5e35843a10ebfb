//! Whitted-style ray tracing: eye rays follow perfect reflection and refraction (the branch at
//! glass is chosen by Fresnel, one per sample) up to `max_depth`; at the first non-specular
//! surface the shared [`direct_lighting`] samples the lights with shadow rays (area lights are
//! sampled over their surface: soft shadows), and a constant ambient term stands for all
//! indirect light. No light ever reaches a diffuse surface through glass or a mirror: caustics
//! stay dark (a known limitation, not a bug). One jittered sample per pixel per iteration,
//! seeded from (seed, iteration, pixel).
//!
//! [`direct_lighting`]: crate::integrators::direct_lighting

use crate::integrators::Job;
use std::f32::consts::PI;

use super::common::camera_path::camera_path;
use super::common::progressive;
use super::{Integrator, RenderOutput};

/// Uniform ambient radiance arriving at every non-specular surface (reflected as
/// `pi * f(wo, n) * AMBIENT`, i.e. `albedo * AMBIENT` on a diffuse surface).
pub const AMBIENT: f32 = 0.05;

/// Whitted-style ray tracing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Whitted;

impl Integrator for Whitted {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput {
        let (scene, settings, _cancel) = (job.scene, job.settings, job.cancel);
        progressive::render(
            job,
            |_| ((), 0),
            |_, camera, x, y, rng| {
                let (l, vp) = camera_path(scene, camera, settings, x, y, rng);
                match vp {
                    Some(vp) => {
                        let n = vp.bsdf.frame.n;
                        let n = if n.dot(vp.wo) < 0.0 { -n } else { n };
                        l + vp.beta * vp.bsdf.f(vp.wo, n) * (PI * AMBIENT)
                    }
                    None => l,
                }
            },
        )
    }
}
