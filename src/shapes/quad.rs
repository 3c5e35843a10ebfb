//! Parallelogram `origin + s*edge_u + t*edge_v`.

use glam::{BVec4A, Vec2, Vec3A, Vec4};

use std::f32::consts::PI;

use super::{
    AreaSample, SolidAngleSample, SplitShape, area_pdf_to_solid_angle, area_to_solid_angle,
};
use crate::geometry::{Aabb, Hit, Ray};

/// Below this solid angle (steradians) a rectangle is sampled by area: the spherical
/// rectangle's area `g0 + g1 - k` loses its digits to cancellation, and area sampling is
/// already near-uniform in solid angle there (pbrt-v4 uses 3e-4 for its spherical triangles).
const MIN_SPHERICAL_RECT: f32 = 1e-3;

/// Beyond this many diagonals from its center a rectangle is sampled by area: there the area
/// sampler's density varies little over the rectangle, and the spherical rectangle's four
/// `acos` and its inverse map cost more than the variance they save (measured on the Cornell
/// box: docs/measurements.md, "Light sampling").
const NEAR_DIAGONALS: f32 = 1.5;

/// The spherical rectangle a rectangle subtends from a receiver `o` (Ureña, Fajardo and King,
/// "An Area-Preserving Parametrization for Spherical Rectangles", 2013), in the rectangle's
/// frame `(x, y, z)` with the receiver at the origin and the rectangle at `z = z0 < 0`.
#[derive(Debug, Clone, Copy)]
struct SphericalRect {
    x: Vec3A,
    y: Vec3A,
    z: Vec3A,
    x0: f32,
    x1: f32,
    y0: f32,
    y1: f32,
    z0: f32,
    b0: f32,
    b1: f32,
    k: f32,
    /// Solid angle.
    s: f32,
}

impl SphericalRect {
    /// The point of the rectangle (relative to the receiver) for `u` in [0,1)^2: uniform in
    /// solid angle.
    fn sample(&self, u: Vec2) -> Vec3A {
        let au = u.x * self.s + self.k;
        let fu = (au.cos() * self.b0 - self.b1) / au.sin();
        let cu = (1.0 / (fu * fu + self.b0 * self.b0).sqrt())
            .copysign(fu)
            .clamp(-1.0, 1.0);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).max(1e-12).sqrt()).clamp(self.x0, self.x1);
        let d2 = xu * xu + self.z0 * self.z0;
        let h0 = self.y0 / (d2 + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d2 + self.y1 * self.y1).sqrt();
        let hv = h0 + u.y * (h1 - h0);
        let hv2 = hv * hv;
        let yv = if hv2 < 1.0 - 1e-6 {
            (hv * d2.sqrt() / (1.0 - hv2).sqrt()).clamp(self.y0, self.y1)
        } else {
            self.y1
        };
        self.x * xu + self.y * yv + self.z * self.z0
    }
}

#[derive(Debug, Clone, Copy)]
pub struct Quad {
    origin: Vec3A,
    eu: Vec3A,
    ev: Vec3A,
    n: Vec3A,
    /// Dual vectors of the edges in the quad's plane: for a point `q` (relative to `origin`)
    /// in the plane, `s = q . du` and `t = q . dv` (`du = ev x w`, `dv = w x eu` with
    /// `w = cross / |cross|^2`): two dot products per test instead of two cross products.
    du: Vec3A,
    dv: Vec3A,
    area: f32,
}

impl Quad {
    pub fn new(origin: Vec3A, eu: Vec3A, ev: Vec3A) -> Result<Self, String> {
        let c = eu.cross(ev);
        let area = crate::geometry::scaled_length(c);
        if !(area.is_finite() && area > 0.0 && origin.is_finite()) {
            return Err("quad edges are parallel or degenerate (zero area)".into());
        }
        let n = c / area;
        // c / |c|^2, without squaring |c| (edges 1e11 long would overflow it).
        let w = n / area;
        Ok(Self {
            origin,
            eu,
            ev,
            n,
            du: ev.cross(w),
            dv: w.cross(eu),
            area,
        })
    }
}

impl Quad {
    /// The spherical rectangle the quad subtends from `p`, if `p` is within [`NEAR_DIAGONALS`]
    /// of its center, the quad is a rectangle (edges perpendicular), `p` is off its plane and
    /// the solid angle is at least [`MIN_SPHERICAL_RECT`]; otherwise the quad is sampled by
    /// area.
    fn spherical_rect(&self, p: Vec3A) -> Option<SphericalRect> {
        let (lu2, lv2) = (self.eu.length_squared(), self.ev.length_squared());
        let center = self.origin + 0.5 * (self.eu + self.ev);
        if (p - center).length_squared() >= NEAR_DIAGONALS * NEAR_DIAGONALS * (lu2 + lv2) {
            return None;
        }
        let (lu, lv) = (lu2.sqrt(), lv2.sqrt());
        let (x, y) = (self.eu / lu, self.ev / lv);
        if x.dot(y).abs() > 1e-4 {
            return None;
        }
        let d = self.origin - p;
        let (mut z, mut z0) = (self.n, d.dot(self.n));
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        if z0.is_nan() || z0 >= 0.0 {
            return None;
        }
        let (x0, y0) = (d.dot(x), d.dot(y));
        let (x1, y1) = (x0 + lu, y0 + lv);
        let v00 = Vec3A::new(x0, y0, z0);
        let v01 = Vec3A::new(x0, y1, z0);
        let v10 = Vec3A::new(x1, y0, z0);
        let v11 = Vec3A::new(x1, y1, z0);
        let n0 = v00.cross(v10).normalize();
        let n1 = v10.cross(v11).normalize();
        let n2 = v11.cross(v01).normalize();
        let n3 = v01.cross(v00).normalize();
        let angle = |a: Vec3A, b: Vec3A| (-a.dot(b)).clamp(-1.0, 1.0).acos();
        let (g0, g1, g2, g3) = (angle(n0, n1), angle(n1, n2), angle(n2, n3), angle(n3, n0));
        let k = 2.0 * PI - g2 - g3;
        let s = g0 + g1 - k;
        (s >= MIN_SPHERICAL_RECT && s.is_finite()).then_some(SphericalRect {
            x,
            y,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: n0.z,
            b1: n2.z,
            k,
            s,
        })
    }

    /// Signed distance of `p` from the quad's plane, positive on the side its normal faces.
    #[inline]
    pub fn height_above(&self, p: Vec3A) -> f32 {
        self.n.dot(p - self.origin)
    }

    /// A point of the quad for the receiver `p`, from `u` in [0,1)^2: uniform in the solid
    /// angle the quad subtends if it is a rectangle seen under at least [`MIN_SPHERICAL_RECT`]
    /// steradians, uniform by area otherwise. The density is per solid angle at `p` and is
    /// what [`Quad::pdf_toward`] gives for the same point.
    pub fn sample_toward(&self, p: Vec3A, u: Vec2) -> Option<SolidAngleSample> {
        let Some(rect) = self.spherical_rect(p) else {
            let s = SplitShape::sample(self, u)?;
            return area_to_solid_angle(p, s.p, s.n, self.area);
        };
        let q = rect.sample(u);
        let dist = q.length();
        if dist.is_nan() || dist <= 0.0 {
            return None;
        }
        Some(SolidAngleSample {
            p: p + q,
            n: self.n,
            wi: q / dist,
            pdf: 1.0 / rect.s,
        })
    }

    /// Solid-angle density at `p` of [`Quad::sample_toward`] choosing the point `pl` of the
    /// quad (normal `nl`).
    pub fn pdf_toward(&self, p: Vec3A, pl: Vec3A, nl: Vec3A) -> f32 {
        match self.spherical_rect(p) {
            Some(rect) => 1.0 / rect.s,
            None => area_pdf_to_solid_angle(p, pl, nl, self.area),
        }
    }

    #[inline]
    fn st(&self, ray: &Ray, t: f32) -> (f32, f32) {
        let q = ray.at(t) - self.origin;
        (q.dot(self.du), q.dot(self.dv))
    }
}

mod octet;
pub use octet::QuadOctet;

/// Up to four quads tested at once, one per SIMD lane (structure of arrays). Each lane runs
/// the operations of [`Quad::hit_t`] in the same order (dot products as `(x + y) + z`, as glam
/// computes them), so a lane's `t` and its accept/reject decision are bit-identical to the
/// scalar test. Unused lanes have a zero normal: their `denom` is 0 and they never hit.
#[derive(Debug, Clone, Copy)]
pub struct QuadPacket {
    n: [Vec4; 3],
    origin: [Vec4; 3],
    du: [Vec4; 3],
    dv: [Vec4; 3],
}

#[inline(always)]
fn dot4(a: &[Vec4; 3], b: &[Vec4; 3]) -> Vec4 {
    (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]
}

impl QuadPacket {
    /// The packet of `quads` (at most four).
    pub fn new(quads: &[Quad]) -> Self {
        assert!(quads.len() <= 4, "a packet holds four quads");
        let lanes = |f: &dyn Fn(&Quad) -> Vec3A| -> [Vec4; 3] {
            let mut out = [Vec4::ZERO; 3];
            for (lane, q) in quads.iter().enumerate() {
                let v = f(q);
                for (axis, o) in out.iter_mut().enumerate() {
                    o[lane] = v[axis];
                }
            }
            out
        };
        Self {
            n: lanes(&|q| q.n),
            origin: lanes(&|q| q.origin),
            du: lanes(&|q| q.du),
            dv: lanes(&|q| q.dv),
        }
    }

    /// The lanes whose quad the ray hits with `t_min < t < t_max`, and each lane's `t`.
    #[inline(always)]
    fn hits(&self, ray: &Ray, t_min: f32, t_max: f32) -> (BVec4A, Vec4) {
        let d = [ray.d.x, ray.d.y, ray.d.z].map(Vec4::splat);
        let o = [ray.o.x, ray.o.y, ray.o.z].map(Vec4::splat);
        let denom = dot4(&self.n, &d);
        let to_origin = [0, 1, 2].map(|a| self.origin[a] - o[a]);
        let t = dot4(&self.n, &to_origin) / denom;
        // `ray.at(t) - origin`, per lane.
        let q = [0, 1, 2].map(|a| (o[a] + d[a] * t) - self.origin[a]);
        let (s, v) = (dot4(&q, &self.du), dot4(&q, &self.dv));
        let (zero, one) = (Vec4::ZERO, Vec4::ONE);
        let mask = denom.cmpne(zero)
            & t.cmpgt(Vec4::splat(t_min))
            & t.cmplt(Vec4::splat(t_max))
            & s.cmpge(zero)
            & s.cmple(one)
            & v.cmpge(zero)
            & v.cmple(one);
        (mask, t)
    }

    /// The nearest hit with `t_min < t < t_max`: its lane and `t` (on equal `t`, the lowest
    /// lane, as a scalar loop over the quads in lane order would keep).
    #[inline]
    pub fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(usize, f32)> {
        let (mask, t) = self.hits(ray, t_min, t_max);
        if !mask.any() {
            return None;
        }
        let t = Vec4::select(mask, t, Vec4::INFINITY);
        let best = t.min_element();
        let lane = t.cmpeq(Vec4::splat(best)).bitmask().trailing_zeros() as usize;
        Some((lane, best))
    }

    /// Whether any quad of the packet is hit with `t_min < t < t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.hits(ray, t_min, t_max).0.any()
    }
}

impl SplitShape for Quad {
    /// Nearest `t` with `t_min < t < t_max`, without the surface data (see [`Quad::hit_at`]).
    #[inline]
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let denom = self.n.dot(ray.d);
        if denom == 0.0 {
            return None;
        }
        let t = self.n.dot(self.origin - ray.o) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let (s, v) = self.st(ray, t);
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&v)).then_some(t)
    }

    /// The full surface data at ray parameter `t` (a value [`Quad::hit_t`] returned).
    fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        let (s, v) = self.st(ray, t);
        Hit::from_parts(t, ray.at(t), self.n, self.n, Vec2::new(s, v), self.eu)
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_points([
            self.origin,
            self.origin + self.eu,
            self.origin + self.ev,
            self.origin + self.eu + self.ev,
        ])
    }

    fn area(&self) -> f32 {
        self.area
    }

    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        Some(AreaSample {
            p: self.origin + self.eu * u.x + self.ev * u.y,
            n: self.n,
            pdf: 1.0 / self.area,
        })
    }
}

/// What packet tests share (quads here, mesh triangles in the BVH): the checks of a packet's
/// lanes against the scalar test of each lane's shape.
#[cfg(test)]
pub(crate) mod packet_check {
    use glam::{BVec4A, Vec4};

    /// The `t` range of case `i`: a bounded one every third case.
    pub(crate) fn t_range(i: usize) -> (f32, f32) {
        if i.is_multiple_of(3) {
            (0.5, 2.0)
        } else {
            (0.0, f32::INFINITY)
        }
    }

    /// Asserts that each of the first `count` lanes (`mask`, `t` from the packet) answers as
    /// `scalar(lane, t_min, t_max)` does, bit for bit, and that the empty lanes miss; returns
    /// the nearest (lane, `t`) a scalar loop over the lanes keeps.
    pub(crate) fn lanes(
        mask: BVec4A,
        t: Vec4,
        count: usize,
        (t_min, t_max): (f32, f32),
        case: usize,
        scalar: impl Fn(usize, f32, f32) -> Option<f32>,
    ) -> Option<(usize, f32)> {
        let mut best = None;
        let mut limit = t_max;
        for lane in 0..count {
            let want = scalar(lane, t_min, t_max);
            assert_eq!(
                mask.test(lane),
                want.is_some(),
                "lane {lane} of case {case}"
            );
            if let Some(w) = want {
                assert_eq!(t[lane].to_bits(), w.to_bits(), "lane {lane} of case {case}");
            }
            if let Some(w) = scalar(lane, t_min, limit) {
                limit = w;
                best = Some((lane, w));
            }
        }
        for lane in count..4 {
            assert!(!mask.test(lane), "empty lane {lane} hit in case {case}");
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::sampling_tests::{
        assert_density_integrates_to_one, assert_estimate, mean_se,
    };
    use glam::DVec3;

    /// `int max(0, m . w) dw` over the polygon `corners` seen from `p`, all of it above the
    /// horizon of `m`: Lambert's formula, `1/2 |sum_i gamma_i m . (v_i x v_i+1) / |..||`, in f64.
    fn polygon_irradiance(p: Vec3A, m: Vec3A, corners: &[Vec3A]) -> f64 {
        let (p, m) = (p.as_dvec3(), m.as_dvec3());
        let v: Vec<DVec3> = corners
            .iter()
            .map(|c| (c.as_dvec3() - p).normalize())
            .collect();
        let mut sum = 0.0;
        for i in 0..v.len() {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            let c = a.cross(b);
            sum += a.dot(b).clamp(-1.0, 1.0).acos() * m.dot(c / c.length());
        }
        0.5 * sum.abs()
    }

    /// Solid-angle sampling of a quad averages to the analytic irradiance from every side and
    /// distance: close above, off to one side, grazing (a hair off the plane, where the
    /// spherical rectangle is thin), far (area sampling below the solid-angle threshold),
    /// behind, and for a parallelogram that is not a rectangle (area sampling). Each sample
    /// lies on the quad, and [`Quad::pdf_toward`] gives it the sampler's density.
    #[test]
    fn solid_angle_sampling_gives_the_analytic_irradiance() {
        let rect = Quad::new(
            Vec3A::new(-0.5, 1.0, -0.25),
            Vec3A::new(1.0, 0.0, 0.0),
            Vec3A::new(0.0, 0.0, 0.5),
        )
        .unwrap();
        let slanted = Quad::new(
            Vec3A::new(-0.5, 1.0, -0.25),
            Vec3A::new(1.0, 0.0, 0.0),
            Vec3A::new(0.4, 0.0, 0.5),
        )
        .unwrap();
        let mut rng = Rng::new(21);
        let cases = [
            (rect, Vec3A::new(0.0, 0.9, 0.0), "close above"),
            (rect, Vec3A::new(0.1, 0.0, 0.0), "near"),
            (rect, Vec3A::new(2.0, 0.5, 1.0), "to one side"),
            (
                rect,
                Vec3A::new(0.7, 0.999, 0.1),
                "grazing, beside the edge",
            ),
            (rect, Vec3A::new(0.2, 0.9999, 0.1), "a hair under the quad"),
            (rect, Vec3A::new(0.0, 1.2, 0.0), "behind"),
            (rect, Vec3A::new(30.0, -40.0, 5.0), "far"),
            (slanted, Vec3A::new(0.0, 0.5, 0.0), "parallelogram"),
        ];
        for (quad, p, what) in cases {
            let corners = [
                quad.origin,
                quad.origin + quad.eu,
                quad.origin + quad.eu + quad.ev,
                quad.origin + quad.ev,
            ];
            let m = if quad.n.dot(quad.origin - p) > 0.0 {
                quad.n
            } else {
                -quad.n
            };
            let want = polygon_irradiance(p, m, &corners);
            let estimate = mean_se(100_000, || {
                let Some(s) = quad.sample_toward(p, rng.vec2()) else {
                    return 0.0;
                };
                let q = s.p - quad.origin;
                let (a, b) = (q.dot(quad.du), q.dot(quad.dv));
                assert!(
                    (-1e-4..=1.0001).contains(&a) && (-1e-4..=1.0001).contains(&b),
                    "{what}: sample ({a}, {b}) off the quad"
                );
                let back = quad.pdf_toward(p, s.p, s.n);
                assert!(
                    (back / s.pdf - 1.0).abs() < 1e-3,
                    "{what}: {back} vs {}",
                    s.pdf
                );
                (m.dot(s.wi).max(0.0) / s.pdf) as f64
            });
            assert_estimate(what, estimate, want, 1e-4);
        }
    }

    /// Edges 1e11 long are legal (world coordinates go to 1e12), but the square of their cross
    /// product (1e44) overflows f32: the quad was refused as "degenerate (zero area)".
    #[test]
    fn a_quad_with_edges_1e11_long_is_built_and_hit() {
        for s in [1e-4f32, 1.0, 1e11] {
            let quad = Quad::new(
                Vec3A::new(-s, 0.0, -s),
                2.0 * s * Vec3A::X,
                2.0 * s * Vec3A::Z,
            )
            .unwrap_or_else(|e| panic!("size {s}: {e}"));
            assert!((quad.area / (4.0 * s * s) - 1.0).abs() < 1e-5, "size {s}");
            let ray = Ray::new(Vec3A::new(0.3 * s, s, 0.2 * s), -Vec3A::Y);
            let hit =
                crate::shapes::Shape::intersect(&quad, &ray, 0.0, f32::INFINITY).expect("a hit");
            assert!((hit.t / s - 1.0).abs() < 1e-5, "size {s}: t = {}", hit.t);
            assert!((hit.uv - glam::Vec2::new(0.65, 0.6)).abs().max_element() < 1e-5);
        }
    }

    /// The density [`Quad::pdf_toward`] gives a point a ray from `p` hits is a normalized
    /// density over the directions that hit the quad (MIS uses it for BSDF samples): its
    /// integral over uniform directions is one.
    #[test]
    fn pdf_toward_integrates_to_one() {
        let quad = Quad::new(Vec3A::new(-1.0, 0.5, -1.0), 2.0 * Vec3A::X, 1.5 * Vec3A::Z).unwrap();
        let mut rng = Rng::new(23);
        for p in [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(0.3, 0.49, 0.2),
            Vec3A::new(3.0, 1.5, 0.0),
        ] {
            assert_density_integrates_to_one(
                &quad,
                p,
                |p, pl, nl| quad.pdf_toward(p, pl, nl),
                &mut rng,
            );
        }
    }

    fn random_vec(rng: &mut Rng) -> Vec3A {
        Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE
    }

    /// A packet gives, lane by lane, exactly the scalar test's answer (same `t` bits, same
    /// accept/reject), and its nearest hit is the one a scalar loop over the quads keeps. Some
    /// rays start on a quad's plane or run parallel to it, and some packets have empty lanes.
    #[test]
    fn packets_match_the_scalar_test_bit_for_bit() {
        let mut rng = Rng::new(11);
        let mut hits = 0;
        for i in 0..20_000 {
            let count = 1 + i % 4;
            let quads: Vec<Quad> = (0..count)
                .map(|_| {
                    let e = if rng.f32() < 0.2 {
                        Vec3A::X
                    } else {
                        random_vec(&mut rng)
                    };
                    Quad::new(random_vec(&mut rng), e, random_vec(&mut rng)).unwrap()
                })
                .collect();
            let packet = QuadPacket::new(&quads);
            let mut o = 2.0 * random_vec(&mut rng);
            let mut d = uniform_sphere(rng.vec2());
            match i % 10 {
                0 => o = quads[0].origin + 0.5 * quads[0].eu, // on the first quad
                1 => d = quads[0].eu.normalize(),             // parallel to it
                2..=6 => {
                    // Toward a random quad, near or across its edges.
                    let q = &quads[i % count];
                    let (a, b) = (1.4 * rng.f32() - 0.2, 1.4 * rng.f32() - 0.2);
                    d = (q.origin + a * q.eu + b * q.ev - o).normalize();
                }
                _ => {}
            }
            let ray = Ray::new(o, d);
            let (t_min, t_max) = packet_check::t_range(i);
            let (mask, t) = packet.hits(&ray, t_min, t_max);
            let scalar_best =
                packet_check::lanes(mask, t, count, (t_min, t_max), i, |k, lo, hi| {
                    quads[k].hit_t(&ray, lo, hi)
                });
            assert_eq!(packet.hit_t(&ray, t_min, t_max), scalar_best, "case {i}");
            assert_eq!(packet.occluded(&ray, t_min, t_max), scalar_best.is_some());
            hits += usize::from(scalar_best.is_some());
        }
        assert!(hits > 2000, "{hits} of 20000 cases hit");
    }
}
