//! Surface of revolution of a Bezier profile around the y axis (scene glue).
//!
//! The numerical work (f64) is in [`crate::bezier::lathe`]; this file converts to the renderer's
//! f32 types. Area and area sampling cover the swept side only; the flat caps of a partial sweep
//! are not sampled (see `docs/bezier.md`).

use std::sync::Arc;

use glam::{DVec3, Vec2, Vec3A};

use super::{AreaSample, BoxedHit, Deferred, Shape, solver_of};
use crate::bezier::Solver;
use crate::bezier::lathe::{CoarseShell, Lathe, LatheHit, NearestHit, Part, Parts};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::{IntersectMethod, Profile};

/// A surface of revolution, or some of its parts (see [`Revolve::split`]).
pub struct Revolve {
    lathe: Arc<Lathe>,
    parts: Parts,
    solver: Solver,
    bounds: Aabb,
    /// The side area of the whole surface, `None` for a part (which is not sampled).
    area: Option<f64>,
    /// The f32 test that ends most misses before the f64 work (see [`CoarseShell`]).
    coarse: Option<CoarseShell>,
}

/// f32 bounds that contain the f64 box (rounded outward).
pub(crate) fn outward_box(lo: DVec3, hi: DVec3) -> Aabb {
    let pad = 1e-6
        * (hi - lo)
            .max_element()
            .max(lo.abs().max(hi.abs()).max_element());
    Aabb::new(
        (lo - DVec3::splat(pad)).as_vec3a(),
        (hi + DVec3::splat(pad)).as_vec3a(),
    )
}

impl Revolve {
    /// Builds the renderer shape; the error is a message fit for a diagnostic.
    pub fn new(
        profile: &Profile,
        sweep: Option<(f64, f64)>,
        method: IntersectMethod,
    ) -> Result<Self, String> {
        let lathe = Lathe::new(&profile.segments, sweep)?;
        let (lo, hi) = lathe.bounds();
        let area = lathe.area();
        let parts = lathe.all_parts();
        Ok(Self {
            coarse: coarse_of(&lathe, &parts),
            parts,
            lathe: Arc::new(lathe),
            solver: solver_of(method),
            bounds: outward_box(lo, hi),
            area: Some(area),
        })
    }

    /// The surface as separate shapes, one per profile segment (and one for the caps of a
    /// partial sweep), each bounded by its own box, so that a BVH skips the segments a ray
    /// passes by. The nearest of their hits is the surface's hit. The parts share the
    /// surface's data; they have no area and cannot be sampled (a revolve is not a light).
    pub fn split(&self) -> Vec<Revolve> {
        self.lathe
            .separate_parts()
            .into_iter()
            .map(|parts| {
                let (lo, hi) = self.lathe.parts_bounds(&parts);
                Revolve {
                    coarse: coarse_of(&self.lathe, &parts),
                    lathe: Arc::clone(&self.lathe),
                    parts,
                    solver: self.solver,
                    bounds: outward_box(lo, hi),
                    area: None,
                }
            })
            .collect()
    }

    /// The f64 core (for measurements and tests).
    pub fn lathe(&self) -> &Lathe {
        &self.lathe
    }
}

/// The coarse test of some parts of a lathe.
fn coarse_of(lathe: &Lathe, parts: &Parts) -> Option<CoarseShell> {
    CoarseShell::new(&lathe.parts_shell(parts)?, lathe.size())
}

impl Revolve {
    /// The nearest hit with `t_min < t < t_max` and its `t` in f32 (the conversion must not
    /// move the hit outside the caller's interval).
    fn nearest(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(NearestHit, f32)> {
        if let Some(c) = &self.coarse
            && !c.may_meet(ray.o, ray.d, t_min, t_max)
        {
            return None;
        }
        let h = self.lathe.nearest(
            self.parts.clone(),
            ray.o.as_dvec3(),
            ray.d.as_dvec3(),
            t_min as f64,
            t_max as f64,
            self.solver,
        )?;
        let t = h.t as f32;
        (t > t_min && t < t_max).then_some((h, t))
    }
}

fn to_hit(h: LatheHit) -> Hit {
    let n = h.n.as_vec3a();
    Hit {
        t: h.t as f32,
        p: h.p.as_vec3a(),
        n,
        ns: n,
        uv: h.uv.as_vec2(),
        dpdu: h.dpdu.as_vec3a(),
    }
}

impl Shape for Revolve {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let (h, _) = self.nearest(ray, t_min, t_max)?;
        Some(to_hit(self.lathe.complete(
            ray.o.as_dvec3(),
            ray.d.as_dvec3(),
            &h,
            true,
        )))
    }

    /// The surface data (the arc length for `u`, the angle for `v`, the normal) is computed
    /// later, for the nearest hit only.
    fn intersect_boxed(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<BoxedHit> {
        let (h, t) = self.nearest(ray, t_min, t_max)?;
        let part = match h.part {
            Part::Side(i) => i as u32,
            Part::StartCap => u32::MAX - 1,
            Part::EndCap => u32::MAX,
        };
        let rec = Deferred {
            a: h.t_unit,
            b: h.s,
            k: part,
        };
        Some(BoxedHit::Deferred(t, rec))
    }

    fn complete(&self, ray: &Ray, _t: f32, rec: Deferred, uv: bool) -> Hit {
        let part = match rec.k {
            k if k == u32::MAX - 1 => Part::StartCap,
            u32::MAX => Part::EndCap,
            i => Part::Side(i as usize),
        };
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        // The hit as `Lathe::nearest` gave it (its `t` computed the same way).
        let h = NearestHit {
            t: rec.a / d.length(),
            t_unit: rec.a,
            part,
            s: rec.b,
        };
        to_hit(self.lathe.complete(o, d, &h, uv))
    }

    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.nearest(ray, t_min, t_max).is_some()
    }

    fn area(&self) -> f32 {
        self.area.unwrap_or(0.0) as f32
    }

    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        let area = self.area?;
        if area.is_nan() || area <= 0.0 {
            return None;
        }
        let (p, n) = self.lathe.sample(u.as_dvec2())?;
        Some(AreaSample {
            p: p.as_vec3a(),
            n: Vec3A::from(n.as_vec3()),
            pdf: (1.0 / area) as f32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    fn cylinder() -> Profile {
        Profile {
            segments: vec![vec![DVec2::new(1.0, 0.0), DVec2::new(1.0, 2.0)]],
        }
    }

    #[test]
    fn cylinder_hit_in_f32() {
        let r = Revolve::new(&cylinder(), None, IntersectMethod::Robust).unwrap();
        let ray = Ray::new(Vec3A::new(0.0, 1.0, -5.0), Vec3A::Z);
        let h = r.intersect(&ray, 1e-4, f32::INFINITY).unwrap();
        assert!((h.t - 4.0).abs() < 1e-6);
        assert!((h.n - Vec3A::new(0.0, 0.0, -1.0)).length() < 1e-6);
        assert!((h.uv.x - 0.5).abs() < 1e-6);
        assert!(r.intersect(&ray, 1e-4, 3.9).is_none());
        let b = r.bounds();
        assert!(b.min.x <= -1.0 && b.max.y >= 2.0);
        // Side area 2 pi r h.
        assert!((r.area() - 4.0 * std::f32::consts::PI).abs() < 1e-4);
        let s = r.sample(Vec2::new(0.3, 0.7)).unwrap();
        assert!((s.p.x.hypot(s.p.z) - 1.0).abs() < 1e-5 && s.n.y.abs() < 1e-5);
    }

    #[test]
    fn bad_profiles_are_errors_not_panics() {
        let neg = Profile {
            segments: vec![vec![DVec2::new(-1.0, 0.0), DVec2::new(1.0, 2.0)]],
        };
        assert!(Revolve::new(&neg, None, IntersectMethod::Robust).is_err());
        let nan = Profile {
            segments: vec![vec![DVec2::new(f64::NAN, 0.0), DVec2::new(1.0, 2.0)]],
        };
        assert!(Revolve::new(&nan, None, IntersectMethod::Robust).is_err());
        let empty = Profile { segments: vec![] };
        assert!(Revolve::new(&empty, None, IntersectMethod::Robust).is_err());
        let long = Profile {
            segments: vec![vec![DVec2::ONE; 9]],
        };
        assert!(Revolve::new(&long, None, IntersectMethod::Robust).is_err());
        assert!(Revolve::new(&cylinder(), Some((90.0, 10.0)), IntersectMethod::Robust).is_err());
        // Profiles that sweep no surface: on the axis, or one point (a circle).
        for points in [
            vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(0.0, 1.0),
                DVec2::new(0.0, 2.0),
            ],
            vec![DVec2::new(0.5, 1.0); 4],
        ] {
            let flat = Profile {
                segments: vec![points],
            };
            let e = Revolve::new(&flat, None, IntersectMethod::Robust).err();
            assert!(e.is_some_and(|e| e.contains("sweeps no surface")));
        }
        // NaN rays are misses.
        let r = Revolve::new(&cylinder(), None, IntersectMethod::Robust).unwrap();
        let ray = Ray::new(Vec3A::splat(f32::NAN), Vec3A::Z);
        assert!(r.intersect(&ray, 0.0, f32::INFINITY).is_none());
    }
}
