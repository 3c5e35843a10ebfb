//! One render round of `watch` on a worker thread: an optional preview, then the full render,
//! with snapshots to the output file (and the live page). An image that is less converged than
//! the one on disk of the same scene is not written (see `super::kept`).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use sppm_lang::Image;
use sppm_lang::SourceMap;
use sppm_lang::internals::render::{self, RenderOptions};
use sppm_lang::internals::scene::Scene;

use super::super::check::print_diagnostics;
use super::super::live::{self, Hub};
use super::kept::{OnDisk, Written};
use super::{Job, Outcome, status};
use crate::cli::identity::SceneId;

/// What a round renders and where it reports.
pub struct Round {
    pub number: u32,
    pub scene: Scene,
    /// The identity of `scene` (before the preview is made of it).
    pub identity: SceneId,
    /// The image on disk, shared with the other rounds.
    pub on_disk: OnDisk,
    pub output: PathBuf,
    pub preview: bool,
    /// Seconds between snapshots (0: every iteration).
    pub snapshot_every: f64,
    pub threads: Option<usize>,
    pub memory_limit: Option<u64>,
    /// When the change that started the round happened (for the latency line).
    pub changed_at: Instant,
    pub sources: SourceMap,
    pub hub: Option<Arc<Hub>>,
}

/// Starts a render round on a worker thread.
pub fn start(r: Round) -> Job {
    let cancel = Arc::new(AtomicBool::new(false));
    let keep = Arc::new(AtomicBool::new(false));
    let (flag, keep_image) = (cancel.clone(), keep.clone());
    let handle = std::thread::spawn(move || run(r, &flag, &keep_image));
    Job {
        cancel,
        keep,
        handle,
    }
}

fn run(r: Round, cancel: &AtomicBool, keep_image: &AtomicBool) -> Outcome {
    let number = r.number;
    let snapshot_every = Duration::from_secs_f64(r.snapshot_every);
    let full_size = r.scene.settings.resolution;
    // The method and why (the preview renders the scene's own), for the page's message.
    let method = render::method_choice(&r.scene, None);
    let mut stages = Vec::new();
    if r.preview {
        stages.push(("preview", preview_of(&r.scene)));
    }
    stages.push(("full", r.scene));
    let mut first_snapshot = true;
    let output = &r.output;
    let kept_said = AtomicBool::new(false);
    // Every image goes to the file at the full size (a preview is scaled up, so that a viewer
    // never sees the size change) and, unscaled, to the page, which scales it itself; unless
    // the image there is a more converged one of this scene (`Ok(false)`; the page gets the
    // figures only).
    let publish = |image: &Image,
                   exposure: f64,
                   written: Written,
                   change: &dyn Fn(&mut live::Status)|
     -> Result<bool, String> {
        let wrote = r.on_disk.write_if_better(written, output.exists(), || {
            if (image.width, image.height) == full_size {
                image.write(output, exposure).map_err(|d| d.message)
            } else {
                upscale(image, full_size)
                    .write(output, exposure)
                    .map_err(|d| d.message)
            }
        });
        if let Some(hub) = &r.hub {
            match wrote {
                Ok(false) => hub.update(change),
                _ => hub.publish(image, full_size, change),
            }
        }
        if matches!(wrote, Ok(false)) && !kept_said.swap(true, Ordering::Relaxed) {
            status(&format!(
                "render #{number}: the image on disk is a more converged render of this scene; \
                 it is kept until this render catches up"
            ));
        }
        wrote
    };
    for (stage, scene) in stages {
        let options = RenderOptions {
            threads: r.threads,
            memory_limit: r.memory_limit,
            // The page's copies of the image, at the full size whatever the stage.
            held_memory: r.hub.as_ref().map(|_| sppm_lang::MemoryItem {
                what: "live view",
                bytes: live::reserved_memory(full_size.0, full_size.1),
            }),
            ..RenderOptions::default()
        };
        let exposure = scene.settings.exposure;
        let image_at = |iterations| Written {
            scene: r.identity,
            full: stage == "full",
            iterations,
        };
        let mut last_write: Option<Instant> = None;
        let mut written = 0u32;
        let mut on_progress = |p: &render::Progress| {
            let due = last_write.is_none_or(|t| t.elapsed() >= snapshot_every)
                || p.iteration == p.iterations;
            if !due {
                return;
            }
            let rate = p.stats.photons as f64 / p.elapsed.as_secs_f64().max(1e-9);
            let progress = |s: &mut live::Status| {
                s.state = "rendering";
                s.stage = stage;
                s.message = format!("render #{number} {stage} with {method}");
                s.iteration = p.iteration;
                s.iterations = p.iterations;
                s.elapsed = p.elapsed.as_secs_f64();
                s.photons_per_second = rate;
            };
            match publish(&p.image(), exposure, image_at(p.iteration), &progress) {
                Ok(false) => last_write = Some(Instant::now()),
                Ok(true) => {
                    last_write = Some(Instant::now());
                    written = p.iteration;
                    let latency = if first_snapshot {
                        first_snapshot = false;
                        format!(
                            ", {:.3} s after the change",
                            r.changed_at.elapsed().as_secs_f64()
                        )
                    } else {
                        String::new()
                    };
                    let rate = if rate > 0.0 {
                        format!(" ({:.2} Mphotons/s)", rate / 1e6)
                    } else {
                        String::new()
                    };
                    status(&format!(
                        "render #{number} {stage} iteration {}/{} written to {}{latency}{rate}",
                        p.iteration,
                        p.iterations,
                        output.display(),
                    ));
                }
                Err(e) => status(&format!("cannot write the image: {e}")),
            }
        };
        // Warnings of the prepared scene: once per round (the preview's), to the terminal and
        // the page.
        let mut on_warning = |w: &sppm_lang::Diagnostic| {
            if stage == "full" && r.preview {
                return;
            }
            let w = std::slice::from_ref(w);
            print_diagnostics(&r.sources, w);
            if let Some(hub) = &r.hub {
                let view = live::diagnostics_view(&r.sources, w);
                hub.update(|s| s.diagnostics.extend(view));
            }
        };
        match render::render_with_warnings(
            &scene,
            &options,
            cancel,
            &mut on_warning,
            &mut on_progress,
        ) {
            Ok(out) if out.cancelled => {
                if keep_image.load(Ordering::SeqCst) && out.iterations_done > 0 {
                    match publish(&out.image, exposure, image_at(out.iterations_done), &|_| {}) {
                        Ok(true) => status(&format!(
                            "render #{number} {stage} stopped after {} iterations, written to {}",
                            out.iterations_done,
                            output.display()
                        )),
                        Ok(false) => status(&format!(
                            "render #{number} {stage} stopped after {} iterations",
                            out.iterations_done
                        )),
                        Err(e) => status(&format!("cannot write the image: {e}")),
                    }
                }
                return Outcome::Cancelled;
            }
            Ok(out) => {
                let finished = |s: &mut live::Status| {
                    s.iteration = out.iterations_done;
                    s.elapsed = out.elapsed.as_secs_f64();
                    if stage == "full" {
                        s.state = "finished";
                        s.message = format!(
                            "render #{number} finished: {} iterations in {:.2} s with {method}",
                            out.iterations_done,
                            out.elapsed.as_secs_f64()
                        );
                    }
                };
                // Stopped early by a time limit: the last iterations may not be on disk yet.
                if out.iterations_done > written {
                    let image = image_at(out.iterations_done);
                    if let Err(e) = publish(&out.image, exposure, image, &finished) {
                        status(&format!("cannot write the image: {e}"));
                    }
                } else if let Some(hub) = &r.hub {
                    hub.update(finished);
                }
                status(&format!(
                    "render #{number} {stage} finished: {} iterations in {:.2} s",
                    out.iterations_done,
                    out.elapsed.as_secs_f64()
                ));
            }
            // Cancelled while preparing (a change, Ctrl-C): no image, as before any iteration.
            Err(e) if e.interrupted => return Outcome::Cancelled,
            Err(e) => {
                let e = [e];
                print_diagnostics(&r.sources, &e);
                status(&format!("render #{number} failed"));
                if let Some(hub) = &r.hub {
                    let view = live::diagnostics_view(&r.sources, &e);
                    hub.update(|s| {
                        s.state = "failed";
                        s.message = format!("render #{number} failed");
                        s.diagnostics = view;
                    });
                }
                status("waiting for changes");
                return Outcome::Failed;
            }
        }
    }
    status("waiting for changes");
    Outcome::Finished
}

/// `image` scaled to `size` by nearest neighbour (each preview pixel becomes a block).
pub fn upscale(image: &Image, (w, h): (u32, u32)) -> Image {
    let mut out = Image::new(w, h);
    if image.width == 0 || image.height == 0 {
        return out;
    }
    for y in 0..h {
        let sy = (u64::from(y) * u64::from(image.height) / u64::from(h)) as u32;
        for x in 0..w {
            let sx = (u64::from(x) * u64::from(image.width) / u64::from(w)) as u32;
            out.pixels[(y * w + x) as usize] = image.get(sx, sy);
        }
    }
    out
}

/// The quick first picture: a quarter of the resolution (at least 32 pixels on the short
/// side), a tenth of the photons (or the automatic count), at most 4 iterations.
pub fn preview_of(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let (w, h) = s.settings.resolution;
    let short = w.min(h).max(1);
    let factor = (short / 32).clamp(1, 4);
    s.settings.resolution = ((w / factor).max(1), (h / factor).max(1));
    s.settings.photons = s.settings.photons.map(|n| (n / 10).max(1000));
    s.settings.iterations = s.settings.iterations.min(4);
    s.settings.time_limit = None;
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upscale_fills_the_full_size_with_blocks() {
        let mut small = Image::new(2, 1);
        small.pixels = vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let big = upscale(&small, (5, 3));
        assert_eq!((big.width, big.height), (5, 3));
        assert_eq!(big.get(0, 2), [1.0, 0.0, 0.0]);
        assert_eq!(big.get(2, 0), [1.0, 0.0, 0.0]);
        assert_eq!(big.get(3, 1), [0.0, 1.0, 0.0]);
        assert_eq!(big.get(4, 2), [0.0, 1.0, 0.0]);
    }
}
