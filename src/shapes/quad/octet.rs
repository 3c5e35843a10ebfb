//! Up to eight quads tested at once, one per lane of an AVX register: a small scene's quads
//! all in one test (the Cornell box's six), where packets of four took two.

use super::Quad;

/// Up to eight quads, structure of arrays, for the AVX test. Each lane runs the operations of
/// [`Quad::hit_t`](crate::shapes::SplitShape::hit_t) in the same order (dot products as
/// `(x + y) + z`, as glam computes them; no fused multiply-add), so a lane's `t` and its
/// accept/reject decision are bit-identical to the scalar test's and to a
/// [`super::QuadPacket`]'s. Unused lanes have a zero normal: their `denom` is 0 and they never
/// hit.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
pub struct QuadOctet {
    n: [[f32; 8]; 3],
    origin: [[f32; 8]; 3],
    du: [[f32; 8]; 3],
    dv: [[f32; 8]; 3],
}

impl QuadOctet {
    /// The octet of `quads`, if there are at most eight.
    pub fn new(quads: &[Quad]) -> Option<Self> {
        if quads.len() > 8 {
            return None;
        }
        let lanes = |f: &dyn Fn(&Quad) -> glam::Vec3A| -> [[f32; 8]; 3] {
            let mut out = [[0.0; 8]; 3];
            for (lane, q) in quads.iter().enumerate() {
                let v = f(q);
                for (axis, o) in out.iter_mut().enumerate() {
                    o[lane] = v[axis];
                }
            }
            out
        };
        Some(Self {
            n: lanes(&|q| q.n),
            origin: lanes(&|q| q.origin),
            du: lanes(&|q| q.du),
            dv: lanes(&|q| q.dv),
        })
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use std::arch::x86_64::*;

    use super::QuadOctet;
    use crate::geometry::Ray;

    /// `(a0 * b0 + a1 * b1) + a2 * b2`, lane by lane.
    #[target_feature(enable = "avx")]
    #[inline]
    fn dot(a: [__m256; 3], b: [__m256; 3]) -> __m256 {
        _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])),
            _mm256_mul_ps(a[2], b[2]),
        )
    }

    impl QuadOctet {
        /// The lanes whose quad the ray hits with `t_min < t < t_max` (a bit mask), and each
        /// lane's `t`.
        ///
        /// # Safety
        ///
        /// The CPU must have AVX.
        #[target_feature(enable = "avx")]
        #[inline]
        unsafe fn hits(&self, ray: &Ray, t_min: f32, t_max: f32) -> (u32, __m256) {
            // SAFETY: each row holds eight `f32`s.
            let load = |v: &[[f32; 8]; 3]| v.map(|a| unsafe { _mm256_loadu_ps(a.as_ptr()) });
            let (n, origin, du, dv) = (
                load(&self.n),
                load(&self.origin),
                load(&self.du),
                load(&self.dv),
            );
            let d = [ray.d.x, ray.d.y, ray.d.z].map(|x| _mm256_set1_ps(x));
            let o = [ray.o.x, ray.o.y, ray.o.z].map(|x| _mm256_set1_ps(x));
            let denom = dot(n, d);
            let to_origin = [0, 1, 2].map(|a| _mm256_sub_ps(origin[a], o[a]));
            let t = _mm256_div_ps(dot(n, to_origin), denom);
            // `ray.at(t) - origin`, per lane.
            let q = [0, 1, 2]
                .map(|a| _mm256_sub_ps(_mm256_add_ps(o[a], _mm256_mul_ps(d[a], t)), origin[a]));
            let (s, v) = (dot(q, du), dot(q, dv));
            let (zero, one) = (_mm256_setzero_ps(), _mm256_set1_ps(1.0));
            // The predicates of `QuadPacket::hits` (`cmpneq` unordered, the others ordered).
            let mask = [
                _mm256_cmp_ps::<_CMP_NEQ_UQ>(denom, zero),
                _mm256_cmp_ps::<_CMP_GT_OQ>(t, _mm256_set1_ps(t_min)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(t, _mm256_set1_ps(t_max)),
                _mm256_cmp_ps::<_CMP_GE_OQ>(s, zero),
                _mm256_cmp_ps::<_CMP_LE_OQ>(s, one),
                _mm256_cmp_ps::<_CMP_GE_OQ>(v, zero),
                _mm256_cmp_ps::<_CMP_LE_OQ>(v, one),
            ]
            .into_iter()
            .reduce(|a, b| _mm256_and_ps(a, b))
            .unwrap_or(zero);
            (_mm256_movemask_ps(mask) as u32, t)
        }

        /// The nearest hit with `t_min < t < t_max`: its lane and `t` (on equal `t`, the lowest
        /// lane, as a scalar loop over the quads in lane order would keep).
        ///
        /// # Safety
        ///
        /// The CPU must have AVX.
        #[target_feature(enable = "avx")]
        #[inline]
        pub unsafe fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(usize, f32)> {
            // SAFETY: the caller's.
            let (mask, t) = unsafe { self.hits(ray, t_min, t_max) };
            if mask == 0 {
                return None;
            }
            let mut lanes = [0.0f32; 8];
            // SAFETY: `lanes` holds eight `f32`s.
            unsafe { _mm256_storeu_ps(lanes.as_mut_ptr(), t) };
            // The hit lanes' `t` are ordered numbers (`t_min < t`), so the minimum is exact
            // whatever the order the lanes are visited in; the first lane holding it wins.
            let mut best: Option<(usize, f32)> = None;
            let mut bits = mask;
            while bits != 0 {
                let lane = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if best.is_none_or(|(_, b)| lanes[lane] < b) {
                    best = Some((lane, lanes[lane]));
                }
            }
            best
        }

        /// Whether any quad of the octet is hit with `t_min < t < t_max`.
        ///
        /// # Safety
        ///
        /// The CPU must have AVX.
        #[target_feature(enable = "avx")]
        #[inline]
        pub unsafe fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
            // SAFETY: the caller's.
            unsafe { self.hits(ray, t_min, t_max).0 != 0 }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::SplitShape;
    use glam::Vec3A;

    fn random_vec(rng: &mut Rng) -> Vec3A {
        Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE
    }

    /// The octet's nearest hit is, bit for bit, the one a scalar loop over its quads keeps (the
    /// lowest lane on equal `t`), and it is occluded exactly when that loop finds a hit; rays
    /// start on a quad's plane, run parallel to it, aim at its edges, or at a corner several
    /// quads share (equal `t` in several lanes).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_octet_matches_the_scalar_test_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx") {
            return;
        }
        let mut rng = Rng::new(12);
        let (mut hits, mut ties) = (0, 0);
        for i in 0..20_000 {
            let count = 1 + i % 8;
            let corner = random_vec(&mut rng);
            let quads: Vec<Quad> = (0..count)
                .map(|k| {
                    // Every third case: quads sharing a corner (and some an edge).
                    let o = if i % 3 == 0 {
                        corner
                    } else {
                        random_vec(&mut rng)
                    };
                    let e = if k % 2 == 1 && i % 3 == 0 {
                        Vec3A::X
                    } else {
                        random_vec(&mut rng)
                    };
                    Quad::new(o, e, random_vec(&mut rng)).unwrap()
                })
                .collect();
            let octet = QuadOctet::new(&quads).unwrap();
            let mut o = 2.0 * random_vec(&mut rng);
            let mut d = uniform_sphere(rng.vec2());
            match i % 10 {
                0 => o = quads[0].origin + 0.5 * quads[0].eu,
                1 => d = quads[0].eu.normalize(),
                2 | 3 => d = (quads[0].origin - o).normalize(),
                4..=7 => {
                    let q = &quads[i % count];
                    let (a, b) = (1.4 * rng.f32() - 0.2, 1.4 * rng.f32() - 0.2);
                    d = (q.origin + a * q.eu + b * q.ev - o).normalize();
                }
                _ => {}
            }
            let ray = Ray::new(o, d);
            let (t_min, t_max) = if i % 3 == 1 {
                (0.5, 2.0)
            } else {
                (0.0, f32::INFINITY)
            };
            let mut want = None;
            let mut limit = t_max;
            for (lane, q) in quads.iter().enumerate() {
                if let Some(t) = q.hit_t(&ray, t_min, limit) {
                    limit = t;
                    want = Some((lane, t));
                }
            }
            let equal = quads
                .iter()
                .filter(|q| want.is_some_and(|w| q.hit_t(&ray, t_min, t_max) == Some(w.1)))
                .count();
            // SAFETY: AVX was detected above.
            let (got, occluded) = unsafe {
                (
                    octet.hit_t(&ray, t_min, t_max),
                    octet.occluded(&ray, t_min, t_max),
                )
            };
            let bits = |h: Option<(usize, f32)>| h.map(|(l, t)| (l, t.to_bits()));
            assert_eq!(bits(got), bits(want), "case {i}");
            assert_eq!(occluded, want.is_some(), "case {i}");
            hits += usize::from(want.is_some());
            ties += usize::from(want.is_some() && equal > 1);
        }
        assert!(hits > 4000, "{hits} of 20000 cases hit");
        assert!(ties > 100, "{ties} cases with equal t in two lanes");
    }
}
