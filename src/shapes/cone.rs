//! The side of a cone frustum between `base` (radius `r0`) and `cap` (radius `r1`), either
//! radius 0 for a pointed cone (end caps are separate disks, see `prepare::shapes`).
//!
//! In the frame whose z axis runs from `base` to `cap` the side is `x^2 + y^2 = r(z)^2`,
//! `r(z) = r0 + k z` with `k = (r1 - r0) / h`, for `0 <= z <= h`. A ray `o + t d` meets it where
//! `a t^2 + 2 b t + c = 0` with `a = d_x^2 + d_y^2 - k^2 d_z^2`, `b = o_x d_x + o_y d_y -
//! k d_z r(o_z)`, `c = o_x^2 + o_y^2 - r(o_z)^2`. Both radii are at least 0, so `r(z) >= 0` on the
//! whole height: the other nappe of the double cone lies outside `0 <= z <= h` and the height test
//! alone keeps the right one. `a` is 0 for rays parallel to a generator line (one root, which
//! the stable form `c / q` gives without a division by `a`). The arithmetic is f64: `b^2 - a c`
//! cancels for rays that pass far from the cone.

use std::f64::consts::{PI, TAU};

use glam::{DVec3, Vec2};

use super::{AreaSample, SplitShape};
use crate::geometry::{Aabb, Hit, Ray};

#[derive(Debug, Clone, Copy)]
pub struct Cone {
    base: DVec3,
    /// Orthonormal frame: `u`, `v` across the axis, `w` along it.
    u: DVec3,
    v: DVec3,
    w: DVec3,
    height: f64,
    r0: f64,
    r1: f64,
    /// `(r1 - r0) / height`.
    k: f64,
}

impl Cone {
    pub fn new(base: DVec3, cap: DVec3, r0: f64, r1: f64) -> Result<Self, String> {
        let axis = cap - base;
        let height = axis.length();
        if !(r0.is_finite() && r1.is_finite() && r0 >= 0.0 && r1 >= 0.0 && r0.max(r1) > 0.0) {
            return Err(format!(
                "cone radii must be at least 0 and not both 0, got {r0} and {r1}"
            ));
        }
        if !(height.is_finite() && height > 0.0 && base.is_finite()) {
            return Err("cone base and cap are the same point".into());
        }
        let w = axis / height;
        let (u, v) = w.any_orthonormal_pair();
        Ok(Self {
            base,
            u,
            v,
            w,
            height,
            r0,
            r1,
            k: (r1 - r0) / height,
        })
    }

    /// A point or direction (`point`: relative to `base`) in the cone's frame.
    #[inline]
    fn local(&self, p: DVec3) -> DVec3 {
        DVec3::new(p.dot(self.u), p.dot(self.v), p.dot(self.w))
    }

    #[inline]
    fn world(&self, l: DVec3) -> DVec3 {
        self.u * l.x + self.v * l.y + self.w * l.z
    }

    #[inline]
    fn radius_at(&self, z: f64) -> f64 {
        self.r0 + self.k * z
    }

    /// The ray's origin and direction in the cone's frame, and its two roots (unordered, NaN or
    /// infinite where there is none).
    fn roots(&self, ray: &Ray) -> Option<(DVec3, DVec3, [f64; 2])> {
        let o = self.local(ray.o.as_dvec3() - self.base);
        let d = self.local(ray.d.as_dvec3());
        let ro = self.radius_at(o.z);
        let a = d.x * d.x + d.y * d.y - self.k * self.k * d.z * d.z;
        let b = o.x * d.x + o.y * d.y - self.k * d.z * ro;
        let c = o.x * o.x + o.y * o.y - ro * ro;
        let disc = b * b - a * c;
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let q = -(b + disc.sqrt().copysign(b));
        if q == 0.0 {
            // b = 0 and a c = 0: the ray touches the apex or lies on the surface.
            return (a != 0.0).then_some((o, d, [0.0, f64::NAN]));
        }
        Some((o, d, [q / a, c / q]))
    }

    /// [`SplitShape::hit_at`], with `uv` left NaN unless asked for (it costs an `atan2`).
    pub fn hit_at_uv(&self, ray: &Ray, t: f32, uv: bool) -> Hit {
        let o = self.local(ray.o.as_dvec3() - self.base);
        let d = self.local(ray.d.as_dvec3());
        let l = o + d * f64::from(t);
        let z = l.z.clamp(0.0, self.height);
        let r = self.radius_at(z).max(0.0);
        let rho = (l.x * l.x + l.y * l.y).sqrt();
        // The direction across the axis (any at the apex, where it is undefined).
        let (cos, sin) = if rho > 0.0 {
            (l.x / rho, l.y / rho)
        } else {
            (1.0, 0.0)
        };
        let nl = DVec3::new(cos, sin, -self.k) / (1.0 + self.k * self.k).sqrt();
        let uv = if uv {
            let phi = sin.atan2(cos).rem_euclid(TAU);
            Vec2::new((phi / TAU) as f32, (z / self.height) as f32)
        } else {
            Vec2::NAN
        };
        let n = self.world(nl).as_vec3a();
        Hit {
            t,
            p: (self.base + self.world(DVec3::new(r * cos, r * sin, z))).as_vec3a(),
            n,
            ns: n,
            uv,
            dpdu: (self.world(DVec3::new(-sin, cos, 0.0)) * (TAU * r.max(1e-30))).as_vec3a(),
        }
    }
}

impl SplitShape for Cone {
    /// Nearest `t` with `t_min < t < t_max` on the side, without the surface data.
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let (o, d, [t0, t1]) = self.roots(ray)?;
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        [near, far].into_iter().find_map(|t| {
            let z = o.z + d.z * t;
            let tf = t as f32;
            (tf > t_min && tf < t_max && (0.0..=self.height).contains(&z)).then_some(tf)
        })
    }

    fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        self.hit_at_uv(ray, t, true)
    }

    fn bounds(&self) -> Aabb {
        let cap = self.base + self.w * self.height;
        // A disk of radius r about the axis spans r sqrt(1 - w_i^2) along axis i.
        let e = (DVec3::ONE - self.w * self.w).max(DVec3::ZERO).powf(0.5);
        let pts = [
            self.base - e * self.r0,
            self.base + e * self.r0,
            cap - e * self.r1,
            cap + e * self.r1,
        ];
        Aabb::from_points(pts.map(|p| p.as_vec3a()))
    }

    fn area(&self) -> f32 {
        let slant = ((self.r1 - self.r0).powi(2) + self.height * self.height).sqrt();
        (PI * (self.r0 + self.r1) * slant) as f32
    }

    /// Uniform by area: the height with density proportional to `r(z)`, the angle uniform.
    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        let (ux, uy) = (f64::from(u.x), f64::from(u.y));
        // Solve (k / 2) z^2 + r0 z = ux (r0 + r1) h / 2 in the form without cancellation.
        let m = ux * (self.r0 + self.r1) * self.height;
        let den = self.r0 + (self.r0 * self.r0 + self.k * m).max(0.0).sqrt();
        let z = if den > 0.0 { m / den } else { 0.0 }.clamp(0.0, self.height);
        let r = self.radius_at(z).max(0.0);
        let phi = TAU * uy;
        let (sin, cos) = phi.sin_cos();
        let nl = DVec3::new(cos, sin, -self.k) / (1.0 + self.k * self.k).sqrt();
        let area = self.area();
        (area > 0.0).then(|| AreaSample {
            p: (self.base + self.world(DVec3::new(r * cos, r * sin, z))).as_vec3a(),
            n: self.world(nl).as_vec3a(),
            pdf: 1.0 / area,
        })
    }
}

/// The radius of the cone at a world point's height along the axis, and the point's distance
/// from the axis (for tests).
#[cfg(test)]
fn radii_at(c: &Cone, p: glam::Vec3A) -> (f64, f64) {
    let l = c.local(p.as_dvec3() - c.base);
    (c.radius_at(l.z), (l.x * l.x + l.y * l.y).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bezier::Solver;
    use crate::bezier::lathe::Lathe;
    use crate::sampling::Rng;
    use crate::shapes::Shape;
    use crate::shapes::sampling_tests::{assert_estimate, mean_se};
    use glam::{DVec2, Vec3A};

    fn frustum() -> Cone {
        Cone::new(DVec3::ZERO, DVec3::new(0.0, 2.0, 0.0), 1.0, 0.25).unwrap()
    }

    /// The same side as a revolve of the straight profile from `(r0, 0)` to `(r1, h)`
    /// (a degree-1 Bezier segment about the y axis): another intersector of the same surface.
    fn as_lathe(r0: f64, r1: f64, h: f64) -> Lathe {
        Lathe::new(&[vec![DVec2::new(r0, 0.0), DVec2::new(r1, h)]], None).unwrap()
    }

    /// Random rays at the cone agree with the revolve of its profile: the same hits and misses,
    /// `t` within 1e-5 (f32 rays), and every hit on the surface and on the ray.
    #[test]
    fn hits_agree_with_the_revolve_of_its_profile() {
        let mut rng = Rng::new(7);
        for (r0, r1) in [(1.0, 0.25), (0.0, 0.8), (0.6, 0.0), (0.3, 1.2), (0.5, 0.5)] {
            let h = 1.5;
            let cone = Cone::new(DVec3::ZERO, DVec3::new(0.0, h, 0.0), r0, r1).unwrap();
            let lathe = as_lathe(r0, r1, h);
            let (mut hits, mut differ) = (0, 0);
            for _ in 0..20_000 {
                let o = Vec3A::new(
                    4.0 * rng.f32() - 2.0,
                    3.0 * rng.f32() - 0.75,
                    4.0 * rng.f32() - 2.0,
                );
                let target = Vec3A::new(
                    2.0 * rng.f32() - 1.0,
                    h as f32 * rng.f32(),
                    2.0 * rng.f32() - 1.0,
                );
                let d = (target - o).normalize();
                let ray = Ray::new(o, d);
                let ours = cone.hit_t(&ray, 1e-4, f32::INFINITY);
                let theirs = lathe
                    .intersect(
                        o.as_dvec3(),
                        d.as_dvec3(),
                        1e-4,
                        f64::INFINITY,
                        Solver::Robust,
                    )
                    .map(|h| h.t);
                match (ours, theirs) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        assert!(
                            (f64::from(a) - b).abs() < 1e-5,
                            "r {r0}, {r1}: t {a} vs {b}"
                        );
                        let hit = cone.hit_at(&ray, a);
                        let (want, got) = radii_at(&cone, hit.p);
                        assert!(
                            (want - got).abs() < 1e-5,
                            "off the surface: {want} vs {got}"
                        );
                        assert!((hit.p - ray.at(a)).length() < 1e-5);
                        assert!((hit.n.length() - 1.0).abs() < 1e-5);
                    }
                    (None, None) => {}
                    // A ray through the rim may fall on either side of it in the two.
                    _ => differ += 1,
                }
            }
            assert!(hits > 3_000, "r {r0}, {r1}: only {hits} hits");
            assert!(differ <= 2, "r {r0}, {r1}: {differ} rays hit in one only");
        }
    }

    /// Where the quadratic degenerates: rays parallel to a generator line (`a = 0`), rays
    /// through the apex, along the axis, and from far away. Each hit lies on the surface.
    #[test]
    fn degenerate_rays_hit_where_they_should() {
        let cone = Cone::new(DVec3::ZERO, DVec3::new(0.0, 1.0, 0.0), 1.0, 0.0).unwrap();
        // Parallel to the generator line x = 1 - y (a = 0), along x = 0.5 - y inside the cone:
        // one root, on the far generator x = y - 1 at (-0.25, 0.75).
        let d = Vec3A::new(-1.0, 1.0, 0.0).normalize();
        let ray = Ray::new(Vec3A::new(1.5, -1.0, 0.0), d);
        let t = cone
            .hit_t(&ray, 0.0, f32::INFINITY)
            .expect("parallel to a generator line");
        assert!((t - 1.75 * 2f32.sqrt()).abs() < 1e-5, "t {t}");
        let (want, got) = radii_at(&cone, ray.at(t));
        assert!((want - got).abs() < 1e-5, "{want} vs {got}");
        // The same direction along x = 1.5 - y, outside: it meets only the other nappe.
        let ray = Ray::new(Vec3A::new(2.5, -1.0, 0.0), d);
        assert_eq!(cone.hit_t(&ray, 0.0, f32::INFINITY), None);
        // Straight down the axis onto the apex.
        let ray = Ray::new(Vec3A::new(0.0, 3.0, 0.0), Vec3A::new(0.0, -1.0, 0.0));
        let t = cone.hit_t(&ray, 0.0, f32::INFINITY).expect("down the axis");
        assert!((t - 2.0).abs() < 1e-5, "apex at t {t}");
        let n = cone.hit_at(&ray, t).n;
        assert!(
            n.is_finite() && (n.length() - 1.0).abs() < 1e-5,
            "apex normal {n}"
        );
        // From 10^6 units away, across the middle: the near side at the right distance.
        let ray = Ray::new(Vec3A::new(-1.0e6, 0.5, 0.0), Vec3A::X);
        let t = cone.hit_t(&ray, 0.0, f32::INFINITY).expect("from far away");
        assert!((f64::from(t) - (1.0e6 - 0.5)).abs() < 0.1, "t {t}");
        // Grazing past the apex misses; the base plane from below misses the side.
        let ray = Ray::new(Vec3A::new(-2.0, 1.0 + 1e-3, 0.0), Vec3A::X);
        assert_eq!(cone.hit_t(&ray, 0.0, f32::INFINITY), None);
        let ray = Ray::new(Vec3A::new(0.2, -1.0, 0.1), Vec3A::new(0.0, -1.0, 0.0));
        assert_eq!(cone.hit_t(&ray, 0.0, f32::INFINITY), None);
    }

    /// The outward normal points away from the axis (and down the slope); `t` in the window only.
    #[test]
    fn normals_point_out_and_the_window_is_kept() {
        let cone = frustum();
        let ray = Ray::new(Vec3A::new(-3.0, 1.0, 0.0), Vec3A::X);
        let t = cone.hit_t(&ray, 0.0, f32::INFINITY).unwrap();
        let h = cone.hit_at(&ray, t);
        assert!(h.n.x < 0.0 && h.n.y > 0.0, "{}", h.n);
        assert_eq!(cone.hit_t(&ray, 0.0, t * 0.999), None);
        let t2 = cone.hit_t(&ray, t * 1.001, f32::INFINITY).unwrap();
        assert!(cone.hit_at(&ray, t2).n.x > 0.0);
    }

    /// Area sampling: uniform by area (the mean height of a frustum's side is where its
    /// area splits) and the area itself against a numerical integral.
    #[test]
    fn sampling_is_uniform_by_area() {
        let cone = frustum();
        let mut rng = Rng::new(3);
        let (r0, r1, h) = (1.0f64, 0.25f64, 2.0f64);
        let want_area = PI * (r0 + r1) * ((r1 - r0).powi(2) + h * h).sqrt();
        assert!((f64::from(Shape::area(&cone)) - want_area).abs() < 1e-4 * want_area);
        // Mean height by area: int z r(z) dz / int r(z) dz.
        let n = 10_000;
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..n {
            let z = (i as f64 + 0.5) / n as f64 * h;
            let r = r0 + (r1 - r0) * z / h;
            num += z * r;
            den += r;
        }
        let est = mean_se(200_000, || {
            let s = Shape::sample(&cone, rng.vec2()).unwrap();
            let (want, got) = radii_at(&cone, s.p);
            assert!((want - got).abs() < 1e-5);
            f64::from(s.p.y)
        });
        assert_estimate("mean height", est, num / den, 1e-3);
    }

    #[test]
    fn refuses_degenerate_cones() {
        assert!(Cone::new(DVec3::ZERO, DVec3::Y, 0.0, 0.0).is_err());
        assert!(Cone::new(DVec3::ZERO, DVec3::Y, -1.0, 1.0).is_err());
        assert!(Cone::new(DVec3::ZERO, DVec3::ZERO, 1.0, 1.0).is_err());
        assert!(Cone::new(DVec3::ZERO, DVec3::Y, f64::NAN, 1.0).is_err());
    }
}
