//! `settings { ... }`: the render settings.

use super::Sink;
use crate::diag::short_number;
use crate::diag::{At, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, count, num, positive, range_error, word};
use crate::eval::props::{PropSpec, p, w};
use crate::eval::value::Value;
use crate::scene::animation::MAX_CLOCK;
use crate::scene::{
    Antialias, Handedness, Integrator, MAX_FRAME, MAX_ITERATIONS, MAX_PHOTONS, MAX_RESOLUTION_SIDE,
    Settings,
};
use crate::span::Span;
use crate::syntax::ast::Name;

pub(super) struct SettingsBuilder(pub(super) Settings);

static SETTINGS_PROPS: [PropSpec; 17] = [
    p("resolution", 1, 2, "a width and height", "<512, 512>"),
    p("iterations", 1, 1, "a number", "64"),
    p("photons", 1, 1, "a number", "200000"),
    p("radius", 1, 1, "a number", "0.05"),
    p("alpha", 1, 1, "a number in (0, 1]", "0.7"),
    p("max_depth", 1, 1, "a number", "16"),
    p("seed", 1, 1, "a number", "7"),
    w(
        "integrator",
        "`sppm`, `ppm`, `photon_map`, `path`, `whitted`, `vcm`, `bpt` or `lt`",
        "sppm",
    ),
    p("exposure", 1, 1, "a number", "1"),
    p("time_limit", 1, 1, "a number of seconds", "60"),
    w("antialias", "`jitter` or `adaptive`", "adaptive"),
    p("threshold", 1, 1, "a colour difference", "0.1"),
    w("final_gather", "`on` or `off`", "on"),
    w("handedness", "`right` or `left`", "left"),
    p("frames", 2, 2, "the first and last frame numbers", "0, 99"),
    p(
        "clock_range",
        2,
        2,
        "the clock at the first and the last frame",
        "0, 1",
    ),
    w("cyclic", "`on` or `off`", "on"),
];

impl SettingsBuilder {
    pub(super) fn finish(mut self, span: Span) -> SourceResult<Value> {
        self.0.span = span;
        // The scene's own check of the anti-aliasing threshold (the one `prepare` runs),
        // reported here at the block; the other settings are checked as they are read.
        if self.0.antialias_threshold.is_some()
            && let Err(e) = self.0.validate()
        {
            return Err(vec![e.at(span)]);
        }
        Ok(Value::Settings(Box::new(self.0)))
    }
}

/// `frames first, last`: whole frame numbers from 0 to [`MAX_FRAME`], in order.
fn frames(first: &Arg, last: &Arg) -> SourceResult<(u32, u32)> {
    let frame = |a: &Arg| -> SourceResult<u32> {
        let x = num(a)?;
        if !(0.0..=f64::from(MAX_FRAME)).contains(&x) || x.fract() != 0.0 {
            return Err(range_error(
                a.span,
                format!(
                    "a frame number must be a whole number from 0 to {MAX_FRAME}, found {}",
                    crate::eval::expr::exact_number(x)
                ),
                "e.g. `frames 0, 99` for a hundred frames",
            ));
        }
        Ok(x as u32)
    };
    let (a, b) = (frame(first)?, frame(last)?);
    if b < a {
        return Err(range_error(
            first.span.join(last.span),
            format!("the frames run from {a} back to {b}: the last comes before the first"),
            "give the first frame, then the last: e.g. `frames 0, 99`",
        ));
    }
    Ok((a, b))
}

/// `clock_range initial, final`: finite numbers within [`MAX_CLOCK`] (the clock may run
/// backwards).
fn clock_range(initial: &Arg, last: &Arg) -> SourceResult<(f64, f64)> {
    let clock = |a: &Arg| -> SourceResult<f64> {
        let x = num(a)?;
        if !x.is_finite() || x.abs() > MAX_CLOCK {
            return Err(range_error(
                a.span,
                format!(
                    "the clock must stay within ±{}, found {}",
                    short_number(MAX_CLOCK),
                    short_number(x)
                ),
                "e.g. `clock_range 0, 1` (the default)",
            ));
        }
        Ok(x)
    };
    Ok((clock(initial)?, clock(last)?))
}

impl Sink for SettingsBuilder {
    fn kind(&self) -> String {
        "settings".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &SETTINGS_PROPS
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        let s = &mut self.0;
        match kw.text.as_str() {
            "resolution" => {
                let (w, h, span) = if args.len() == 2 {
                    (
                        num(&args[0])?,
                        num(&args[1])?,
                        args[0].span.join(args[1].span),
                    )
                } else {
                    let v = args[0].value.vec2().at(args[0].span)?;
                    (v.x, v.y, args[0].span)
                };
                for x in [w, h] {
                    if !(1.0..=f64::from(MAX_RESOLUTION_SIDE)).contains(&x) || x.fract() != 0.0 {
                        return Err(range_error(
                            span,
                            format!(
                                "resolution must be whole numbers from 1 to {MAX_RESOLUTION_SIDE}, found {} x {}",
                                crate::eval::expr::exact_number(w),
                                crate::eval::expr::exact_number(h)
                            ),
                            "e.g. `resolution <512, 512>`",
                        ));
                    }
                }
                s.resolution = (w as u32, h as u32);
            }
            "iterations" => {
                s.iterations = count(&args[0], "iterations", f64::from(MAX_ITERATIONS))? as u32
            }
            "photons" => s.photons = Some(count(&args[0], "photons", MAX_PHOTONS as f64)? as u64),
            "radius" => s.radius = Some(positive(&args[0], "radius")?),
            "alpha" => {
                let a = num(&args[0])?;
                if !(a > 0.0 && a <= 1.0) {
                    return Err(range_error(
                        args[0].span,
                        format!("alpha must be in (0, 1], found {}", short_number(a)),
                        "SPPM uses 2/3 or 0.7",
                    ));
                }
                s.alpha = a;
            }
            "max_depth" => s.max_depth = count(&args[0], "max_depth", 1000.0)? as u32,
            "seed" => {
                let x = num(&args[0])?;
                // Above 2^53 not every whole number is a number of the language (an f64):
                // `seed 9007199254740993` would be read as ...992 without a word.
                const MAX_SEED: f64 = 9_007_199_254_740_992.0;
                if !(0.0..=MAX_SEED).contains(&x) || x.fract() != 0.0 {
                    return Err(range_error(
                        args[0].span,
                        format!(
                            "seed must be a whole number from 0 to 2^53, found {}",
                            short_number(x)
                        ),
                        "e.g. `seed 7`; a scene's numbers are 64-bit floats, exact as whole \
                         numbers up to 2^53 (`--seed` takes any 64-bit seed)",
                    ));
                }
                s.seed = x as u64;
            }
            "integrator" => {
                let names: Vec<&str> = Integrator::ALL.iter().map(|i| i.name()).collect();
                s.integrator =
                    Some(Integrator::from_name(&word(&args[0], &names)?).expect("known name"));
            }
            "exposure" => s.exposure = positive(&args[0], "exposure")?,
            "time_limit" => s.time_limit = Some(positive(&args[0], "time limit")?),
            "antialias" => {
                let names: Vec<&str> = Antialias::ALL.iter().map(|a| a.name()).collect();
                let name = word(&args[0], &names)?;
                s.antialias = *Antialias::ALL
                    .iter()
                    .find(|a| a.name() == name)
                    .expect("known name");
            }
            "threshold" => s.antialias_threshold = Some(positive(&args[0], "threshold")?),
            "final_gather" => s.final_gather = word(&args[0], &["on", "off"])? == "on",
            "handedness" => {
                let names: Vec<&str> = Handedness::ALL.iter().map(|h| h.name()).collect();
                let name = word(&args[0], &names)?;
                s.handedness = *Handedness::ALL
                    .iter()
                    .find(|h| h.name() == name)
                    .expect("known name");
            }
            "frames" => s.frames = Some(frames(&args[0], &args[1])?),
            "clock_range" => s.clock_range = Some(clock_range(&args[0], &args[1])?),
            "cyclic" => s.cyclic = word(&args[0], &["on", "off"])? == "on",
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional_help(&self) -> &'static str {
        "settings take properties only, e.g. `settings { iterations 64 }`"
    }
}
