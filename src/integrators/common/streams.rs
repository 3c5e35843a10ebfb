//! The random streams of every integrator. A generator is seeded from (render seed, iteration,
//! stream, index) by [`stream_seed`]; the stream keeps the sequences of different uses apart
//! (SPPM's camera pass and its photons, say, draw from different sequences for the same index).
//! The numeric values are part of every image: changing one changes the renders that use it.

use crate::sampling::{Rng, index_seed, iteration_seed, stream_seed};

/// One use of random numbers. The discriminants are the stream numbers given to
/// [`stream_seed`] (the compiler rejects two variants with the same number).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub(crate) enum Stream {
    /// SPPM's and PPM's camera pass, indexed by pixel.
    Camera = 0,
    /// SPPM's and PPM's photon pass, indexed by photon (also
    /// [`crate::integrators::sppm::photon_flux`]).
    Photon = 1,
    /// The per-pixel samples of the progressive loop (path, Whitted, photon mapping's eye rays),
    /// indexed by pixel.
    Pixel = 2,
    /// Photon mapping's photons, indexed by photon.
    PhotonMap = 3,
    /// Whitted's adaptive supersamples, indexed by pixel.
    Supersample = 4,
    /// SPPM's extra camera samples (emitted and direct light only), indexed by pixel.
    CameraExtra = 5,
    /// SPPM's final-gather paths, indexed by pixel.
    Gather = 6,
    /// VCM's (and BPT's, light tracing's) light paths, indexed by path.
    VcmLight = 7,
    /// VCM's camera paths, indexed by pixel.
    VcmCamera = 8,
    /// VCM's extra camera paths (where a pixel's camera paths vary most), indexed by pixel.
    VcmCameraExtra = 9,
}

impl Stream {
    #[cfg(test)]
    const ALL: [Stream; 10] = [
        Stream::Camera,
        Stream::Photon,
        Stream::Pixel,
        Stream::PhotonMap,
        Stream::Supersample,
        Stream::CameraExtra,
        Stream::Gather,
        Stream::VcmLight,
        Stream::VcmCamera,
        Stream::VcmCameraExtra,
    ];

    /// The generator of item `index` of this stream in iteration `iteration`.
    #[inline]
    pub(crate) fn rng(self, seed: u64, iteration: u32, index: u64) -> Rng {
        Rng::new(stream_seed(seed, iteration, self as u32, index))
    }

    /// The generators of this stream in iteration `iteration`, for a loop over many items:
    /// the part of the seed they share is hashed once (two of the three mixes per item).
    #[inline]
    pub(crate) fn rngs(self, seed: u64, iteration: u32) -> StreamRngs {
        StreamRngs(iteration_seed(seed, iteration, self as u32))
    }
}

/// [`Stream::rngs`]: the generators of one stream and iteration.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StreamRngs(u64);

impl StreamRngs {
    /// The generator of item `index`: the one [`Stream::rng`] gives.
    #[inline]
    pub(crate) fn rng(self, index: u64) -> Rng {
        Rng::new(index_seed(self.0, index))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every stream has its own number, and the numbers are those the stored images were
    /// rendered with.
    #[test]
    fn streams_are_distinct_and_keep_their_numbers() {
        let ids = Stream::ALL.map(|s| s as u32);
        for (i, a) in ids.iter().enumerate() {
            assert!(!ids[i + 1..].contains(a), "stream {a} used twice");
        }
        assert_eq!(ids, [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
    }

    /// A stream's generators from [`Stream::rngs`] draw the same numbers as [`Stream::rng`]
    /// for every item (the photon pass uses the first, the images were made with the second).
    #[test]
    fn hoisted_generators_are_the_same() {
        for stream in Stream::ALL {
            for (seed, iteration) in [(0, 0), (1, 3), (u64::MAX, u32::MAX)] {
                let rngs = stream.rngs(seed, iteration);
                for index in [0, 1, 2, 4095, 1 << 40, u64::MAX] {
                    let (mut a, mut b) = (rngs.rng(index), stream.rng(seed, iteration, index));
                    let (a, b): (Vec<u32>, Vec<u32>) =
                        (0..4).map(|_| (a.next_u32(), b.next_u32())).unzip();
                    assert_eq!(
                        a, b,
                        "{stream:?} seed {seed} iteration {iteration} index {index}"
                    );
                }
            }
        }
    }
}
