//! Light-transport algorithms. Each integrator renders a [`PreparedScene`] with the shared
//! sampling, materials, lights and film code; `run` dispatches on the scene's choice.

mod direct;
mod kdtree;
pub mod path;
pub mod photon_map;
pub mod ppm;
mod progressive;
pub mod sppm;
pub mod whitted;

pub use direct::direct_lighting;

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::film::Image;
use crate::prepare::{EffectiveSettings, PreparedScene, RenderError};
use crate::scene::Integrator;

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

pub fn run(
    scene: &PreparedScene,
    settings: &EffectiveSettings,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
) -> Result<RenderOutput, RenderError> {
    match settings.integrator {
        Integrator::Sppm => Ok(sppm::render(scene, settings, cancel, on_progress)),
        Integrator::Ppm => Ok(ppm::render(scene, settings, cancel, on_progress)),
        Integrator::Path => Ok(path::render(scene, settings, cancel, on_progress)),
        Integrator::Whitted => Ok(whitted::render(scene, settings, cancel, on_progress)),
        Integrator::PhotonMap => Ok(photon_map::render(scene, settings, cancel, on_progress)),
    }
}
