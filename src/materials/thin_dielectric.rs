//! Thin dielectric (a window pane, a soap film): two parallel smooth interfaces so close that
//! a ray leaves where it entered, along its own direction. The light bouncing between the two
//! faces is summed in closed form (pbrt-v4's `ThinDielectricBxDF`, Mitsuba's
//! `thindielectric`): with `R` the Fresnel reflectance of one face and `T = 1 - R`, the pane
//! reflects `R' = R + T^2 R / (1 - R^2)` and transmits `1 - R'`. Nothing is refracted, so
//! radiance and importance are carried alike and no medium is entered.

use glam::Vec3A;

use super::BsdfSample;
use super::dielectric::fresnel;

/// The pane's reflectance at `cos` (one face's Fresnel with the inter-reflections summed).
pub fn reflectance(cos: f32, eta: f32) -> f32 {
    let r = fresnel(cos.abs(), eta);
    if r >= 1.0 {
        return 1.0;
    }
    let t = 1.0 - r;
    r + t * t * r / (1.0 - r * r)
}

/// Reflects with probability `R'`, else passes straight through; either way the weight is
/// the tint (the choice's probability is the lobe's share).
pub fn sample(eta: f32, tint: Vec3A, wo: Vec3A, uc: f32) -> Option<BsdfSample> {
    let r = reflectance(wo.z, eta);
    let (wi, pdf) = if uc < r {
        (Vec3A::new(-wo.x, -wo.y, wo.z), r)
    } else {
        (-wo, 1.0 - r)
    };
    Some(BsdfSample {
        wi,
        weight: tint,
        pdf,
        specular: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::check::{COS_O, bsdf, delta_choice, fresnel64, wo_at};
    use crate::materials::{Lobes, TransportMode};
    use crate::sampling::Rng;
    use glam::Vec2;

    /// A pane reflects as often as its summed reflectance says (chi-square of the choice
    /// against the series in `f64`) and otherwise passes light straight on, from both sides
    /// at every angle down to grazing (cos 1e-3), for three indices.
    #[test]
    fn pane_chooses_by_its_reflectance_from_both_sides() {
        let etas = [1.2f32, 1.5, 4.0];
        let cases = COS_O.len() * etas.len() * 2;
        let mut seed = 950;
        for &eta in &etas {
            for &c in &COS_O {
                for side in [1.0f32, -1.0] {
                    let wo = wo_at(c) * Vec3A::new(1.0, 1.0, side);
                    let b = bsdf(Lobes::ThinGlass {
                        eta,
                        tint: Vec3A::ONE,
                    });
                    let r = fresnel64(f64::from(c), f64::from(eta));
                    let t = 1.0 - r;
                    // Light leaves by the front after 1, 3, 5, ... passes.
                    let r_pane = r + (0..2000).map(|k| t * t * r * r.powi(2 * k)).sum::<f64>();
                    seed += 1;
                    if let Err(e) = delta_choice(&b, wo, r_pane, Some(-wo), cases, seed) {
                        panic!("eta {eta}, cos {}: {e}", wo.z);
                    }
                }
            }
        }
    }

    /// The closed form agrees with the series it sums: light bouncing inside the pane leaves
    /// through the front after `2k + 1` passes (`R + T^2 R (1 + R^2 + R^4 + ...)`), and a
    /// normal-incidence pane of n = 1.5 reflects 2R / (1 + R) = 0.0769 (R = 0.04); grazing
    /// light is all reflected.
    #[test]
    fn reflectance_sums_the_inter_reflections() {
        for cos in [1.0f32, 0.7, 0.3, 0.05] {
            let r = fresnel(cos, 1.5);
            let t = 1.0 - r;
            let series: f32 = r + (0..200).map(|k| t * t * r * r.powi(2 * k)).sum::<f32>();
            assert!((reflectance(cos, 1.5) - series).abs() < 1e-5, "{cos}");
        }
        assert!((reflectance(1.0, 1.5) - 0.08 / 1.04).abs() < 1e-5);
        assert!(reflectance(1e-6, 1.5) > 0.999);
    }

    /// A clear pane in a white furnace loses nothing: reflected plus transmitted weight is one
    /// at every angle, from both sides and in both transport modes, the transmitted direction is
    /// `-wo` exactly (no offset, no bending), and the reflected share is `R'`.
    #[test]
    fn a_pane_in_a_furnace_keeps_all_energy() {
        let mut rng = Rng::new(7);
        let b = bsdf(Lobes::ThinGlass {
            eta: 1.5,
            tint: Vec3A::ONE,
        });
        assert!(b.is_specular() && !b.is_glossy());
        for cos in [1.0f32, 0.6, 0.15, 1e-3] {
            for side in [1.0f32, -1.0] {
                for mode in [TransportMode::Radiance, TransportMode::Importance] {
                    let wo = wo_at(cos) * Vec3A::new(1.0, 1.0, side);
                    let n = 20_000;
                    let (mut total, mut reflected) = (0.0f64, 0.0f64);
                    for _ in 0..n {
                        let s = b.sample(wo, rng.f32(), Vec2::ZERO, mode).unwrap();
                        total += f64::from(s.weight.x);
                        if s.wi.z * wo.z > 0.0 {
                            reflected += f64::from(s.weight.x);
                            assert_eq!(s.wi, Vec3A::new(-wo.x, -wo.y, wo.z));
                        } else {
                            assert_eq!(s.wi, -wo);
                        }
                    }
                    let (total, reflected) = (total / f64::from(n), reflected / f64::from(n));
                    assert!((total - 1.0).abs() < 1e-6, "{cos} {side}: {total}");
                    let want = f64::from(reflectance(cos, 1.5));
                    let se = (want * (1.0 - want) / f64::from(n)).sqrt();
                    assert!(
                        (reflected - want).abs() < 5.0 * se + 1e-4,
                        "{cos}: {reflected}"
                    );
                }
            }
        }
    }
}
