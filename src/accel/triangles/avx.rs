//! The leaf tests with AVX: two packets as eight lanes (the operations of
//! [`TrianglePacket::hits`], in the same order, with comparisons of the same NaN behaviour, so
//! each lane gives the same bits), and the ray's broadcasts set up once per query for both
//! that test and the four-lane one (which takes their low halves).

use std::arch::x86_64::*;

use glam::{BVec4A, Vec4};

use super::TrianglePacket;
use crate::geometry::Ray;

type V3 = [__m256; 3];

/// The ray's direction and origin, each coordinate broadcast to eight lanes.
pub(crate) struct Lanes {
    d: V3,
    o: V3,
}

/// `x` broadcast to eight lanes, as a value the compiler cannot see through: otherwise it
/// folds the low half that the four-lane test takes into a broadcast of its own, and each
/// query made (and spilled) both.
///
/// # Safety
///
/// The CPU must have AVX.
#[target_feature(enable = "avx")]
#[inline]
unsafe fn opaque_splat(x: f32) -> __m256 {
    let mut v = _mm256_set1_ps(x);
    // SAFETY: an empty template: `v` is left as it is, in a register.
    unsafe {
        std::arch::asm!("/* {0} */", inout(ymm_reg) v, options(pure, nomem, nostack, preserves_flags));
    }
    v
}

/// The ray set up for the leaf tests (once per query).
///
/// # Safety
///
/// The CPU must have AVX.
#[target_feature(enable = "avx")]
#[inline]
pub(super) unsafe fn lanes(ray: &Ray) -> Lanes {
    // SAFETY: the caller's AVX.
    unsafe {
        Lanes {
            d: [
                opaque_splat(ray.d.x),
                opaque_splat(ray.d.y),
                opaque_splat(ray.d.z),
            ],
            o: [
                opaque_splat(ray.o.x),
                opaque_splat(ray.o.y),
                opaque_splat(ray.o.z),
            ],
        }
    }
}

/// The ray set up for the leaf tests, as broadcasts the compiler sees through.
///
/// # Safety
///
/// The CPU must have AVX.
#[target_feature(enable = "avx")]
#[inline]
pub(super) unsafe fn plain_lanes(ray: &Ray) -> Lanes {
    Lanes {
        d: [ray.d.x, ray.d.y, ray.d.z].map(|c| _mm256_set1_ps(c)),
        o: [ray.o.x, ray.o.y, ray.o.z].map(|c| _mm256_set1_ps(c)),
    }
}

/// [`TrianglePacket::hits`] with the low halves of `lanes`: the same operations on the
/// same values, so the same bits.
///
/// # Safety
///
/// The CPU must have AVX.
#[target_feature(enable = "avx")]
#[inline]
pub(super) unsafe fn packet_hits(
    lanes: &Lanes,
    packet: &TrianglePacket,
    t_min: f32,
    t_max: f32,
) -> (BVec4A, Vec4, [Vec4; 2]) {
    let half =
        |v: &V3| -> [Vec4; 3] { [0, 1, 2].map(|a| Vec4::from(_mm256_castps256_ps128(v[a]))) };
    packet.hits_with(&half(&lanes.d), &half(&lanes.o), t_min, t_max)
}

/// The eight lanes' mask (bit `k`: lane `k`; the first packet's lanes are 0..4), `t` and
/// barycentric coordinates.
///
/// # Safety
///
/// The CPU must have AVX.
#[target_feature(enable = "avx")]
#[inline]
pub(super) unsafe fn hits(
    lanes: &Lanes,
    pair: &[TrianglePacket; 2],
    t_min: f32,
    t_max: f32,
) -> (u32, __m256, __m256, __m256) {
    let [a, b] = pair;
    let join = |x: glam::Vec4, y: glam::Vec4| {
        _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(x.into()), y.into())
    };
    let field = |f: fn(&TrianglePacket) -> &[glam::Vec4; 3]| -> V3 {
        let (x, y) = (f(a), f(b));
        [join(x[0], y[0]), join(x[1], y[1]), join(x[2], y[2])]
    };
    let (v0, e1, e2) = (field(|p| &p.v0), field(|p| &p.e1), field(|p| &p.e2));
    let mul = |x, y| _mm256_mul_ps(x, y);
    let add = |x, y| _mm256_add_ps(x, y);
    let sub = |x, y| _mm256_sub_ps(x, y);
    let dot = |x: &V3, y: &V3| add(add(mul(x[0], y[0]), mul(x[1], y[1])), mul(x[2], y[2]));
    let cross = |x: &V3, y: &V3| -> V3 {
        [
            sub(mul(x[1], y[2]), mul(x[2], y[1])),
            sub(mul(x[2], y[0]), mul(x[0], y[2])),
            sub(mul(x[0], y[1]), mul(x[1], y[0])),
        ]
    };
    let (d, o) = (&lanes.d, &lanes.o);
    let pv = cross(d, &e2);
    let det = dot(&e1, &pv);
    let one = _mm256_set1_ps(1.0);
    let inv = _mm256_div_ps(one, det);
    let tv = [sub(o[0], v0[0]), sub(o[1], v0[1]), sub(o[2], v0[2])];
    let b1 = mul(dot(&tv, &pv), inv);
    let qv = cross(&tv, &e1);
    let b2 = mul(dot(d, &qv), inv);
    let t = mul(dot(&e2, &qv), inv);
    let zero = _mm256_setzero_ps();
    let abs = _mm256_andnot_ps(_mm256_set1_ps(-0.0), det);
    // `cmpneq` and the negated `<`, `>` are true on NaN, the others false, as in
    // `TrianglePacket::hits`.
    let and = |x, y| _mm256_and_ps(x, y);
    let mask = and(
        and(
            and(
                _mm256_cmp_ps::<_CMP_NEQ_UQ>(det, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(abs, _mm256_set1_ps(f32::INFINITY)),
            ),
            and(
                _mm256_cmp_ps::<_CMP_GE_OQ>(b1, zero),
                _mm256_cmp_ps::<_CMP_LE_OQ>(b1, one),
            ),
        ),
        and(
            and(
                _mm256_cmp_ps::<_CMP_NLT_UQ>(b2, zero),
                _mm256_cmp_ps::<_CMP_NGT_UQ>(add(b1, b2), one),
            ),
            and(
                _mm256_cmp_ps::<_CMP_GT_OQ>(t, _mm256_set1_ps(t_min)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(t, _mm256_set1_ps(t_max)),
            ),
        ),
    );
    (_mm256_movemask_ps(mask) as u32, t, b1, b2)
}

/// [`TrianglePacket::hit_t`] over the eight lanes.
///
/// # Safety
///
/// The CPU must have AVX.
#[target_feature(enable = "avx")]
#[inline]
pub(super) unsafe fn hit_t(
    lanes: &Lanes,
    pair: &[TrianglePacket; 2],
    t_min: f32,
    t_max: f32,
) -> Option<(u32, f32, [f32; 2])> {
    // SAFETY: the caller's AVX.
    let (mask, t, b1, b2) = unsafe { hits(lanes, pair, t_min, t_max) };
    if mask == 0 {
        return None;
    }
    let mut ts = [0.0f32; 8];
    // SAFETY: `ts` holds eight `f32`s.
    unsafe { _mm256_storeu_ps(ts.as_mut_ptr(), t) };
    // The lowest of the nearest lanes, as a scalar loop keeps.
    let mut lane = mask.trailing_zeros() as usize;
    let mut rest = mask & (mask - 1);
    while rest != 0 {
        let k = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        if ts[k] < ts[lane] {
            lane = k;
        }
    }
    let (mut b1s, mut b2s) = ([0.0f32; 8], [0.0f32; 8]);
    // SAFETY: as above.
    unsafe {
        _mm256_storeu_ps(b1s.as_mut_ptr(), b1);
        _mm256_storeu_ps(b2s.as_mut_ptr(), b2);
    }
    Some((
        pair[lane / 4].ids[lane % 4],
        ts[lane],
        [b1s[lane], b2s[lane]],
    ))
}
