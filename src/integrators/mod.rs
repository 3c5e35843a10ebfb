//! Light-transport algorithms. Each method is a type implementing [`Integrator`], in its own
//! file or folder: `sppm/`, `ppm.rs`, `photon_map/`, `path.rs`, `whitted.rs`, `vcm/` (also
//! `bpt` and `lt`); [`for_method`]
//! picks the one the settings name. Code more than one of them uses is in `common/`: the eye
//! path, direct lighting, photon tracing, the progressive loop and the random streams.
//!
//! An interface (a trait) rather than one enum with a `render` method: each method stays a
//! self-contained type beside its own code, a new method is a new type plus one line in
//! [`for_method`] (the only place that lists them all), and the one dynamic call per render
//! costs nothing.
//!
//! An integrator cannot fail: everything that can go wrong with a scene is found while it is
//! prepared ([`crate::prepare`]), so `render` returns its output directly.

mod common;
pub mod path;
pub mod photon_map;
pub mod ppm;
pub mod sppm;
pub mod vcm;
pub mod whitted;

pub use common::direct::direct_lighting;

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::film::Image;
use crate::prepare::{EffectiveSettings, PreparedScene};
use crate::scene::Integrator as Method;

/// Counters over the whole render.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RenderStats {
    pub camera_paths: u64,
    pub photons: u64,
    pub deposits: u64,
    /// Wall time spent in the camera passes.
    pub camera_time: Duration,
    /// Wall time spent building photon lookup structures and tracing photons (SPPM: tracing
    /// the photons, the grid builds and the visible points' gathers; photon mapping: the map
    /// builds).
    pub photon_time: Duration,
    /// SPPM: the camera pass's ray casts over the photon pass's chosen after the last
    /// iteration (1 until both parts' noise is known; `sppm/balance.rs`); 0 for the others.
    pub camera_ratio: f64,
}

/// Reported after every finished iteration.
pub struct Progress<'a> {
    /// Iterations finished so far (1-based count).
    pub iteration: u32,
    pub iterations: u32,
    pub elapsed: Duration,
    pub stats: RenderStats,
    pub(crate) snapshot: &'a dyn Fn() -> Image,
}

impl Progress<'_> {
    /// The image as it stands after this iteration (computed on demand).
    pub fn image(&self) -> Image {
        (self.snapshot)()
    }
}

/// The result of a render.
#[derive(Debug, Clone)]
pub struct RenderOutput {
    pub image: Image,
    pub iterations_done: u32,
    /// Stopped by the cancel flag (the image holds the finished iterations).
    pub cancelled: bool,
    pub elapsed: Duration,
    pub stats: RenderStats,
}

/// One render's inputs: the prepared scene, the settings (iterations, photons, time limit...),
/// the cancel flag (checked inside every pass) and the callback that runs after every finished
/// iteration.
pub struct Job<'j, 'a> {
    pub scene: &'j PreparedScene<'a>,
    pub settings: &'j EffectiveSettings,
    pub cancel: &'j AtomicBool,
    pub on_progress: &'j mut (dyn FnMut(&Progress) + Send),
}

/// A light-transport method.
pub trait Integrator: Send + Sync {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput;
}

/// The integrator of `method` (the settings' `integrator`).
pub fn for_method(method: Method) -> Box<dyn Integrator> {
    match method {
        Method::Sppm => Box::new(sppm::Sppm),
        Method::Ppm => Box::new(ppm::Ppm),
        Method::Path => Box::new(path::PathTracer),
        Method::Whitted => Box::new(whitted::Whitted),
        Method::PhotonMap => Box::new(photon_map::PhotonMap),
        Method::Vcm => Box::new(vcm::Vcm::new(vcm::Mode::VCM)),
        Method::Bpt => Box::new(vcm::Vcm::new(vcm::Mode::BPT)),
        Method::Lt => Box::new(vcm::Vcm::new(vcm::Mode::LT)),
    }
}
