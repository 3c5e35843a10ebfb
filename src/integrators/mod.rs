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

use crate::render::{EffectiveSettings, PreparedScene, Progress, RenderError, RenderOutput};
use crate::scene::Integrator;

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
