//! A torus about the y axis at the origin (POV-Ray's `torus { R, r }`: major radius `R` from
//! the axis to the tube's centre, minor radius `r` of the tube, `R > r > 0`); the renderer
//! places it with its object's transform.
//!
//! A ray `p(u) = q + u d` (unit `d`) meets the surface where
//! `F(u) = (|p|^2 + R^2 - r^2)^2 - 4 R^2 (p_x^2 + p_z^2) = 0`, a quartic in `u`. It is formed
//! about `q`, the middle of the ray's chord through the bounding sphere of radius `R + r` (so
//! that its terms are of the size of the torus, whatever the ray's origin), turned into the
//! Bernstein basis on that chord and its roots isolated by the Bezier root finder
//! ([`crate::bezier::roots`]), which cannot miss a simple root. A double root (a ray tangent to
//! the surface) counts as a hit only where the point lies on the surface within rounding.

use std::f64::consts::{PI, TAU};

use glam::{DVec3, Vec2, Vec3A};

use super::{AreaSample, SplitShape};
use crate::bezier::bernstein::Bernstein;
use crate::bezier::roots::{RootKind, find_roots};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::TORUS_MAX_ASPECT;

/// The largest ratio of major to minor radius ([`TORUS_MAX_ASPECT`]). The quartic's terms
/// cancel as the tube gets thinner against its ring (relative conditioning about `(R / r)^2`):
/// at 1000 and 2000 every hit of 20 000 rays aimed at the surface lies on it and every miss is
/// one of sphere tracing too; at 10 000, 2-3 % of the hits lie off the surface by more than
/// 0.1 % of `r`.
pub const MAX_ASPECT: f64 = TORUS_MAX_ASPECT;

#[derive(Debug, Clone, Copy)]
pub struct Torus {
    major: f64,
    minor: f64,
}

impl Torus {
    pub fn new(major: f64, minor: f64) -> Result<Self, String> {
        if !(minor.is_finite() && major.is_finite() && minor > 0.0 && major > minor) {
            return Err(format!(
                "a torus needs a major radius greater than its minor radius and both positive, \
                 got {major} and {minor}"
            ));
        }
        if major > MAX_ASPECT * minor {
            return Err(format!(
                "a torus whose major radius is more than {MAX_ASPECT} times its minor radius \
                 is too thin to intersect reliably (major {major}, minor {minor}): make the \
                 minor radius at least the major radius / {MAX_ASPECT}"
            ));
        }
        Ok(Self { major, minor })
    }

    /// The signed distance of `p` from the surface (negative inside the tube).
    pub fn distance(&self, p: DVec3) -> f64 {
        let rho = (p.x * p.x + p.z * p.z).sqrt() - self.major;
        (rho * rho + p.y * p.y).sqrt() - self.minor
    }

    /// The nearest `t` (along the ray's own direction) with `t_min < t < t_max`.
    fn nearest(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        let dl = d.length();
        if !(dl > 0.0 && dl.is_finite() && o.is_finite()) {
            return None;
        }
        let d = d / dl;
        // The chord through the bounding sphere: |o + u d|^2 = (R + r)^2.
        let bound = self.major + self.minor;
        let b = o.dot(d);
        let closest = o - b * d;
        let h2 = bound * bound - closest.length_squared();
        if h2.is_nan() || h2 <= 0.0 {
            return None;
        }
        let half = h2.sqrt();
        // The chord around its middle `q = o + tm d`, `u` in [-half, half].
        let tm = -b;
        let q = closest;
        let (r2, big2) = (self.minor * self.minor, self.major * self.major);
        let a = q.length_squared() + big2 - r2;
        let bb = q.dot(d);
        let c = q.x * q.x + q.z * q.z;
        let dd = q.x * d.x + q.z * d.z;
        let e = d.x * d.x + d.z * d.z;
        // F(u) = u^4 + 4B u^3 + (4B^2 + 2A - 4R^2 E) u^2 + (4AB - 8R^2 D) u + A^2 - 4R^2 C.
        let power = [
            a * a - 4.0 * big2 * c,
            4.0 * a * bb - 8.0 * big2 * dd,
            4.0 * bb * bb + 2.0 * a - 4.0 * big2 * e,
            4.0 * bb,
            1.0,
        ];
        let f = bernstein_on(&power, -half, half)?;
        let mut roots = Vec::new();
        find_roots(&f, &mut roots);
        let (lo, hi) = (f64::from(t_min) * dl, f64::from(t_max) * dl);
        for root in roots {
            let t_unit = tm + (-half + 2.0 * half * root.t);
            if !(t_unit > lo && t_unit < hi) {
                continue;
            }
            if root.kind == RootKind::Multiple {
                // A touch: a hit only where the point is on the surface within rounding.
                let p = o + t_unit * d;
                if self.distance(p).abs() > 1e-9 * bound {
                    continue;
                }
            }
            let t = (t_unit / dl) as f32;
            if t > t_min && t < t_max {
                return Some(t);
            }
        }
        None
    }

    /// The surface data at `t`, with `uv` left NaN unless asked for.
    pub fn hit_at_uv(&self, ray: &Ray, t: f32, uv: bool) -> Hit {
        let p = ray.o.as_dvec3() + ray.d.as_dvec3() * f64::from(t);
        let rho = (p.x * p.x + p.z * p.z).sqrt();
        // The direction from the axis (any, on the axis: not a point of the surface).
        let (sx, sz) = if rho > 0.0 {
            (p.x / rho, p.z / rho)
        } else {
            (0.0, 1.0)
        };
        let centre = DVec3::new(sx * self.major, 0.0, sz * self.major);
        let n = (p - centre).normalize_or(DVec3::Y);
        // Back onto the surface: the tube's centre plus the minor radius along the normal.
        let on = centre + n * self.minor;
        let uv = if uv {
            let phi = sx.atan2(sz).rem_euclid(TAU);
            let theta = n.y.atan2(n.x * sx + n.z * sz).rem_euclid(TAU);
            Vec2::new((phi / TAU) as f32, (theta / TAU) as f32)
        } else {
            Vec2::NAN
        };
        let ring = self.major + self.minor * (n.x * sx + n.z * sz);
        let n = n.as_vec3a();
        Hit {
            t,
            p: on.as_vec3a(),
            n,
            ns: n,
            uv,
            dpdu: (DVec3::new(sz, 0.0, -sx) * (TAU * ring.max(1e-30))).as_vec3a(),
        }
    }
}

/// The Bernstein form on `[u0, u1]` (as `s` in [0, 1]) of the polynomial with power
/// coefficients `power` (constant first) in `u`.
fn bernstein_on(power: &[f64; 5], u0: f64, u1: f64) -> Option<Bernstein> {
    // Taylor shift to u0, then scale by the interval's length: coefficients in `s`.
    let mut c = *power;
    for k in 0..4 {
        for j in (k..4).rev() {
            c[j] += u0 * c[j + 1];
        }
    }
    let len = u1 - u0;
    let mut scale = 1.0;
    for v in &mut c {
        *v *= scale;
        scale *= len;
    }
    // Power to Bernstein: b_k = sum_{i <= k} C(k, i) / C(4, i) a_i.
    const BINOM: [[f64; 5]; 5] = [
        [1.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0, 0.0],
        [1.0, 2.0, 1.0, 0.0, 0.0],
        [1.0, 3.0, 3.0, 1.0, 0.0],
        [1.0, 4.0, 6.0, 4.0, 1.0],
    ];
    let b: [f64; 5] =
        std::array::from_fn(|k| (0..=k).map(|i| BINOM[k][i] / BINOM[4][i] * c[i]).sum());
    Bernstein::new(&b)
}

impl SplitShape for Torus {
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        self.nearest(ray, t_min, t_max)
    }

    fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        self.hit_at_uv(ray, t, true)
    }

    fn bounds(&self) -> Aabb {
        let (a, r) = ((self.major + self.minor) as f32, self.minor as f32);
        Aabb::new(Vec3A::new(-a, -r, -a), Vec3A::new(a, r, a))
    }

    fn area(&self) -> f32 {
        (4.0 * PI * PI * self.major * self.minor) as f32
    }

    /// Uniform by area: the angle around the axis uniform, the angle around the tube with
    /// density proportional to `R + r cos(theta)` (its distribution inverted by Newton's method).
    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        let (phi, target) = (TAU * f64::from(u.x), TAU * self.major * f64::from(u.y));
        // cdf(theta) = R theta + r sin(theta), increasing since R > r.
        let mut theta = TAU * f64::from(u.y);
        for _ in 0..32 {
            let g = self.major * theta + self.minor * theta.sin() - target;
            let step = g / (self.major + self.minor * theta.cos());
            theta = (theta - step).clamp(0.0, TAU);
            if step.abs() < 1e-14 {
                break;
            }
        }
        let (sp, cp) = phi.sin_cos();
        let (st, ct) = theta.sin_cos();
        let n = DVec3::new(ct * sp, st, ct * cp);
        let p = DVec3::new(sp * self.major, 0.0, cp * self.major) + n * self.minor;
        Some(AreaSample {
            p: p.as_vec3a(),
            n: n.as_vec3a(),
            pdf: 1.0 / self.area(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::shapes::Shape;
    use crate::shapes::sampling_tests::{assert_estimate, mean_se};

    /// Sphere tracing with the exact distance (its absolute value, so that a ray from inside
    /// the tube finds its exit): an independent reference for the first hit. `None` for a
    /// miss; `Err` where it cannot decide (a ray that passes within 1e-6 of the surface without
    /// touching it, or too many steps).
    fn march(t: &Torus, o: DVec3, d: DVec3) -> Result<Option<f64>, ()> {
        let (mut u, mut closest) = (0.0, f64::INFINITY);
        for _ in 0..200_000 {
            let dist = t.distance(o + u * d).abs();
            closest = closest.min(dist);
            if dist < 1e-12 {
                return Ok(Some(u));
            }
            u += dist;
            if u > 50.0 {
                return if closest < 1e-6 { Err(()) } else { Ok(None) };
            }
        }
        Err(())
    }

    #[test]
    fn hits_agree_with_sphere_tracing() {
        let torus = Torus::new(1.0, 0.3).unwrap();
        let mut rng = Rng::new(11);
        let (mut hits, mut misses, mut undecided) = (0, 0, 0);
        for k in 0..20_000 {
            let o = Vec3A::new(
                6.0 * rng.f32() - 3.0,
                4.0 * rng.f32() - 2.0,
                6.0 * rng.f32() - 3.0,
            );
            // Half the rays aimed at the tube, half anywhere near.
            let target = if k % 2 == 0 {
                let phi = TAU as f32 * rng.f32();
                Vec3A::new(phi.sin(), 0.6 * rng.f32() - 0.3, phi.cos())
            } else {
                Vec3A::new(
                    3.0 * rng.f32() - 1.5,
                    rng.f32() - 0.5,
                    3.0 * rng.f32() - 1.5,
                )
            };
            let d = (target - o).normalize();
            let ray = Ray::new(o, d);
            let ours = torus.hit_t(&ray, 0.0, f32::INFINITY);
            match march(&torus, o.as_dvec3(), d.as_dvec3()) {
                Ok(Some(t)) => {
                    let a = ours.unwrap_or_else(|| panic!("missed {ray:?} (reference t {t})"));
                    assert!((f64::from(a) - t).abs() < 1e-5, "{ray:?}: t {a} vs {t}");
                    let h = torus.hit_at(&ray, a);
                    assert!(torus.distance(h.p.as_dvec3()).abs() < 1e-5);
                    assert!((h.p - ray.at(a)).length() < 1e-5);
                    assert!(h.n.dot(d) < 0.0 || torus.distance(o.as_dvec3()) < 0.0);
                    hits += 1;
                }
                Ok(None) => {
                    assert_eq!(ours, None, "{ray:?}: a false hit");
                    misses += 1;
                }
                Err(()) => undecided += 1,
            }
        }
        assert!(hits > 5000 && misses > 2000, "{hits} hits, {misses} misses");
        assert!(
            undecided < 20,
            "{undecided} rays the reference could not decide"
        );
    }

    /// Rays where a quartic solver fails: through the hole along the axis (a miss), along the
    /// equator through the centre (four roots, the nearest taken; the next ones after it),
    /// grazing the top (a double root), from inside the tube, and from far away.
    #[test]
    fn hard_rays() {
        let torus = Torus::new(1.0, 0.25).unwrap();
        let down = Ray::new(Vec3A::new(0.0, 5.0, 0.0), Vec3A::new(0.0, -1.0, 0.0));
        assert_eq!(torus.hit_t(&down, 0.0, f32::INFINITY), None);
        let across = Ray::new(Vec3A::new(-3.0, 0.0, 0.0), Vec3A::X);
        let expect = [1.75f32, 2.25, 3.75, 4.25];
        let mut t_min = 0.0;
        for e in expect {
            let t = torus.hit_t(&across, t_min, f32::INFINITY).expect("equator");
            assert!((t - e).abs() < 1e-5, "{t} vs {e}");
            t_min = t + 1e-4;
        }
        assert_eq!(torus.hit_t(&across, t_min, f32::INFINITY), None);
        // Tangent to the top of the tube at (0, 0.25, 1): touches it (within rounding).
        let top = Ray::new(Vec3A::new(-2.0, 0.25, 1.0), Vec3A::X);
        if let Some(t) = torus.hit_t(&top, 0.0, f32::INFINITY) {
            assert!((t - 2.0).abs() < 1e-3, "touch at {t}");
        }
        // Just above the top: a miss; just below: two hits close together.
        let above = Ray::new(Vec3A::new(-2.0, 0.2501, 1.0), Vec3A::X);
        assert_eq!(torus.hit_t(&above, 0.0, f32::INFINITY), None);
        let below = Ray::new(Vec3A::new(-2.0, 0.2499, 1.0), Vec3A::X);
        let t = torus
            .hit_t(&below, 0.0, f32::INFINITY)
            .expect("just below the top");
        assert!(torus.distance(below.at(t).as_dvec3()).abs() < 1e-5);
        // From inside the tube, outward: the exit.
        let inside = Ray::new(Vec3A::new(1.0, 0.0, 0.0), Vec3A::Y);
        let t = torus
            .hit_t(&inside, 1e-4, f32::INFINITY)
            .expect("from inside");
        assert!((t - 0.25).abs() < 1e-5);
        // From 10^5 away toward the tube.
        let far = Ray::new(Vec3A::new(-1.0e5, 0.0, 0.0), Vec3A::X);
        let t = torus
            .hit_t(&far, 0.0, f32::INFINITY)
            .expect("from far away");
        assert!((f64::from(t) - (1.0e5 - 1.25)).abs() < 0.02, "{t}");
    }

    #[test]
    fn sampling_is_uniform_by_area() {
        let torus = Torus::new(1.0, 0.4).unwrap();
        let mut rng = Rng::new(5);
        // By area, the mean distance from the axis is R + r^2 / (2 R).
        let est = mean_se(200_000, || {
            let s = Shape::sample(&torus, rng.vec2()).unwrap();
            assert!(torus.distance(s.p.as_dvec3()).abs() < 1e-5);
            f64::from((s.p.x * s.p.x + s.p.z * s.p.z).sqrt())
        });
        assert_estimate("mean distance from the axis", est, 1.0 + 0.16 / 2.0, 1e-3);
    }

    /// The thinnest torus allowed: rays aimed at points of its surface hit it on the surface,
    /// and those that miss (grazing the tube after the f32 rounding of the ray) miss in sphere
    /// tracing too.
    #[test]
    fn the_thinnest_torus_allowed_is_hit_exactly() {
        let (big, small) = (1.0, 1.0 / MAX_ASPECT);
        let torus = Torus::new(big, small).unwrap();
        let mut rng = Rng::new(3);
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..20_000 {
            let (phi, th) = (TAU * f64::from(rng.f32()), TAU * f64::from(rng.f32()));
            let ring = big + small * th.cos();
            let target = DVec3::new(ring * phi.sin(), small * th.sin(), ring * phi.cos());
            let jitter = Vec3A::new(rng.f32(), rng.f32(), rng.f32()) - Vec3A::splat(0.5);
            let o = target.as_vec3a() + jitter * (4.0 * big as f32);
            let d = (target.as_vec3a() - o).normalize();
            let ray = Ray::new(o, d);
            match torus.hit_t(&ray, 0.0, f32::INFINITY) {
                Some(t) => {
                    let off = torus.distance(ray.at(t).as_dvec3()).abs();
                    assert!(off < 1e-3 * small, "{ray:?}: {off} off the surface");
                    hits += 1;
                }
                None => {
                    assert_eq!(
                        march(&torus, o.as_dvec3(), d.as_dvec3()).unwrap_or(None),
                        None,
                        "{ray:?}: missed"
                    );
                    misses += 1;
                }
            }
        }
        assert!(hits > 19_000, "{hits} hits, {misses} misses");
    }

    #[test]
    fn refuses_bad_radii() {
        assert!(Torus::new(1.0, 0.5 / MAX_ASPECT).is_err());
        assert!(Torus::new(1.0, 1.0).is_err());
        assert!(Torus::new(0.5, 1.0).is_err());
        assert!(Torus::new(1.0, 0.0).is_err());
        assert!(Torus::new(f64::NAN, 0.1).is_err());
    }
}
