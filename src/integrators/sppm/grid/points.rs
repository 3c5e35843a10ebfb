//! The gather's distance tests over a run of the photon grid's entry positions, four entries at
//! a time where the CPU is x86-64 (whose SSE every such CPU has): the four differences are
//! squared as `Vec3A`s, transposed, and summed as `(x + y) + z`, the order of `Vec3A`'s
//! `length_squared` (no fused multiply-add), so every point takes the photons the one-at-a-time
//! test takes, in the same order.

use glam::Vec3A;

/// Calls `f(k)` for every entry `k` in `start..end` of `points` within `r2` (squared) of `p`,
/// in increasing `k`. Entries outside `points` are none.
#[inline]
pub(super) fn within(
    points: &[Vec3A],
    start: usize,
    end: usize,
    p: Vec3A,
    r2: f32,
    f: impl FnMut(usize),
) {
    let end = end.min(points.len());
    // SAFETY: every x86-64 CPU has SSE2.
    #[cfg(target_arch = "x86_64")]
    unsafe {
        sse::within(points, start, end, p, r2, f)
    };
    #[cfg(not(target_arch = "x86_64"))]
    one_by_one(points, start, end, p, r2, f);
}

/// Asks the CPU to bring the cache line of `items[k]` in: a hint, which changes no result
/// (nothing where `k` is out of range, or on a CPU other than x86-64).
#[inline(always)]
pub(super) fn prefetch<T>(items: &[T], k: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(item) = items.get(k) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch reads nothing into the program and cannot fault; the address is
        // an element's.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((item as *const T).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (items, k);
}

/// [`within`] one entry at a time, from `start` on (`end` at most the length of `points`).
#[inline]
fn one_by_one(
    points: &[Vec3A],
    start: usize,
    end: usize,
    p: Vec3A,
    r2: f32,
    mut f: impl FnMut(usize),
) {
    for (k, q) in points.iter().enumerate().take(end).skip(start) {
        if (*q - p).length_squared() <= r2 {
            f(k);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod sse {
    use std::arch::x86_64::*;

    use glam::Vec3A;

    /// [`super::within`] four entries at a time. A group of four may reach past `end` (into
    /// the next bucket's entries, never past `points`): the lanes past `end` are dropped.
    ///
    /// # Safety
    ///
    /// The CPU must have SSE2 (every x86-64 CPU has).
    #[target_feature(enable = "sse2")]
    #[inline]
    pub(super) fn within(
        points: &[Vec3A],
        start: usize,
        end: usize,
        p: Vec3A,
        r2: f32,
        mut f: impl FnMut(usize),
    ) {
        let (pv, r2v) = (__m128::from(p), _mm_set1_ps(r2));
        let mut k = start;
        while k < end {
            let Some(&[a, b, c, d]) = points.get(k..k + 4) else {
                // Fewer than four entries left in the whole array.
                super::one_by_one(points, k, end, p, r2, f);
                return;
            };
            // Each entry's squared differences, as `Vec3A::length_squared` multiplies them.
            let sq = [a, b, c, d].map(|q| {
                let v = _mm_sub_ps(__m128::from(q), pv);
                _mm_mul_ps(v, v)
            });
            // Transposed: the four entries' x, y and z in one register each.
            let lo01 = _mm_unpacklo_ps(sq[0], sq[1]);
            let lo23 = _mm_unpacklo_ps(sq[2], sq[3]);
            let hi01 = _mm_unpackhi_ps(sq[0], sq[1]);
            let hi23 = _mm_unpackhi_ps(sq[2], sq[3]);
            let (x, y, z) = (
                _mm_movelh_ps(lo01, lo23),
                _mm_movehl_ps(lo23, lo01),
                _mm_movelh_ps(hi01, hi23),
            );
            let d2 = _mm_add_ps(_mm_add_ps(x, y), z);
            // `<=`, false for NaN (an ordered compare), as the scalar test.
            let mut mask = _mm_movemask_ps(_mm_cmple_ps(d2, r2v)) as u32;
            if end - k < 4 {
                mask &= (1 << (end - k)) - 1;
            }
            while mask != 0 {
                let j = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                f(k + j);
            }
            k += 4;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// The four-at-a-time test takes exactly the entries the `Vec3A` test takes, in order, for
    /// runs of every length and offset (to the array's end and past it), points exactly on
    /// the radius included.
    #[test]
    fn within_matches_the_vec3a_test() {
        let mut rng = Rng::new(5);
        let n = 300;
        let q: Vec<Vec3A> = (0..n)
            .map(|_| Vec3A::new(rng.f32(), rng.f32(), rng.f32()))
            .collect();
        let (mut taken, mut left, mut edges) = (0, 0, 0);
        for i in 0..2000 {
            let p = Vec3A::new(rng.f32(), rng.f32(), rng.f32());
            let start = (i * 7) % (n + 3);
            let end = start + i % 13;
            // Every fourth radius: exactly an entry's distance (the test is `<=`).
            let r2 = if i % 4 == 0 && start < n {
                edges += 1;
                (q[start + (i % 3).min(n - 1 - start)] - p).length_squared()
            } else {
                0.3 * rng.f32()
            };
            let want: Vec<usize> = (start..end.min(n))
                .filter(|&k| (q[k] - p).length_squared() <= r2)
                .collect();
            let mut got = Vec::new();
            within(&q, start, end, p, r2, |k| got.push(k));
            assert_eq!(got, want, "run {start}..{end}");
            taken += want.len();
            left += end.min(n).saturating_sub(start) - want.len();
        }
        assert!(
            taken > 2000 && left > 2000 && edges > 400,
            "{taken} taken, {left} left"
        );
    }
}
