//! Parallelogram `origin + s*edge_u + t*edge_v`.

use glam::{BVec4A, Vec2, Vec3A, Vec4};

use super::{AreaSample, SplitShape};
use crate::geometry::{Aabb, Hit, Ray};

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
        let area = c.length();
        if !(area.is_finite() && area > 0.0 && origin.is_finite()) {
            return Err("quad edges are parallel or degenerate (zero area)".into());
        }
        let n = c / area;
        let w = c / c.length_squared();
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
    #[inline]
    fn st(&self, ray: &Ray, t: f32) -> (f32, f32) {
        let q = ray.at(t) - self.origin;
        (q.dot(self.du), q.dot(self.dv))
    }
}

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
        Hit {
            t,
            p: ray.at(t),
            n: self.n,
            ns: self.n,
            uv: Vec2::new(s, v),
            dpdu: self.eu,
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, uniform_sphere};

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
            let (t_min, t_max) = if i % 3 == 0 {
                (0.5, 2.0)
            } else {
                (0.0, f32::INFINITY)
            };
            let (mask, t) = packet.hits(&ray, t_min, t_max);
            let mut scalar_best: Option<(usize, f32)> = None;
            let mut limit = t_max;
            for (lane, q) in quads.iter().enumerate() {
                let want = q.hit_t(&ray, t_min, t_max);
                assert_eq!(mask.test(lane), want.is_some(), "lane {lane} of case {i}");
                if let Some(w) = want {
                    assert_eq!(t[lane].to_bits(), w.to_bits(), "lane {lane} of case {i}");
                }
                if let Some(w) = q.hit_t(&ray, t_min, limit) {
                    limit = w;
                    scalar_best = Some((lane, w));
                }
            }
            for lane in count..4 {
                assert!(!mask.test(lane), "empty lane {lane} hit in case {i}");
            }
            assert_eq!(packet.hit_t(&ray, t_min, t_max), scalar_best, "case {i}");
            assert_eq!(packet.occluded(&ray, t_min, t_max), scalar_best.is_some());
            hits += usize::from(scalar_best.is_some());
        }
        assert!(hits > 2000, "{hits} of 20000 cases hit");
    }
}
