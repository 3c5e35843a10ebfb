//! Direct lighting at a non-specular surface point: one light sample (lights chosen by power)
//! and one BSDF sample, combined with the power heuristic (MIS). Delta lights use light
//! sampling alone; a BSDF sample that escapes sees the environment light weighted by MIS (a
//! uniform background is never chosen for a light sample, so its BSDF sample weighs 1).

use glam::Vec3A;

use super::{medium_after, transmittance};
use crate::geometry::Ray;
use crate::lights::LightSample;
use crate::materials::{Bsdf, TransportMode};
use crate::prepare::{PreparedScene, SurfaceHit};
use crate::sampling::{Rng, power_heuristic};

/// Reflected (or, through frosted glass, transmitted) direct radiance toward `wo`, at a point
/// inside a medium of absorption `medium` (zero: none). A light sample or a BSDF sample that
/// reaches a light crosses no other surface, so the whole way to the light is in the medium on
/// its side of this surface (`medium_after`: the same one but across frosted glass).
pub fn direct_lighting(
    scene: &PreparedScene,
    sh: &SurfaceHit,
    bsdf: &Bsdf,
    wo: Vec3A,
    medium: Vec3A,
    rng: &mut Rng,
) -> Vec3A {
    let p = sh.hit.p;
    let n = sh.hit.n;
    let mut l = Vec3A::ZERO;
    // Light sampling.
    if let Some(s) = sample_light(scene, sh, rng) {
        let ls = &s.sample;
        let f = bsdf.f(wo, ls.wi) * ls.wi.dot(bsdf.frame.n).abs();
        if f != Vec3A::ZERO && !scene.occluded(&s.shadow_ray, s.t_max) {
            let w = if ls.delta {
                1.0
            } else {
                power_heuristic(s.light_pdf * ls.pdf, bsdf.pdf(wo, ls.wi))
            };
            let absorbed = s.transmittance(scene, sh, wo, medium);
            l += f * ls.li * absorbed * (w / (s.light_pdf * ls.pdf));
        }
    }
    // Whether the point lies on light `li`'s own surface (sampled there by area).
    let own = scene.prim_light.get(sh.prim as usize).copied();
    let on_light = |li: usize| own == Some(li as u32);
    // BSDF sampling.
    let uc = rng.f32();
    let ub = rng.vec2();
    if let Some(bs) = bsdf.sample(wo, uc, ub, TransportMode::Radiance)
        && !bs.specular
    {
        let ray = scene.spawn_ray(p, n, bs.wi);
        // Only a light adds here: an area light the ray ends on, or the environment light it
        // escapes to. Without an environment light, a ray that misses every area light's box
        // is done without a closest-hit search.
        let env = scene.environment_light();
        if env.is_some() || scene.may_hit_light(&ray) {
            match scene.intersect(&ray, f32::INFINITY) {
                Some(h2) => {
                    if let Some((li, al)) = scene.area_light(h2.prim) {
                        let le = al.le(h2.hit.n, -bs.wi);
                        if le != Vec3A::ZERO {
                            let light_pdf = scene.light_distr.pdf(li)
                                * al.pdf_li_from(p, h2.hit.p, h2.hit.n, on_light(li));
                            let medium = medium_after(scene, sh, wo, bs.wi, medium);
                            let absorbed = transmittance(medium, h2.hit.t * ray.d.length());
                            l += bs.weight * le * absorbed * power_heuristic(bs.pdf, light_pdf);
                        }
                    }
                }
                // A non-black background is the environment light: weigh its BSDF sample
                // against light sampling.
                None => {
                    if let Some((li, env)) = env {
                        let le = env.le(bs.wi);
                        if le != Vec3A::ZERO {
                            let light_pdf = scene.light_distr.pdf(li) * env.pdf_li(bs.wi);
                            l += bs.weight * le * power_heuristic(bs.pdf, light_pdf);
                        }
                    }
                }
            }
        }
    }
    l
}

/// A light sample for next-event estimation at a surface point: the light (chosen by power),
/// its probability, the sample, and the shadow ray that must be unoccluded for it to count.
pub(crate) struct SampledLight {
    pub(crate) light: usize,
    pub(crate) light_pdf: f32,
    pub(crate) sample: LightSample,
    /// Toward the sky: infinite (anything along the way shadows it, an infinite plane far
    /// beyond the finite objects included).
    pub(crate) shadow_ray: Ray,
    pub(crate) t_max: f32,
}

impl SampledLight {
    /// Absorption on the way to the light, from a point inside a medium of absorption
    /// `medium` (see [`direct_lighting`]). Toward the sky the distance is unknown; a path
    /// reaches it only out of the glass it was in, as an escaping path does, unabsorbed.
    pub(crate) fn transmittance(
        &self,
        scene: &PreparedScene,
        sh: &SurfaceHit,
        wo: Vec3A,
        medium: Vec3A,
    ) -> Vec3A {
        if self.t_max.is_finite() {
            let medium = medium_after(scene, sh, wo, self.sample.wi, medium);
            transmittance(medium, self.t_max * self.shadow_ray.d.length())
        } else {
            Vec3A::ONE
        }
    }
}

/// Chooses a light by power and samples it from the surface point of `sh` (by area on the
/// light's own surface when the point lies on it). Draws one number and a pair from `rng`
/// whether or not a sample results.
pub(crate) fn sample_light(
    scene: &PreparedScene,
    sh: &SurfaceHit,
    rng: &mut Rng,
) -> Option<SampledLight> {
    let (p, n) = (sh.hit.p, sh.hit.n);
    let uc = rng.f32();
    let ul = rng.vec2();
    let (li, pl) = scene.light_distr.sample(uc)?;
    let on_light = scene.prim_light.get(sh.prim as usize) == Some(&(li as u32));
    let ls = scene.lights[li].sample_li_from(p, ul, on_light)?;
    let (shadow_ray, t_max) = if scene.environment == Some(li) {
        (scene.spawn_ray(p, n, ls.wi), f32::INFINITY)
    } else {
        scene.spawn_ray_to(p, n, ls.p, ls.n)
    };
    let t_max = if ls.delta { t_max * 0.9999 } else { t_max };
    Some(SampledLight {
        light: li,
        light_pdf: pl,
        sample: ls,
        shadow_ray,
        t_max,
    })
}
