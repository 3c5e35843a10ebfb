//! The render API used by the CLI (and later by `watch`): prepare a `Scene`, run its integrator
//! with overridable settings, report progress per iteration, stop promptly on cancel.

mod prepared;

pub use prepared::{PreparedScene, SurfaceHit};

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::film::Image;
use crate::integrators;
use crate::scene::{Integrator, Scene};
use crate::span::Span;

/// Overrides of the scene's `settings` (command-line flags); `None` keeps the scene's value.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RenderOptions {
    pub iterations: Option<u32>,
    pub photons: Option<u64>,
    pub seed: Option<u64>,
    /// Seconds.
    pub time_limit: Option<f64>,
    /// Worker threads; `None`: rayon's default (all cores). The image does not depend on it.
    pub threads: Option<usize>,
}

/// The settings a render actually uses (scene settings with the options applied).
#[derive(Debug, Clone, PartialEq)]
pub struct EffectiveSettings {
    pub width: u32,
    pub height: u32,
    pub iterations: u32,
    pub photons: u64,
    pub radius: Option<f64>,
    pub alpha: f64,
    pub max_depth: u32,
    pub seed: u64,
    pub integrator: Integrator,
    pub time_limit: Option<f64>,
}

/// A render failure; `span` points at the declaration that caused it when there is one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct RenderError {
    pub message: String,
    pub span: Option<Span>,
}

impl RenderError {
    pub fn new(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            span: None,
        }
    }
}

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

/// Largest accepted image side and pixel count.
const MAX_SIDE: u32 = 1 << 15;
const MAX_PIXELS: u64 = 1 << 27;

pub fn effective_settings(
    scene: &Scene,
    o: &RenderOptions,
) -> Result<EffectiveSettings, RenderError> {
    let s = &scene.settings;
    let (width, height) = s.resolution;
    if width == 0
        || height == 0
        || width > MAX_SIDE
        || height > MAX_SIDE
        || width as u64 * height as u64 > MAX_PIXELS
    {
        return Err(RenderError::new(format!(
            "resolution {width}x{height} is out of range (1..={MAX_SIDE} per side, at most {MAX_PIXELS} pixels)"
        )));
    }
    let alpha = s.alpha;
    if !(alpha > 0.0 && alpha <= 1.0) {
        return Err(RenderError::new(format!(
            "alpha must be in (0, 1], got {alpha}"
        )));
    }
    let radius = s.radius;
    if let Some(r) = radius
        && !(r > 0.0 && r.is_finite())
    {
        return Err(RenderError::new(format!(
            "radius must be positive, got {r}"
        )));
    }
    let time_limit = o.time_limit.or(s.time_limit);
    if let Some(t) = time_limit
        && (t.is_nan() || t < 0.0)
    {
        return Err(RenderError::new(format!(
            "time limit must be >= 0, got {t}"
        )));
    }
    if o.threads == Some(0) {
        return Err(RenderError::new("threads must be at least 1"));
    }
    Ok(EffectiveSettings {
        width,
        height,
        iterations: o.iterations.unwrap_or(s.iterations),
        photons: o.photons.unwrap_or(s.photons),
        radius,
        alpha,
        max_depth: s.max_depth.clamp(1, 1024),
        seed: o.seed.unwrap_or(s.seed),
        integrator: s.integrator,
        time_limit,
    })
}

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
    match options.threads {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| RenderError::new(format!("cannot start {n} threads: {e}")))?;
            pool.install(|| integrators::run(&prepared, &settings, cancel, on_progress))
        }
        None => integrators::run(&prepared, &settings, cancel, on_progress),
    }
}
