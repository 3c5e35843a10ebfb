//! A GGX microfacet lobe (Schlick Fresnel tinted by `specular`) over a Lambertian base scaled by
//! `1 - max(specular)` so that the sum stays below one for common parameters. Sampling picks
//! the lobe with probability one half and samples the GGX distribution of normals.

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3A};

use super::BsdfSample;
use crate::sampling::cosine_hemisphere;

fn d_ggx(h: Vec3A, a2: f32) -> f32 {
    let c2 = h.z * h.z;
    let k = (a2 - 1.0) * c2 + 1.0;
    a2 / (PI * k * k)
}

fn g1(v: Vec3A, a2: f32) -> f32 {
    let c2 = v.z * v.z;
    if c2 == 0.0 {
        return 0.0;
    }
    let tan2 = (1.0 - c2).max(0.0) / c2;
    2.0 / (1.0 + (1.0 + a2 * tan2).sqrt())
}

fn schlick(f0: Vec3A, cos: f32) -> Vec3A {
    let m = (1.0 - cos.abs()).clamp(0.0, 1.0);
    let m5 = m * m * m * m * m;
    f0 + (Vec3A::ONE - f0) * m5
}

fn flip(wo: Vec3A, wi: Vec3A) -> (Vec3A, Vec3A) {
    // Evaluate in the hemisphere of wo (two-sided).
    if wo.z < 0.0 {
        (Vec3A::new(wo.x, wo.y, -wo.z), Vec3A::new(wi.x, wi.y, -wi.z))
    } else {
        (wo, wi)
    }
}

pub fn f(albedo: Vec3A, specular: Vec3A, alpha: f32, wo: Vec3A, wi: Vec3A) -> Vec3A {
    let (wo, wi) = flip(wo, wi);
    let a2 = alpha * alpha;
    let h = (wo + wi).normalize_or_zero();
    let base = albedo * (1.0 - specular.max_element()).max(0.0) * FRAC_1_PI;
    if h == Vec3A::ZERO {
        return base;
    }
    let spec = schlick(specular, wi.dot(h)) * (d_ggx(h, a2) * g1(wo, a2) * g1(wi, a2))
        / (4.0 * wo.z * wi.z);
    base + spec
}

pub fn pdf(_albedo: Vec3A, _specular: Vec3A, alpha: f32, wo: Vec3A, wi: Vec3A) -> f32 {
    let (wo, wi) = flip(wo, wi);
    let a2 = alpha * alpha;
    let h = (wo + wi).normalize_or_zero();
    let spec = if h == Vec3A::ZERO || wo.dot(h) <= 0.0 {
        0.0
    } else {
        d_ggx(h, a2) * h.z / (4.0 * wo.dot(h))
    };
    0.5 * spec + 0.5 * wi.z * FRAC_1_PI
}

pub fn sample(
    albedo: Vec3A,
    specular: Vec3A,
    alpha: f32,
    wo: Vec3A,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    let (wof, _) = flip(wo, wo);
    let wi = if uc < 0.5 {
        let a2 = alpha * alpha;
        let tan2 = a2 * u.x / (1.0 - u.x).max(1e-7);
        let cos_t = 1.0 / (1.0 + tan2).sqrt();
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let h = Vec3A::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
        let wi = h * (2.0 * wof.dot(h)) - wof;
        if wi.z <= 0.0 {
            return None;
        }
        wi
    } else {
        cosine_hemisphere(u)
    };
    let p = pdf(albedo, specular, alpha, wof, wi);
    if p <= 0.0 {
        return None;
    }
    let value = f(albedo, specular, alpha, wof, wi);
    let wi = if wo.z < 0.0 {
        Vec3A::new(wi.x, wi.y, -wi.z)
    } else {
        wi
    };
    Some(BsdfSample {
        wi,
        weight: value * wi.z.abs() / p,
        pdf: p,
        specular: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Sampling weights average to the directional albedo, which stays below one.
    #[test]
    fn energy_stays_bounded() {
        let mut rng = Rng::new(3);
        let wo = Vec3A::new(0.5, 0.0, 0.866).normalize();
        let n = 200_000;
        let mut sum = Vec3A::ZERO;
        for _ in 0..n {
            if let Some(s) = sample(
                Vec3A::splat(0.5),
                Vec3A::splat(0.5),
                0.3,
                wo,
                rng.f32(),
                rng.vec2(),
            ) {
                sum += s.weight;
            }
        }
        let albedo = sum / n as f32;
        println!("glossy directional albedo {albedo}");
        assert!(albedo.x > 0.3 && albedo.x < 1.0, "{albedo}");
    }
}
