//! Arguments shared by several commands: the argument shapes, the value parsers with their
//! ranges, the output size and the interpreter's limits.

use std::path::PathBuf;

use clap::{Arg, ArgAction, ArgMatches};
use sppm_lang::EvalOptions;

/// The positional scene file every command that loads one takes.
pub(super) fn scene_arg() -> Arg {
    Arg::new("scene")
        .value_name("SCENE")
        .value_parser(clap::value_parser!(PathBuf))
        .required(true)
        .help("The scene file (.scn)")
}

/// `--long VALUE`, taken once (a repeat replaces it).
pub(super) fn option(id: &'static str, long: &'static str, value_name: &'static str) -> Arg {
    Arg::new(id)
        .long(long)
        .value_name(value_name)
        .action(ArgAction::Set)
}

/// `-o/--output PATH`; each command gives its own help (and whether it is required).
pub(super) fn output_arg(value_name: &'static str) -> Arg {
    option("output", "output", value_name)
        .short('o')
        .value_parser(clap::value_parser!(PathBuf))
}

/// `--threads N`, from 1 to [`MAX_THREADS`]; each command gives its own help.
pub(super) fn threads_arg() -> Arg {
    option("threads", "threads", "THREADS").value_parser(parse_threads)
}

/// `--long` without a value.
pub(super) fn flag(id: &'static str, long: &'static str) -> Arg {
    Arg::new(id).long(long).action(ArgAction::SetTrue)
}

/// An argument the parser has made sure of (required, or with a default).
pub(super) fn required<T: Clone + Send + Sync + 'static>(
    m: &mut ArgMatches,
    id: &str,
) -> Result<T, clap::Error> {
    m.remove_one::<T>(id).ok_or_else(|| {
        clap::Error::raw(
            clap::error::ErrorKind::MissingRequiredArgument,
            format!("the following required argument was not provided: {id}"),
        )
    })
}

/// [`EvalOptions`]' step limit as the default of `--max-steps`.
pub(super) fn default_max_steps() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| EvalOptions::default().max_steps.to_string())
}

/// Whether a flag made by [`flag`] was given.
pub(super) fn switch(m: &mut ArgMatches, id: &str) -> bool {
    m.remove_one::<bool>(id).unwrap_or(false)
}

/// The limits of the render options, checked again by the render (the library's callers have
/// no command line).
pub use sppm_lang::internals::prepare::{MAX_ITERATIONS, MAX_PHOTONS, MAX_THREADS};
/// Longest time limit or snapshot interval in seconds (a year).
pub const MAX_SECONDS: f64 = 365.0 * 24.0 * 3600.0;

/// A positive number of seconds, at most [`MAX_SECONDS`].
pub fn parse_seconds(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number of seconds"))?;
    if !(v > 0.0 && v <= MAX_SECONDS) {
        return Err(format!(
            "must be more than 0 and at most {MAX_SECONDS} seconds (a year), got {text}"
        ));
    }
    Ok(v)
}

/// A byte count with an optional binary suffix: `1500000`, `512K`, `512M`, `4G`.
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    // A plain number (`1500000`, `1e9`) is bytes; otherwise digits then a unit.
    let split = if t.parse::<f64>().is_ok() {
        None
    } else {
        t.char_indices().find(|(_, c)| c.is_ascii_alphabetic())
    };
    let (digits, unit) = match split {
        Some((i, _)) => (&t[..i], &t[i..]),
        None => (t, ""),
    };
    let shift = match unit.to_ascii_uppercase().as_str() {
        "" | "B" => 0,
        "K" | "KB" | "KIB" => 10,
        "M" | "MB" | "MIB" => 20,
        "G" | "GB" | "GIB" => 30,
        "T" | "TB" | "TIB" => 40,
        _ => return Err(format!("unknown unit `{unit}`; use K, M, G or T")),
    };
    let n: f64 = digits
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a size such as 512M or 4G"))?;
    let bytes = n * (1u64 << shift) as f64;
    if !(1.0..1.8e19).contains(&bytes) {
        return Err(format!("`{text}` is out of range"));
    }
    Ok(bytes as u64)
}

/// A thread count from 1 to [`MAX_THREADS`].
pub fn parse_threads(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number"))?;
    if !(1..=MAX_THREADS).contains(&n) {
        return Err(format!("must be from 1 to {MAX_THREADS}, got {n}"));
    }
    Ok(n)
}

/// Largest `--scale` factor (the result is range-checked again by the render).
pub const MAX_SCALE: f64 = 64.0;

/// `WxH`, or one side with the other left out (`640x`, `x480`) to keep the scene's aspect ratio.
pub fn parse_resolution(text: &str) -> Result<Resolution, String> {
    let usage = || format!("`{text}` is not a resolution such as 640x480, 640x or x480");
    let (w, h) = text.trim().split_once(['x', 'X']).ok_or_else(usage)?;
    let side = |s: &str| -> Result<Option<u32>, String> {
        if s.is_empty() {
            return Ok(None);
        }
        match s.parse::<u32>() {
            Ok(n) if (1..=sppm_lang::internals::scene::MAX_RESOLUTION_SIDE).contains(&n) => {
                Ok(Some(n))
            }
            Ok(n) => Err(format!(
                "each side must be from 1 to {}, got {n}",
                sppm_lang::internals::scene::MAX_RESOLUTION_SIDE
            )),
            Err(_) => Err(usage()),
        }
    };
    match (side(w)?, side(h)?) {
        (None, None) => Err(usage()),
        (Some(w), Some(h))
            if u64::from(w) * u64::from(h) > sppm_lang::internals::scene::MAX_PIXELS =>
        {
            Err(format!(
                "{w}x{h} is {} pixels, more than the limit of {}",
                u64::from(w) * u64::from(h),
                sppm_lang::internals::scene::MAX_PIXELS
            ))
        }
        (w, h) => Ok(Resolution {
            width: w,
            height: h,
        }),
    }
}

/// A scale factor for the scene's resolution: more than 0, at most [`MAX_SCALE`].
pub fn parse_scale(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if !(v > 0.0 && v <= MAX_SCALE) {
        return Err(format!(
            "must be more than 0 and at most {MAX_SCALE}, got {text}"
        ));
    }
    Ok(v)
}

/// A resolution from the command line; a side left out follows the scene's aspect ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resolution {
    pub width: Option<u32>,
    pub height: Option<u32>,
}

/// The image size, overriding the scene's `settings { resolution }`.
#[derive(Debug, Clone)]
pub struct SizeArgs {
    pub resolution: Option<Resolution>,
    pub scale: Option<f64>,
}

impl SizeArgs {
    pub fn args() -> [Arg; 2] {
        [
            option("resolution", "resolution", "WxH")
                .value_parser(parse_resolution)
                .help(
                    "Image size `WxH` (e.g. 320x240); `320x` or `x240` keeps the scene's aspect \
                     ratio. Settings derived from the pixel size (the default initial radius) \
                     follow it",
                ),
            option("scale", "scale", "F")
                .value_parser(parse_scale)
                .conflicts_with("resolution")
                .help(
                    "Scale the scene's resolution by F (e.g. 0.25 for a quick preview), keeping \
                     its aspect ratio",
                ),
        ]
    }

    pub fn from_matches(m: &mut ArgMatches) -> Self {
        Self {
            resolution: m.remove_one("resolution"),
            scale: m.remove_one("scale"),
        }
    }

    pub fn is_set(&self) -> bool {
        self.resolution.is_some() || self.scale.is_some()
    }

    /// The resolution a scene of `scene_size` renders at with these flags.
    pub fn apply(&self, (w, h): (u32, u32)) -> (u32, u32) {
        let aspect = f64::from(w.max(1)) / f64::from(h.max(1));
        let side = |v: f64| v.round().clamp(1.0, f64::from(u32::MAX)) as u32;
        match (self.resolution, self.scale) {
            (Some(r), _) => match (r.width, r.height) {
                (Some(w), Some(h)) => (w, h),
                (Some(w), None) => (w, side(f64::from(w) / aspect)),
                (None, Some(h)) => (side(f64::from(h) * aspect), h),
                (None, None) => (w, h),
            },
            (None, Some(f)) => (side(f64::from(w) * f), side(f64::from(h) * f)),
            (None, None) => (w, h),
        }
    }

    /// Sets `scene`'s resolution as the flags ask; a size beyond the render's limits is the
    /// flag's fault (a usage error naming it), not the scene's.
    pub fn apply_to(&self, scene: &mut sppm_lang::internals::scene::Scene) -> Result<(), String> {
        scene.settings.resolution = self.resolution_for(scene.settings.resolution)?;
        Ok(())
    }

    /// The resolution a scene of `scene_size` renders at, checked as [`SizeArgs::apply_to`]
    /// checks it.
    pub fn resolution_for(&self, scene_size: (u32, u32)) -> Result<(u32, u32), String> {
        use sppm_lang::internals::scene::{MAX_PIXELS, MAX_RESOLUTION_SIDE};
        let (w, h) = self.apply(scene_size);
        let side = w.max(h);
        if self.is_set() && (side > MAX_RESOLUTION_SIDE || u64::from(w) * u64::from(h) > MAX_PIXELS)
        {
            let flag = if self.scale.is_some() {
                "--scale"
            } else {
                "--resolution"
            };
            return Err(format!(
                "{flag} makes the image {w}x{h}, beyond {MAX_RESOLUTION_SIDE} pixels per side or \
                 {MAX_PIXELS} pixels in all; ask for a smaller size"
            ));
        }
        Ok((w, h))
    }
}

/// Limits of the scene interpreter.
#[derive(Debug, Clone)]
pub struct LimitArgs {
    pub max_iterations: u64,
    pub max_depth: u64,
    pub memory_limit: Option<u64>,
    pub max_steps: u64,
}

impl LimitArgs {
    pub fn args() -> [Arg; 4] {
        [
            option("max_iterations", "max-iterations", "MAX_ITERATIONS")
                .value_parser(clap::value_parser!(u64))
                .default_value("1000000")
                .help("Most iterations a single `#while`/`#for` loop may run"),
            option("max_depth", "max-depth", "MAX_DEPTH")
                .value_parser(clap::value_parser!(u64).range(1..=100_000))
                .default_value("256")
                .help("Deepest macro call nesting (recursion depth)"),
            option("memory_limit", "memory-limit", "BYTES")
                .value_parser(parse_bytes)
                .help(
                    "Most memory a render may need (e.g. `4G`, `512M`; default: 2 GiB or half \
                     the machine's memory, whichever is less). Checked against an estimate \
                     before rendering starts",
                ),
            option("max_steps", "max-steps", "MAX_STEPS")
                .value_parser(clap::value_parser!(u64).range(1..))
                .default_value(default_max_steps())
                .help(
                    "Most evaluation steps in all (statements, loop iterations, macro calls, \
                     operations)",
                ),
        ]
    }

    pub fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            max_iterations: required(m, "max_iterations")?,
            max_depth: required(m, "max_depth")?,
            memory_limit: m.remove_one("memory_limit"),
            max_steps: required(m, "max_steps")?,
        })
    }

    pub fn options(&self) -> EvalOptions {
        EvalOptions {
            max_iterations: self.max_iterations,
            max_depth: self.max_depth as usize,
            max_steps: self.max_steps,
            // Resolved here, so that images are checked against the limit the render will
            // have (the machine's default included) as they are loaded.
            memory_limit: Some(
                self.memory_limit
                    .unwrap_or_else(sppm_lang::internals::prepare::default_memory_limit),
            ),
            ..EvalOptions::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_side_left_out_keeps_the_aspect_ratio() {
        let size = |r: &str| SizeArgs {
            resolution: Some(parse_resolution(r).unwrap()),
            scale: None,
        };
        assert_eq!(size("320x").apply((640, 480)), (320, 240));
        assert_eq!(size("x100").apply((640, 480)), (133, 100));
        assert_eq!(size("50x50").apply((640, 480)), (50, 50));
        let scale = SizeArgs {
            resolution: None,
            scale: Some(0.25),
        };
        assert_eq!(scale.apply((640, 480)), (160, 120));
        // Never below one pixel.
        assert_eq!(scale.apply((2, 1)), (1, 1));
    }
}
