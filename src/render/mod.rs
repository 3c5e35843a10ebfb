//! The render API used by the CLI (and later by `watch`): prepare a `Scene`, run its integrator
//! with overridable settings, report progress per iteration, stop promptly on cancel.

pub use crate::integrators::{Progress, RenderOutput, RenderStats};
pub use crate::prepare::{
    EffectiveSettings, PreparedScene, RenderError, RenderOptions, SurfaceHit, effective_settings,
};

use std::sync::atomic::AtomicBool;

use crate::integrators;
use crate::scene::Scene;

/// Renders `scene`. `cancel` is checked inside every pass; `on_progress` runs after every
/// iteration (on the calling thread's pool) and may call [`Progress::image`].
pub fn render(
    scene: &Scene,
    options: &RenderOptions,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
) -> Result<RenderOutput, RenderError> {
    let settings = effective_settings(scene, options)?;
    let prepared = PreparedScene::new(scene)?;
    let integrator = integrators::for_method(settings.integrator);
    let mut run = || integrator.render(&prepared, &settings, cancel, on_progress);
    match options.threads {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| RenderError::new(format!("cannot start {n} threads: {e}")))?;
            Ok(pool.install(run))
        }
        None => Ok(run()),
    }
}
