//! [`Bsdf::eval`] against the separate calls it stands for, and [`Bsdf::samples_delta`]
//! against the samples.

use glam::Vec3A;

use super::{Bsdf, Lobes, TransportMode};
use crate::geometry::Frame;
use crate::sampling::{Rng, uniform_sphere};

/// One lobe of every kind, with parameters drawn from `r` (frosted glass and the rough
/// conductor and coat at a random roughness, their smooth forms too).
fn lobes(r: &mut Rng, kind: usize) -> Lobes {
    let color = |r: &mut Rng| Vec3A::new(r.f32(), r.f32(), r.f32());
    let alpha = |r: &mut Rng| [0.0, 1e-3, 0.05, r.f32()][(r.f32() * 4.0) as usize % 4];
    match kind {
        0 => Lobes::Diffuse { albedo: color(r) },
        // A black Lambertian lobe: `f` zero for every pair.
        1 => Lobes::Diffuse {
            albedo: Vec3A::ZERO,
        },
        2 => Lobes::Mirror { tint: color(r) },
        3 => Lobes::Glass {
            eta: 1.0 + r.f32(),
            tint: color(r),
            alpha: alpha(r),
        },
        4 => Lobes::ThinGlass {
            eta: 1.0 + r.f32(),
            tint: color(r),
        },
        5 => Lobes::Glossy {
            albedo: color(r),
            specular: color(r),
            alpha: alpha(r).max(1e-3),
        },
        6 => Lobes::Conductor {
            eta: color(r) * 2.0,
            k: color(r) * 4.0,
            alpha: alpha(r),
        },
        _ => Lobes::Coated {
            albedo: color(r),
            eta: 1.0 + r.f32(),
            alpha: alpha(r),
        },
    }
}

/// `eval` gives `f_mode`, `pdf` and the reverse `pdf` bit for bit, and `None` exactly where
/// `f_mode` is zero, for every kind of lobe, bumped or not, in a tilted frame whose geometric
/// normal differs from the shading normal (so that the side tests reject some pairs), in
/// both transport modes.
#[test]
fn eval_gives_the_separate_calls_values() {
    let mut r = Rng::new(11);
    let (mut some, mut none) = (0, 0);
    for n in 0..80_000 {
        let ns = uniform_sphere(r.vec2());
        let ng = (ns + 0.3 * uniform_sphere(r.vec2())).normalize();
        let tangent = uniform_sphere(r.vec2());
        let l = lobes(&mut r, n % 8);
        let b = if n % 3 == 0 {
            let np = (ns + 0.5 * uniform_sphere(r.vec2())).normalize();
            Bsdf::bumped(l, Frame::from_normal_tangent(ns, tangent), ng, np)
        } else {
            Bsdf::new(l, ns, tangent, ng)
        };
        let (wo, wi) = (uniform_sphere(r.vec2()), uniform_sphere(r.vec2()));
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            let f = b.f_mode(wo, wi, mode);
            match b.eval(wo, wi, mode) {
                Some(e) => {
                    some += 1;
                    assert_eq!(
                        e.f.to_array().map(f32::to_bits),
                        f.to_array().map(f32::to_bits)
                    );
                    assert_ne!(f, Vec3A::ZERO);
                    assert_eq!(e.pdf.to_bits(), b.pdf(wo, wi).to_bits(), "{b:?}");
                    assert_eq!(e.pdf_rev.to_bits(), b.pdf(wi, wo).to_bits(), "{b:?}");
                }
                None => {
                    none += 1;
                    assert_eq!(f, Vec3A::ZERO, "{b:?} {wo} {wi}");
                }
            }
        }
    }
    // Both outcomes were exercised often.
    assert!(
        some > 20_000 && none > 20_000,
        "{some} with a value, {none} without"
    );
}

/// A BSDF that [`Bsdf::samples_delta`] says has no delta lobe never gives a specular sample,
/// and each kind that says it has one does give one: every kind of lobe, bumped or not, in
/// both transport modes; and it says so exactly for the smooth kinds (mirror, pane, and glass,
/// conductor or coat of roughness 0), not for the rough ones.
#[test]
fn samples_delta_says_which_bsdfs_give_specular_samples() {
    let mut r = Rng::new(12);
    let mut specular_seen = [false; 8];
    for n in 0..160_000 {
        let kind = n % 8;
        let l = lobes(&mut r, kind);
        let smooth = match l {
            Lobes::Diffuse { .. } | Lobes::Glossy { .. } => Some(false),
            Lobes::Mirror { .. } | Lobes::ThinGlass { .. } => Some(true),
            Lobes::Glass { alpha, .. }
            | Lobes::Conductor { alpha, .. }
            | Lobes::Coated { alpha, .. } => {
                (alpha == 0.0 || alpha >= 0.05).then_some(alpha == 0.0)
            }
        };
        let b = if n % 3 == 0 {
            let np = (Vec3A::Z + 0.5 * uniform_sphere(r.vec2())).normalize();
            Bsdf::bumped(l, Frame::from_normal(Vec3A::Z), Vec3A::Z, np)
        } else {
            Bsdf::new(l, Vec3A::Z, Vec3A::X, Vec3A::Z)
        };
        if let Some(smooth) = smooth {
            assert_eq!(b.samples_delta(), smooth, "{b:?}");
        }
        let wo = uniform_sphere(r.vec2());
        let mode = if n % 2 == 0 {
            TransportMode::Radiance
        } else {
            TransportMode::Importance
        };
        if let Some(s) = b.sample(wo, r.f32(), r.vec2(), mode)
            && s.specular
        {
            assert!(b.samples_delta(), "{b:?}: a specular sample {s:?}");
            specular_seen[kind] = true;
        }
    }
    // The mirror, smooth glass, the pane, the smooth conductor and the smooth coat.
    for kind in [2, 3, 4, 6, 7] {
        assert!(specular_seen[kind], "kind {kind} gave no specular sample");
    }
}
