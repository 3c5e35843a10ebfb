//! Light-transport algorithms. Each integrator renders a [`PreparedScene`] with the shared
//! sampling, materials, lights and film code; `run` dispatches on the scene's choice.

mod direct;
pub mod sppm;

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
        other => Err(RenderError::new(format!(
            "the `{}` integrator is not available yet; use `sppm`",
            other.name()
        ))),
    }
}
