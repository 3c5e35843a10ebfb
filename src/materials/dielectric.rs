//! Smooth dielectric: Fresnel reflection and refraction, total internal reflection.
//! (Beer–Lambert absorption happens along the path inside, see the integrator.)

use glam::Vec3A;

use super::{BsdfSample, TransportMode};

/// Unpolarised Fresnel reflectance; `cos_i` on the side of `eta` = n_t / n_i.
pub fn fresnel(cos_i: f32, eta: f32) -> f32 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rp * rp + rs * rs)
}

pub fn sample(
    eta: f32,
    tint: Vec3A,
    wo: Vec3A,
    uc: f32,
    mode: TransportMode,
) -> Option<BsdfSample> {
    let r = fresnel(wo.z, eta);
    if uc < r {
        return Some(BsdfSample {
            wi: Vec3A::new(-wo.x, -wo.y, wo.z),
            weight: tint,
            pdf: r,
            specular: true,
        });
    }
    // Refract: relative index seen from wo's side.
    let (etap, n) = if wo.z > 0.0 {
        (eta, Vec3A::Z)
    } else {
        (1.0 / eta, -Vec3A::Z)
    };
    let cos_i = wo.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (etap * etap);
    if sin2_t >= 1.0 {
        return None; // r == 1 then; unreachable but safe
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let wi = -wo / etap + n * (cos_i / etap - cos_t);
    let mut weight = tint;
    if mode == TransportMode::Radiance {
        weight /= etap * etap;
    }
    Some(BsdfSample {
        wi: wi.normalize(),
        weight,
        pdf: 1.0 - r,
        specular: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::Lobes;
    use crate::materials::check::{COS_O, bsdf, delta_choice, fresnel64, wo_at};

    /// Smooth glass reflects as often as Fresnel says (chi-square of the choice against an
    /// `f64` Fresnel) and refracts by Snell's law, from outside and from inside, at every
    /// angle down to grazing (cos 1e-3: from inside that is total internal reflection, so no
    /// sample may refract), for a dense and a barely denser glass.
    #[test]
    fn smooth_glass_chooses_by_fresnel_from_both_sides() {
        let etas = [1.5f32, 1.05];
        let cases = COS_O.len() * etas.len() * 2;
        let mut seed = 900;
        for &eta in &etas {
            for &c in &COS_O {
                for side in [1.0f32, -1.0] {
                    let wo = wo_at(c) * Vec3A::new(1.0, 1.0, side);
                    let b = bsdf(Lobes::Glass {
                        eta,
                        tint: Vec3A::ONE,
                        alpha: 0.0,
                    });
                    // The index across over the index on wo's side.
                    let etap = if side > 0.0 {
                        f64::from(eta)
                    } else {
                        1.0 / f64::from(eta)
                    };
                    let cos_i = f64::from(c);
                    let sin2_t = (1.0 - cos_i * cos_i) / (etap * etap);
                    let transmitted = (sin2_t < 1.0).then(|| {
                        let (wo, n) = (wo.as_dvec3(), glam::DVec3::Z * f64::from(side));
                        let t = -wo / etap + n * (cos_i / etap - (1.0 - sin2_t).sqrt());
                        t.normalize().as_vec3a()
                    });
                    seed += 1;
                    let r = fresnel64(cos_i, etap);
                    if let Err(e) = delta_choice(&b, wo, r, transmitted, cases, seed) {
                        panic!("eta {eta}, cos {}: {e}", wo.z);
                    }
                }
            }
        }
    }

    #[test]
    fn fresnel_limits() {
        assert!((fresnel(1.0, 1.5) - 0.04).abs() < 1e-4);
        // Total internal reflection from inside beyond the critical angle.
        assert_eq!(fresnel(-0.3, 1.5), 1.0);
        assert!(fresnel(0.0001, 1.5) > 0.99);
    }

    #[test]
    fn refraction_obeys_snell() {
        let wo = Vec3A::new(0.6, 0.0, 0.8);
        // uc = 0.99 > R: refraction.
        let s = sample(1.5, Vec3A::ONE, wo, 0.99, TransportMode::Radiance).unwrap();
        assert!(s.wi.z < 0.0);
        let sin_t = (s.wi.x * s.wi.x + s.wi.y * s.wi.y).sqrt();
        assert!((0.6 - 1.5 * sin_t).abs() < 1e-5);
        assert!((s.weight.x - 1.0 / 2.25).abs() < 1e-6);
        let p = sample(1.5, Vec3A::ONE, wo, 0.99, TransportMode::Importance).unwrap();
        assert_eq!(p.weight, Vec3A::ONE);
    }
}
