//! splitmix64 as an f64 stream: the seeded generator of test and benchmark ray sets (the
//! Bezier stress test and `sppm-measure bezier` draw the same rays from it). Renders use
//! [`super::Rng`].

use glam::DVec3;

/// splitmix64's increment (the golden ratio in 64 bits).
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// splitmix64's finaliser: a bijective 64-bit mix in which every input bit reaches every
/// output bit.
pub const fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// One step of splitmix64 (Steele, Lea and Flood 2014) from `state`: the next state and the
/// output. The one definition of the generator in the crate (`const`: tables are built with
/// it at compile time).
pub const fn splitmix64(state: u64) -> (u64, u64) {
    let state = state.wrapping_add(GOLDEN);
    (state, mix64(state))
}

/// splitmix64 as a stream of 53-bit uniform doubles.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(state: u64) -> Self {
        Self(state)
    }

    /// The stream of item `i` of kind `kind` under `seed`: independent of the order (and the
    /// thread) in which items are made. The first value is skipped.
    pub fn for_item(seed: u64, kind: usize, i: usize) -> Self {
        let mut r =
            Self(seed.wrapping_mul(0xD134_2543_DE82_EF95) ^ ((kind as u64) << 48) ^ (i as u64));
        r.f();
        r
    }

    /// Uniform in [0, 1).
    pub fn f(&mut self) -> f64 {
        let (state, z) = splitmix64(self.0);
        self.0 = state;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.f()
    }

    /// A uniform unit vector (rejection from the cube).
    pub fn unit(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length_squared();
            if l > 1e-6 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }

    /// +1 or -1 with equal odds.
    pub fn sign(&mut self) -> f64 {
        if self.f() < 0.5 { 1.0 } else { -1.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_uniform_and_distinct() {
        let a: Vec<f64> = (0..1000)
            .map(|_| 0.0)
            .scan(SplitMix64::for_item(7, 0, 3), |r, _: f64| Some(r.f()))
            .collect();
        let b: Vec<f64> = (0..1000)
            .map(|_| 0.0)
            .scan(SplitMix64::for_item(7, 0, 3), |r, _: f64| Some(r.f()))
            .collect();
        assert_eq!(a, b);
        assert!(a.iter().all(|v| (0.0..1.0).contains(v)));
        let mean = a.iter().sum::<f64>() / a.len() as f64;
        assert!((mean - 0.5).abs() < 0.05, "{mean}");
        let mut c = SplitMix64::for_item(7, 1, 3);
        assert_ne!(a[0], c.f());
        let u = SplitMix64::new(1).unit();
        assert!((u.length() - 1.0).abs() < 1e-12);
    }
}
