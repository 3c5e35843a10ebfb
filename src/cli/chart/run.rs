//! Rendering and measuring the chosen methods one after another, each until its time budget,
//! and stopping at once on Ctrl-C or SIGTERM.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use sppm_lang::Diagnostic;
use sppm_lang::Image;
use sppm_lang::internals::compare::{ImageView, Window, error};
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::scene::Scene;

use super::methods::Method;
use super::{Errors, Row};
use crate::cli::reference::to_f32;

/// Why a method did not finish.
pub enum Failure {
    /// Ctrl-C or SIGTERM during its render.
    Interrupted,
    /// Its render failed (after the validation every method passed).
    Render(Diagnostic),
    /// Its measurement failed.
    Other(String),
}

/// The flags that stop a render: `cancel`, raised by the budget or an interruption, and
/// `interrupted`, raised by an interruption only.
#[derive(Clone, Default)]
pub struct Stop {
    cancel: Arc<AtomicBool>,
    interrupted: Arc<AtomicBool>,
}

impl Stop {
    /// Flags that Ctrl-C and SIGTERM raise (both: the render in flight stops at once).
    pub fn on_interrupt() -> Self {
        let stop = Self::default();
        let s = stop.clone();
        // A second handler cannot be installed (e.g. in tests); the chart runs without it.
        let _ = ctrlc::set_handler(move || {
            s.interrupted.store(true, Ordering::SeqCst);
            s.cancel.store(true, Ordering::SeqCst);
        });
        stop
    }
}

/// Renders and measures each chosen method in turn with `measure`, adding the rows of each
/// that finishes to `rows`: the first method that does not finish, with why (the methods
/// after it are not run).
pub fn run_methods(
    chosen: &[(Method, Scene)],
    budget: f64,
    rows: &mut Vec<Row>,
    mut measure: impl FnMut(&Scene) -> Result<Vec<Measured>, Failure>,
) -> Option<(String, Failure)> {
    for (m, s) in chosen {
        say!("chart: {} ({budget} s)", m.label);
        let measured = match measure(s) {
            Ok(measured) => measured,
            Err(f) => return Some((m.label.clone(), f)),
        };
        if measured.is_empty() {
            say!("warning: chart: {} finished no iteration", m.label);
        }
        for (iterations, seconds, whole, window) in measured {
            say!(
                "  {iterations:>6} it {seconds:>8.2} s  rmse {:.5}  relmse {:.5}{}",
                whole.rmse,
                whole.rel_mse,
                window.map_or(String::new(), |w| format!(
                    "  window rmse {:.5} relmse {:.5}",
                    w.rmse, w.rel_mse
                ))
            );
            rows.push(Row {
                method: m.label.clone(),
                iterations,
                seconds,
                whole,
                window,
            });
        }
    }
    None
}

/// One measurement: iterations, seconds of rendering, errors on the whole image and window.
pub type Measured = (u32, f64, Errors, Option<Errors>);

/// Renders `scene` until the first iteration that ends past `budget` seconds, measuring the
/// error at the checkpoints and at the last iteration.
pub fn measure(
    scene: &Scene,
    options: &RenderOptions,
    budget: f64,
    stop: &Stop,
    ref_view: ImageView<'_>,
    window: Option<Window>,
) -> Result<Vec<Measured>, Failure> {
    // Lowered before the interruption is looked at: an interruption from here on raises it
    // again.
    stop.cancel.store(false, Ordering::SeqCst);
    if stop.interrupted.load(Ordering::SeqCst) {
        return Err(Failure::Interrupted);
    }
    let checkpoints: Vec<f64> = (0..6).rev().map(|k| budget / f64::from(1 << k)).collect();
    let errors = |img: &Image| -> Result<(Errors, Option<Errors>), String> {
        let pix = to_f32(img);
        let v = ImageView::new(img.width, img.height, &pix)?;
        let whole = error(v, ref_view, None)?;
        let win = window.map(|w| error(v, ref_view, Some(w))).transpose()?;
        Ok((whole.into(), win.map(Errors::from)))
    };
    let mut next = 0usize;
    let mut overhead = 0.0f64;
    let mut measured = Vec::new();
    let mut failure = None;
    let mut on_progress = |p: &sppm_lang::internals::render::Progress| {
        let t = p.elapsed.as_secs_f64() - overhead;
        if next < checkpoints.len() && t >= checkpoints[next] {
            let t0 = Instant::now();
            while next < checkpoints.len() && t >= checkpoints[next] {
                next += 1;
            }
            match errors(&p.image()) {
                Ok((whole, win)) => measured.push((p.iteration, t, whole, win)),
                Err(e) => failure = Some(e),
            }
            overhead += t0.elapsed().as_secs_f64();
        }
        if t >= budget {
            stop.cancel.store(true, Ordering::SeqCst);
        }
    };
    let out = match render(scene, options, &stop.cancel, &mut on_progress) {
        Ok(out) => out,
        // Stopped before its first iteration ended (in the prepare stage): the render reports
        // that as an error, but it is the interruption, not a failure of the method.
        Err(_) if stop.interrupted.load(Ordering::SeqCst) => return Err(Failure::Interrupted),
        Err(e) => return Err(Failure::Render(e)),
    };
    if stop.interrupted.load(Ordering::SeqCst) {
        return Err(Failure::Interrupted);
    }
    if let Some(e) = failure {
        return Err(Failure::Other(e));
    }
    // The last iteration is always measured (the render may stop between checkpoints).
    if measured.last().is_none_or(|r| r.0 != out.iterations_done) && out.iterations_done > 0 {
        let (whole, win) = errors(&out.image).map_err(Failure::Other)?;
        let t = out.elapsed.as_secs_f64() - overhead;
        measured.push((out.iterations_done, t, whole, win));
    }
    Ok(measured)
}
