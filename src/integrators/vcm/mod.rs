//! Vertex connection and merging (Georgiev, Křivánek, Davidovič & Slusallek 2012), with
//! bidirectional path tracing (`bpt`: connections only) and light tracing (`lt`: light paths
//! connected to the camera only) as flags of the same code.
//!
//! Each iteration traces one light path per pixel, or with merging a quarter as many where
//! that measured better in the first iterations (`light_count.rs`; `light_path.rs`): their
//! non-specular vertices are stored, and each is connected to a lens point, splatted onto the
//! film. Then one camera path per pixel (`camera_path.rs`) adds, at every non-specular vertex,
//! next-event estimation, connections to every vertex of the light path with the pixel's index
//! (modulo the light paths' count), and merges with the light vertices within the camera
//! path's radius (`grid.rs`); a connection that would add little to its pixel plays Russian
//! roulette before its shadow ray (`roulette.rs`). Every technique is weighted by the power
//! heuristic through the recursive quantities of `mis.rs`. Pixels that see through mirrors or
//! glass also take camera paths that stop at their first non-delta bounce, for the part only
//! camera paths sample: more where that part has varied (`DELTA_CAMERA_PATHS`) than where it
//! has not yet (`DELTA_CAMERA_PATHS_QUIET`).
//!
//! Each camera path has its own radius: `r_0` is the scene's `radius` if set (the same for
//! every path), else SPPM's (1.5 pixel footprints where the path first meets a non-specular
//! surface, the footprint carried through mirrors and glass by `common::footprint`, measured
//! once a pixel), times the pixel's own scale, which shrinks as SPPM's pixel radius does, by
//! the light vertices its first camera path found (`pixel_radius.rs`). The weights stay exact:
//! a light vertex carries its quantities in parts that each camera path evaluates with its own
//! radius (`mis.rs`), and a light-traced splat with the radius of a camera path that would
//! see its vertex directly (with its pixel's scale). A pixel's scale changes only between
//! iterations, so each iteration's weights use a radius fixed before it. The merge grid is
//! built for the 90th percentile of the radii of the previous iteration's pixels (their first
//! camera paths), and answers larger queries too.
//!
//! With `final_gather on`, a camera path whose first bounce is non-specular merges at its
//! second vertex with `GATHER_RADIUS_FACTOR` times its own radius (SPPM's gather points'
//! rule), from a second grid built for that factor times the merge grid's radius: the final
//! gather, a technique of its own in the weights (`mis.rs`).
//!
//! The environment light starts light paths as it emits photons (pbrt-v4's `SampleLe`): a
//! direction by the sky's own sampling density, a point of a disk as wide as the bounding
//! sphere of the finite shapes, outside the scene, facing it. Its position density counts in
//! the weights only where such a path can pass (everywhere within that sphere, not on the far
//! part of an infinite plane), so next-event estimation and escaping camera paths take over
//! there. Light tracing alone sees nothing lit through a delta bounce next to the camera (a
//! mirror's reflection of a wall): no light path can reach the lens through it, and it leaves
//! the far part of an infinite plane under a sky dark.
//!
//! A `vcm` render first runs `WARM_UP` passes whose values it does not keep, so that its extra
//! and delta-only camera paths know where the pixels vary from its first kept iteration on:
//! without them a render's first two iterations are its noisiest (docs/measurements.md). A
//! chain of a still (`render --chain k/n`) of any of the three methods does the same (every
//! chain would pay those iterations again: docs/farm.md). `bpt` and `lt` renders of their own
//! have none. A chain's pixels shrink their radii over its own iterations, as SPPM's do.
//!
//! Determinism: light paths are seeded by their index, camera paths by their pixel, and the
//! splats of each iteration are added in light-path order.

mod camera_path;
mod grid;
mod light_count;
mod light_path;
mod mis;
mod pixel_radius;
mod roulette;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use super::common::camera_samples::{RAYS_PER_CAMERA_SAMPLE, SampleStats, allocate};
use super::common::streams::Stream;
use super::common::{medium_after, progressive};
use super::{Integrator, Job, RenderOutput, RenderStats};
use crate::camera::Camera;
use crate::materials::{Bsdf, BsdfSample, TransportMode};
use crate::prepare::{
    EffectiveSettings, GATHER_RADIUS_FACTOR, InitialRadius, PreparedScene, SurfaceHit,
};
use crate::sampling::{PiecewiseConstant1D, Rng};
use grid::Grid;
use light_count::LightCount;
use light_path::{LightVertex, Splat, Stored, VertexSurface};
use mis::{Factors, Parts};
use pixel_radius::PixelRadii;

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
}

impl Vcm {
    pub fn new(mode: Mode) -> Self {
        Self { mode }
    }
}

/// Extra camera paths per iteration, as a share of the pixels, given to the pixels whose
/// camera paths vary most (Neyman allocation, as SPPM's camera samples: a directly visible
/// light's edge, a small light's soft shadow). Each pixel's estimate is the mean of its camera
/// paths, every one weighted as the only one (unbiased; the light paths are shared).
const EXTRA_CAMERA_PATHS: f64 = 0.5;

/// Camera paths per iteration that stop at their first non-delta bounce, in each pixel whose
/// delta part has varied (a light's edge, a light seen through glass): they add only what a
/// camera path sees through delta bounces alone, which no other technique samples, at the cost
/// of the eye ray and the delta bounces. That part is the mean of every camera path of the
/// pixel, the rest the mean of the full ones (both unbiased).
const DELTA_CAMERA_PATHS: u32 = 4;

/// Delta-only camera paths per iteration in a pixel whose camera paths have left their first
/// vertex by a delta bounce but whose delta part has not varied yet: enough to find a light
/// seen rarely through glass (after which the pixel takes `DELTA_CAMERA_PATHS`), fewer where
/// the delta bounces only ever reach a non-delta surface (on `crystal_tree` 93 % of the
/// delta-only paths were in such pixels and 1 in 1 700 of all of them saw any light, for a
/// third of the render's CPU time: docs/measurements.md).
const DELTA_CAMERA_PATHS_QUIET: u32 = 2;

/// Passes a `vcm` render (and every chain) runs before its first iteration, whose values are
/// not kept: they measure where the pixels vary for the extra and delta-only camera paths,
/// which a render would otherwise lack in its first two iterations (then its iterations vary
/// most: `docs/measurements.md`, `docs/farm.md`).
const WARM_UP: u32 = 2;

/// Mixed into a render's seed for its warm-up passes' streams.
const WARM_UP_SALT: u64 = 0x5be0_cd19_137e_2179;

/// Light paths traced per parallel task: the unit of work whose results are joined in order.
const CHUNK: usize = 1024;

/// What the camera and light passes of one iteration share.
struct Context<'c, 's, 'a> {
    scene: &'s PreparedScene<'a>,
    settings: &'s EffectiveSettings,
    camera: Camera,
    mode: Mode,
    /// Light paths this iteration.
    light_paths: f64,
    radius: Radius,
    /// Each pixel's scale of its radius (`pixel_radius.rs`; empty: 1 for every pixel).
    pixel_scales: &'c [f64],
    /// Each pixel's connection roulette floor this iteration (`roulette.rs`; 0 or missing: no
    /// roulette).
    connect_floors: &'c [f32],
    /// Longest path, in segments: the path tracer's (`max_depth` bounces and a light sample).
    max_len: u32,
    /// Light choice for light paths (every light, by power).
    emitters: &'c PiecewiseConstant1D,
    /// Each light's probability in `emitters`.
    emit_probs: &'c [f64],
    vertices: &'c [LightVertex],
    grid: Option<&'c Grid>,
    /// The final gather is on (the scene's `final_gather`, with merging).
    gather: bool,
    /// The final gather's grid (none without it).
    gather_grid: Option<&'c Grid>,
}

impl Context<'_, '_, '_> {
    /// The density of a light path starting on light `li` at a point of normal `n` (zero for
    /// a delta light) in unit direction `dir`: the light's choice times the densities of the
    /// point (per area) and the direction (per solid angle). For the environment, `p` is a
    /// point the path passes on its way in ([`crate::lights::Light::emission_pdf`]).
    fn emission_pdf_w(&self, li: usize, p: Vec3A, n: Vec3A, dir: Vec3A) -> f64 {
        let choice = self.emit_probs.get(li).copied().unwrap_or(0.0);
        let (pos, d) = self.scene.lights[li].emission_pdf(p, n, dir);
        choice * f64::from(pos) * f64::from(d)
    }

    /// The index of pixel (`x`, `y`) in the per-pixel arrays (row by row).
    fn pixel_index(&self, x: u32, y: u32) -> usize {
        y as usize * self.settings.resolution.0 as usize + x as usize
    }

    /// Pixel `pixel`'s connection roulette floor this iteration (0: none).
    fn connect_floor(&self, pixel: usize) -> f32 {
        self.connect_floors.get(pixel).copied().unwrap_or(0.0)
    }

    /// Pixel `pixel`'s scale of its radius this iteration.
    fn pixel_scale(&self, pixel: usize) -> f64 {
        self.pixel_scales.get(pixel).copied().unwrap_or(1.0)
    }

    /// The weights' constants for a camera path of radius `radius` this iteration.
    /// With the final gather on, those of its merge too, `GATHER_RADIUS_FACTOR` times `radius`.
    fn factors(&self, radius: f64) -> Factors {
        let m = self.mode;
        let f = Factors::new(radius, self.light_paths, m.use_vc, m.use_vm);
        if self.gather {
            f.with_gather(GATHER_RADIUS_FACTOR)
        } else {
            f
        }
    }
}

/// The merge radius rule: the initial radius of a camera path from what it sees (a pixel's
/// shrink is applied by the caller, `pixel_radius.rs`).
#[derive(Debug, Clone, Copy)]
struct Radius {
    rule: InitialRadius,
    /// Where the rule has no value: the one at the distance in focus, else 1e-3.
    fallback: f64,
}

impl Radius {
    /// The radius of a camera path of a pixel whose radius scale is `scale` that sees a point
    /// `distance` from the lens directly (the footprint rule's straight ray): a light-traced
    /// splat's, computed as the camera path's own (`camera_path::set_radius`).
    fn at(&self, distance: f64, scale: f64) -> f64 {
        self.or_fallback(Some(
            self.rule.at(distance).unwrap_or(self.fallback) * scale,
        ))
    }

    /// `r0`, or the fallback where there is none, kept above 1e-7.
    fn or_fallback(&self, r0: Option<f64>) -> f64 {
        r0.unwrap_or(self.fallback).max(1e-7)
    }
}

/// A bounce of a subpath at a surface (light paths in importance mode, camera paths in
/// radiance mode): samples the BSDF, updates the MIS quantities `q` and the absorbing
/// `medium` the path is in. The caller applies the sample's weight and Russian roulette.
/// `merge_ratio`: the merge's factor at this vertex over the plain merge's (`G` at a camera
/// path's final gather vertex, else 1: `Factors::merge_ratio`).
#[allow(clippy::too_many_arguments)]
fn bounce(
    ctx: &Context,
    sh: &SurfaceHit,
    bsdf: &Bsdf,
    wo: Vec3A,
    mode: TransportMode,
    q: &mut Parts,
    medium: &mut Vec3A,
    rng: &mut Rng,
    merge_ratio: f64,
) -> Option<BsdfSample> {
    let (uc, u) = bounce_numbers(rng);
    let s = bsdf.sample(wo, uc, u, mode)?;
    let cos_out = f64::from(s.wi.dot(bsdf.frame.n).abs());
    if s.specular {
        q.scatter_specular(cos_out);
    } else {
        let rev = f64::from(bsdf.pdf(s.wi, wo));
        q.scatter(cos_out, f64::from(s.pdf), rev, merge_ratio);
    }
    *medium = medium_after(ctx.scene, sh, wo, s.wi, *medium);
    Some(s)
}

/// The numbers [`bounce`] draws from `rng` (whether or not its BSDF then samples a direction):
/// a path that ends where it would bounce draws them too, so that the stream goes on as
/// though it had bounced.
fn bounce_numbers(rng: &mut Rng) -> (f32, glam::Vec2) {
    (rng.f32(), rng.vec2())
}

impl Integrator for Vcm {
    fn render(&self, job: Job<'_, '_>) -> RenderOutput {
        let (scene, settings, cancel) = (job.scene, job.settings, job.cancel);
        let (w, h) = settings.resolution;
        let n_paths = (w * h) as usize;
        // Every light starts light paths, chosen by power (the environment's counts the disk
        // its paths leave from).
        let powers: Vec<f64> = scene.lights.iter().map(|l| l.power().max(0.0)).collect();
        let emitters = PiecewiseConstant1D::new(&powers);
        let emit_probs: Vec<f64> = (0..powers.len())
            .map(|i| f64::from(emitters.pdf(i)))
            .collect();
        let rule = settings.initial_radius(&scene.scene.camera);
        let fallback = rule.at(scene.camera.focus_distance()).unwrap_or(1e-3);
        // The grid's radius: the 90th percentile of the last iteration's pixels' `r_0` (of
        // their first camera path). Merges of a larger radius read more cells; wider cells
        // for all would slow every merge (the largest `r_0` is 1.3-3x the median on the
        // examples, the 90th percentile 1.05-1.45x).
        let mut grid_r0 = fallback;
        let mut r0s = Vec::with_capacity(n_paths);
        let mode = self.mode;
        // The final gather where the scene asks for SPPM's (`final_gather on`): merging only.
        let gather = mode.use_vm && settings.final_gather;
        let mut pass = LightPass::default();
        // Each pixel's camera paths so far, and its extra camera paths for the next iteration.
        let mut samples = vec![SampleStats::default(); n_paths];
        let mut extra = vec![0u32; n_paths];
        // Each pixel's delta parts so far, whether a camera path left its first vertex by a
        // delta bounce, and the non-delta parts of its full camera paths (its connections'
        // roulette floor: `roulette.rs`).
        let mut parts = vec![(SampleStats::default(), false, SampleStats::default()); n_paths];
        // Each pixel's footprint ratio through mirrors and glass (0 until measured).
        let mut ratios = vec![0.0; n_paths];
        let extra_budget = (n_paths as f64 * EXTRA_CAMERA_PATHS) as u64;
        // With merging, the light paths' count is measured (`light_count.rs`); else one a pixel.
        let mut light_count = LightCount::default();
        // Each pixel's radius shrinks by the light vertices it found (merging only: without
        // it the radius enters no weight).
        let mut pixel_radii = PixelRadii::new(if mode.use_vm { n_paths } else { 0 });
        // One pass: iteration `iter` of the streams of `seed`; `counted` passes feed the
        // light-path count's pilot and the pixels' radii.
        let radius = Radius { rule, fallback };
        let mut floors: Vec<f32> = Vec::with_capacity(n_paths);
        let mut pass_of = |iter: u32,
                           seed: u64,
                           counted: bool,
                           stats: &mut RenderStats|
         -> Option<(Vec<Vec3A>, u64)> {
            let n_light = if mode.use_vm {
                light_count.light_paths(if counted { iter } else { 0 }, n_paths)
            } else {
                n_paths
            };
            // Decided before the pass from the earlier ones, in pixel order.
            floors.clear();
            if mode.use_vc {
                roulette::floors(parts.iter().map(|p| &p.2), &mut floors);
            }
            let mut ctx = Context {
                scene,
                settings,
                camera: scene.camera,
                mode,
                light_paths: n_light as f64,
                radius,
                pixel_scales: pixel_radii.scales(),
                connect_floors: &floors,
                max_len: settings.max_depth.saturating_add(1),
                emitters: &emitters,
                emit_probs: &emit_probs,
                vertices: &[],
                grid: None,
                gather,
                gather_grid: None,
            };
            let t_light = Instant::now();
            if !pass.run(&ctx, n_light, n_paths, seed, iter, cancel) {
                return None;
            }
            let grid_radius = radius.or_fallback(Some(grid_r0));
            let has_grid = mode.use_vm && pass.grid.build(&pass.positions, grid_radius as f32);
            let gather_radius = (grid_radius * GATHER_RADIUS_FACTOR) as f32;
            let has_gather = gather && pass.gather_grid.build(&pass.positions, gather_radius);
            stats.photon_time += t_light.elapsed();
            ctx.vertices = &pass.vertices;
            ctx.grid = has_grid.then_some(&pass.grid);
            ctx.gather_grid = has_gather.then_some(&pass.gather_grid);
            let (chunks, film) = (&pass.chunks, &pass.film);
            let t_camera = Instant::now();
            let finite = |l: Vec3A| if l.is_finite() { l } else { Vec3A::ZERO };
            // The delta-only camera paths, counted with the others in the statistics.
            let delta_paths = AtomicU64::new(0);
            let (values, (r0, found)): (Vec<Vec3A>, (Vec<f64>, Vec<u32>)) = samples
                .par_iter_mut()
                .zip(parts.par_iter_mut())
                .zip(extra.par_iter())
                .zip(ratios.par_iter_mut())
                .enumerate()
                .map(|(i, (((px, (sp_stats, seen_delta, rs)), &extra), ratio))| {
                    let splat = film[i].as_vec3a();
                    if cancel.load(Ordering::Relaxed) {
                        return (Vec3A::ZERO, (0.0, 0));
                    }
                    let mut rng = Stream::VcmCamera.rng(seed, iter, i as u64);
                    // With fewer light paths than pixels, each serves every n_light-th pixel.
                    let own = light_path_of(chunks, i % n_light);
                    let (x, y) = (i as u32 % w, i as u32 / w);
                    // Delta paths where an earlier iteration's camera paths saw varying
                    // emission through delta bounces or straight on (a light's edge), fewer
                    // where they only saw through a mirror or glass; decided before this
                    // iteration's paths, so that their count does not depend on them.
                    let only = if sp_stats.varies() {
                        DELTA_CAMERA_PATHS
                    } else if *seen_delta {
                        DELTA_CAMERA_PATHS_QUIET
                    } else {
                        0
                    };
                    delta_paths.fetch_add(u64::from(only), Ordering::Relaxed);
                    let first = camera_path::radiance(&ctx, x, y, own, &mut rng, false, ratio);
                    let (mut spec, mut rest) = (finite(first.specular), finite(first.rest));
                    px.add(spec + rest);
                    rs.add(rest);
                    sp_stats.add(spec);
                    *seen_delta |= first.through_delta;
                    let mut rng = Stream::VcmCameraExtra.rng(seed, iter, i as u64);
                    for k in 0..extra + only {
                        let r = camera_path::radiance(&ctx, x, y, own, &mut rng, k >= extra, ratio);
                        let (sp, re) = (finite(r.specular), finite(r.rest));
                        if k < extra {
                            px.add(sp + re);
                            rs.add(re);
                        }
                        sp_stats.add(sp);
                        spec += sp;
                        rest += re;
                    }
                    let mean = spec / (1 + extra + only) as f32 + rest / (1 + extra) as f32;
                    (finite(mean + splat), (first.r0, first.found))
                })
                .unzip();
            r0s.clear();
            r0s.extend(r0.into_iter().filter(|&r| r > 0.0));
            if !r0s.is_empty() {
                let k = (r0s.len() - 1) * 9 / 10;
                grid_r0 = *r0s.select_nth_unstable_by(k, f64::total_cmp).1;
            }
            stats.camera_paths +=
                extra.iter().map(|&e| u64::from(e)).sum::<u64>() + delta_paths.into_inner();
            if extra_budget > 0 {
                let rays = (n_paths as u64 + extra_budget) as f64 * RAYS_PER_CAMERA_SAMPLE;
                allocate(&samples, rays as u64, &mut extra);
            }
            if mode.use_vm && counted {
                light_count.observe(iter, &values);
            }
            if mode.use_vm && counted {
                pixel_radii.observe(&found, n_light, settings.alpha);
            }
            stats.camera_time += t_camera.elapsed();
            (!cancel.load(Ordering::Relaxed)).then_some((values, n_light as u64))
        };
        // A render with merging (`vcm`), and every chain, first runs `WARM_UP` passes that
        // only teach the adaptive camera paths (extra and delta-only) where the pixels vary:
        // their values are not kept, and their streams are those of a seed of their own.
        let warm_up = if mode.use_vm || settings.chain().is_some() {
            WARM_UP
        } else {
            0
        };
        let warm_seed = crate::sampling::mix64(settings.seed ^ WARM_UP_SALT);
        progressive::render_means(job, |iter, stats| {
            if iter == 0 {
                for w in 0..warm_up {
                    pass_of(w, warm_seed, false, stats)?;
                }
            }
            pass_of(iter, settings.seed, true, stats)
        })
    }
}

/// One chunk's share of a light pass: its paths' stored vertices, where each path's end,
/// and its splats. Connections read a path's vertices here; merges read the list every
/// chunk's vertices are copied to (`LightPass::vertices`), without their surfaces.
#[derive(Default)]
struct Chunk {
    stored: Stored,
    ends: Vec<u32>,
    splats: Vec<Splat>,
}

/// The stored vertices of light path `j` and their surfaces (none for a path not traced).
fn light_path_of(chunks: &[Chunk], j: usize) -> (&[LightVertex], &[VertexSurface]) {
    let Some(chunk) = chunks.get(j / CHUNK) else {
        return (&[], &[]);
    };
    let k = j % CHUNK;
    let start = if k == 0 {
        Some(&0)
    } else {
        chunk.ends.get(k - 1)
    };
    let range = match (start, chunk.ends.get(k)) {
        (Some(&s), Some(&e)) if s <= e => s as usize..e as usize,
        _ => return (&[], &[]),
    };
    let s = &chunk.stored;
    match (s.vertices.get(range.clone()), s.surfaces.get(range)) {
        (Some(v), Some(su)) => (v, su),
        _ => (&[], &[]),
    }
}

/// The light pass's buffers, kept across iterations: once grown to their size, an iteration
/// allocates nothing.
#[derive(Default)]
struct LightPass {
    chunks: Vec<Chunk>,
    /// The stored vertices of every light path in path order, for merges, and their
    /// positions, for the grids.
    vertices: Vec<LightVertex>,
    positions: Vec<Vec3A>,
    /// Light tracing's film.
    film: Vec<DVec3>,
    grid: Grid,
    /// The final gather's grid, cells as wide as its radius needs.
    gather_grid: Grid,
}

impl LightPass {
    /// Traces `n_paths` light paths into the buffers, light tracing onto a film of `n_pixels`.
    /// `false` when cancelled.
    fn run(
        &mut self,
        ctx: &Context,
        n_paths: usize,
        n_pixels: usize,
        seed: u64,
        iter: u32,
        cancel: &AtomicBool,
    ) -> bool {
        self.chunks
            .resize_with(n_paths.div_ceil(CHUNK), Chunk::default);
        self.chunks
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, chunk)| {
                chunk.stored.vertices.clear();
                chunk.stored.surfaces.clear();
                chunk.ends.clear();
                chunk.splats.clear();
                if cancel.load(Ordering::Relaxed) {
                    return;
                }
                for i in c * CHUNK..((c + 1) * CHUNK).min(n_paths) {
                    let mut rng = Stream::VcmLight.rng(seed, iter, i as u64);
                    light_path::trace(ctx, &mut rng, &mut chunk.stored, &mut chunk.splats);
                    chunk.ends.push(chunk.stored.vertices.len() as u32);
                }
            });
        if cancel.load(Ordering::Relaxed) {
            return false;
        }
        self.vertices.clear();
        self.positions.clear();
        self.film.clear();
        self.film.resize(n_pixels, DVec3::ZERO);
        // Only merges read the list and the grids the positions (`bpt` keeps neither).
        let merges = ctx.mode.use_vm;
        for chunk in &self.chunks {
            if merges {
                self.vertices.extend_from_slice(&chunk.stored.vertices);
                self.positions
                    .extend(chunk.stored.surfaces.iter().map(|s| s.p));
            }
            for &(pixel, c) in &chunk.splats {
                self.film[pixel as usize] += c.as_dvec3();
            }
        }
        true
    }
}
