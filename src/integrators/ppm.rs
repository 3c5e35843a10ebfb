//! Progressive photon mapping (Hachisuka, Ogaki & Jensen 2008): the eye ray of every pixel is
//! fixed (pixel center, lens center) for the whole render, so each pixel keeps one hit point
//! while many photon passes refine its estimate with the same radius reduction as SPPM
//! (`N += alpha M`, `r^2 *= N_new / (N + M)`). Direct light at the hit point is re-sampled every
//! pass. Because the eye ray never moves, PPM cannot anti-alias, blur depth of field, or
//! average a pixel over glossy/refracted directions beyond the one fixed eye ray; at glass the
//! reflected or refracted branch is still chosen by Fresnel in each pass (one hit point per
//! pixel and pass, instead of the paper's tree of hit points).
//!
//! The loop, the photon pass and the pixel update are SPPM's (`sppm::render_with`); only
//! the eye path differs.

use crate::integrators::Job;

use super::common::camera_path::fixed_camera_path;
use super::{Integrator, RenderOutput, sppm};

/// Progressive photon mapping.
#[derive(Debug, Clone, Copy, Default)]
pub struct Ppm;

impl Integrator for Ppm {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput {
        sppm::render_with(job, fixed_camera_path, false).0
    }
}
