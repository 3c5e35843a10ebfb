//! PCG32 (O'Neill 2014): a small, fast, statistically solid generator with selectable streams.

use glam::Vec2;

const MULT: u64 = 0x5851_f42d_4c95_7f2d;

use super::splitmix::mix64;

/// Hashes (seed, iteration, stream kind, index) into a 64-bit stream seed.
#[inline]
pub fn stream_seed(seed: u64, iteration: u32, kind: u32, index: u64) -> u64 {
    index_seed(iteration_seed(seed, iteration, kind), index)
}

/// The part of [`stream_seed`] that does not depend on the index: a loop over the items of one
/// stream and iteration (the photons of a pass) computes it once, then [`index_seed`] per item.
#[inline]
pub fn iteration_seed(seed: u64, iteration: u32, kind: u32) -> u64 {
    let a = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
    mix64(a ^ ((iteration as u64) << 32 | kind as u64))
}

/// [`stream_seed`] of item `index`, from its [`iteration_seed`].
#[inline]
pub fn index_seed(iteration_seed: u64, index: u64) -> u64 {
    mix64(iteration_seed ^ index.wrapping_mul(0xd1b5_4a32_d192_ed03))
}

/// The render seed of chain `chain` of a still rendered as several chains under `seed`. For one
/// `seed`, distinct chains get distinct seeds (two bijective mixes, the second of the chain
/// number), so their streams ([`stream_seed`]) are as apart as two iterations of one render.
pub fn chain_seed(seed: u64, chain: u32) -> u64 {
    mix64(mix64(seed ^ 0x3c6e_f372_fe94_f82b) ^ u64::from(chain))
}

/// A PCG32 generator.
#[derive(Debug, Clone)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    /// A generator whose sequence is fixed by `seed` (see [`stream_seed`]).
    pub fn new(seed: u64) -> Self {
        let inc = (mix64(seed ^ 0x6a09_e667_f3bc_c909) << 1) | 1;
        let mut r = Self { state: 0, inc };
        r.next_u32();
        r.state = r.state.wrapping_add(mix64(seed));
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    pub fn vec2(&mut self) -> Vec2 {
        Vec2::new(self.f32(), self.f32())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mean_and_range() {
        let mut r = Rng::new(stream_seed(1, 2, 3, 4));
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let x = r.f32();
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
        }
        let mean = sum / n as f64;
        assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
    }

    #[test]
    fn streams_differ() {
        let mut a = Rng::new(stream_seed(0, 0, 0, 1));
        let mut b = Rng::new(stream_seed(0, 0, 0, 2));
        assert_ne!(a.next_u32(), b.next_u32());
        assert_ne!(stream_seed(0, 1, 0, 0), stream_seed(0, 0, 0, 1));
    }
}
