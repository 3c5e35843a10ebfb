//! Direct-light noise of area-light sampling: a diffuse plane lit at close range by a small
//! sphere and by a square, each light sampled by area and by solid angle ([`LightSampling`]).
//! The "pixels" are a `size` x `size` grid of points on the plane square `[-1, 1]^2` under the
//! light; at each, the renderer's own direct-lighting estimator (`direct_lighting`: one light
//! sample and one BSDF sample with MIS, shadow rays included) runs for the view straight down.
//! Both samplers run in one process on one thread, alternating every round (which goes first
//! alternates too); each round gives every point `per_round` estimates. Reported per scene and
//! sampler: the per-point variance of one estimate (averaged over the points), the mean, wall
//! and CPU time per estimate, and the variance at equal time (variance x CPU time) as a ratio
//! of area to solid angle.

use std::time::Instant;

use glam::Vec3A;
use sppm_lang::EvalOptions;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::integrators::direct_lighting;
use sppm_lang::internals::lights::{Light, LightSampling};
use sppm_lang::internals::render::{PreparedScene, RenderOptions, prepare};
use sppm_lang::internals::sampling::Rng;
use sppm_lang::internals::scene::Scene;

/// The two test scenes: `(name, scene text)`.
pub const SCENES: [(&str, &str); 2] = [
    (
        "sphere",
        "plane { <0, 1, 0>, 0 material { diffuse rgb <0.8, 0.8, 0.8> } }
         area_light { sphere { <0.3, 0.35, 0.2>, 0.15 } radiance rgb <20, 20, 20> }",
    ),
    (
        "quad",
        "plane { <0, 1, 0>, 0 material { diffuse rgb <0.8, 0.8, 0.8> } }
         area_light { quad { <0.1, 0.35, 0>, <0.4, 0, 0>, <0, 0, 0.4> } radiance rgb <20, 20, 20> }",
    ),
];

/// One scene and sampler's figures.
#[derive(Debug, Clone)]
pub struct Row {
    pub scene: &'static str,
    pub sampling: LightSampling,
    /// Mean over the points of the per-point variance of one estimate (channel mean).
    pub variance: f64,
    /// Mean over the points (to show both samplers agree).
    pub mean: f64,
    /// Seconds per estimate.
    pub wall_per_estimate: f64,
    pub cpu_per_estimate: f64,
}

impl Row {
    /// Variance at equal CPU time: variance of one estimate times its CPU time.
    pub fn variance_times_time(&self) -> f64 {
        self.variance * self.cpu_per_estimate
    }
}

/// The scene text, loaded.
pub fn scene(text: &str) -> Result<Scene, String> {
    let loaded =
        sppm_lang::internals::eval::load_source("lights.scn", text, &EvalOptions::default());
    loaded
        .scene
        .ok_or_else(|| format!("test scene does not load: {:?}", loaded.diagnostics))
}

/// Process CPU time (user + system) in seconds, from `/proc/self/stat` (clock ticks of 10 ms);
/// `None` where it cannot be read.
pub fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')')?.1;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn set_sampling(prepared: &mut PreparedScene, sampling: LightSampling) {
    for l in &mut prepared.lights {
        if let Light::Area(a) = l {
            a.sampling = sampling;
        }
    }
}

/// Runs both samplers on both scenes: `size` x `size` points, `rounds` rounds of `per_round`
/// estimates per point and sampler.
pub fn run(size: u32, rounds: u32, per_round: u32, log: &dyn Fn(&str)) -> Result<Vec<Row>, String> {
    let samplers = [LightSampling::Area, LightSampling::SolidAngle];
    let mut rows = Vec::new();
    for (name, text) in SCENES {
        let scene = scene(text)?;
        let (_, mut prepared) =
            prepare(&scene, &RenderOptions::default()).map_err(|e| e.to_string())?;
        let mut hits = Vec::new();
        for j in 0..size {
            for i in 0..size {
                let at = |k: u32| -1.0 + 2.0 * (k as f32 + 0.5) / size as f32;
                // From below: the plane point, not the light above it.
                let ray = Ray::new(Vec3A::new(at(i), -1e-3, at(j)), Vec3A::Y);
                let sh = prepared
                    .intersect(&ray, f32::INFINITY)
                    .ok_or("a grid point misses the plane")?;
                hits.push(sh);
            }
        }
        let n = hits.len();
        let mut sum = vec![vec![0.0f64; n]; 2];
        let mut sum2 = vec![vec![0.0f64; n]; 2];
        let mut time = [(0.0f64, 0.0f64); 2];
        for round in 0..rounds {
            for k in 0..2 {
                let s = if round % 2 == 0 { k } else { 1 - k };
                set_sampling(&mut prepared, samplers[s]);
                let mut rng = Rng::new(u64::from(round) * 2 + s as u64);
                let (cpu0, t0) = (cpu_seconds().unwrap_or(0.0), Instant::now());
                for (i, sh) in hits.iter().enumerate() {
                    let bsdf = prepared.bsdf(sh);
                    for _ in 0..per_round {
                        let l =
                            direct_lighting(&prepared, sh, &bsdf, Vec3A::Y, Vec3A::ZERO, &mut rng);
                        let v = f64::from(l.x + l.y + l.z) / 3.0;
                        sum[s][i] += v;
                        sum2[s][i] += v * v;
                    }
                }
                time[s].0 += t0.elapsed().as_secs_f64();
                time[s].1 += cpu_seconds().unwrap_or(0.0) - cpu0;
            }
        }
        let count = f64::from(rounds) * f64::from(per_round);
        for s in 0..2 {
            let (mut var, mut mean) = (0.0, 0.0);
            for i in 0..n {
                let m = sum[s][i] / count;
                var += (sum2[s][i] / count - m * m).max(0.0) * count / (count - 1.0);
                mean += m;
            }
            let estimates = count * n as f64;
            let row = Row {
                scene: name,
                sampling: samplers[s],
                variance: var / n as f64,
                mean: mean / n as f64,
                wall_per_estimate: time[s].0 / estimates,
                cpu_per_estimate: time[s].1 / estimates,
            };
            log(&format!("{row:?}"));
            rows.push(row);
        }
    }
    Ok(rows)
}
