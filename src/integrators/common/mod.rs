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
use crate::prepare::{PreparedScene, SurfaceHit};
use crate::sampling::Rng;

/// Bounces before Russian roulette may end a camera path.
const ROULETTE_BOUNCES: u32 = 4;

/// Russian roulette for a camera path after its `bounces`-th bounce, whose throughput is now
/// `beta`: from the fourth bounce on, it ends with probability `1 - max(beta)` (at most 0.95)
/// and survivors carry the difference. Returns whether the path goes on with a usable `beta`.
#[inline]
pub(crate) fn camera_roulette(beta: &mut Vec3A, bounces: u32, rng: &mut Rng) -> bool {
    if bounces >= ROULETTE_BOUNCES {
        let q = (1.0 - beta.max_element()).max(0.05);
        if rng.f32() < q {
            return false;
        }
        *beta /= 1.0 - q;
    }
    beta.is_finite() && beta.max_element() > 0.0
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
