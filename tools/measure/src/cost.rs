//! Cost per ray of the Bezier surfaces against a quad, measured in the same run
//! (`cargo run --release -p sppm-measure -- cost`).
//!
//! Each surface (the vase revolve, a goblet revolve, the wavy patch) and a quad spanning the
//! same bounding box (its diagonal section) answer the same seeded random rays (from a sphere
//! of 3 sizes around the box through a uniform point inside it) through the renderer's [`Bvh`],
//! one thread, closest hit with full surface data. The subjects take turns on every chunk of
//! 256 rays; each pass's time is summed per subject and the median pass is reported, with the
//! ratio to the quad's time in the same pass.

use std::time::Instant;

use glam::{DVec2, DVec3, Vec3A};

use sppm_lang::internals::accel::Bvh;
use sppm_lang::internals::geometry::{Aabb, Ray};
use sppm_lang::internals::sampling::SplitMix64;
use sppm_lang::internals::scene::{IntersectMethod, Profile};
use sppm_lang::internals::shapes::Shape;
use sppm_lang::internals::shapes::patch::BezierPatch;
use sppm_lang::internals::shapes::primitive::AnyShape;
use sppm_lang::internals::shapes::quad::Quad;
use sppm_lang::internals::shapes::revolve::Revolve;

use crate::bezier::{T_MIN, random_ray, vase_profile, wavy_points};

/// The goblet of `examples/goblet.scn` (same profile, unscaled): underside, foot, stem, outside
/// of the bowl, lip, inside of the bowl, from the axis at the bottom to the axis at 0.46.
pub fn goblet_profile() -> Profile {
    let seg = |p: &[(f64, f64)]| p.iter().map(|&(r, h)| DVec2::new(r, h)).collect::<Vec<_>>();
    Profile {
        segments: vec![
            seg(&[(0.0, 0.0), (0.1, 0.0), (0.2, 0.0), (0.3, 0.0)]),
            seg(&[(0.3, 0.0), (0.3, 0.03), (0.1, 0.04), (0.04, 0.08)]),
            seg(&[(0.04, 0.08), (0.03, 0.2), (0.03, 0.35), (0.05, 0.42)]),
            seg(&[(0.05, 0.42), (0.3, 0.45), (0.32, 0.7), (0.27, 0.9)]),
            seg(&[(0.27, 0.9), (0.265, 0.905), (0.255, 0.905), (0.25, 0.9)]),
            seg(&[(0.25, 0.9), (0.3, 0.7), (0.27, 0.47), (0.0, 0.46)]),
        ],
    }
}

/// One timed subject.
pub struct CostRow {
    pub name: String,
    pub ns_per_ray: f64,
    /// Over the quad's time on the same rays in the same passes.
    pub vs_quad: f64,
    /// Share of the rays that hit.
    pub hit_rate: f64,
}

fn random_rays(lo: DVec3, hi: DVec3, n: usize, seed: u64) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let (o, d) = random_ray(&mut SplitMix64::for_item(seed, 0, i), lo, hi);
            Ray::new(o.as_vec3a(), d.normalize().as_vec3a())
        })
        .collect()
}

/// A quad on the diagonal section of the box `lo..hi`.
fn section_quad(lo: DVec3, hi: DVec3) -> Result<AnyShape, String> {
    let (lo, hi) = (lo.as_vec3a(), hi.as_vec3a());
    let q = Quad::new(
        lo,
        Vec3A::new(hi.x - lo.x, 0.0, hi.z - lo.z),
        Vec3A::new(0.0, hi.y - lo.y, 0.0),
    )?;
    Ok(AnyShape::Quad(q))
}

/// Median ns per ray of `surface` (its primitives, in the box `b`) and of a quad over the same
/// box, alternating on every chunk.
fn pair(
    name: &str,
    (surface, b): (Vec<AnyShape>, Aabb),
    rays: usize,
    repeats: usize,
) -> Result<CostRow, String> {
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let rays = random_rays(lo, hi, rays, 7);
    let subjects = [
        Bvh::new(surface.into_iter().map(|s| (s, 0)).collect()).map_err(|e| e.to_string())?,
        Bvh::new(vec![(section_quad(lo, hi)?, 0)]).map_err(|e| e.to_string())?,
    ];
    let mut passes = Vec::new();
    let mut hits = 0usize;
    for pass in 0..repeats.max(1) {
        let mut secs = [0.0f64; 2];
        hits = 0;
        for (c, chunk) in rays.chunks(256).enumerate() {
            for turn in 0..2 {
                let s = (turn + c + pass) % 2;
                let start = Instant::now();
                let mut n = 0usize;
                for ray in chunk {
                    n += usize::from(
                        std::hint::black_box(subjects[s].intersect(
                            ray,
                            T_MIN as f32,
                            f32::INFINITY,
                        ))
                        .is_some(),
                    );
                }
                secs[s] += start.elapsed().as_secs_f64();
                if s == 0 {
                    hits += n;
                }
            }
        }
        passes.push(secs);
    }
    passes.sort_by(|a, b| (a[0] / a[1]).total_cmp(&(b[0] / b[1])));
    let mid = passes[passes.len() / 2];
    let per = |s: f64| s * 1e9 / rays.len() as f64;
    Ok(CostRow {
        name: name.into(),
        ns_per_ray: per(mid[0]),
        vs_quad: mid[0] / mid[1],
        hit_rate: hits as f64 / rays.len() as f64,
    })
}

/// The vase, the goblet and the wavy patch, each against its quad.
pub fn run(rays: usize, repeats: usize) -> Result<Vec<CostRow>, String> {
    // Split as the renderer places it: one primitive per profile segment.
    let revolve = |p: &Profile| -> Result<(Vec<AnyShape>, Aabb), String> {
        let whole = Revolve::new(p, None, IntersectMethod::Robust)?;
        let parts = whole.split().into_iter();
        Ok((
            parts.map(|part| AnyShape::Other(Box::new(part))).collect(),
            whole.bounds(),
        ))
    };
    // Cut into pieces as the renderer places it.
    let patch = BezierPatch::new(&wavy_points(), IntersectMethod::Robust)?;
    let patch_bounds = patch.bounds();
    let pieces = patch
        .split()
        .into_iter()
        .map(|piece| AnyShape::Other(Box::new(piece)))
        .collect();
    Ok(vec![
        pair("revolve vase", revolve(&vase_profile())?, rays, repeats)?,
        pair("revolve goblet", revolve(&goblet_profile())?, rays, repeats)?,
        pair("patch wavy", (pieces, patch_bounds), rays, repeats)?,
    ])
}
