//! The per-pixel state of (S)PPM and its progressive update: after every photon pass each pixel
//! adds the flux its visible point gathered and shrinks its radius by `alpha`; the image is
//! `Ld / k + tau / (k N_e pi r^2)`.

use std::f64::consts::PI;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use crate::film::Image;
use crate::geometry::Frame;
use crate::integrators::common::camera_path::VisiblePoint;
use crate::materials::{Bsdf, Lobes};

/// A visible point as a pixel keeps it from the camera pass to the photon gather: a
/// [`VisiblePoint`] whose BSDF's bump is kept as its perturbed normal alone, in the padding
/// beside `distance`, and rebuilt where the point is used ([`Bsdf::from_parts`]). A bump's
/// derived geometry would make every pixel larger, bumped or not (the size is checked by a
/// test below).
#[derive(Debug, Clone, Copy)]
pub(super) struct StoredPoint {
    pub(super) p: Vec3A,
    pub(super) wo: Vec3A,
    pub(super) beta: Vec3A,
    pub(super) medium: Vec3A,
    lobes: Lobes,
    frame: Frame,
    ng: Vec3A,
    pub(super) distance: f32,
    /// The bump's perturbed normal in the shading frame; all zero without a bump.
    bump: [f32; 3],
}

impl StoredPoint {
    pub(super) fn new(vp: &VisiblePoint) -> Self {
        let b = &vp.bsdf;
        StoredPoint {
            p: vp.p,
            wo: vp.wo,
            beta: vp.beta,
            medium: vp.medium,
            lobes: b.lobes,
            frame: b.frame,
            ng: b.ng,
            distance: vp.distance,
            bump: b.bump_normal().map_or([0.0; 3], |n| n.to_array()),
        }
    }

    /// The visible point it was made from, bit for bit.
    pub(super) fn point(&self) -> VisiblePoint {
        // A perturbed normal is a unit vector, never zero.
        let bump = (self.bump != [0.0; 3]).then(|| Vec3A::from_array(self.bump));
        VisiblePoint {
            p: self.p,
            wo: self.wo,
            bsdf: Bsdf::from_parts(self.lobes, self.frame, self.ng, bump),
            beta: self.beta,
            distance: self.distance,
            medium: self.medium,
        }
    }
}

/// A pixel's progressive estimate: the light its camera paths found, and the photons at their
/// visible points. With final gathering a pixel has a second one, for its gather paths and
/// gather points (`super::gather_path`).
#[derive(Clone)]
pub(super) struct Pixel {
    /// Sum over iterations of emitted + direct radiance.
    pub(super) ld: DVec3,
    pub(super) tau: DVec3,
    pub(super) n: f64,
    pub(super) radius: f64,
    pub(super) vp: Option<StoredPoint>,
}

impl Pixel {
    /// A pixel before its first iteration.
    pub(super) fn new(radius: f64) -> Self {
        Pixel {
            ld: DVec3::ZERO,
            tau: DVec3::ZERO,
            n: 0.0,
            radius,
            vp: None,
        }
    }
}

/// Adds every pixel's camera-pass light `lds` and its gathered flux `phi` from `m` photons
/// (then zeroes them), with the radius reduction `N += alpha M`, `r^2 *= N_new / (N + M)`;
/// drops the visible points.
pub(super) fn update(
    pixels: &mut [Pixel],
    lds: &[Vec3A],
    phi: &mut [DVec3],
    m: &mut [u64],
    alpha: f64,
) {
    pixels
        .par_iter_mut()
        .zip(lds.par_iter())
        .zip(phi.par_iter_mut().zip(m.par_iter_mut()))
        .for_each(|((px, l), (ph, mm))| {
            px.ld += l.as_dvec3();
            if *mm > 0
                && let Some(vp) = px.vp
            {
                let mf = *mm as f64;
                let n_new = px.n + alpha * mf;
                let r_new = px.radius * (n_new / (px.n + mf)).sqrt();
                let flux = vp.beta.as_dvec3() * *ph;
                px.tau = (px.tau + flux) * (r_new * r_new) / (px.radius * px.radius);
                px.n = n_new;
                px.radius = r_new;
            }
            *ph = DVec3::ZERO;
            *mm = 0;
            px.vp = None;
        });
}

/// The image after `iters` iterations of `emitted` photons in all; `gather`: the pixels'
/// final-gather estimates (empty without final gathering).
pub(super) fn image_of(
    pixels: &[Pixel],
    gather: &[Pixel],
    width: u32,
    height: u32,
    iters: u32,
    emitted: u64,
) -> Image {
    let mut img = Image::new(width, height);
    if iters == 0 {
        return img;
    }
    let k = iters as f64;
    let np = (emitted as f64).max(1.0);
    img.pixels
        .par_iter_mut()
        .zip(pixels.par_iter())
        .enumerate()
        .for_each(|(i, (out, px))| {
            let density = |tau: DVec3, radius: f64| {
                let area = PI * radius * radius;
                if emitted > 0 && area > 0.0 {
                    tau / (np * area)
                } else {
                    DVec3::ZERO
                }
            };
            let mut l = px.ld / k + density(px.tau, px.radius);
            if let Some(g) = gather.get(i) {
                l += g.ld / k + density(g.tau, g.radius);
            }
            *out = l.to_array();
        });
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, uniform_sphere};

    /// A stored point is no larger than a visible point without a bump would be (its fields
    /// with the BSDF's lobes, frame and `ng`), and gives back the visible point it was made
    /// from: a bumped BSDF's values, densities and samples bit for bit.
    #[test]
    fn stored_points_are_as_small_as_unbumped_ones_and_give_the_bsdf_back() {
        type Unbumped = (Vec3A, Vec3A, Vec3A, Vec3A, Lobes, Frame, Vec3A, f32);
        assert!(
            std::mem::size_of::<StoredPoint>() <= std::mem::size_of::<Unbumped>(),
            "{} bytes",
            std::mem::size_of::<StoredPoint>()
        );
        let mut rng = Rng::new(3);
        let lobes = Lobes::Coated {
            albedo: Vec3A::new(0.7, 0.2, 0.1),
            eta: 1.5,
            alpha: 0.1,
        };
        for k in 0..200 {
            let ns = uniform_sphere(rng.vec2());
            let frame = Frame::from_normal_tangent(ns, ns.any_orthonormal_vector());
            let np = (ns + 0.8 * uniform_sphere(rng.vec2())).normalize();
            let bsdf = if k % 4 == 0 {
                Bsdf::new(lobes, ns, frame.s, ns)
            } else {
                Bsdf::bumped(lobes, frame, ns, np)
            };
            let vp = VisiblePoint {
                p: Vec3A::ONE,
                wo: uniform_sphere(rng.vec2()),
                bsdf,
                beta: Vec3A::splat(0.5),
                distance: 2.0,
                medium: Vec3A::ZERO,
            };
            let back = StoredPoint::new(&vp).point();
            assert_eq!(back.bsdf, vp.bsdf);
            assert_eq!((back.p, back.wo, back.beta), (vp.p, vp.wo, vp.beta));
            for _ in 0..8 {
                let wi = uniform_sphere(rng.vec2());
                let (u, uc) = (rng.vec2(), rng.f32());
                let mode = crate::materials::TransportMode::Radiance;
                assert_eq!(back.bsdf.f(vp.wo, wi), vp.bsdf.f(vp.wo, wi));
                assert_eq!(back.bsdf.pdf(vp.wo, wi), vp.bsdf.pdf(vp.wo, wi));
                assert_eq!(
                    back.bsdf.sample(vp.wo, uc, u, mode),
                    vp.bsdf.sample(vp.wo, uc, u, mode)
                );
            }
        }
    }
}
