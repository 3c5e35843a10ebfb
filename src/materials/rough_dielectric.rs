//! Rough dielectric (frosted glass): the microfacet model of Walter et al. 2007, "Microfacet
//! Models for Refraction through Rough Surfaces", in pbrt-v4's form (`DielectricBxDF`), with
//! glossy.rs's GGX distribution, separable Smith shadowing and visible-normal sampling. The
//! local frame's `z` points out of the glass; `eta` is inside over outside.
//!
//! A sample picks a normal visible from `wo`, then reflects with the Fresnel probability `F`
//! and refracts through that normal otherwise. Transmission carries radiance scaled by
//! `1 / eta'^2` (`eta'` the index on `wi`'s side over that on `wo`'s), importance unscaled, so
//! in radiance mode `f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2` (Veach 1997, eq. 5.14) and the
//! importance-mode value is the adjoint `f(wi, wo)`.

use glam::{Vec2, Vec3A};

use super::dielectric::fresnel;
use super::glossy::{d_ggx, g1, sample_visible_normal};
use super::{BsdfSample, TransportMode};

/// GGX `alpha` below which glass is smooth (a delta lobe, dielectric.rs): a finer lobe's peak
/// overflows `f32` densities and no picture can tell it from a smooth one (pbrt-v4's
/// "effectively smooth" threshold).
pub const MIN_ALPHA: f32 = 1e-3;

/// The half vector of a reflection (`wo + wi`) or a refraction (`eta' wi + wo`), facing the
/// outside, with `eta'` the relative index of the refraction (1 for a reflection). `None` where
/// it is undefined or the microfacet faces away from either direction.
fn half_vector(eta: f32, wo: Vec3A, wi: Vec3A) -> Option<(Vec3A, f32)> {
    let (co, ci) = (wo.z, wi.z);
    if co == 0.0 || ci == 0.0 {
        return None;
    }
    let etap = if co * ci > 0.0 {
        1.0
    } else if co > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let wm = wi * etap + wo;
    if wm.length_squared() == 0.0 || !wm.is_finite() {
        return None;
    }
    let wm = wm.normalize();
    let wm = if wm.z < 0.0 { -wm } else { wm };
    // Microfacets seen from behind by either direction contribute nothing.
    if wm.dot(wi) * ci < 0.0 || wm.dot(wo) * co < 0.0 {
        return None;
    }
    Some((wm, etap))
}

/// `f(wo, wi)` (without tint) and the density of sampling `wi`, for transport `mode`.
pub fn eval(eta: f32, alpha: f32, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> (f32, f32) {
    let Some((wm, etap)) = half_vector(eta, wo, wi) else {
        return (0.0, 0.0);
    };
    let a2 = alpha.max(MIN_ALPHA).powi(2);
    let (co, ci) = (wo.z, wi.z);
    let (om, im) = (wo.dot(wm), wi.dot(wm));
    // Across the surface, Fresnel from the outer direction's cosine: the same value as from
    // the inner one, which near the critical angle is ill-conditioned (0.2 % of `1 - F` from
    // the rounding of `f32` directions, enough to break reciprocity).
    let outer = if etap != 1.0 && co < 0.0 { im } else { om };
    let r = fresnel(outer, eta);
    let d = d_ggx(wm, a2);
    // Density of the visible normal: G1(wo) |wo.wm| D(wm) / |cos_o|.
    let visible = g1(wo, a2) * om.abs() * d / co.abs();
    let g = g1(wo, a2) * g1(wi, a2);
    if etap == 1.0 {
        let f = d * g * r / (4.0 * co * ci).abs();
        let pdf = visible / (4.0 * om.abs()) * r;
        return (f, pdf);
    }
    let denom = (im + om / etap).powi(2);
    if denom == 0.0 {
        return (0.0, 0.0);
    }
    let mut f = d * (1.0 - r) * g * (im * om / (denom * ci * co)).abs();
    if mode == TransportMode::Radiance {
        f /= etap * etap;
    }
    let pdf = visible * im.abs() / denom * (1.0 - r);
    (f, pdf)
}

/// Samples `wi` for `wo`: a visible normal, then reflection or refraction by Fresnel.
pub fn sample(
    eta: f32,
    tint: Vec3A,
    alpha: f32,
    wo: Vec3A,
    uc: f32,
    u: Vec2,
    mode: TransportMode,
) -> Option<BsdfSample> {
    let side = if wo.z > 0.0 { 1.0 } else { -1.0 };
    // Normals visible from wo, turned to face the outside.
    let wm = sample_visible_normal(wo * side, alpha.max(MIN_ALPHA), u);
    let om = wo.dot(wm);
    if om * side <= 0.0 {
        return None;
    }
    let r = fresnel(om, eta);
    let wi = if uc < r {
        let wi = wm * (2.0 * om) - wo;
        if wi.z * wo.z <= 0.0 {
            return None;
        }
        wi
    } else {
        // Refraction through wm: the relative index seen from wo's side.
        let (etap, n) = if om > 0.0 {
            (eta, wm)
        } else {
            (1.0 / eta, -wm)
        };
        let cos_i = wo.dot(n);
        let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (etap * etap);
        if sin2_t >= 1.0 {
            return None;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        let wi = (-wo / etap + n * (cos_i / etap - cos_t)).normalize();
        if wi.z * wo.z >= 0.0 {
            return None;
        }
        wi
    };
    let (f, pdf) = eval(eta, alpha, wo, wi, mode);
    if pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    Some(BsdfSample {
        wi,
        weight: tint * (f * wi.z.abs() / pdf),
        pdf,
        specular: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::Lobes;
    use crate::materials::check::{COS_O, alpha, bsdf, check_mode, no_nan, wo_at};

    /// Frosted glass passes every check of the harness (chi-square of `sample` against `pdf`
    /// on the whole sphere, `pdf` integrating to at most one, generalized reciprocity, albedo at
    /// most one in importance, weights equal to `f |cos| / pdf`), from outside and from
    /// inside (where total internal reflection takes part), in both transport modes, from
    /// sharp to fully rough, at every angle down to grazing.
    #[test]
    fn rough_glass_passes() {
        let roughness = [1e-4f32, 0.3, 0.6, 1.0];
        let modes = [TransportMode::Radiance, TransportMode::Importance];
        let cases = COS_O.len() * roughness.len() * 2 * modes.len();
        let mut seed = 500;
        for &c in &COS_O {
            for &r in &roughness {
                for side in [1.0f32, -1.0] {
                    for &mode in &modes {
                        let b = bsdf(Lobes::Glass {
                            eta: 1.5,
                            tint: Vec3A::ONE,
                            alpha: alpha(r),
                        });
                        let wo = wo_at(c) * Vec3A::new(1.0, 1.0, side);
                        seed += 1;
                        if let Err(e) = check_mode(&b, wo, cases, seed, mode) {
                            panic!("roughness {r} cos {} {mode:?}: {e}", wo.z);
                        }
                    }
                }
            }
        }
        no_nan(500_000, 5, |r| Lobes::Glass {
            eta: [1.0001, 1.33, 1.5, 2.4, 1.0 / 1.5][(r.f32() * 5.0) as usize % 5],
            tint: Vec3A::splat(r.f32()),
            alpha: [1e-8, 1e-4, 1e-3, 2e-3, r.f32()][(r.f32() * 5.0) as usize % 5],
        });
    }

    /// Below the smooth threshold (roughness 0.0316, alpha 1e-3) glass is the smooth delta
    /// lobe: specular, its samples exactly those of dielectric.rs (roughness 1e-4 included),
    /// while a rough glass at alpha below 0.3 counts as glossy and a rougher one as neither.
    #[test]
    fn tiny_roughness_is_smooth_glass() {
        for alpha in [0.0, 1e-8, 9e-4] {
            let b = bsdf(Lobes::Glass {
                eta: 1.5,
                tint: Vec3A::ONE,
                alpha,
            });
            assert!(b.is_specular() && !b.is_glossy(), "{alpha}");
            for uc in [0.01, 0.5, 0.99] {
                let wo = wo_at(0.6);
                let s = b
                    .sample(wo, uc, Vec2::splat(0.3), TransportMode::Radiance)
                    .unwrap();
                let want = super::super::dielectric::sample(
                    1.5,
                    Vec3A::ONE,
                    wo,
                    uc,
                    TransportMode::Radiance,
                )
                .unwrap();
                assert_eq!(s, want);
            }
        }
        let sharp = bsdf(Lobes::Glass {
            eta: 1.5,
            tint: Vec3A::ONE,
            alpha: 0.04,
        });
        assert!(!sharp.is_specular() && sharp.is_glossy());
        let frosted = bsdf(Lobes::Glass {
            eta: 1.5,
            tint: Vec3A::ONE,
            alpha: 0.5,
        });
        assert!(!frosted.is_specular() && !frosted.is_glossy());
    }

    /// As the roughness shrinks, the rough lobe's reflected share at normal incidence tends to
    /// the smooth glass's Fresnel value (0.04 for n = 1.5) and the rest is transmitted: the
    /// mean weights in importance mode (no `1/eta^2`), split by side, over 200 000 samples.
    #[test]
    fn sharp_rough_glass_tends_to_fresnel() {
        let mut rng = crate::sampling::Rng::new(41);
        let b = bsdf(Lobes::Glass {
            eta: 1.5,
            tint: Vec3A::ONE,
            alpha: 0.01,
        });
        let n = 200_000;
        let (mut refl, mut trans) = (0.0f64, 0.0f64);
        for _ in 0..n {
            if let Some(s) = b.sample(Vec3A::Z, rng.f32(), rng.vec2(), TransportMode::Importance) {
                if s.wi.z > 0.0 {
                    refl += f64::from(s.weight.x);
                } else {
                    trans += f64::from(s.weight.x);
                }
            }
        }
        let (refl, trans) = (refl / f64::from(n), trans / f64::from(n));
        assert!((refl - 0.04).abs() < 0.003, "reflected {refl}");
        assert!((trans - 0.96).abs() < 0.005, "transmitted {trans}");
    }
}
