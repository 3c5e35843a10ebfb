//! POV-Ray's `superellipsoid { <e, n> }` in its own space: the points of the cube [-1, 1]^3
//! with `(|x|^(2/e) + |y|^(2/e))^(e/n) + |z|^(2/n) <= 1` (z is the axis of the north-south
//! exponent `n`; `e` shapes the cross-sections). Exponents near 0 make a box with rounded
//! edges, 1 a sphere, 2 an octahedron, beyond 2 a pinched star.
//!
//! The function is raised to the power `n / 2`, which makes it the gauge
//! `G(p) = ||(||(x, y)||_p, z)||_q` (p = 2/e, q = 2/n): homogeneous of degree 1 and increasing
//! in each of `|x|`, `|y|`, `|z|`. Both are computed as a largest term times a factor in
//! [1, 2^(1/p)], so that no power overflows or underflows whatever the exponents. Because `G`
//! increases with each absolute coordinate, its exact range over a stretch of the ray follows
//! from the ranges of `|x|`, `|y|`, `|z|` there; stretches whose range excludes 1 hold no
//! crossing and are dropped, the others are halved (nearest first) down to a width of
//! [`LEAF`] of the chord, and the first leaf whose ends lie on opposite sides is bisected to
//! full precision. No crossing can be skipped, near-box (tiny exponents, where naive root
//! finders step over the sharp edges) and pinched (exponents of 2 and beyond, where the
//! gradient is unbounded at the cusps) alike; a leaf that the surface only touches (both ends
//! on one side) is a graze, not a hit.

use std::f64::consts::TAU;

use arrayvec::ArrayVec;
use glam::{DVec2, DVec3, Vec2, Vec3A};

use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};

/// Leaf width of the subdivision, relative to the ray's chord through the cube.
pub const LEAF: f64 = 1e-9;

/// Most stretches one ray may visit: a bound on the work of one ray (about a second). A ray
/// that crosses the surface visits a few hundred; one that runs within a fraction ε of a flat
/// face (an octahedron's, a pinched shape's) visits about 30/ε, since the range of the gauge
/// over a stretch is wider than its true change by about 1/ε there (the stress tests' grazing
/// rays, down to ε = 1e-5, stay below this bound).
const MAX_VISITS: u32 = 4_000_000;

/// The exponents a superellipsoid accepts (the scene's own range): beyond them the shape is a
/// box or a set of needles to within rounding.
pub const EXPONENTS: (f64, f64) = crate::scene::SUPERELLIPSOID_EXPONENTS;

#[derive(Debug, Clone, Copy)]
pub struct Superellipsoid {
    /// 2 / e and 2 / n.
    p: f64,
    q: f64,
}

/// `(a^k + b^k)^(1/k)` for `a, b >= 0`, without overflow or underflow.
#[inline]
fn norm(a: f64, b: f64, k: f64) -> f64 {
    let (big, small) = if a >= b { (a, b) } else { (b, a) };
    if big == 0.0 {
        return 0.0;
    }
    big * (1.0 + (small / big).powf(k)).powf(1.0 / k)
}

impl Superellipsoid {
    pub fn new(e: f64, n: f64) -> Result<Self, String> {
        for (v, what) in [(e, "east-west"), (n, "north-south")] {
            if !(EXPONENTS.0..=EXPONENTS.1).contains(&v) {
                return Err(format!(
                    "a superellipsoid's {what} exponent must lie in [{}, {}], got {v}",
                    EXPONENTS.0, EXPONENTS.1
                ));
            }
        }
        Ok(Self {
            p: 2.0 / e,
            q: 2.0 / n,
        })
    }

    /// The gauge `G` of a point given by its absolute coordinates (1 on the surface).
    #[inline]
    pub fn gauge_abs(&self, ax: f64, ay: f64, az: f64) -> f64 {
        norm(norm(ax, ay, self.p), az, self.q)
    }

    /// The gauge of `p`: below 1 inside, above 1 outside.
    pub fn gauge(&self, p: DVec3) -> f64 {
        self.gauge_abs(p.x.abs(), p.y.abs(), p.z.abs())
    }

    /// The nearest crossing of the surface with `t_min < t < t_max` (in units of `d`).
    pub fn nearest(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
        if !(o.is_finite() && d.is_finite()) || d == DVec3::ZERO {
            return None;
        }
        // The chord through the cube (a hair larger, so that its faces' points are inside it).
        let (mut a, mut b) = (t_min, t_max);
        for k in 0..3 {
            let (ok, dk) = (o[k], d[k]);
            if dk == 0.0 {
                if ok.abs() > 1.0 {
                    return None;
                }
                continue;
            }
            let (t0, t1) = ((-1.0 - 1e-12 - ok) / dk, (1.0 + 1e-12 - ok) / dk);
            a = a.max(t0.min(t1));
            b = b.min(t0.max(t1));
        }
        if a.is_nan() || b.is_nan() || a >= b {
            return None;
        }
        // A leaf is never narrower than the rounding of `t` itself (a chord that grazes the
        // cube is shorter than that), so halving always ends.
        let leaf = (LEAF * (b - a)).max(8.0 * f64::EPSILON * a.abs().max(b.abs()));
        let g = |t: f64| self.gauge(o + t * d) - 1.0;
        // Stretches still to look at, the nearest on top. Halving is depth first and a
        // stretch at depth k is 2^-k of the chord, a leaf by depth 30 (LEAF = 1e-9): the
        // stack holds at most one stretch per depth, so it lives on the stack of the thread.
        let mut stack: ArrayVec<(f64, f64, f64, f64), 64> = ArrayVec::new();
        stack.push((a, b, g(a), g(b)));
        let mut visits = 0;
        while let Some((lo, hi, glo, ghi)) = stack.pop() {
            visits += 1;
            if visits > MAX_VISITS {
                return None;
            }
            let (pa, pb) = (o + lo * d, o + hi * d);
            let range = |k: usize| {
                let (u, v) = (pa[k], pb[k]);
                let min = if (u < 0.0) != (v < 0.0) && u != 0.0 && v != 0.0 {
                    0.0
                } else {
                    u.abs().min(v.abs())
                };
                (min, u.abs().max(v.abs()))
            };
            let (x, y, z) = (range(0), range(1), range(2));
            if self.gauge_abs(x.0, y.0, z.0) > 1.0 || self.gauge_abs(x.1, y.1, z.1) < 1.0 {
                continue;
            }
            let mid = 0.5 * (lo + hi);
            if hi - lo <= leaf || mid <= lo || mid >= hi {
                if (glo < 0.0) != (ghi < 0.0) {
                    return Some(self.bisect(&g, lo, hi, glo));
                }
                continue;
            }
            let gm = g(mid);
            if stack.try_push((mid, hi, gm, ghi)).is_err()
                || stack.try_push((lo, mid, glo, gm)).is_err()
            {
                return None;
            }
        }
        None
    }

    fn bisect(&self, g: &impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, glo: f64) -> f64 {
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if (g(mid) < 0.0) == (glo < 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The outward unit normal at `p` (on or near the surface): the gradient of the gauge,
    /// formed in logarithms so that no power overflows at the sharp edges of a near-box or the
    /// cusps of a pinched shape.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        let (ax, ay, az) = (
            p.x.abs().max(1e-300),
            p.y.abs().max(1e-300),
            p.z.abs().max(1e-300),
        );
        let r = norm(ax, ay, self.p).max(1e-300);
        // F = r^q + |z|^q, r = (|x|^p + |y|^p)^(1/p):
        // dF/dx = q r^(q-p) |x|^(p-1), dF/dz = q |z|^(q-1).
        let lx = (self.q - self.p) * r.ln() + (self.p - 1.0) * ax.ln();
        let ly = (self.q - self.p) * r.ln() + (self.p - 1.0) * ay.ln();
        let lz = (self.q - 1.0) * az.ln();
        let top = lx.max(ly).max(lz);
        let n = DVec3::new(
            (lx - top).exp() * p.x.signum(),
            (ly - top).exp() * p.y.signum(),
            (lz - top).exp() * p.z.signum(),
        );
        n.normalize_or(p.normalize_or(DVec3::Z))
    }

    /// The point, normal, uv and `dp/du` of the hit at `t`: u around the z axis (0 at +x,
    /// ¼ at +y), v from the −z pole (0) to the +z pole (1) by the angle from the axis.
    pub fn surface(&self, o: DVec3, d: DVec3, t: f64) -> (DVec3, DVec3, DVec2, DVec3) {
        let p = o + t * d;
        let n = self.normal(p);
        let phi = p.y.atan2(p.x).rem_euclid(TAU);
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let theta = rho.atan2(-p.z);
        let uv = DVec2::new(phi / TAU, theta / std::f64::consts::PI);
        let around = DVec3::new(-p.y, p.x, 0.0) * TAU;
        let dpdu = if around.length_squared() > 0.0 {
            around
        } else {
            n.any_orthonormal_vector()
        };
        (p, n, uv, dpdu)
    }
}

impl Shape for Superellipsoid {
    fn bounds(&self) -> Aabb {
        Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0)).padded(1e-6)
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        let (lo, hi) = super::f64_range(t_min, t_max);
        let t = self.nearest(o, d, lo, hi)?;
        let tf = t as f32;
        if !(tf > t_min && tf < t_max) {
            return None;
        }
        let (p, n, uv, dpdu) = self.surface(o, d, t);
        let n = n.as_vec3a();
        Some(Hit {
            t: tf,
            p: p.as_vec3a(),
            n,
            ns: n,
            uv: uv.as_vec2(),
            dpdu: dpdu.as_vec3a(),
        })
    }

    /// A superellipsoid is not a light's shape: it is never sampled.
    fn area(&self) -> f32 {
        0.0
    }

    fn sample(&self, _u: Vec2) -> Option<AreaSample> {
        None
    }
}
