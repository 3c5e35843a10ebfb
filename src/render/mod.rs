//! The render API used by the CLI and `watch`: prepare a `Scene`, run its integrator with
//! overridable settings, report progress per iteration, stop promptly on cancel.
//!
//! The caller's [`RenderOptions::cancel`] and the `cancel` flag of these functions stop the
//! work alike: the prepare stage with [`Diagnostic::interrupted`], the passes as described
//! below.
//!
//! A time limit is a deadline: when it passes, the iteration in flight is abandoned like a
//! cancelled one (its partial work is dropped) and the output holds the iterations finished
//! before it; `cancelled` in the output says only whether the caller cancelled.

pub use crate::integrators::{Progress, RenderOutput, RenderStats};
pub use crate::prepare::{
    EffectiveSettings, InitialRadius, MethodChoice, MethodSource, PreparedScene, RADIUS_FOOTPRINTS,
    RenderOptions, SurfaceHit, effective_settings, method_choice, prepare,
};

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::diag::Diagnostic;
use crate::integrators;
use crate::scene::Scene;

/// Renders `scene`. `cancel` is checked in the prepare stage and inside every pass;
/// `on_progress` runs after every iteration (on the calling thread's pool) and may call
/// [`Progress::image`].
pub fn render(
    scene: &Scene,
    options: &RenderOptions,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
) -> Result<RenderOutput, Diagnostic> {
    render_with_warnings(scene, options, cancel, &mut |_| {}, on_progress)
}

/// [`render`], telling `on_warning` the prepared scene's [warnings](PreparedScene::warnings)
/// before the first iteration, and those of the render itself
/// ([`PreparedScene::render_warnings`]) after the last.
pub fn render_with_warnings(
    scene: &Scene,
    options: &RenderOptions,
    cancel: &AtomicBool,
    on_warning: &mut dyn FnMut(&Diagnostic),
    on_progress: &mut (dyn FnMut(&Progress) + Send),
) -> Result<RenderOutput, Diagnostic> {
    let stop = || options.cancel.is_cancelled() || cancel.load(Ordering::Relaxed);
    let (settings, prepared) = crate::prepare::prepare_until(scene, options, &stop)?;
    for w in prepared.warnings() {
        on_warning(&w);
    }
    let out = render_prepared(&prepared, &settings, options, cancel, on_progress)?;
    for w in prepared.render_warnings() {
        on_warning(&w);
    }
    Ok(out)
}

/// The part of [`render_with_warnings`] after [`prepare`]: runs the integrator on `prepared`
/// with the `settings` prepare made from `options`. A caller that prepares the scene itself
/// keeps it afterwards (a process about to exit may leave a large one unfreed).
pub fn render_prepared(
    prepared: &PreparedScene,
    settings: &EffectiveSettings,
    options: &RenderOptions,
    cancel: &AtomicBool,
    on_progress: &mut (dyn FnMut(&Progress) + Send),
) -> Result<RenderOutput, Diagnostic> {
    // The method was chosen with the settings; a caller that rewrote `integrator` through
    // `DerefMut` afterwards would run another than it asked for.
    debug_assert!(settings.integrator.is_none_or(|i| i == settings.method()));
    let integrator = integrators::for_method(settings.method());
    let deadline = settings
        .time_limit
        .and_then(|t| Duration::try_from_secs_f64(t).ok())
        .and_then(|t| Instant::now().checked_add(t));
    let stop = AtomicBool::new(false);
    let finished = AtomicBool::new(false);
    // The options' cancel is the integrator's own flag unless it is another than `cancel`:
    // then, as for a deadline, a watchdog raises one flag for both.
    let other = (!options.cancel.same(cancel)).then_some(options.cancel.flag());
    let watched = deadline.is_some() || other.is_some();
    let flag = if watched { &stop } else { cancel };
    let cancelled =
        || cancel.load(Ordering::Relaxed) || other.is_some_and(|o| o.load(Ordering::Relaxed));
    // A cancel raised from the progress callback stops the next iteration, as when the
    // integrator watches `cancel` itself (the watchdog would see it only later).
    let mut progress = |p: &Progress| {
        options.cancel.set_progress(p.iteration, p.iterations);
        on_progress(p);
        if watched && cancelled() {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let mut run = || {
        integrator.render(integrators::Job {
            scene: prepared,
            settings,
            cancel: flag,
            on_progress: &mut progress,
        })
    };
    let out = std::thread::scope(|s| {
        if watched {
            // The watchdog: raises the integrator's flag at the deadline or on the caller's
            // cancel, and ends with the render.
            let (stop, finished, cancelled) = (&stop, &finished, &cancelled);
            s.spawn(move || {
                while !finished.load(Ordering::Relaxed) {
                    let now = Instant::now();
                    if deadline.is_some_and(|end| now >= end) || cancelled() {
                        stop.store(true, Ordering::Relaxed);
                        return;
                    }
                    let left = deadline.map_or(Duration::MAX, |end| end - now);
                    std::thread::sleep(left.min(Duration::from_millis(5)));
                }
            });
        }
        // Ends the watchdog however the render ends, a panic included (the scope would
        // otherwise wait for the watchdog until the deadline).
        struct Finish<'f>(&'f AtomicBool);
        impl Drop for Finish<'_> {
            fn drop(&mut self) {
                self.0.store(true, Ordering::Relaxed);
            }
        }
        let _finish = Finish(&finished);
        match options.threads {
            Some(n) => rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map(|pool| pool.install(&mut run))
                .map_err(|e| Diagnostic::unplaced(format!("cannot start {n} threads: {e}"))),
            None => Ok(run()),
        }
    });
    let mut out = out?;
    out.cancelled = cancelled();
    Ok(out)
}
