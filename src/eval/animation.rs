//! Loading one frame of an animation.
//!
//! A scene may declare its own frames (`settings { frames 0, 99 }`), and its evaluation depends
//! on the frame (`clock`), so a frame is found in two loads: the scene evaluated as a still
//! gives the frame range, then the frame's own evaluation gives its scene. The second load is
//! skipped when the still read no animation name (every frame is then the still), and it must
//! declare the same range as the first: a range that moves with the clock has no frames.

use std::path::Path;

use super::{EvalOptions, Loaded, load_file};
use crate::diag::Diagnostic;
use crate::files::FileError;
use crate::scene::{FrameRange, Settings};

/// The parts of a frame range a caller gives over the scene's own `settings`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RangeOverride {
    /// The first and last frames (`render --frames A..B`).
    pub frames: Option<(u32, u32)>,
    /// The clock at the first and last frames (`render --clock A..B`).
    pub clock: Option<(f64, f64)>,
}

/// The animation `settings` declares, with `over` taking precedence: `None` when neither
/// names frames (a still). `Err`: a range that cannot be rendered ([`FrameRange::check`]).
pub fn frame_range(
    settings: &Settings,
    over: &RangeOverride,
) -> Result<Option<FrameRange>, String> {
    let Some((first, last)) = over.frames.or(settings.frames) else {
        return Ok(None);
    };
    let (initial_clock, final_clock) = over.clock.or(settings.clock_range).unwrap_or((0.0, 1.0));
    let range = FrameRange {
        first,
        last,
        initial_clock,
        final_clock,
        cyclic: settings.cyclic,
    };
    range.check().map_err(|d| d.message)?;
    Ok(Some(range))
}

/// Loads frame `frame` of `range` from the scene at `path`. `still` is the load of the same
/// file as a still (`options.frame` `None`) that gave `range` through [`frame_range`] with
/// `over`; it is returned as it is when it read no animation name. Otherwise the file is
/// evaluated again with the frame set, and a load that declares another range than `range`
/// ends with an error at its settings (and no scene). `Err` only when the file cannot be read.
pub fn load_frame(
    path: &Path,
    options: &EvalOptions,
    still: &Loaded,
    over: &RangeOverride,
    range: &FrameRange,
    frame: u32,
) -> Result<Loaded, FileError> {
    if !still.animated {
        return Ok(still.clone());
    }
    let options = EvalOptions {
        frame: range.frame(frame),
        ..options.clone()
    };
    let mut loaded = load_file(path, &options)?;
    let declared = loaded
        .scene
        .as_ref()
        .map(|s| (frame_range(&s.settings, over), s.settings.span));
    if let Some((declared, span)) = declared
        && declared.as_ref() != Ok(&Some(*range))
    {
        let now = match declared {
            Ok(Some(r)) => format!(
                "frames {}..{}, clock {} to {}",
                r.first, r.last, r.initial_clock, r.final_clock
            ),
            Ok(None) => "no frames".to_string(),
            Err(e) => e,
        };
        let d = Diagnostic::error(
            span,
            format!(
                "the frame range changes with the frame: read as a still the scene declares \
                 frames {}..{} (clock {} to {}), at frame {frame} {now}",
                range.first, range.last, range.initial_clock, range.final_clock
            ),
        )
        .with_label("the range depends on an animation value")
        .with_help(
            "write `frames`, `clock_range` and `cyclic` with values that do not depend on \
             `clock`, `frame_number` or the other animation values",
        );
        loaded.diagnostics.insert(0, d);
        loaded.scene = None;
    }
    Ok(loaded)
}
