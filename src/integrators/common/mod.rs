//! Code more than one integrator uses: the eye path to the first non-specular surface, direct
//! lighting, photon emission and tracing, absorption inside dielectrics, the progressive
//! iteration loop and the random streams.

pub(crate) mod camera_path;
pub(crate) mod camera_samples;
pub(crate) mod direct;
pub(crate) mod footprint;
pub(crate) mod photons;
pub(crate) mod progressive;
pub(crate) mod streams;

use glam::Vec3A;

use crate::geometry::Ray;
use crate::materials::{Bsdf, Lobes};
use crate::prepare::{PreparedScene, SurfaceHit};
use crate::sampling::Rng;

/// Bounces before Russian roulette may end a camera path.
const ROULETTE_BOUNCES: u32 = 4;

/// Russian roulette for a camera path after its `bounces`-th bounce, whose throughput is now
/// `beta`: from the fourth bounce on, it ends with probability `1 - max(beta * eta_scale)` (at
/// most 0.95) and survivors carry the difference. Returns whether the path goes on with a
/// usable `beta`. `eta_scale` is the product of the path's [`refraction_scale`]s, which undoes
/// the `1 / eta^2` a radiance path takes on entering glass (and gives back on leaving it), as
/// pbrt's `etaScale` does. Judged on `beta` alone, a camera path inside glass would end with
/// probability `1 - 1/eta^2` (0.56 at index 1.5) at every roulette there, though the light it
/// carries is not smaller: on `crystal_tree` that doubled the variance of what the camera sees
/// through the glass.
#[inline]
pub(crate) fn camera_roulette(
    beta: &mut Vec3A,
    eta_scale: f32,
    bounces: u32,
    rng: &mut Rng,
) -> bool {
    if bounces >= ROULETTE_BOUNCES {
        let q = (1.0 - (*beta * eta_scale).max_element()).max(0.05);
        if rng.f32() < q {
            return false;
        }
        *beta /= 1.0 - q;
    }
    beta.is_finite() && beta.max_element() > 0.0
}

/// The factor that undoes what a radiance path's throughput takes from the index of
/// refraction when it scatters at `bsdf` from `wo` to `wi`: `(n_i / n_o)^2`, the indices on
/// each direction's side of a glass (`Lobes::Glass`, smooth or frosted), 1 for a reflection
/// and every other material (a thin pane has air on both sides).
#[inline]
pub(crate) fn refraction_scale(bsdf: &Bsdf, wo: Vec3A, wi: Vec3A) -> f32 {
    match bsdf.lobes {
        Lobes::Glass { eta, .. } => {
            let n = bsdf.frame.n;
            let index = |w: Vec3A| if n.dot(w) < 0.0 { eta } else { 1.0 };
            let r = index(wi) / index(wo);
            r * r
        }
        _ => 1.0,
    }
}

/// Beer–Lambert absorption along the segment `ray` ran to `sh` inside an absorbing dielectric:
/// where it hits a glass from its inner side, that glass's absorption (a textured one averaged
/// with the medium's, its value where the path passed in); anywhere else, that of
/// the `medium` the path is in (see [`medium_after`]): a path inside coloured glass is absorbed
/// on its way to an object or a light inside the glass as well.
#[inline(always)]
pub(crate) fn attenuate_inside(
    scene: &PreparedScene,
    sh: &SurfaceHit,
    ray: &Ray,
    medium: Vec3A,
    beta: &mut Vec3A,
) {
    // No material absorbs: the medium is zero and every glass clear.
    if !scene.absorbs() {
        return;
    }
    let inner_side = ray.d.dot(sh.hit.n) > 0.0;
    // Outside every glass and arriving from the outer side (most segments): nothing absorbs.
    // Checked inline; the rest is a call.
    if !inner_side && medium == Vec3A::ZERO {
        return;
    }
    attenuate_glass(scene, sh, ray, medium, inner_side, beta);
}

/// [`attenuate_inside`] where a glass may absorb (`inner_side`: the segment ends on the inner
/// side of the surface).
#[inline(never)]
fn attenuate_glass(
    scene: &PreparedScene,
    sh: &SurfaceHit,
    ray: &Ray,
    medium: Vec3A,
    inner_side: bool,
    beta: &mut Vec3A,
) {
    let sigma = match inner_side
        .then(|| scene.glass_absorption_varying(sh))
        .flatten()
    {
        // A textured absorption is looked up at both ends of the segment: where the path
        // passed into the glass (the medium it carries) and here. Their mean is the same
        // whichever way the segment is crossed, so camera paths and photons absorb alike.
        Some((glass, true)) => 0.5 * (glass + medium),
        Some((glass, false)) => glass,
        None => medium,
    };
    if sigma != Vec3A::ZERO {
        let dist = sh.hit.t * ray.d.length();
        *beta *= transmittance(sigma, dist);
    }
}

/// Beer–Lambert transmittance through `dist` of a medium of absorption `sigma`.
#[inline]
pub(crate) fn transmittance(sigma: Vec3A, dist: f32) -> Vec3A {
    if sigma == Vec3A::ZERO {
        Vec3A::ONE
    } else {
        (-sigma * dist).exp()
    }
}

/// The absorbing medium a path is in after it scattered at `sh` from `wo` into `wi` (both
/// pointing away from the surface): passing through a glass into it, that glass's absorption;
/// out of it, none (zero; nested glasses are not tracked: leaving the inner one leaves both);
/// any reflection, and any other surface, keeps `medium`.
#[inline]
pub(crate) fn medium_after(
    scene: &PreparedScene,
    sh: &SurfaceHit,
    wo: Vec3A,
    wi: Vec3A,
    medium: Vec3A,
) -> Vec3A {
    // No material absorbs: every glass's absorption is zero, as the medium is.
    if !scene.absorbs() {
        return medium;
    }
    let n = sh.hit.n;
    let (o, i) = (wo.dot(n), wi.dot(n));
    if o * i >= 0.0 {
        return medium;
    }
    match scene.glass_absorption(sh) {
        None => medium,
        Some(glass) if i < 0.0 => glass,
        Some(_) => Vec3A::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3A};

    use super::{camera_roulette, refraction_scale};
    use crate::materials::{Bsdf, Lobes, TransportMode};
    use crate::sampling::Rng;

    /// `refraction_scale` undoes exactly what radiance transport adds to a glass sample's
    /// weight: radiance weight times the scale is the importance weight, for smooth and
    /// frosted glass, from outside and from inside, refracted and reflected.
    #[test]
    fn refraction_scale_undoes_the_radiance_factor_of_glass() {
        let mut rng = Rng::new(7);
        let mut refracted = [0u32; 2];
        for alpha in [0.0f32, 0.3] {
            let lobes = Lobes::Glass {
                eta: 1.5,
                tint: Vec3A::ONE,
                alpha,
            };
            let b = Bsdf::new(lobes, Vec3A::Z, Vec3A::X, Vec3A::Z);
            for k in 0..400 {
                let side = if k % 2 == 0 { 1.0 } else { -1.0 };
                let wo = Vec3A::new(rng.f32() - 0.5, rng.f32() - 0.5, side * (0.1 + rng.f32()))
                    .normalize();
                let (uc, u) = (rng.f32(), Vec2::new(rng.f32(), rng.f32()));
                let (Some(r), Some(i)) = (
                    b.sample(wo, uc, u, TransportMode::Radiance),
                    b.sample(wo, uc, u, TransportMode::Importance),
                ) else {
                    continue;
                };
                assert_eq!(r.wi, i.wi);
                let scale = refraction_scale(&b, wo, r.wi);
                if wo.z * r.wi.z < 0.0 {
                    refracted[usize::from(wo.z < 0.0)] += 1;
                    assert!((scale - 1.0).abs() > 0.5, "a refraction's scale is eta^+-2");
                } else {
                    assert_eq!(scale, 1.0, "a reflection keeps the throughput");
                }
                let (a, e) = (r.weight * scale, i.weight);
                assert!(
                    (a - e).abs().max_element() <= 1e-4 * e.abs().max_element().max(1e-3),
                    "alpha {alpha}, wo {wo}: radiance {} x {scale} against importance {e}",
                    r.weight
                );
            }
        }
        assert!(
            refracted.iter().all(|&n| n > 50),
            "refractions {refracted:?}"
        );
    }

    /// Inside glass a camera path's throughput is `1 / eta^2` of the light it carries: judged
    /// with the scale the roulette ends it as rarely as outside (5 %), judged on the
    /// throughput alone it would end 56 % of such paths at index 1.5.
    #[test]
    fn the_roulette_inside_glass_follows_the_scaled_throughput() {
        let mut rng = Rng::new(11);
        let (mut plain, mut scaled) = (0u32, 0u32);
        let n = 20_000;
        for _ in 0..n {
            let mut beta = Vec3A::splat(1.0 / 2.25);
            plain += u32::from(camera_roulette(&mut beta, 1.0, 4, &mut rng));
            let mut beta = Vec3A::splat(1.0 / 2.25);
            scaled += u32::from(camera_roulette(&mut beta, 2.25, 4, &mut rng));
            assert!((beta.x - 1.0 / 2.25 / 0.95).abs() < 1e-6 || beta.x == 1.0 / 2.25);
        }
        let (plain, scaled) = (f64::from(plain) / n as f64, f64::from(scaled) / n as f64);
        assert!((plain - 1.0 / 2.25).abs() < 0.02, "plain survival {plain}");
        assert!((scaled - 0.95).abs() < 0.01, "scaled survival {scaled}");
    }
}
