//! Animation: a range of frames over which the scene's `clock` runs, and the values the
//! language's built-in animation names take for one frame.
//!
//! As in POV-Ray, `clock` runs linearly from the initial to the final clock over the frames;
//! `clock_delta` is the clock's step from one frame to the next. A cyclic animation (one whose
//! last frame leads back into its first) stops one step short of the final clock, so that the
//! frame after the last would be the first again.

use crate::diag::Diagnostic;

/// Highest frame number (frame numbers go into file names; seven digits at most).
pub const MAX_FRAME: u32 = 9_999_999;

/// Largest clock value in magnitude a range may name (far beyond any use, and every step of a
/// range between such values is still a finite number).
pub const MAX_CLOCK: f64 = 1e12;

/// The frames of an animation and the clock they span.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameRange {
    /// The first and last frame numbers, both rendered.
    pub first: u32,
    pub last: u32,
    /// The clock at the first frame, and at the last one (or, when cyclic, one frame after it).
    pub initial_clock: f64,
    pub final_clock: f64,
    /// The frame after the last is the first again (a loop).
    pub cyclic: bool,
}

impl FrameRange {
    /// Frames `first..=last` with the clock from 0 to 1 (POV-Ray's default), not cyclic.
    pub fn new(first: u32, last: u32) -> Self {
        Self {
            first,
            last,
            initial_clock: 0.0,
            final_clock: 1.0,
            cyclic: false,
        }
    }

    /// Why the range cannot be rendered, if it cannot: frames out of order or beyond
    /// [`MAX_FRAME`], a clock that is not a finite number within [`MAX_CLOCK`].
    /// The diagnostic is at no place: the caller knows where the range came from.
    pub fn check(&self) -> Result<(), Diagnostic> {
        if self.last < self.first {
            return Err(Diagnostic::unplaced(format!(
                "the frame range {}..{} ends before it starts",
                self.first, self.last
            )));
        }
        if self.last > MAX_FRAME {
            return Err(Diagnostic::unplaced(format!(
                "frame {} is beyond the highest frame number, {MAX_FRAME}",
                self.last
            )));
        }
        for c in [self.initial_clock, self.final_clock] {
            if !(c.is_finite() && c.abs() <= MAX_CLOCK) {
                return Err(Diagnostic::unplaced(format!(
                    "the clock must run between finite numbers within ±{MAX_CLOCK:e}, found {c}"
                )));
            }
        }
        Ok(())
    }

    /// The frame numbers, in order.
    pub fn frames(&self) -> std::ops::RangeInclusive<u32> {
        self.first..=self.last
    }

    /// How many frames the range holds.
    pub fn len(&self) -> u32 {
        self.last.saturating_sub(self.first) + 1
    }

    /// Never: a range holds at least its first frame.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The clock's step from one frame to the next: the clock's span over the frames' span
    /// (one more when cyclic). A single frame that is not cyclic has no step: 0 (POV-Ray, which
    /// does not animate then, leaves its own value undefined).
    pub fn clock_delta(&self) -> f64 {
        let steps =
            f64::from(self.last.saturating_sub(self.first)) + if self.cyclic { 1.0 } else { 0.0 };
        if steps == 0.0 {
            0.0
        } else {
            (self.final_clock - self.initial_clock) / steps
        }
    }

    /// The clock at frame `frame` (computed from the first frame, so that a frame's clock is
    /// the same whichever frames are rendered with it).
    pub fn clock_at(&self, frame: u32) -> f64 {
        if frame == self.last && !self.cyclic && self.last != self.first {
            // Exactly the final clock, free of the step's rounding.
            return self.final_clock;
        }
        self.initial_clock + self.clock_delta() * (f64::from(frame) - f64::from(self.first))
    }

    /// Frame `frame` of this range, if the range holds it.
    pub fn frame(&self, frame: u32) -> Option<Frame> {
        self.frames().contains(&frame).then_some(Frame {
            number: frame,
            range: *self,
        })
    }
}

/// One frame of an animation: what the scene's animation names read while it is evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub number: u32,
    pub range: FrameRange,
}

/// The built-in names an animated scene reads, with what they are.
pub const ANIMATION_NAMES: [(&str, &str); 8] = [
    ("clock", "the animation's clock"),
    ("clock_delta", "the clock's step from one frame to the next"),
    ("clock_on", "whether an animation is being rendered"),
    ("frame_number", "the number of the frame being rendered"),
    ("initial_clock", "the clock at the first frame"),
    ("final_clock", "the clock at the last frame"),
    ("initial_frame", "the first frame's number"),
    ("final_frame", "the last frame's number"),
];

/// The value of animation name `name` while `frame` is evaluated (`None`: a still, where every
/// one is 0 and `clock_on` false, as in POV-Ray). `None` for a name that is not one of them.
pub fn animation_value(name: &str, frame: Option<&Frame>) -> Option<f64> {
    let Some(f) = frame else {
        return ANIMATION_NAMES
            .iter()
            .any(|(n, _)| *n == name)
            .then_some(0.0);
    };
    let r = &f.range;
    Some(match name {
        "clock" => r.clock_at(f.number),
        "clock_delta" => r.clock_delta(),
        "clock_on" => 1.0,
        "frame_number" => f64::from(f.number),
        "initial_clock" => r.initial_clock,
        "final_clock" => r.final_clock,
        "initial_frame" => f64::from(r.first),
        "final_frame" => f64::from(r.last),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clock_runs_from_initial_to_final_over_the_frames() {
        let r = FrameRange::new(0, 4);
        assert_eq!(r.clock_delta(), 0.25);
        let clocks: Vec<f64> = r.frames().map(|k| r.clock_at(k)).collect();
        assert_eq!(clocks, [0.0, 0.25, 0.5, 0.75, 1.0]);
        // POV-Ray's frames 1..10 from clock 0 to 1: a ninth per frame, the last at 1.
        let r = FrameRange::new(1, 10);
        assert!((r.clock_delta() - 1.0 / 9.0).abs() < 1e-15);
        assert_eq!(r.clock_at(1), 0.0);
        assert_eq!(r.clock_at(10), 1.0);
    }

    #[test]
    fn a_cyclic_range_stops_one_step_short_of_the_final_clock() {
        let r = FrameRange {
            cyclic: true,
            ..FrameRange::new(0, 3)
        };
        assert_eq!(r.clock_delta(), 0.25);
        assert_eq!(r.clock_at(3), 0.75);
        // The frame after the last would have the final clock: the first again, for a loop.
        assert_eq!(r.clock_at(4), 1.0);
        // A single cyclic frame steps through the whole clock.
        let one = FrameRange {
            cyclic: true,
            ..FrameRange::new(5, 5)
        };
        assert_eq!((one.clock_delta(), one.clock_at(5)), (1.0, 0.0));
    }

    #[test]
    fn a_single_frame_has_the_initial_clock_and_no_step() {
        let r = FrameRange {
            initial_clock: 2.0,
            final_clock: 3.0,
            ..FrameRange::new(7, 7)
        };
        assert_eq!((r.clock_at(7), r.clock_delta()), (2.0, 0.0));
    }

    #[test]
    fn a_still_reads_zero_everywhere() {
        for (name, _) in ANIMATION_NAMES {
            assert_eq!(animation_value(name, None), Some(0.0), "{name}");
        }
        assert_eq!(animation_value("pi", None), None);
        let f = FrameRange::new(10, 20).frame(15).unwrap();
        assert_eq!(animation_value("frame_number", Some(&f)), Some(15.0));
        assert_eq!(animation_value("clock", Some(&f)), Some(0.5));
        assert_eq!(animation_value("final_frame", Some(&f)), Some(20.0));
        assert_eq!(animation_value("clock_on", Some(&f)), Some(1.0));
        assert!(FrameRange::new(10, 20).frame(21).is_none());
    }

    #[test]
    fn bad_ranges_are_refused() {
        assert!(FrameRange::new(5, 4).check().is_err());
        assert!(FrameRange::new(0, MAX_FRAME + 1).check().is_err());
        let nan = FrameRange {
            final_clock: f64::NAN,
            ..FrameRange::new(0, 1)
        };
        assert!(nan.check().is_err());
        assert!(FrameRange::new(0, MAX_FRAME).check().is_ok());
    }
}
