//! Perlin gradient noise, turbulence, and the `noise`, `marble` and `wood` patterns built on it.
//!
//! The noise is Ken Perlin's "improved" gradient noise (quintic fade, the twelve cube-edge
//! gradients). Its permutation table is a compile-time constant shuffled by our own code from a
//! fixed seed, so every evaluation everywhere gives the same value: no global state, no entropy.

use crate::sampling::splitmix64;

/// The seed the permutation table is shuffled from. Changing it changes every noisy texture.
const SEED: u64 = 0x5eed_0f9e_7a11_a5e7;

/// A Fisher–Yates shuffle of 0..=255 from `seed`, doubled to 512 entries so that lookups
/// `perm[perm[x] + y]` never need a wrap.
const fn build_permutation(seed: u64) -> [u8; 512] {
    let mut p = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        p[i] = i as u8;
        i += 1;
    }
    let mut state = seed;
    let mut i = 255;
    while i > 0 {
        let (next, r) = splitmix64(state);
        state = next;
        let j = (r % (i as u64 + 1)) as usize;
        let t = p[i];
        p[i] = p[j];
        p[j] = t;
        i -= 1;
    }
    let mut out = [0u8; 512];
    let mut i = 0;
    while i < 512 {
        out[i] = p[i & 255];
        i += 1;
    }
    out
}

static PERM: [u8; 512] = build_permutation(SEED);

#[inline]
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lerp(t: f64, a: f64, b: f64) -> f64 {
    a + t * (b - a)
}

/// Perlin's improved-noise gradient rule: for the low 4 bits `h` of a hash, `u` is x (h < 8)
/// or y, `v` is y (h < 4), x (h = 12, 14) or z, and the result is `±u ± v` with the signs from
/// bits 0 and 1. Returned as the gradient vector.
const fn gradient_of(h: u8) -> [f64; 3] {
    let mut g = [0.0; 3];
    let (u, v) = (
        if h < 8 { 0 } else { 1 },
        if h < 4 {
            1
        } else if h == 12 || h == 14 {
            0
        } else {
            2
        },
    );
    g[u] += if h & 1 == 0 { 1.0 } else { -1.0 };
    g[v] += if h & 2 == 0 { 1.0 } else { -1.0 };
    g
}

const fn gradient_table() -> [[f64; 3]; 16] {
    let mut t = [[0.0; 3]; 16];
    let mut h = 0;
    while h < 16 {
        t[h] = gradient_of(h as u8);
        h += 1;
    }
    t
}

/// The 16 gradients (the 12 cube edges, four of them twice), looked up instead of branched on:
/// hash bits are random, so branches on them would mispredict.
static GRADIENTS: [[f64; 3]; 16] = gradient_table();

#[inline]
fn grad(hash: u8, x: f64, y: f64, z: f64) -> f64 {
    let g = &GRADIENTS[(hash & 15) as usize];
    g[0] * x + g[1] * y + g[2] * z
}

/// The lattice cell (mod 256) and the fraction within it. Coordinates that are not finite or
/// beyond 1e15 (where f64 has no fraction left) count as 0. `floor` by integer conversion: it
/// avoids a libm call on targets without a rounding instruction.
#[inline]
fn split(x: f64) -> (usize, f64) {
    let x = if x.abs() < 1e15 { x } else { 0.0 };
    let i = x as i64;
    let i = if (i as f64) > x { i - 1 } else { i };
    // Two's complement keeps the low bits right for negative cells.
    ((i & 255) as usize, x - i as f64)
}

/// Perlin gradient noise at `p`, in about [-1, 1] (exactly 0 on integer lattice points).
/// Non-finite coordinates count as 0.
pub fn perlin(x: f64, y: f64, z: f64) -> f64 {
    let (xi, x) = split(x);
    let (yi, y) = split(y);
    let (zi, z) = split(z);
    let (u, v, w) = (fade(x), fade(y), fade(z));
    let p = &PERM;
    let a = p[xi] as usize + yi;
    let aa = p[a] as usize + zi;
    let ab = p[a + 1] as usize + zi;
    let b = p[xi + 1] as usize + yi;
    let ba = p[b] as usize + zi;
    let bb = p[b + 1] as usize + zi;
    lerp(
        w,
        lerp(
            v,
            lerp(u, grad(p[aa], x, y, z), grad(p[ba], x - 1.0, y, z)),
            lerp(
                u,
                grad(p[ab], x, y - 1.0, z),
                grad(p[bb], x - 1.0, y - 1.0, z),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(p[aa + 1], x, y, z - 1.0),
                grad(p[ba + 1], x - 1.0, y, z - 1.0),
            ),
            lerp(
                u,
                grad(p[ab + 1], x, y - 1.0, z - 1.0),
                grad(p[bb + 1], x - 1.0, y - 1.0, z - 1.0),
            ),
        ),
    )
}

/// Octave count used when a file asks for 0 (one octave) or an absurd number (capped at 16:
/// beyond that the octaves are finer than f64 resolves at unit scale anyway).
#[inline]
fn octave_count(octaves: u32) -> u32 {
    octaves.clamp(1, 16)
}

/// Fractal sum of `octaves` noise octaves (frequency doubling, amplitude halving), normalised
/// by the amplitude sum so the result stays in about [-1, 1].
pub fn fbm(x: f64, y: f64, z: f64, octaves: u32) -> f64 {
    let (mut sum, mut amp, mut norm, mut f) = (0.0, 1.0, 0.0, 1.0);
    for _ in 0..octave_count(octaves) {
        sum += amp * perlin(x * f, y * f, z * f);
        norm += amp;
        amp *= 0.5;
        f *= 2.0;
    }
    sum / norm
}

/// Turbulence: the fractal sum of `|noise|`, normalised to [0, about 1].
pub fn turbulence(x: f64, y: f64, z: f64, octaves: u32) -> f64 {
    let (mut sum, mut amp, mut norm, mut f) = (0.0, 1.0, 0.0, 1.0);
    for _ in 0..octave_count(octaves) {
        sum += amp * perlin(x * f, y * f, z * f).abs();
        norm += amp;
        amp *= 0.5;
        f *= 2.0;
    }
    sum / norm
}

/// Triangle wave of period 1: 0 at integers, 1 at half-integers.
#[inline]
fn triangle(t: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    let f = t - t.floor();
    1.0 - (2.0 * f - 1.0).abs()
}

/// The `noise` pattern value in [0, 1]: `0.5 + 0.5 * fbm`, clamped.
pub fn noise_value(x: f64, y: f64, z: f64, octaves: u32) -> f64 {
    (0.5 + 0.5 * fbm(x, y, z, octaves)).clamp(0.0, 1.0)
}

/// The `marble` pattern value in [0, 1]: veins perpendicular to x, a triangle wave of period 1
/// over `x + turbulence * turb(p)`.
pub fn marble_value(x: f64, y: f64, z: f64, amount: f64, octaves: u32) -> f64 {
    let amount = if amount.is_finite() { amount } else { 0.0 };
    triangle(x + amount * turbulence(x, y, z, octaves)).clamp(0.0, 1.0)
}

/// The `wood` pattern value in [0, 1]: rings around the z axis one unit apart, a triangle wave
/// over `sqrt(x² + y²) + turbulence * turb(p)`.
pub fn wood_value(x: f64, y: f64, z: f64, amount: f64, octaves: u32) -> f64 {
    let amount = if amount.is_finite() { amount } else { 0.0 };
    let r = (x * x + y * y).sqrt();
    triangle(r + amount * turbulence(x, y, z, octaves)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(n: usize) -> impl Iterator<Item = (f64, f64, f64)> {
        // A deterministic scatter over a box that spans several lattice cells and negatives.
        (0..n).map(|i| {
            let t = i as f64;
            (
                (t * 0.618_034).fract() * 40.0 - 20.0,
                (t * 0.414_213_5).fract() * 40.0 - 20.0,
                (t * 0.732_050_8).fract() * 40.0 - 20.0,
            )
        })
    }

    #[test]
    fn permutation_is_a_permutation() {
        let mut seen = [false; 256];
        for &v in &PERM[..256] {
            seen[v as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
        assert_eq!(PERM[..256], PERM[256..]);
        // Not the identity: the shuffle did something.
        assert!(
            PERM[..256]
                .iter()
                .enumerate()
                .filter(|(i, v)| *i == **v as usize)
                .count()
                < 16
        );
    }

    #[test]
    fn noise_is_deterministic_and_in_range() {
        let (mut lo, mut hi, mut sum, mut n) = (f64::MAX, f64::MIN, 0.0, 0);
        for (x, y, z) in points(200_000) {
            let a = perlin(x, y, z);
            assert_eq!(a.to_bits(), perlin(x, y, z).to_bits());
            lo = lo.min(a);
            hi = hi.max(a);
            sum += a;
            n += 1;
        }
        println!(
            "perlin range [{lo:.4}, {hi:.4}], mean {:.4}",
            sum / n as f64
        );
        assert!(lo >= -1.05 && hi <= 1.05, "range [{lo}, {hi}]");
        // It actually varies, both ways, around a mean near zero.
        assert!(lo < -0.6 && hi > 0.6, "range [{lo}, {hi}]");
        assert!((sum / n as f64).abs() < 0.02);
        // A fixed value: the table is built from a fixed seed, not from anything at run time.
        let a = perlin(0.3, 1.7, -2.2);
        let b = perlin(0.3, 1.7, -2.2);
        assert_eq!(a, b);
        assert_eq!(perlin(3.0, -4.0, 5.0), 0.0);
    }

    #[test]
    fn gradient_table_follows_the_improved_noise_rule() {
        // The reference rule, written with branches as in Perlin's paper.
        fn reference(h: u8, x: f64, y: f64, z: f64) -> f64 {
            let h = h & 15;
            let u = if h < 8 { x } else { y };
            let v = if h < 4 {
                y
            } else if h == 12 || h == 14 {
                x
            } else {
                z
            };
            (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
        }
        for h in 0..=255u8 {
            let (x, y, z) = (0.3, -0.7, 0.45);
            assert_eq!(grad(h, x, y, z), reference(h, x, y, z), "hash {h}");
        }
        // Every gradient is a cube edge: two components ±1, one 0.
        for g in GRADIENTS {
            assert_eq!(g.iter().filter(|c| c.abs() == 1.0).count(), 2);
        }
    }

    #[test]
    fn noise_is_continuous() {
        for (x, y, z) in points(2_000) {
            let a = perlin(x, y, z);
            let b = perlin(x + 1e-6, y - 1e-6, z + 1e-6);
            assert!((a - b).abs() < 1e-4, "jump at ({x}, {y}, {z})");
        }
    }

    #[test]
    fn patterns_are_in_unit_range_and_vary() {
        for octaves in [0, 1, 4, 1000] {
            let (mut lo, mut hi) = (1.0f64, 0.0f64);
            for (x, y, z) in points(20_000) {
                for v in [
                    noise_value(x, y, z, octaves),
                    marble_value(x, y, z, 1.5, octaves),
                    wood_value(x, y, z, 0.3, octaves),
                    turbulence(x, y, z, octaves),
                ] {
                    assert!((0.0..=1.0).contains(&v));
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            assert!(lo < 0.1 && hi > 0.9, "octaves {octaves}: [{lo}, {hi}]");
        }
        // Garbage in does not panic and stays in range.
        for v in [f64::NAN, f64::INFINITY, -1e300] {
            assert!((0.0..=1.0).contains(&noise_value(v, 0.5, v, 3)));
            assert!((0.0..=1.0).contains(&marble_value(v, 0.5, v, f64::NAN, 3)));
            assert!((0.0..=1.0).contains(&wood_value(v, v, 0.5, 1.0, 3)));
        }
    }

    #[test]
    fn wood_rings_without_turbulence_are_one_unit_apart() {
        assert!(wood_value(1.0, 0.0, 0.0, 0.0, 1) < 1e-12);
        assert!((wood_value(0.0, 1.5, 3.0, 0.0, 1) - 1.0).abs() < 1e-12);
        assert!((wood_value(0.6, 0.8, -7.0, 0.0, 1)).abs() < 1e-12);
        assert!((marble_value(2.25, 9.0, 9.0, 0.0, 1) - 0.5).abs() < 1e-12);
    }
}
