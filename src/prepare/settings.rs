//! The settings a render uses: the scene's `settings` with the command line's overrides applied,
//! checked once here.

use super::method::{MethodChoice, method_choice, needs_a_lens};
use crate::diag::Diagnostic;
use crate::scene::{Antialias, Integrator, Scene, Settings};

pub use crate::scene::{MAX_ITERATIONS, MAX_PHOTONS};
/// Most worker threads ([`RenderOptions::threads`]).
pub const MAX_THREADS: usize = 1024;

/// Overrides of the scene's `settings` (command-line flags); `None` keeps the scene's value.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RenderOptions {
    /// The integrator; `None`: the scene's `integrator`, else the default rule's
    /// ([`crate::prepare::method_choice`]).
    pub integrator: Option<Integrator>,
    /// Width and height in pixels; `None`: the scene's `resolution`.
    pub resolution: Option<(u32, u32)>,
    pub iterations: Option<u32>,
    pub photons: Option<u64>,
    pub seed: Option<u64>,
    /// Seconds.
    pub time_limit: Option<f64>,
    /// Worker threads; `None`: rayon's default (all cores). The image does not depend on it.
    pub threads: Option<usize>,
    /// Most memory the render may need, in bytes; `None`: [`super::default_memory_limit`].
    pub memory_limit: Option<u64>,
    /// Memory the caller holds beside the render while it runs (a live view's image copies),
    /// counted in the estimate against `memory_limit`.
    pub held_memory: Option<super::MemoryItem>,
    /// Raised by the caller to stop: [`super::prepare`] checks it between its phases, per
    /// object and inside the BVH build, and fails with [`Diagnostic::interrupted`]; the
    /// render's passes stop as for their own cancel flag.
    pub cancel: crate::cancel::Cancel,
    /// `(k, n)`: the render is chain k of n of one still (`render --chain k/n`, its seed already
    /// the chain's own). `bpt` and `lt` chains then run two warm-up passes they do not keep,
    /// as every `vcm` render does. `None`: a render of its own.
    pub chain: Option<(u32, u32)>,
}

/// The settings a render actually uses: the scene's [`Settings`] with the options applied
/// (resolution, integrator, iterations, photons, seed, time limit) and `max_depth` clamped to
/// 1..=1024, and the method it runs, chosen by [`method_choice`] (the option, the scene's
/// setting or the default rule). It reads as those settings (`settings.iterations`, through
/// `Deref`; their `integrator` is the chosen method); what is derived from them is a method
/// ([`EffectiveSettings::width`], [`EffectiveSettings::method`], ...).
#[derive(Debug, Clone, PartialEq)]
pub struct EffectiveSettings {
    settings: Settings,
    method: MethodChoice,
    chain: Option<(u32, u32)>,
}

impl std::ops::Deref for EffectiveSettings {
    type Target = Settings;
    fn deref(&self) -> &Settings {
        &self.settings
    }
}

/// Tests and tools vary one setting of a checked set (`settings.seed = 2`); the method is
/// [`EffectiveSettings::method`]'s, whatever `integrator` they write.
impl std::ops::DerefMut for EffectiveSettings {
    fn deref_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }
}

impl EffectiveSettings {
    /// The integrator the render runs.
    pub fn method(&self) -> Integrator {
        self.method.integrator
    }

    /// The integrator the render runs and why (`check` and `render` print it).
    pub fn method_choice(&self) -> MethodChoice {
        self.method
    }

    /// `(k, n)` when the render is chain k of n of a still ([`RenderOptions::chain`]).
    pub fn chain(&self) -> Option<(u32, u32)> {
        self.chain
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.resolution.0
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.resolution.1
    }

    /// `whitted`'s adaptive anti-aliasing threshold (`antialias adaptive`); `None`: jitter only.
    pub fn adaptive_threshold(&self) -> Option<f64> {
        (self.antialias == Antialias::Adaptive).then(|| {
            self.antialias_threshold
                .unwrap_or(Antialias::DEFAULT_THRESHOLD)
        })
    }
}

/// Initial SPPM/PPM gather radii per pixel footprint: a pixel's radius starts at this many
/// widths of its footprint at its first visible point. Chosen with `tools/every_example.py`
/// on every example at equal CPU time (docs/integrators.md, "The factor on every example"):
/// among 1, 1.5 and 2, 1.5 gave the lowest RMSE against path tracing over all examples
/// (geometric mean) and a lower relative MSE than 1.
pub const RADIUS_FOOTPRINTS: f64 = 1.5;

/// With final gathering, a pixel's gather points start with this many times the initial radius
/// of its visible point (chosen with the furnace, see `docs/integrators.md`).
pub const GATHER_RADIUS_FACTOR: f64 = 4.0;

/// How SPPM and PPM choose a pixel's initial gather radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InitialRadius {
    /// The scene's `radius`, for every pixel.
    Fixed(f64),
    /// Each pixel's radius starts at `per_distance` times the length of the camera path to the
    /// pixel's first visible point (through mirrors and glass): [`RADIUS_FOOTPRINTS`] widths of
    /// the pixel's footprint there. Where the camera looks does not enter it.
    Footprint { per_distance: f64 },
    /// An orthographic camera's pixels have one footprint at every distance: each pixel's
    /// radius starts at this, [`RADIUS_FOOTPRINTS`] pixel heights of the view.
    Orthographic(f64),
}

impl InitialRadius {
    /// The radius of a pixel whose first visible point is `distance` along the camera path;
    /// `None` when there is no usable value (the pixel then waits for its next visible point).
    pub fn at(self, distance: f64) -> Option<f64> {
        let r = match self {
            InitialRadius::Fixed(r) | InitialRadius::Orthographic(r) => r,
            InitialRadius::Footprint { per_distance } => per_distance * distance,
        };
        (r.is_finite() && r > 0.0).then_some(r)
    }
}

impl std::fmt::Display for InitialRadius {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            InitialRadius::Fixed(r) => write!(f, "{r} (settings)"),
            InitialRadius::Orthographic(r) => write!(
                f,
                "{r:.3e} ({RADIUS_FOOTPRINTS} pixel footprints of the orthographic view)"
            ),
            InitialRadius::Footprint { per_distance } => write!(
                f,
                "{per_distance:.3e} x the distance to each pixel's first visible point ({RADIUS_FOOTPRINTS} pixel footprints)"
            ),
        }
    }
}

impl EffectiveSettings {
    /// The initial radius rule for a render of `camera` with these settings: the scene's
    /// `radius`, else [`RADIUS_FOOTPRINTS`] pixel footprints at each pixel's first visible
    /// point (a pixel spans `2 tan(fov / 2) / height` radians), times `radius_scale`; for an
    /// orthographic camera, as many pixel heights of its view. (Hidden from the root's
    /// documentation: the camera is the crate's own scene model.)
    #[doc(hidden)]
    pub fn initial_radius(&self, camera: &crate::scene::Camera) -> InitialRadius {
        if let Some(r) = self.radius {
            return InitialRadius::Fixed(r * self.radius_scale);
        }
        if camera.orthographic {
            let pixel = camera.up.length() / f64::from(self.height().max(1));
            return InitialRadius::Orthographic(RADIUS_FOOTPRINTS * pixel * self.radius_scale);
        }
        let pixel = 2.0 * (0.5 * camera.fov.to_radians()).tan() / f64::from(self.height().max(1));
        InitialRadius::Footprint {
            per_distance: RADIUS_FOOTPRINTS * pixel * self.radius_scale,
        }
    }
}

use crate::scene::{MAX_PIXELS, MAX_RESOLUTION_SIDE as MAX_SIDE};

pub fn effective_settings(
    scene: &Scene,
    o: &RenderOptions,
) -> Result<EffectiveSettings, Diagnostic> {
    let s = &scene.settings;
    let (width, height) = o.resolution.unwrap_or(s.resolution);
    if width == 0
        || height == 0
        || width > MAX_SIDE
        || height > MAX_SIDE
        || width as u64 * height as u64 > MAX_PIXELS
    {
        return Err(Diagnostic::unplaced(format!(
            "resolution {width}x{height} is out of range (1..={MAX_SIDE} per side, at most {MAX_PIXELS} pixels)"
        )));
    }
    // The scene's own numbers are checked by `Scene::validate`; here the overrides, and the
    // counts as overridden (a scene built by hand may hold any count).
    let time_limit = o.time_limit.or(s.time_limit);
    if let Some(t) = o.time_limit
        && !(t > 0.0 && t.is_finite())
    {
        return Err(Diagnostic::unplaced(format!(
            "time limit must be a positive number of seconds, got {t}"
        )));
    }
    if let Some(n) = o.threads
        && !(1..=MAX_THREADS).contains(&n)
    {
        return Err(Diagnostic::unplaced(format!(
            "threads must be from 1 to {MAX_THREADS}, got {n}"
        )));
    }
    // More iterations only under a time limit, which then ends the render (`reference`).
    let iterations = o.iterations.unwrap_or(s.iterations);
    if iterations == 0 || (iterations > MAX_ITERATIONS && time_limit.is_none()) {
        return Err(Diagnostic::unplaced(format!(
            "iterations must be from 1 to {MAX_ITERATIONS}, got {iterations}"
        ))
        .with_help(format!(
            "ask for 1 to {MAX_ITERATIONS} iterations, or set a time limit to end the render"
        )));
    }
    // 0 is allowed: methods without photons are run with it.
    let photons = o.photons.or(s.photons);
    if let Some(n) = photons
        && n > MAX_PHOTONS
    {
        return Err(Diagnostic::unplaced(format!(
            "photons per iteration must be at most {MAX_PHOTONS}, got {n}"
        ))
        .with_help(format!(
            "ask for at most {MAX_PHOTONS} photons per iteration (more iterations add more)"
        )));
    }
    if let Some((k, n)) = o.chain
        && !(1..=n).contains(&k)
    {
        return Err(Diagnostic::unplaced(format!(
            "chain {k} of {n} is not a chain: chains are numbered 1 to their count"
        )));
    }
    let method = method_choice(scene, o.integrator);
    let integrator = method.integrator;
    // Light tracing connects scene points to the lens; an orthographic camera's rays are
    // parallel, so no point but those on a pixel's own ray can reach it (a delta direction).
    // The default rule never chooses such a method for an orthographic camera.
    if scene.camera.orthographic && needs_a_lens(integrator) {
        return Err(Diagnostic::unplaced(format!(
            "`{}` connects light paths to the camera, which an orthographic camera cannot take",
            integrator.name()
        ))
        .with_help(
            "render an orthographic view with `sppm`, `path`, `ppm`, `photon_map` or `whitted`",
        ));
    }
    Ok(EffectiveSettings {
        settings: Settings {
            resolution: (width, height),
            iterations,
            photons,
            max_depth: s.max_depth.clamp(1, 1024),
            seed: o.seed.unwrap_or(s.seed),
            integrator: Some(integrator),
            time_limit,
            ..s.clone()
        },
        method,
        chain: o.chain,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_chain(chain: Option<(u32, u32)>) -> Result<EffectiveSettings, Diagnostic> {
        let options = RenderOptions {
            chain,
            ..RenderOptions::default()
        };
        let l =
            crate::eval::load_source("chain.scn", "sphere { <0, 0, 0>, 1 }", &Default::default());
        effective_settings(&l.scene.expect("a scene"), &options)
    }

    #[test]
    fn a_chain_outside_its_count_is_refused() {
        for bad in [(0, 3), (4, 3), (1, 0)] {
            let e = with_chain(Some(bad)).unwrap_err();
            assert!(e.message.contains("not a chain"), "{}", e.message);
        }
    }
}
