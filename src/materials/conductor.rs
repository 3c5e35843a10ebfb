//! A metal: Fresnel reflection for a complex index of refraction `eta + i k` per RGB channel,
//! either smooth (`alpha` 0: a delta lobe, like the mirror) or a GGX microfacet lobe sampled
//! by its visible normals, sharing glossy.rs's distribution, shadowing and sampler.
//!
//! Single-scattering GGX loses the light that would bounce between microfacets (and, at high
//! roughness, the half of the mirrored directions that fall below the horizon): with `F = 1`
//! the directional albedo at normal incidence is 0.998 at roughness 0.2, 0.916 at 0.5, 0.627
//! at 0.75 and 0.307 at 1 (`conductor_energy_loss`; the same figures come from a 1-D quadrature
//! over the half-vector angle). It is not compensated (Kulla and Conty 2017 would add the
//! missing energy back); docs/language.md says so.

use glam::{Vec2, Vec3A};

use super::BsdfSample;
use super::glossy::{d_ggx, flip, g1, sample_visible_normal, unflipped_sample};

/// GGX `alpha` below which the rough lobe's density overflows `f32` near the peak: rough
/// lobes use at least this much (glossy.rs keeps the same floor).
const MIN_ALPHA: f32 = 1e-3;

/// Unpolarised Fresnel reflectance of a conductor for one channel at `cos` (the exact
/// equations for a complex index, in the closed form of pbrt-v3's `FrConductor`).
fn fresnel1(cos: f32, eta: f32, k: f32) -> f32 {
    let c = cos.abs().min(1.0);
    let (c2, s2) = (c * c, 1.0 - c * c);
    let (e2, k2) = (eta * eta, k * k);
    let t0 = e2 - k2 - s2;
    let a2b2 = (t0 * t0 + 4.0 * e2 * k2).max(0.0).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let (t1, t2) = (a2b2 + c2, 2.0 * a * c);
    let (t3, t4) = (c2 * a2b2 + s2 * s2, t2 * s2);
    if t1 + t2 <= 0.0 || t3 + t4 <= 0.0 {
        // Grazing incidence on an index of exactly 1: the limit is total reflection.
        return 1.0;
    }
    let rs = (t1 - t2) / (t1 + t2);
    let rp = rs * (t3 - t4) / (t3 + t4);
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}

/// Per-channel Fresnel reflectance at `cos`.
pub fn fresnel(cos: f32, eta: Vec3A, k: Vec3A) -> Vec3A {
    Vec3A::new(
        fresnel1(cos, eta.x, k.x),
        fresnel1(cos, eta.y, k.y),
        fresnel1(cos, eta.z, k.z),
    )
}

pub fn f(eta: Vec3A, k: Vec3A, alpha: f32, wo: Vec3A, wi: Vec3A) -> Vec3A {
    if alpha == 0.0 {
        return Vec3A::ZERO;
    }
    let (wo, wi) = flip(wo, wi);
    let a2 = alpha.max(MIN_ALPHA).powi(2);
    let h = (wo + wi).normalize_or_zero();
    if h == Vec3A::ZERO || wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3A::ZERO;
    }
    fresnel(wi.dot(h), eta, k) * (d_ggx(h, a2) * g1(wo, a2) * g1(wi, a2)) / (4.0 * wo.z * wi.z)
}

/// Visible-normal density: `G1(wo) (wo.h) D(h) / cos_o` over `4 wo.h`.
pub fn pdf(alpha: f32, wo: Vec3A, wi: Vec3A) -> f32 {
    if alpha == 0.0 {
        return 0.0;
    }
    let (wo, wi) = flip(wo, wi);
    let a2 = alpha.max(MIN_ALPHA).powi(2);
    let h = (wo + wi).normalize_or_zero();
    if h == Vec3A::ZERO || wo.dot(h) <= 0.0 || wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    g1(wo, a2) * d_ggx(h, a2) / (4.0 * wo.z)
}

pub fn sample(eta: Vec3A, k: Vec3A, alpha: f32, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
    if alpha == 0.0 {
        return Some(BsdfSample {
            wi: Vec3A::new(-wo.x, -wo.y, wo.z),
            weight: fresnel(wo.z, eta, k),
            pdf: 1.0,
            specular: true,
        });
    }
    let (wof, _) = flip(wo, wo);
    let h = sample_visible_normal(wof, alpha.max(MIN_ALPHA), u);
    let wi = h * (2.0 * wof.dot(h)) - wof;
    if wi.z <= 0.0 {
        return None;
    }
    let p = pdf(alpha, wof, wi);
    if p <= 0.0 {
        return None;
    }
    let value = f(eta, k, alpha, wof, wi);
    Some(unflipped_sample(wo, wi, value, p))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::Lobes;
    use crate::materials::check::{COS_O, alpha, bsdf, check, no_nan, wo_at};
    use crate::scene::metals::METALS;

    fn metal(name: &str) -> (Vec3A, Vec3A) {
        let m = METALS.iter().find(|m| m.name == name).unwrap();
        let v = |a: [f64; 3]| Vec3A::new(a[0] as f32, a[1] as f32, a[2] as f32);
        (v(m.eta), v(m.k))
    }

    /// Rough and smooth conductors pass the harness for several metals and roughnesses at
    /// every angle.
    #[test]
    fn conductor_passes() {
        let metals = ["Au", "Ag", "Cu", "Fe", "brass"];
        let roughness = [0.0, 0.3, 0.6, 1.0];
        let cases = COS_O.len() * metals.len() * roughness.len();
        for (i, &c) in COS_O.iter().enumerate() {
            for (j, name) in metals.iter().enumerate() {
                for (l, &r) in roughness.iter().enumerate() {
                    let (eta, k) = metal(name);
                    let b = bsdf(Lobes::Conductor {
                        eta,
                        k,
                        alpha: alpha(r),
                    });
                    let seed = (100 * i + 10 * j + l) as u64;
                    if let Err(e) = check(&b, wo_at(c), cases, seed) {
                        panic!("{name} roughness {r} at cos {c}: {e}");
                    }
                }
            }
        }
        no_nan(500_000, 3, |r| {
            let m = &METALS[(r.f32() * METALS.len() as f32) as usize % METALS.len()];
            let v = |a: [f64; 3]| Vec3A::new(a[0] as f32, a[1] as f32, a[2] as f32);
            Lobes::Conductor {
                eta: v(m.eta),
                k: v(m.k),
                alpha: [0.0, 1e-8, 1e-4, r.f32()][(r.f32() * 4.0) as usize % 4],
            }
        });
    }

    /// The exact Fresnel equations: the normal-incidence value is the closed form
    /// `((n-1)^2 + k^2) / ((n+1)^2 + k^2)`, grazing incidence reflects everything, and a
    /// zero `k` gives the dielectric's value (n = 1.5: 0.04 at normal incidence).
    #[test]
    fn fresnel_matches_closed_forms() {
        for (n, k) in [(0.18f32, 3.1f32), (2.9, 3.0), (1.5, 0.0), (1.0, 0.0)] {
            let want = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
            let got = fresnel1(1.0, n, k);
            assert!((got - want).abs() < 1e-5, "{n} {k}: {got} vs {want}");
            assert!((fresnel1(0.0, n, k) - 1.0).abs() < 1e-5, "{n} {k} grazing");
        }
        // Dielectric n = 1.5 at 60 degrees: Rs 0.1766, Rp 0.0018 (standard tables).
        let got = fresnel1(0.5, 1.5, 0.0);
        assert!((got - 0.5 * (0.176_6 + 0.001_8)).abs() < 1e-3, "{got}");
    }

    /// A smooth conductor is a delta lobe: specular samples weighted by the Fresnel value,
    /// mirrored about the normal; a rough one at alpha below 0.3 counts as glossy.
    #[test]
    fn smooth_is_specular_and_rough_is_glossy() {
        let (eta, k) = metal("Au");
        let smooth = bsdf(Lobes::Conductor { eta, k, alpha: 0.0 });
        assert!(smooth.is_specular() && !smooth.is_glossy());
        let wo = wo_at(0.6);
        let s = smooth
            .sample(
                wo,
                0.5,
                Vec2::splat(0.5),
                super::super::TransportMode::Radiance,
            )
            .unwrap();
        assert!(s.specular && (s.wi - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
        assert_eq!(s.weight, fresnel(0.6, eta, k));
        let rough = bsdf(Lobes::Conductor {
            eta,
            k,
            alpha: 0.04,
        });
        assert!(!rough.is_specular() && rough.is_glossy());
        let very = bsdf(Lobes::Conductor { eta, k, alpha: 0.5 });
        assert!(!very.is_specular() && !very.is_glossy());
    }

    /// Single-scattering energy loss: the directional albedo of a conductor with `F = 1`
    /// (eta 0, k 0) at normal incidence falls with roughness. The expected figures (documented
    /// in docs/language.md and the module doc) come from an independent 1-D quadrature of
    /// `G1(wi) D(h) cos_h` over the half-vector angle; the sampler must match them within 0.005.
    #[test]
    fn conductor_energy_loss() {
        let mut rng = crate::sampling::Rng::new(23);
        let mut previous = 1.0f64;
        for (r, documented) in [
            (0.2f32, 0.998f64),
            (0.5, 0.916),
            (0.75, 0.627),
            (1.0, 0.307),
        ] {
            let b = bsdf(Lobes::Conductor {
                eta: Vec3A::ZERO,
                k: Vec3A::ZERO,
                alpha: alpha(r),
            });
            let n = 400_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                if let Some(s) = b.sample(
                    Vec3A::Z,
                    rng.f32(),
                    rng.vec2(),
                    super::super::TransportMode::Radiance,
                ) {
                    sum += f64::from(s.weight.x);
                }
            }
            let albedo = sum / f64::from(n);
            println!("roughness {r}: white-furnace albedo {albedo:.4}");
            assert!(
                (albedo - documented).abs() < 0.005,
                "roughness {r}: {albedo}"
            );
            assert!(albedo <= previous + 1e-3);
            previous = albedo;
        }
    }
}
