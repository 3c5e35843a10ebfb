//! Vertex connection and merging (Georgiev, Křivánek, Davidovič & Slusallek 2012), with
//! bidirectional path tracing (`bpt`: connections only) and light tracing (`lt`: light paths
//! connected to the camera only) as flags of the same code.
//!
//! Each iteration traces one light path per pixel (`light_path.rs`): their non-specular
//! vertices are stored, and each is connected to a lens point, splatted onto the film. Then one
//! camera path per pixel (`camera_path.rs`) adds, at every non-specular vertex, next-event
//! estimation, connections to every vertex of the light path with the same index, and merges
//! with the light vertices within the iteration's radius (`grid.rs`). Every technique is
//! weighted by the power heuristic through the recursive quantities of `mis.rs`.
//!
//! The radius shrinks as SPPM's does on average: `r_i = r_0 i^((alpha - 1) / 2)` (global, so
//! that every light path's weights hold for every pixel); `r_0` is the scene's `radius`, else
//! SPPM's pixel footprint rule at the distance in focus.
//!
//! The environment light starts no light path (its photons leave a disk around the scene,
//! whose densities the other techniques cannot share): camera paths reach it by next-event
//! estimation and by escaping, weighed against each other. Light tracing alone therefore sees
//! the sky only straight on and in mirrors, and nothing lit through a delta bounce next to
//! the camera (a mirror's reflection of a wall): no light path can reach the lens through it.
//!
//! Determinism: light paths are seeded by their index, camera paths by their pixel, and the
//! splats of each iteration are added in light-path order.

mod camera_path;
mod grid;
mod light_path;
mod mis;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use super::common::progressive;
use super::common::streams::Stream;
use super::{Integrator, Job, RenderOutput};
use crate::camera::Camera;
use crate::lights::Light;
use crate::prepare::PreparedScene;
use crate::sampling::PiecewiseConstant1D;
use grid::Grid;
use light_path::LightVertex;
use mis::Factors;

/// Which techniques run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mode {
    /// Connections: next-event estimation, camera to light vertex, light vertex to camera.
    pub use_vc: bool,
    /// Merging at camera vertices.
    pub use_vm: bool,
    /// Light tracing alone (camera paths only follow delta bounces to what they see).
    pub light_trace_only: bool,
}

impl Mode {
    pub const VCM: Mode = Mode {
        use_vc: true,
        use_vm: true,
        light_trace_only: false,
    };
    pub const BPT: Mode = Mode {
        use_vc: true,
        use_vm: false,
        light_trace_only: false,
    };
    pub const LT: Mode = Mode {
        use_vc: false,
        use_vm: false,
        light_trace_only: true,
    };
}

/// Vertex connection and merging, or one of its special cases.
#[derive(Debug, Clone, Copy)]
pub struct Vcm {
    pub mode: Mode,
    /// Multiplies the initial radius (tests shrink it toward zero).
    pub radius_scale: f64,
}

impl Vcm {
    pub fn new(mode: Mode) -> Self {
        Self {
            mode,
            radius_scale: 1.0,
        }
    }
}

/// Light paths traced per parallel task: the unit of work whose results are joined in order.
const CHUNK: usize = 1024;

/// What the camera and light passes of one iteration share.
struct Context<'c, 's, 'a> {
    scene: &'s PreparedScene<'a>,
    camera: Camera,
    mode: Mode,
    factors: Factors,
    /// Longest path, in segments: the path tracer's (`max_depth` bounces and a light sample).
    max_len: u32,
    /// Light choice for light paths (every light but the environment, by power) and the
    /// light each entry is.
    emitters: &'c PiecewiseConstant1D,
    emitter_lights: &'c [usize],
    /// Each light's probability in `emitters` (0 for the environment).
    emit_probs: &'c [f64],
    radius: f32,
    vm_normalization: f32,
    vertices: &'c [LightVertex],
    positions: &'c [Vec3A],
    grid: Option<&'c Grid>,
}

impl Context<'_, '_, '_> {
    /// The probability that a light path starts on light `li`.
    fn emit_pdf(&self, li: usize) -> f64 {
        self.emit_probs.get(li).copied().unwrap_or(0.0)
    }
}

impl Integrator for Vcm {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput {
        let (scene, settings, cancel) = (job.scene, job.settings, job.cancel);
        let (w, h) = (settings.width, settings.height);
        let n_paths = (w * h) as usize;
        let emitter_lights: Vec<usize> = (0..scene.lights.len())
            .filter(|&i| !matches!(scene.lights[i], Light::Environment(_)))
            .collect();
        let powers: Vec<f64> = emitter_lights
            .iter()
            .map(|&i| scene.lights[i].power().max(0.0))
            .collect();
        let emitters = PiecewiseConstant1D::new(&powers);
        let mut emit_probs = vec![0.0; scene.lights.len()];
        for (k, &li) in emitter_lights.iter().enumerate() {
            emit_probs[li] = f64::from(emitters.pdf(k));
        }
        let r0 = settings
            .initial_radius(&scene.scene.camera)
            .at(scene.camera.focus_distance())
            .unwrap_or(1e-3)
            * self.radius_scale;
        let mode = self.mode;
        progressive::render_means(job, |iter, stats| {
            let radius = r0 * f64::from(iter + 1).powf(0.5 * (settings.alpha - 1.0));
            let radius = radius.max(1e-7);
            let mut ctx = Context {
                scene,
                camera: scene.camera,
                mode,
                factors: Factors::new(radius, n_paths as f64, mode.use_vc, mode.use_vm),
                max_len: settings.max_depth.saturating_add(1),
                emitters: &emitters,
                emitter_lights: &emitter_lights,
                emit_probs: &emit_probs,
                radius: radius as f32,
                vm_normalization: (1.0 / (std::f64::consts::PI * radius * radius * n_paths as f64))
                    as f32,
                vertices: &[],
                positions: &[],
                grid: None,
            };
            let t_light = Instant::now();
            let (vertices, ends, film) = light_pass(&ctx, n_paths, settings.seed, iter, cancel)?;
            let positions: Vec<Vec3A> = vertices.iter().map(|v| v.p).collect();
            let grid = if mode.use_vm {
                Grid::new(&positions, ctx.radius)
            } else {
                None
            };
            stats.photon_time += t_light.elapsed();
            ctx.vertices = &vertices;
            ctx.positions = &positions;
            ctx.grid = grid.as_ref();
            let t_camera = Instant::now();
            let seed = settings.seed;
            let values: Vec<Vec3A> = (0..n_paths)
                .into_par_iter()
                .map(|i| {
                    let splat = film[i].as_vec3a();
                    if cancel.load(Ordering::Relaxed) {
                        return Vec3A::ZERO;
                    }
                    let mut rng = Stream::VcmCamera.rng(seed, iter, i as u64);
                    let start = if i == 0 { 0 } else { ends[i - 1] as usize };
                    let own = &vertices[start..ends[i] as usize];
                    let (x, y) = (i as u32 % w, i as u32 / w);
                    let l = camera_path::radiance(&ctx, x, y, own, &mut rng) + splat;
                    if l.is_finite() { l } else { Vec3A::ZERO }
                })
                .collect();
            stats.camera_time += t_camera.elapsed();
            (!cancel.load(Ordering::Relaxed)).then_some((values, n_paths as u64))
        })
    }
}

/// One light path per pixel: the stored vertices in path order, where each path's vertices
/// end, and light tracing's film. `None` when cancelled.
fn light_pass(
    ctx: &Context,
    n_paths: usize,
    seed: u64,
    iter: u32,
    cancel: &AtomicBool,
) -> Option<(Vec<LightVertex>, Vec<u32>, Vec<DVec3>)> {
    let chunks: Vec<_> = (0..n_paths.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut vertices = Vec::new();
            let mut ends = Vec::new();
            let mut splats = Vec::new();
            if cancel.load(Ordering::Relaxed) {
                return (vertices, ends, splats);
            }
            for i in c * CHUNK..((c + 1) * CHUNK).min(n_paths) {
                let mut rng = Stream::VcmLight.rng(seed, iter, i as u64);
                light_path::trace(ctx, &mut rng, &mut vertices, &mut splats);
                ends.push(vertices.len() as u32);
            }
            (vertices, ends, splats)
        })
        .collect();
    if cancel.load(Ordering::Relaxed) {
        return None;
    }
    let mut vertices = Vec::new();
    let mut ends = Vec::with_capacity(n_paths);
    let mut film = vec![DVec3::ZERO; n_paths];
    for (v, e, s) in chunks {
        let base = vertices.len() as u32;
        ends.extend(e.iter().map(|x| x + base));
        vertices.extend(v);
        for (pixel, c) in s {
            film[pixel as usize] += c.as_dvec3();
        }
    }
    Some((vertices, ends, film))
}
