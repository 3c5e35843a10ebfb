//! `sppm-lang render` of an animated scene: each frame of the clock's range loaded and rendered
//! by itself, into the files a frame pattern names.

use std::path::PathBuf;
use std::process::ExitCode;

use sppm_lang::Cancel;
use sppm_lang::internals::eval::RangeOverride;

use super::check::print_diagnostics;
use super::frames::FramePattern;
use super::render::{RenderArgs, render_scene};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE};

/// Renders the frames of `range` that `args` asks for (`--frame K`, else all), each loaded by
/// itself, into the files `pattern` names; stops at the first frame that fails, naming it (the
/// frames written before it are complete files and stay).
pub(super) fn run(
    args: &RenderArgs,
    options: &sppm_lang::EvalOptions,
    still: sppm_lang::internals::eval::Loaded,
    pattern: Option<FramePattern>,
    range: &sppm_lang::FrameRange,
    cancel: &Cancel,
) -> ExitCode {
    let usage = |e: String| {
        say!("error: {e}");
        ExitCode::from(EXIT_USAGE)
    };
    let frames = match args.frame {
        Some(k) if !range.frames().contains(&k) => {
            return usage(format!(
                "frame {k} is outside the animation's frames {}..{}",
                range.first, range.last
            ));
        }
        Some(k) => k..=k,
        None => range.frames(),
    };
    let count = frames.end() - frames.start() + 1;
    // One frame may go to a plain name; several need a place for their numbers.
    let output_of = |k: u32| -> Result<PathBuf, String> {
        let path = match (&pattern, &args.output) {
            (Some(p), _) => p.path(k),
            (None, Some(o)) if count == 1 => o.clone(),
            (None, Some(o)) => {
                return Err(format!(
                    "output `{}` has no place for the frame number, and {count} frames are to be \
                     written: put `%04d` in its name, e.g. `frame_%04d.png`",
                    o.display()
                ));
            }
            (None, None) => FramePattern::for_scene(&args.scene)
                .ok_or_else(|| format!("`{}` is not a scene file name", args.scene.display()))?
                .path(k),
        };
        super::output_path(Some(&path), &args.scene)
    };
    // Every name is checked before the first frame renders, but not with a check on disk per
    // frame (a range may hold millions): the first name fully (its folder is every frame's, the
    // number being in the file name), then only the names that something already holds: the
    // folder's entries and the scene's inputs that some frame of the range would replace.
    let check =
        |k: u32| output_of(k).and_then(|o| super::check_not_an_input(&[&o], &still.dependencies));
    let first = match output_of(*frames.start()) {
        Ok(o) => o,
        Err(e) => return usage(e),
    };
    if let Err(e) = check(*frames.start()) {
        return usage(e);
    }
    if count > 1 {
        let named = pattern
            .clone()
            .or_else(|| FramePattern::for_scene(&args.scene));
        let folder = first
            .parent()
            .filter(|f| !f.as_os_str().is_empty())
            .unwrap_or(std::path::Path::new("."));
        let held = std::fs::read_dir(folder)
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.file_name())
            .chain(
                still
                    .dependencies
                    .iter()
                    .filter_map(|d| d.file_name().map(Into::into)),
            );
        for name in held {
            let frame = name
                .to_str()
                .and_then(|n| named.as_ref()?.frame_of(n))
                .filter(|k| frames.contains(k));
            if let Some(k) = frame
                && let Err(e) = check(k)
            {
                return usage(e);
            }
        }
    }
    if !still.animated {
        // Every frame is the still: its warnings are said once.
        print_diagnostics(&still.sources, &still.diagnostics);
        if count > 1 {
            say!(
                "warning: `{}` reads no animation value (`clock`, `frame_number`, ...): its {count} \
                 frames are the same image",
                args.scene.display()
            );
        }
    }
    let over = RangeOverride {
        frames: args.frames,
        clock: args.clock,
    };
    let stopped = |k: u32, written: u32| {
        if written > 0 {
            say!(
                "error: frame {k} failed; the {written} frame{} before it {} written",
                if written == 1 { "" } else { "s" },
                if written == 1 { "is" } else { "are" }
            );
        } else {
            say!("error: frame {k} failed; no frame was written");
        }
        ExitCode::from(EXIT_SCENE_ERROR)
    };
    for k in frames.clone() {
        // The frames before this one, all written.
        let written = k - frames.start();
        let loaded = match sppm_lang::internals::eval::load_frame(
            &args.scene,
            options,
            &still,
            &over,
            range,
            k,
        ) {
            Ok(l) => l,
            Err(e) => {
                say!("error: {}", e.with_path(&args.scene));
                return stopped(k, written);
            }
        };
        if loaded.interrupted {
            say!("interrupted at frame {k}");
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
        if still.animated {
            print_diagnostics(&loaded.sources, &loaded.diagnostics);
        }
        let Some(scene) = loaded.scene.as_ref().filter(|_| !loaded.has_errors()) else {
            return stopped(k, written);
        };
        let output = match output_of(k)
            .and_then(|o| super::check_not_an_input(&[&o], &loaded.dependencies).map(|()| o))
        {
            Ok(o) => o,
            Err(e) => {
                say!("error: {e}");
                return stopped(k, written);
            }
        };
        say!(
            "frame {k} of {}..{} (clock {})",
            range.first,
            range.last,
            sppm_lang::internals::diag::short_number(range.clock_at(k))
        );
        let last = k == *frames.end();
        if let Err(code) = render_scene(scene, args, &loaded.sources, &output, cancel, last) {
            stopped(k, written);
            return code;
        }
        if cancel.is_cancelled() && !last {
            say!("interrupted after frame {k}; the frames after it were not rendered");
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
    }
    ExitCode::SUCCESS
}
