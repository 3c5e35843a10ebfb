//! The per-pixel state of (S)PPM and its progressive update: after every photon pass each pixel
//! adds the flux its visible point gathered and shrinks its radius by `alpha`; the image is
//! `Ld / k + tau / (k N_e pi r^2)`.

use std::f64::consts::PI;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use crate::film::Image;
use crate::integrators::common::camera_path::VisiblePoint;

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
    pub(super) vp: Option<VisiblePoint>,
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
