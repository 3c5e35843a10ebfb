//! Bicubic Bezier patch (scene glue).
//!
//! The numerical work (f64) is in [`crate::bezier::patch`]. Area is integrated by Gauss-Legendre
//! quadrature over a grid of parameter cells; sampling picks a cell by its area and a parameter
//! point uniformly inside it (uniform by area up to the variation of `|dpdu x dpdv|` within a
//! cell; documented in `docs/bezier.md`).

use glam::{DVec2, DVec3, Vec2};

use super::revolve::outward_box;
use super::{AreaSample, Shape, solver_of};
use crate::bezier::Solver;
use crate::bezier::patch::Patch;
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::IntersectMethod;

/// Parameter cells per side of the area table.
const CELLS: usize = 16;

/// Pieces per side a patch is cut into for the BVH ([`BezierPatch::split`]): of 1, 2, 4, 8, 16
/// and 32, 8 rendered the teapot fastest (docs/measurements.md).
pub const PIECES: u32 = 8;

pub struct BezierPatch {
    patch: Patch,
    solver: Solver,
    bounds: Aabb,
    /// Cumulative area over the `CELLS x CELLS` cells, row-major in u.
    cdf: Vec<f64>,
}

impl BezierPatch {
    /// Builds the renderer shape; the error is a message fit for a diagnostic.
    pub fn new(points: &[DVec3; 16], method: IntersectMethod) -> Result<Self, String> {
        let patch = Patch::new(points)?;
        let (lo, hi) = patch.bounds();
        let solver = solver_of(method);
        const X: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
        const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
        let h = 0.5 / CELLS as f64;
        let mut cdf = vec![0.0];
        for i in 0..CELLS {
            for j in 0..CELLS {
                let (cu, cv) = ((2 * i + 1) as f64 * h, (2 * j + 1) as f64 * h);
                let mut a = 0.0;
                for (xu, wu) in X.iter().zip(W) {
                    for (xv, wv) in X.iter().zip(W) {
                        let (_, pu, pv) = patch.eval(cu + h * xu, cv + h * xv);
                        a += wu * wv * pu.cross(pv).length();
                    }
                }
                let last = *cdf.last().unwrap_or(&0.0);
                cdf.push(last + a * h * h);
            }
        }
        Ok(Self {
            patch,
            solver,
            bounds: outward_box(lo, hi),
            cdf,
        })
    }

    /// The patch as [`PIECES`] x [`PIECES`] separate shapes over equal parameter squares, each bounded by its
    /// own control net's box (tighter than the whole net's), so that a BVH skips the pieces a
    /// ray passes by and each piece's subdivision starts nearer its hit. The nearest of their
    /// hits is the patch's hit, in the patch's own `(u, v)`. The pieces have no area and cannot
    /// be sampled (a patch is not a light).
    pub fn split(&self) -> Vec<BezierPatch> {
        self.patch
            .pieces(PIECES)
            .into_iter()
            .map(|patch| {
                let (lo, hi) = patch.bounds();
                BezierPatch {
                    patch,
                    solver: self.solver,
                    bounds: outward_box(lo, hi),
                    cdf: Vec::new(),
                }
            })
            .collect()
    }

    /// The f64 core (for measurements and tests).
    pub fn patch(&self) -> &Patch {
        &self.patch
    }
}

impl Shape for BezierPatch {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let h = self.patch.intersect(
            ray.o.as_dvec3(),
            ray.d.as_dvec3(),
            t_min as f64,
            t_max as f64,
            self.solver,
        )?;
        let n = h.n.as_vec3a();
        let hit = Hit {
            t: h.t as f32,
            p: h.p.as_vec3a(),
            n,
            ns: n,
            uv: h.uv.as_vec2(),
            dpdu: h.dpdu.as_vec3a(),
        };
        (hit.t > t_min && hit.t < t_max).then_some(hit)
    }

    fn area(&self) -> f32 {
        self.cdf.last().copied().unwrap_or(0.0) as f32
    }

    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        let total = *self.cdf.last()?;
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = (u.x as f64).clamp(0.0, 1.0) * total;
        let k = self
            .cdf
            .partition_point(|&a| a <= target)
            .clamp(1, self.cdf.len() - 1)
            - 1;
        let (lo, hi) = (self.cdf[k], self.cdf[k + 1]);
        let fu = if hi > lo {
            (target - lo) / (hi - lo)
        } else {
            0.5
        };
        let (i, j) = (k / CELLS, k % CELLS);
        let uv = DVec2::new(
            (i as f64 + fu.clamp(0.0, 1.0)) / CELLS as f64,
            (j as f64 + (u.y as f64).clamp(0.0, 1.0)) / CELLS as f64,
        );
        let (p, _, _) = self.patch.eval(uv.x, uv.y);
        Some(AreaSample {
            p: p.as_vec3a(),
            n: self.patch.normal(uv.x, uv.y).as_vec3a(),
            pdf: (1.0 / total) as f32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    /// The flat patch z = 0 over [0, 3]^2.
    fn flat() -> [DVec3; 16] {
        std::array::from_fn(|k| DVec3::new((k / 4) as f64, (k % 4) as f64, 0.0))
    }

    #[test]
    fn flat_patch_hit_area_and_sample() {
        let p = BezierPatch::new(&flat(), IntersectMethod::Robust).unwrap();
        let ray = Ray::new(Vec3A::new(1.5, 0.75, 4.0), -Vec3A::Z);
        let h = p.intersect(&ray, 1e-4, f32::INFINITY).unwrap();
        assert!((h.t - 4.0).abs() < 1e-6);
        assert!((h.uv - Vec2::new(0.5, 0.25)).length() < 1e-6);
        assert!((h.n - Vec3A::Z).length() < 1e-6);
        assert!((p.area() - 9.0).abs() < 1e-4);
        let s = p.sample(Vec2::new(0.2, 0.9)).unwrap();
        assert!(s.p.z.abs() < 1e-6 && (s.pdf - 1.0 / 9.0).abs() < 1e-6);
        let miss = Ray::new(Vec3A::new(3.5, 0.75, 4.0), -Vec3A::Z);
        assert!(p.intersect(&miss, 1e-4, f32::INFINITY).is_none());
        let mut bad = flat();
        bad[3].x = f64::INFINITY;
        assert!(BezierPatch::new(&bad, IntersectMethod::Robust).is_err());
    }
}
