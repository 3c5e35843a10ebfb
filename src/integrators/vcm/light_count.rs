//! How many light paths an iteration traces, as a share of the pixels. One a pixel suits
//! scenes whose light arrives by way of glass (merging and light tracing carry the caustics);
//! where smooth direct light dominates (a glossy vase, the teapot) a quarter as many do
//! better even per iteration: light tracing and merging, whose weights grow with the count,
//! then leave more of the weight to next-event estimation and BSDF sampling, and an iteration
//! costs less. Which holds is measured: the first [`PILOT`] iterations alternate the two
//! counts, each pixel's values are kept apart by count, and the count whose iterations vary
//! less over the image (the sum of the pixels' variances) is kept from then on. Each iteration
//! is unbiased on its own, so the image stays unbiased. The choice comes from the pixel values
//! alone, summed in pixel order: the same on any thread count.

use glam::Vec3A;

use crate::integrators::common::camera_samples::SampleStats;

/// The shares of the pixels tried: every pixel, a quarter of them.
pub(super) const SHARES: [f64; 2] = [1.0, 0.25];

/// Iterations that alternate the two shares before one is kept (half of them each).
pub(super) const PILOT: u32 = 12;

/// The pilot's per-pixel sums and the share chosen.
#[derive(Debug, Default)]
pub(super) struct LightCount {
    /// Per pixel and share: that share's pilot iterations of the pixel.
    sums: Vec<[SampleStats; 2]>,
    runs: [u32; 2],
    chosen: Option<usize>,
}

impl LightCount {
    /// Which of [`SHARES`] iteration `iter` (from 0) uses.
    pub(super) fn choice(&self, iter: u32) -> usize {
        self.chosen.unwrap_or(iter as usize % 2)
    }

    /// The light paths iteration `iter` traces for `pixels` pixels (at least one).
    pub(super) fn light_paths(&self, iter: u32, pixels: usize) -> usize {
        ((pixels as f64 * SHARES[self.choice(iter)]).round() as usize).max(1)
    }

    /// Records iteration `iter`'s pixel values; at the end of the pilot, keeps the share
    /// whose iterations varied less (every pixel's sample variance summed; on a tie, all
    /// the pixels).
    pub(super) fn observe(&mut self, iter: u32, values: &[Vec3A]) {
        if self.chosen.is_some() {
            return;
        }
        let k = self.choice(iter);
        self.sums.resize(values.len(), [SampleStats::default(); 2]);
        for (s, v) in self.sums.iter_mut().zip(values) {
            s[k].add(*v);
        }
        self.runs[k] += 1;
        if self.runs[0] + self.runs[1] >= PILOT {
            let variance = |k: usize| {
                self.sums
                    .iter()
                    .map(|s| s[k].variance().unwrap_or(0.0))
                    .sum::<f64>()
            };
            let (full, fewer) = (variance(0), variance(1));
            self.chosen = Some(if fewer < full { 1 } else { 0 });
            self.sums = Vec::new();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Feeds the pilot iterations whose pixels scatter by `spread[k]` around 1 with share k.
    fn pilot(spread: [f32; 2]) -> LightCount {
        let mut lc = LightCount::default();
        let mut rng = Rng::new(7);
        for iter in 0..PILOT {
            assert_eq!(
                lc.choice(iter),
                iter as usize % 2,
                "alternates during the pilot"
            );
            let s = spread[lc.choice(iter)];
            let values: Vec<Vec3A> = (0..64)
                .map(|_| Vec3A::splat(1.0 + s * (rng.f32() - 0.5)))
                .collect();
            lc.observe(iter, &values);
        }
        lc
    }

    /// The share whose iterations vary less is kept for every later iteration.
    #[test]
    fn keeps_the_share_that_varies_less() {
        let fewer = pilot([1.0, 0.3]);
        let full = pilot([0.3, 1.0]);
        for iter in PILOT..PILOT + 5 {
            assert_eq!(fewer.choice(iter), 1);
            assert_eq!(full.choice(iter), 0);
        }
        assert_eq!(fewer.light_paths(PILOT, 1000), 250);
        assert_eq!(full.light_paths(PILOT, 1000), 1000);
        // Never none, however few the pixels.
        assert_eq!(fewer.light_paths(PILOT, 1), 1);
    }

    /// Equal variances (here none) keep a light path for every pixel.
    #[test]
    fn a_tie_keeps_every_pixel() {
        assert_eq!(pilot([0.0, 0.0]).choice(PILOT), 0);
    }
}
