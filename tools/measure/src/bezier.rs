//! Speed against accuracy of the Bezier surfaces: the robust and the Newton intersectors, and
//! tessellated meshes of the same surface at several triangle counts, on one fixed, seeded ray
//! set per surface (`cargo run --release -p sppm-measure -- bezier`).
//!
//! Every method runs through the renderer's own path: a [`Bvh`] over the renderer's shapes
//! ([`Revolve`] / [`BezierPatch`] for the analytic methods, one shape; the mesh's triangles
//! from [`mesh_triangles`] for a mesh), with f32 rays, answering [`Bvh::intersect`] (closest hit
//! with its full surface data), one thread. The rays are generated in f64 and rounded to f32
//! first, so every method and the reference see exactly the same ray.
//!
//! - Speed: nanoseconds per ray, the median over `repeats` passes over the ray set; the methods
//!   take turns on every chunk of rays (in a rotating order), so a change in the machine's load
//!   hits them alike. Each is also given as a ratio to the robust method's time in the same run.
//! - Accuracy, against [`reference`](mod@crate::reference) (the slow intersectors that share no
//!   root finder with the production code), on the rays the reference can decide: misses (the
//!   reference hits, the method does not) as a share of the reference's hits, false hits (the
//!   method hits, the reference does not) as a share of the reference's misses, and the
//!   relative error of `t` on rays both hit (median, 99th percentile, maximum; above [`FAR`] it
//!   is counted as a far hit: for an analytic method a hit on another part of the surface, e.g.
//!   a Newton root behind the nearest one). The renderer's `t` is f32, so about 6e-8 is the
//!   floor of every method here.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{DAffine3, DVec2, DVec3};
use rayon::prelude::*;

use sppm_lang::internals::accel::Bvh;
use sppm_lang::internals::bezier::lathe::Lathe;
use sppm_lang::internals::bezier::patch::Patch;
use sppm_lang::internals::chart::{ChartSpec, Series, draw, draw_panels};
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::sampling::SplitMix64;
use sppm_lang::internals::scene::{IntersectMethod, Profile};
use sppm_lang::internals::shapes::mesh::mesh_triangles;
use sppm_lang::internals::shapes::patch::BezierPatch;
use sppm_lang::internals::shapes::primitive::AnyShape;
use sppm_lang::internals::shapes::revolve::Revolve;

use crate::reference::{self, RefHit};
use crate::tessellate::{lathe_mesh, patch_mesh};

/// A relative `t` error above this is counted as a hit on another part of the surface.
pub const FAR: f64 = 1e-3;

/// Smallest ray parameter of a hit, for every method and the reference.
pub const T_MIN: f64 = 1e-4;

/// The two surfaces measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Surface {
    /// The vase of `benches/bezier.rs`: three cubic segments, a flat bottom from a pole.
    Revolve,
    /// The bumpy height field of `benches/bezier.rs`.
    Patch,
}

impl Surface {
    pub fn name(self) -> &'static str {
        match self {
            Surface::Revolve => "revolve",
            Surface::Patch => "patch",
        }
    }
}

/// A way to intersect the surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    Robust,
    Newton {
        starts: u32,
        iterations: u32,
    },
    /// A tessellation into a `rows x cols` grid (see [`crate::tessellate`]).
    Mesh {
        rows: usize,
        cols: usize,
    },
}

impl Method {
    pub fn label(&self) -> String {
        match *self {
            Method::Robust => "robust".into(),
            Method::Newton { starts, iterations } => format!("newton-s{starts}-i{iterations}"),
            Method::Mesh { rows, cols } => format!("mesh-{rows}x{cols}"),
        }
    }
}

/// What to measure.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Rays per ray kind.
    pub rays: usize,
    /// Timed passes over the ray set (the median is reported).
    pub repeats: usize,
    pub seed: u64,
    /// Newton settings `(starts, iterations)` for the revolve and the patch.
    pub lathe_newton: Vec<(u32, u32)>,
    pub patch_newton: Vec<(u32, u32)>,
    /// Mesh grids `(rows, cols)`: revolve in (profile, angle), patch in (u, v).
    pub lathe_grids: Vec<(usize, usize)>,
    pub patch_grids: Vec<(usize, usize)>,
}

impl Options {
    /// The full measurement: Newton at 3 x 4 settings, meshes of 32 to 524 288 triangles.
    pub fn full(rays: usize) -> Self {
        let iterations = [4, 8, 16, 32];
        let settings = |starts: [u32; 3]| {
            starts
                .iter()
                .flat_map(|&s| iterations.iter().map(move |&i| (s, i)))
                .collect()
        };
        Self {
            rays,
            repeats: 3,
            seed: 1,
            lathe_newton: settings([2, 4, 8]),
            patch_newton: settings([4, 9, 16]),
            lathe_grids: (0..8).map(|k| (2 << k, 8 << k)).collect(),
            patch_grids: (0..8).map(|k| (4 << k, 4 << k)).collect(),
        }
    }
}

/// One line of the result: a method on one ray kind (or `all` of them) of one surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub surface: Surface,
    pub method: Method,
    /// A ray kind's name, or `all`.
    pub kind: String,
    /// Triangles in the BVH (meshes; degenerate ones dropped), 0 for the analytic methods.
    pub triangles: usize,
    /// Time to tessellate and build the BVH, milliseconds.
    pub build_ms: f64,
    pub ns_per_ray: f64,
    /// `ns_per_ray` over the robust method's on the same rays in the same run.
    pub time_vs_robust: f64,
    pub rays: usize,
    /// Rays the reference cannot decide (near tangencies): left out of the accuracy counts.
    pub ambiguous: usize,
    pub ref_hits: usize,
    pub misses: usize,
    pub false_hits: usize,
    /// Rays both hit.
    pub both: usize,
    /// Rays both hit with a relative `t` error above [`FAR`]: another part of the surface (for
    /// an analytic method; a coarse mesh's facets alone can be that far off).
    pub far_hits: usize,
    /// Relative `t` error on rays both hit; NaN when there are none.
    pub t_err_median: f64,
    pub t_err_p99: f64,
    pub t_err_max: f64,
}

impl Row {
    pub fn miss_rate(&self) -> f64 {
        self.misses as f64 / self.ref_hits.max(1) as f64
    }

    /// Far hits as a share of the rays both hit.
    pub fn far_rate(&self) -> f64 {
        self.far_hits as f64 / self.both.max(1) as f64
    }

    pub fn false_hit_rate(&self) -> f64 {
        let ref_misses = self.rays - self.ambiguous - self.ref_hits;
        self.false_hits as f64 / ref_misses.max(1) as f64
    }
}

/// The test and benchmark vase (`benches/bezier.rs`, `tests/bezier_stress.rs`, `tests/bezier_props.rs`).
pub fn vase_profile() -> Profile {
    let seg = |p: &[(f64, f64)]| p.iter().map(|&(r, h)| DVec2::new(r, h)).collect::<Vec<_>>();
    Profile {
        segments: vec![
            seg(&[(0.0, 0.0), (0.5, 0.0), (0.6, 0.05), (0.6, 0.2)]),
            seg(&[(0.6, 0.2), (0.6, 0.6), (1.0, 0.8), (0.7, 1.2)]),
            seg(&[(0.7, 1.2), (0.4, 1.6), (0.3, 1.8), (0.45, 2.0)]),
        ],
    }
}

/// The test and benchmark bumpy height field over [0, 3]^2 (the same files).
pub fn wavy_points() -> [DVec3; 16] {
    let z = [
        [0.0, 0.8, -0.6, 0.2],
        [0.5, -1.2, 1.4, -0.3],
        [-0.4, 1.5, -1.1, 0.6],
        [0.3, -0.2, 0.7, 0.0],
    ];
    std::array::from_fn(|k| DVec3::new((k / 4) as f64, (k % 4) as f64, z[k / 4][k % 4]))
}

/// The seeded ray streams (shared with `tests/bezier_stress.rs`).
type Rng = SplitMix64;

/// A ray from a sphere of 3 sizes around the box through a uniform point inside it, with a
/// direction length between 0.2 and 2 times the distance.
pub fn random_ray(rng: &mut Rng, lo: DVec3, hi: DVec3) -> (DVec3, DVec3) {
    let c = 0.5 * (lo + hi);
    let o = c + rng.unit() * 3.0 * (hi - lo).max_element();
    let target = DVec3::new(
        rng.range(lo.x, hi.x),
        rng.range(lo.y, hi.y),
        rng.range(lo.z, hi.z),
    );
    (o, (target - o) * rng.range(0.2, 2.0))
}

/// A ray along the tangent plane at `p` (unit normal `n`, tangent `t`), passing at a distance
/// between 1e-5 and 1e-2 sizes above or below the surface, from 2 sizes away.
fn grazing_ray(rng: &mut Rng, p: DVec3, n: DVec3, t: DVec3, size: f64) -> (DVec3, DVec3) {
    let t = (t - n * t.dot(n)).normalize_or(n.any_orthonormal_vector());
    let delta = 10f64.powf(rng.range(-5.0, -2.0)) * size * rng.sign();
    (p + n * delta - t * 2.0 * size, t)
}

/// The rays of one kind, rounded to f32, with the reference's answers.
pub struct RayKind {
    pub name: &'static str,
    pub rays: Vec<Ray>,
    pub reference: Vec<RefHit>,
}

fn make_kind(
    name: &'static str,
    index: usize,
    opts: &Options,
    make: impl Fn(&mut Rng) -> (DVec3, DVec3) + Sync,
    answer: impl Fn(DVec3, DVec3) -> RefHit + Sync + Send,
) -> RayKind {
    let rays: Vec<Ray> = (0..opts.rays)
        .map(|i| {
            let (o, d) = make(&mut Rng::for_item(opts.seed, index, i));
            Ray::new(o.as_vec3a(), d.as_vec3a())
        })
        .collect();
    let reference = rays
        .par_iter()
        .map(|r| answer(r.o.as_dvec3(), r.d.as_dvec3()))
        .collect();
    RayKind {
        name,
        rays,
        reference,
    }
}

/// Random, grazing and near-pole rays (the vase's flat bottom meets the axis at the origin).
fn lathe_kinds(lathe: &Lathe, opts: &Options) -> Vec<RayKind> {
    let (lo, hi) = lathe.bounds();
    let size = lathe.size();
    let answer = |o, d| reference::lathe(lathe, o, d, T_MIN, f64::INFINITY);
    vec![
        make_kind("random", 0, opts, |r| random_ray(r, lo, hi), answer),
        make_kind(
            "grazing",
            1,
            opts,
            |r| {
                let u = DVec2::new(r.f(), r.f());
                let (p, n) = lathe.sample(u).unwrap_or((DVec3::ZERO, DVec3::Y));
                let t = r.unit();
                grazing_ray(r, p, n, t, size)
            },
            answer,
        ),
        make_kind(
            "pole",
            2,
            opts,
            |r| {
                let target = r.unit() * 10f64.powf(r.range(-6.0, -3.0)) * size;
                let o = target + r.unit() * 3.0 * size;
                (o, target - o)
            },
            answer,
        ),
    ]
}

/// Random and grazing rays.
fn patch_kinds(patch: &Patch, opts: &Options) -> Vec<RayKind> {
    let (lo, hi) = patch.bounds();
    let size = patch.size();
    let answer = |o, d| reference::patch(patch, o, d, T_MIN, f64::INFINITY);
    vec![
        make_kind("random", 0, opts, |r| random_ray(r, lo, hi), answer),
        make_kind(
            "grazing",
            1,
            opts,
            |r| {
                let (u, v) = (r.range(0.02, 0.98), r.range(0.02, 0.98));
                let (p, pu, pv) = patch.eval(u, v);
                let a = r.range(0.0, std::f64::consts::TAU);
                let t = pu.normalize() * a.cos() + pv.normalize() * a.sin();
                grazing_ray(r, p, patch.normal(u, v), t, size)
            },
            answer,
        ),
    ]
}

/// A method ready to run: its BVH.
struct Subject {
    method: Method,
    bvh: Bvh,
    triangles: usize,
    build_ms: f64,
}

fn analytic(method: Method, shape: AnyShape) -> Subject {
    Subject {
        method,
        bvh: Bvh::new(vec![(shape, 0)]).expect("one shape fits"),
        triangles: 0,
        build_ms: 0.0,
    }
}

fn mesh_subject(
    method: Method,
    tessellate: impl FnOnce() -> sppm_lang::internals::scene::MeshData,
) -> Result<Subject, String> {
    let start = Instant::now();
    let mesh = tessellate();
    let tris = mesh_triangles(&mesh, &DAffine3::IDENTITY)?;
    let triangles = tris.len();
    let bvh = Bvh::new(
        tris.into_iter()
            .map(|t| (AnyShape::Triangle(t), 0))
            .collect(),
    )
    .map_err(|e| e.to_string())?;
    Ok(Subject {
        method,
        bvh,
        triangles,
        build_ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

fn newton(starts: u32, iterations: u32) -> (Method, IntersectMethod) {
    (
        Method::Newton { starts, iterations },
        IntersectMethod::Newton { iterations, starts },
    )
}

fn lathe_subjects(
    profile: &Profile,
    lathe: &Lathe,
    opts: &Options,
) -> Result<Vec<Subject>, String> {
    let revolve = |m| -> Result<AnyShape, String> {
        Ok(AnyShape::Other(Box::new(Revolve::new(profile, None, m)?)))
    };
    let mut out = vec![analytic(Method::Robust, revolve(IntersectMethod::Robust)?)];
    for &(s, i) in &opts.lathe_newton {
        let (method, im) = newton(s, i);
        out.push(analytic(method, revolve(im)?));
    }
    for &(rows, cols) in &opts.lathe_grids {
        let m = Method::Mesh { rows, cols };
        out.push(mesh_subject(m, || lathe_mesh(lathe, rows, cols))?);
    }
    Ok(out)
}

fn patch_subjects(
    points: &[DVec3; 16],
    patch: &Patch,
    opts: &Options,
) -> Result<Vec<Subject>, String> {
    let shape = |m| -> Result<AnyShape, String> {
        Ok(AnyShape::Other(Box::new(BezierPatch::new(points, m)?)))
    };
    let mut out = vec![analytic(Method::Robust, shape(IntersectMethod::Robust)?)];
    for &(s, i) in &opts.patch_newton {
        let (method, im) = newton(s, i);
        out.push(analytic(method, shape(im)?));
    }
    for &(rows, cols) in &opts.patch_grids {
        let m = Method::Mesh { rows, cols };
        out.push(mesh_subject(m, || patch_mesh(patch, rows, cols))?);
    }
    Ok(out)
}

/// Rays timed at a time: the methods take turns on each chunk.
const CHUNK: usize = 256;

/// Timed passes: `times[subject][kind][pass]` in seconds, and each subject's answers (`t`).
type Timing = (Vec<Vec<Vec<f64>>>, Vec<Vec<Vec<Option<f32>>>>);

/// Each pass runs every chunk of [`CHUNK`] rays through every subject in turn (in an order that
/// rotates with the chunk and the pass), so that a change in the machine's load, or the caches
/// the previous subject left, falls on all of them alike.
fn time_subjects(subjects: &[Subject], kinds: &[RayKind], repeats: usize) -> Timing {
    let n = subjects.len();
    let mut times = vec![vec![Vec::with_capacity(repeats); kinds.len()]; n];
    let mut answers: Vec<Vec<Vec<Option<f32>>>> = (0..n)
        .map(|_| kinds.iter().map(|k| vec![None; k.rays.len()]).collect())
        .collect();
    let t_min = T_MIN as f32;
    for pass in 0..repeats.max(1) {
        for (k, kind) in kinds.iter().enumerate() {
            let mut secs = vec![0.0; n];
            for (c, chunk) in kind.rays.chunks(CHUNK).enumerate() {
                let first = c * CHUNK;
                for turn in 0..n {
                    let s = (turn + c + pass) % n;
                    let bvh = &subjects[s].bvh;
                    let out = &mut answers[s][k][first..first + chunk.len()];
                    let start = Instant::now();
                    for (slot, ray) in out.iter_mut().zip(chunk) {
                        *slot = bvh.intersect(ray, t_min, f32::INFINITY).map(|h| h.0.t);
                    }
                    secs[s] += start.elapsed().as_secs_f64();
                    std::hint::black_box(out);
                }
            }
            for (s, t) in secs.into_iter().enumerate() {
                times[s][k].push(t);
            }
        }
    }
    (times, answers)
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// Accuracy counts of `got` against the reference.
struct Accuracy {
    rays: usize,
    ambiguous: usize,
    ref_hits: usize,
    misses: usize,
    false_hits: usize,
    /// Relative `t` errors on rays both hit.
    errors: Vec<f64>,
}

fn accuracy<'a>(pairs: impl Iterator<Item = (&'a RefHit, &'a Option<f32>)>) -> Accuracy {
    let mut a = Accuracy {
        rays: 0,
        ambiguous: 0,
        ref_hits: 0,
        misses: 0,
        false_hits: 0,
        errors: Vec::new(),
    };
    for (want, got) in pairs {
        a.rays += 1;
        if want.ambiguous {
            a.ambiguous += 1;
            continue;
        }
        a.ref_hits += want.t.is_some() as usize;
        match (want.t, got) {
            (Some(_), None) => a.misses += 1,
            (None, Some(_)) => a.false_hits += 1,
            (Some(w), Some(g)) => a.errors.push((*g as f64 - w).abs() / w.abs().max(1e-300)),
            (None, None) => {}
        }
    }
    a
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

fn rows_for(surface: Surface, subjects: &[Subject], kinds: &[RayKind], repeats: usize) -> Vec<Row> {
    let (times, answers) = time_subjects(subjects, kinds, repeats);
    let passes = times.first().and_then(|t| t.first()).map_or(0, Vec::len);
    // Per subject: per-kind median seconds, then the median of the per-pass totals.
    let mut secs: Vec<Vec<f64>> = Vec::new();
    for t in &times {
        let mut per: Vec<f64> = t.iter().map(|k| median(&mut k.clone())).collect();
        let mut totals: Vec<f64> = (0..passes).map(|p| t.iter().map(|k| k[p]).sum()).collect();
        per.push(median(&mut totals));
        secs.push(per);
    }
    let robust = subjects
        .iter()
        .position(|s| s.method == Method::Robust)
        .unwrap_or(0);
    let total_rays: usize = kinds.iter().map(|k| k.rays.len()).sum();
    let mut rows = Vec::new();
    for (s, subject) in subjects.iter().enumerate() {
        for k in 0..=kinds.len() {
            let (name, n, mut acc) = if k < kinds.len() {
                let kind = &kinds[k];
                let acc = accuracy(kind.reference.iter().zip(&answers[s][k]));
                (kind.name.to_string(), kind.rays.len(), acc)
            } else {
                let pairs = kinds
                    .iter()
                    .enumerate()
                    .flat_map(|(k, kind)| kind.reference.iter().zip(&answers[s][k]));
                ("all".to_string(), total_rays, accuracy(pairs))
            };
            acc.errors.sort_by(f64::total_cmp);
            let ns = secs[s][k] * 1e9 / n.max(1) as f64;
            let robust_ns = secs[robust][k] * 1e9 / n.max(1) as f64;
            rows.push(Row {
                surface,
                method: subject.method,
                kind: name,
                triangles: subject.triangles,
                build_ms: subject.build_ms,
                ns_per_ray: ns,
                time_vs_robust: ns / robust_ns,
                rays: acc.rays,
                ambiguous: acc.ambiguous,
                ref_hits: acc.ref_hits,
                misses: acc.misses,
                false_hits: acc.false_hits,
                both: acc.errors.len(),
                far_hits: acc.errors.iter().filter(|e| **e > FAR).count(),
                t_err_median: quantile(&acc.errors, 0.5),
                t_err_p99: quantile(&acc.errors, 0.99),
                t_err_max: acc.errors.last().copied().unwrap_or(f64::NAN),
            });
        }
    }
    rows
}

/// Runs the whole measurement; `progress` receives a line per stage.
pub fn run(opts: &Options, progress: &dyn Fn(&str)) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();

    let profile = vase_profile();
    let lathe = Lathe::new(&profile.segments, None)?;
    progress(&format!(
        "revolve: reference for {} rays per kind",
        opts.rays
    ));
    let kinds = lathe_kinds(&lathe, opts);
    progress("revolve: building the meshes");
    let subjects = lathe_subjects(&profile, &lathe, opts)?;
    progress(&format!("revolve: timing {} methods", subjects.len()));
    rows.extend(rows_for(Surface::Revolve, &subjects, &kinds, opts.repeats));
    drop(subjects);

    let points = wavy_points();
    let patch = Patch::new(&points)?;
    progress(&format!("patch: reference for {} rays per kind", opts.rays));
    let kinds = patch_kinds(&patch, opts);
    progress("patch: building the meshes");
    let subjects = patch_subjects(&points, &patch, opts)?;
    progress(&format!("patch: timing {} methods", subjects.len()));
    rows.extend(rows_for(Surface::Patch, &subjects, &kinds, opts.repeats));
    Ok(rows)
}

fn num(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        format!("{v:.4e}")
    }
}

/// The CSV table: a header and one line per row.
pub fn csv(rows: &[Row]) -> String {
    let mut out = String::from(
        "surface,method,kind,starts,iterations,rows,cols,triangles,build_ms,ns_per_ray,\
         time_vs_robust,rays,ambiguous,ref_hits,misses,miss_rate,false_hits,false_hit_rate,\
         both_hit,far_hits,t_err_median,t_err_p99,t_err_max\n",
    );
    for r in rows {
        let (starts, iterations, grid_rows, grid_cols) = match r.method {
            Method::Robust => (String::new(), String::new(), String::new(), String::new()),
            Method::Newton { starts, iterations } => (
                starts.to_string(),
                iterations.to_string(),
                String::new(),
                String::new(),
            ),
            Method::Mesh { rows, cols } => (
                String::new(),
                String::new(),
                rows.to_string(),
                cols.to_string(),
            ),
        };
        let _ = writeln!(
            out,
            "{},{},{},{starts},{iterations},{grid_rows},{grid_cols},{},{:.1},{:.1},{:.4},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.surface.name(),
            r.method.label(),
            r.kind,
            r.triangles,
            r.build_ms,
            r.ns_per_ray,
            r.time_vs_robust,
            r.rays,
            r.ambiguous,
            r.ref_hits,
            r.misses,
            num(r.miss_rate()),
            r.false_hits,
            num(r.false_hit_rate()),
            r.both,
            r.far_hits,
            num(r.t_err_median),
            num(r.t_err_p99),
            num(r.t_err_max),
        );
    }
    out
}

/// One chart: a file-name suffix, its spec and its series.
#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    pub suffix: String,
    pub spec: ChartSpec,
    pub series: Vec<Series>,
}

/// Six charts over the `all` rows, against ns per ray, for the revolve and the patch: wrong
/// answers (miss rate plus false-hit rate), far hits (relative `t` error above [`FAR`], as a
/// share of the rays both hit: Newton's wrong, farther roots, or a coarse mesh's facets) and the
/// median relative `t` error. One series for the robust method
/// (a point), one per Newton start count (over its iteration counts), one for the meshes (over
/// their triangle counts). A log axis cannot show zero: a zero rate is drawn at half of the
/// smallest rate the ray set can show, and the axis label and the legend say so.
pub fn charts(rows: &[Row]) -> Vec<Chart> {
    let mut out = Vec::new();
    for surface in [Surface::Revolve, Surface::Patch] {
        let all: Vec<&Row> = rows
            .iter()
            .filter(|r| r.surface == surface && r.kind == "all")
            .collect();
        if all.is_empty() {
            continue;
        }
        let decided = |r: &Row| (r.ref_hits.max(r.rays - r.ambiguous - r.ref_hits)).max(1);
        let floor = 0.5 / all.iter().map(|r| decided(r)).max().unwrap_or(1) as f64;
        // The renderer's `t` is f32: a relative error of exactly 0 is drawn a decade below
        // its rounding (about 6e-8).
        let t_floor = 1e-9;
        type Pick = fn(&Row) -> f64;
        let far_floor = 0.5 / all.iter().map(|r| r.both).max().unwrap_or(1).max(1) as f64;
        let picks: [(&str, &str, String, f64, Pick); 3] = [
            (
                "wrong",
                "miss + false-hit rate",
                format!("miss rate + false-hit rate (0 drawn at {floor:.1e})"),
                floor,
                |r| r.miss_rate() + r.false_hit_rate(),
            ),
            (
                "far",
                "far hits",
                format!("share of hits with t error > {FAR:.0e} (0 drawn at {far_floor:.1e})"),
                far_floor,
                |r| r.far_rate(),
            ),
            (
                "terr",
                "median relative t error",
                format!("median relative t error, rays both hit (0 drawn at {t_floor:.1e})"),
                t_floor,
                |r| r.t_err_median,
            ),
        ];
        for (suffix, what, y_label, floor, pick) in picks {
            // A zero goes to the floor; the series that has one says so in the legend.
            let mut series: Vec<Series> = Vec::new();
            let mut push = |label: String, pts: Vec<(f64, f64)>| {
                let zero = pts.iter().any(|p| p.1 == 0.0);
                let points = pts
                    .into_iter()
                    .map(|(x, y)| (x, if y == 0.0 { floor } else { y }))
                    .collect();
                let label = if zero {
                    format!("{label}; 0 drawn at {floor:.1e}")
                } else {
                    label
                };
                series.push(Series {
                    label,
                    points,
                    ..Series::default()
                });
            };
            let robust: Vec<(f64, f64)> = all
                .iter()
                .filter(|r| r.method == Method::Robust)
                .map(|r| (r.ns_per_ray, pick(r)))
                .collect();
            push("robust".into(), robust);
            let mut starts: Vec<u32> = all
                .iter()
                .filter_map(|r| match r.method {
                    Method::Newton { starts, .. } => Some(starts),
                    _ => None,
                })
                .collect();
            starts.sort_unstable();
            starts.dedup();
            for s in starts {
                let mut pts: Vec<(u32, f64, f64)> = all
                    .iter()
                    .filter_map(|r| match r.method {
                        Method::Newton { starts, iterations } if starts == s => {
                            Some((iterations, r.ns_per_ray, pick(r)))
                        }
                        _ => None,
                    })
                    .collect();
                pts.sort_by_key(|p| p.0);
                let its: Vec<String> = pts.iter().map(|p| p.0.to_string()).collect();
                push(
                    format!("newton, {s} starts ({} iterations)", its.join("/")),
                    pts.iter().map(|p| (p.1, p.2)).collect(),
                );
            }
            let mut mesh: Vec<(usize, f64, f64)> = all
                .iter()
                .filter(|r| matches!(r.method, Method::Mesh { .. }))
                .map(|r| (r.triangles, r.ns_per_ray, pick(r)))
                .collect();
            mesh.sort_by_key(|p| p.0);
            if let (Some(first), Some(last)) = (mesh.first(), mesh.last()) {
                push(
                    format!("mesh, {} to {} triangles", first.0, last.0),
                    mesh.iter().map(|p| (p.1, p.2)).collect(),
                );
            }
            series.retain(|s| !s.points.is_empty());
            out.push(Chart {
                suffix: format!("_{}_{suffix}", surface.name()),
                spec: ChartSpec {
                    title: format!("{}: {what} against time", surface.name()),
                    x_label: "ns per ray (1 thread, through the BVH)".into(),
                    y_label,
                    log_x: true,
                    log_y: true,
                    floor: None,
                },
                series,
            });
        }
    }
    out
}

fn sibling(path: &Path, suffix: &str, ext: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("bezier");
    path.with_file_name(format!("{stem}{suffix}.{ext}"))
}

/// Writes the CSV (`<stem>.csv`), the six charts (`<stem>_<surface>_<wrong|far|terr>.png/.svg`)
/// and all six on one page, a surface per row (`output` and its `.svg`), each atomically.
/// Returns the paths written.
pub fn write_outputs(rows: &[Row], output: &Path) -> Result<Vec<PathBuf>, String> {
    let mut written = Vec::new();
    let csv_path = output.with_extension("csv");
    let text = csv(rows);
    sppm_lang::internals::atomic_file::write_atomic(&csv_path, |_, f| {
        use std::io::Write as _;
        f.write_all(text.as_bytes())
            .map_err(|e| format!("cannot write `{}`: {e}", csv_path.display()))
    })?;
    written.push(csv_path);
    let charts = charts(rows);
    for c in &charts {
        for ext in ["png", "svg"] {
            let p = sibling(output, &c.suffix, ext);
            draw(&c.spec, &c.series, &p)?;
            written.push(p);
        }
    }
    let panels: Vec<(ChartSpec, Vec<Series>)> =
        charts.into_iter().map(|c| (c.spec, c.series)).collect();
    for ext in ["png", "svg"] {
        let p = output.with_extension(ext);
        draw_panels(&panels, 3, &p)?;
        written.push(p);
    }
    Ok(written)
}
