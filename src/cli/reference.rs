//! `sppm-lang reference`: a reference image for `chart`, with its own noise estimate.
//!
//! The scene is rendered with the path tracer (unbiased: its only error is noise) in two
//! independent halves with different seeds, each with a deadline: the first at half the time,
//! the second at the end of the time (so the whole takes the time given, whatever else the
//! machine runs). With `a` and `b` iterations, the output is their weighted average
//! `M = (a A + b B) / (a + b)`, `ref.exr`, and beside it
//!
//! - `ref.noise.exr`: the scaled difference `D = (A - B) sqrt(a b) / (a + b)`. Its RMS over any
//!   region estimates the RMSE of `M` against the converged image there: an iteration's noise
//!   has some variance `s^2`, so `E[(A - B)^2] = s^2 (1/a + 1/b)` and the variance of `M` is
//!   `s^2 / (a + b)`, which is `E[D^2]` (for `a = b`, `D = (A - B) / 2`). `chart` reads it to
//!   draw the reference's error floor, also for a window;
//! - `ref.noise.json`: the same estimate over the whole image, with how it was made.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use clap::ArgMatches;
use sppm_lang::Image;
use sppm_lang::Integrator;
use sppm_lang::internals::compare::{ErrorStats, ImageView, error};
use sppm_lang::internals::render::{RenderOptions, render};

use super::check::{load_scene, print_diagnostics};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, LimitArgs, SizeArgs, option};

#[derive(Debug)]
pub struct ReferenceArgs {
    pub scene: PathBuf,
    pub time: f64,
    pub output: PathBuf,
    pub seed: Option<u64>,
    pub threads: Option<usize>,
    pub size: SizeArgs,
    pub limits: LimitArgs,
}

impl ReferenceArgs {
    /// `reference`'s flags on `cmd`.
    pub fn command(cmd: clap::Command) -> clap::Command {
        cmd.arg(super::scene_arg())
            .arg(
                option("time", "time", "S")
                    .value_parser(super::parse_seconds)
                    .required(true)
                    .help("Seconds of rendering in all (both halves)"),
            )
            .arg(super::output_arg("OUTPUT").required(true).help(
                "The reference image (.exr); `.noise.exr` and `.noise.json` files go \
                         beside it",
            ))
            .arg(
                option("seed", "seed", "SEED")
                    .value_parser(clap::value_parser!(u64))
                    .help(
                        "Seed of the first half (the second uses the next one); default: the \
                         scene's",
                    ),
            )
            .arg(super::threads_arg().help("Worker threads"))
            .args(SizeArgs::args())
            .args(LimitArgs::args())
    }

    pub fn from_matches(m: &mut ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            scene: super::required(m, "scene")?,
            time: super::required(m, "time")?,
            output: super::required(m, "output")?,
            seed: m.remove_one("seed"),
            threads: m.remove_one("threads"),
            size: SizeArgs::from_matches(m),
            limits: LimitArgs::from_matches(m)?,
        })
    }
}

/// The files a reference `output` comes with: the noise image and the JSON summary.
pub fn noise_paths(output: &Path) -> (PathBuf, PathBuf) {
    let stem = output
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("reference");
    (
        output.with_file_name(format!("{stem}.noise.exr")),
        output.with_file_name(format!("{stem}.noise.json")),
    )
}

pub fn run(args: &ReferenceArgs) -> ExitCode {
    if !args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
    {
        say!(
            "error: the reference `{}` must be an .exr (linear)",
            args.output.display()
        );
        return ExitCode::from(EXIT_USAGE);
    }
    let (noise_exr, noise_json) = noise_paths(&args.output);
    let outputs = [args.output.as_path(), &noise_exr, &noise_json];
    // Before the load, against the scene; after it, against every file it read.
    if let Err(e) = super::check_not_an_input(&outputs, std::slice::from_ref(&args.scene)) {
        say!("error: {e}");
        return ExitCode::from(EXIT_USAGE);
    }
    let (mut scene, sources) = match load_scene(&args.scene, &args.limits.options()) {
        Ok(loaded) => {
            if let Err(e) = super::check_not_an_input(&outputs, &loaded.dependencies) {
                say!("error: {e}");
                return ExitCode::from(EXIT_USAGE);
            }
            (loaded.scene, loaded.sources)
        }
        Err(code) => return code,
    };
    scene.settings.integrator = Some(Integrator::Path);
    if let Err(e) = args.size.apply_to(&mut scene) {
        say!("error: {e}");
        return ExitCode::from(EXIT_USAGE);
    }
    let seed = args.seed.unwrap_or(scene.settings.seed);
    let start = Instant::now();
    let half = |seed: u64, iterations: Option<u32>, time_limit: Option<f64>| {
        let options = RenderOptions {
            iterations: Some(iterations.unwrap_or(u32::MAX)),
            seed: Some(seed),
            time_limit,
            threads: args.threads,
            memory_limit: args.limits.memory_limit,
            ..RenderOptions::default()
        };
        render(&scene, &options, &AtomicBool::new(false), &mut |_| {})
    };
    let a = match half(seed, None, Some(args.time / 2.0)) {
        Ok(out) if out.iterations_done > 0 => out,
        Ok(_) => {
            say!(
                "error: no iteration of the path tracer finished in {} s; give more --time",
                args.time / 2.0
            );
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
        Err(e) => {
            print_diagnostics(&sources, &[e]);
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
    };
    let left = (args.time - start.elapsed().as_secs_f64()).max(0.001);
    let b = match half(seed.wrapping_add(1), None, Some(left)) {
        Ok(out) if out.iterations_done > 0 => out,
        Ok(_) => {
            say!(
                "error: no iteration of the second half finished in {left:.3} s; give more --time"
            );
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
        Err(e) => {
            print_diagnostics(&sources, &[e]);
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
    };
    let (na, nb) = (a.iterations_done, b.iterations_done);
    let (mean, noise) = average_and_noise(&a.image, na, &b.image, nb);
    let estimate = match floor_of(&mean, &noise) {
        Ok(e) => e,
        Err(e) => {
            say!("error: {e}");
            return ExitCode::from(EXIT_SCENE_ERROR);
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    let json = format!(
        "{{\n  \"scene\": {:?},\n  \"integrator\": \"path\",\n  \"seeds\": [{seed}, {}],\n  \
         \"iterations\": [{na}, {nb}],\n  \"seconds\": {seconds:.3},\n  \"rmse\": {:e},\n  \
         \"rel_mse\": {:e}\n}}\n",
        args.scene.display().to_string(),
        seed.wrapping_add(1),
        estimate.rmse,
        estimate.rel_mse
    );
    // The three files together or none of them (a full disk leaves the old ones whole).
    let written = sppm_lang::internals::atomic_file::write_atomic_group(vec![
        (
            args.output.as_path(),
            Box::new(|_, f| mean.encode(&args.output, 1.0, f).map_err(|d| d.message)),
        ),
        (
            noise_exr.as_path(),
            Box::new(|_, f| noise.encode(&noise_exr, 1.0, f).map_err(|d| d.message)),
        ),
        (
            noise_json.as_path(),
            Box::new(|_, f| {
                f.write_all(json.as_bytes())
                    .map_err(|e| format!("cannot write `{}`: {e}", noise_json.display()))
            }),
        ),
    ]);
    if let Err(e) = written {
        say!("error: {e}");
        return ExitCode::from(EXIT_SCENE_ERROR);
    }
    say!(
        "wrote {} ({} path-traced iterations in two halves of {na} and {nb}, {seconds:.1} s); its noise: \
         RMSE {:.3e}, relative MSE {:.3e} (in {} and {})",
        args.output.display(),
        na + nb,
        estimate.rmse,
        estimate.rel_mse,
        noise_exr.display(),
        noise_json.display()
    );
    ExitCode::SUCCESS
}

/// The weighted average of two independent renders of `na` and `nb` iterations, and their
/// scaled difference (see the module's documentation).
pub fn average_and_noise(a: &Image, na: u32, b: &Image, nb: u32) -> (Image, Image) {
    let (na, nb) = (f64::from(na.max(1)), f64::from(nb.max(1)));
    let (wa, wb) = (na / (na + nb), nb / (na + nb));
    let scale = (na * nb).sqrt() / (na + nb);
    let mut mean = Image::new(a.width, a.height);
    let mut noise = Image::new(a.width, a.height);
    for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        mean.pixels[i] = [0, 1, 2].map(|c| wa * p[c] + wb * q[c]);
        noise.pixels[i] = [0, 1, 2].map(|c| scale * (p[c] - q[c]));
    }
    (mean, noise)
}

/// The reference's error floor over `window` (the whole image when `None`): the errors
/// `error` gives for `reference + noise` against `reference` (RMSE: the RMS of the noise;
/// relative MSE with the same weights as a method's).
pub fn floor_in(
    reference: ImageView<'_>,
    noise: ImageView<'_>,
    window: Option<sppm_lang::internals::compare::Window>,
) -> Result<ErrorStats, String> {
    if (reference.width, reference.height) != (noise.width, noise.height) {
        return Err(format!(
            "the noise image is {}x{} but the reference is {}x{}",
            noise.width, noise.height, reference.width, reference.height
        ));
    }
    let noisy: Vec<[f32; 3]> = reference
        .pixels
        .iter()
        .zip(noise.pixels)
        .map(|(p, d)| [0, 1, 2].map(|c| p[c] + d[c]))
        .collect();
    let view = ImageView::new(reference.width, reference.height, &noisy)?;
    error(view, reference, window)
}

/// [`floor_in`] over the whole image, for images in f64.
fn floor_of(reference: &Image, noise: &Image) -> Result<ErrorStats, String> {
    let (r, n) = (to_f32(reference), to_f32(noise));
    let (w, h) = (reference.width, reference.height);
    floor_in(ImageView::new(w, h, &r)?, ImageView::new(w, h, &n)?, None)
}

pub fn to_f32(img: &Image) -> Vec<[f32; 3]> {
    img.pixels.iter().map(|p| p.map(|v| v as f32)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two renders of a constant 1 of 4 and 12 iterations, each iteration with independent
    /// noise of standard deviation s: the weighted average has an RMSE of s / sqrt(16), which
    /// the scaled difference recovers (equal weights would misjudge both).
    #[test]
    fn the_scaled_difference_estimates_the_noise_of_the_average() {
        let (w, h) = (200, 200);
        let s = 0.1;
        let mut state = 12345u64;
        let mut noise = || {
            // Sum of uniforms: zero mean, standard deviation 1 (12 uniforms minus 6).
            (0..12)
                .map(|_| {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    (state >> 11) as f64 / (1u64 << 53) as f64
                })
                .sum::<f64>()
                - 6.0
        };
        let mut a = Image::new(w, h);
        let mut b = Image::new(w, h);
        let (na, nb) = (4u32, 12u32);
        for i in 0..a.pixels.len() {
            a.pixels[i] = [0, 1, 2].map(|_| 1.0 + s / f64::from(na).sqrt() * noise());
            b.pixels[i] = [0, 1, 2].map(|_| 1.0 + s / f64::from(nb).sqrt() * noise());
        }
        let (mean, half) = average_and_noise(&a, na, &b, nb);
        let estimate = floor_of(&mean, &half).unwrap().rmse;
        let truth = mean
            .pixels
            .iter()
            .flat_map(|p| p.iter().map(|v| (v - 1.0) * (v - 1.0)))
            .sum::<f64>()
            / (3 * w * h) as f64;
        let truth = truth.sqrt();
        let expected = s / f64::from(na + nb).sqrt();
        assert!(
            (estimate / expected - 1.0).abs() < 0.02,
            "{estimate} vs {expected}"
        );
        assert!(
            (estimate / truth - 1.0).abs() < 0.02,
            "{estimate} vs {truth}"
        );
    }
}
