//! Extra camera samples where the camera part of an estimate is noisy (a directly visible
//! light's edge, a small light's soft shadow): each pixel's camera samples so far
//! ([`SampleStats`]) and a budget of extra samples shared among the pixels in proportion to the
//! standard deviation of their samples ([`allocate`]: Neyman allocation, which minimises the
//! summed variance for a given number of samples). SPPM sizes the budget against its photon
//! pass (`sppm/balance.rs`); VCM gives a fixed share of the pixels.
//!
//! Every count comes from deterministic quantities (each pixel's own samples, summed in pixel
//! order); never from the clock.

use glam::{DVec3, Vec3A};

/// Rays per camera sample: the eye ray, the shadow ray of the light sample and the BSDF
/// sample's ray (specular bounces add a few; the photon side's gathers are not counted either,
/// so the two omissions roughly cancel).
pub(crate) const RAYS_PER_CAMERA_SAMPLE: f64 = 3.0;

/// The most extra camera samples one pixel takes in one iteration.
pub(crate) const MAX_EXTRA: u32 = 63;

/// One pixel's camera samples so far: their number and the sums of their luminance and of its
/// square, for the variance.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SampleStats {
    n: u32,
    sum: f64,
    sum2: f64,
}

impl SampleStats {
    pub(crate) fn add(&mut self, l: Vec3A) {
        let y = luminance(l.as_dvec3());
        self.n = self.n.saturating_add(1);
        self.sum += y;
        self.sum2 += y * y;
    }

    /// Whether the samples differ: a variance above rounding's (`sum2 - sum^2 / n` of equal
    /// samples can come out a few ulps above zero).
    pub(crate) fn varies(&self) -> bool {
        let n = f64::from(self.n.max(1));
        let mean = self.sum / n;
        self.variance().is_some_and(|v| v > 1e-9 * mean * mean)
    }

    /// The mean luminance of the samples; `None` with fewer than `min` (or none).
    pub(crate) fn mean_of(&self, min: u32) -> Option<f64> {
        (self.n >= min.max(1)).then(|| self.sum / f64::from(self.n))
    }

    /// The sample variance; `None` with fewer than two samples.
    pub(crate) fn variance(&self) -> Option<f64> {
        (self.n >= 2).then(|| {
            let n = f64::from(self.n);
            ((self.sum2 - self.sum * self.sum / n) / (n - 1.0)).max(0.0)
        })
    }
}

fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Each pixel's standard deviation of one camera sample (a pixel with a single sample counts
/// with the mean variance), and their sum; summed in pixel order (the same on every thread
/// count).
pub(crate) fn deviations(stats: &[SampleStats]) -> (impl Fn(&SampleStats) -> f64, f64) {
    let (mut known, mut var_sum) = (0usize, 0.0f64);
    for v in stats.iter().filter_map(SampleStats::variance) {
        known += 1;
        var_sum += v;
    }
    let mean_var = if known > 0 {
        var_sum / known as f64
    } else {
        0.0
    };
    let sd = move |s: &SampleStats| s.variance().unwrap_or(mean_var).sqrt();
    let sd_sum: f64 = stats.iter().map(&sd).sum();
    (sd, sd_sum)
}

/// The extra camera samples of every pixel for the next iteration, given each pixel's samples
/// so far and the camera pass's ray casts: a budget of
/// `camera_rays / RAYS_PER_CAMERA_SAMPLE - pixels` samples shared in proportion to the
/// pixels' standard deviations.
pub(crate) fn allocate(stats: &[SampleStats], camera_rays: u64, extra: &mut [u32]) {
    let pixels = stats.len() as f64;
    let budget = (camera_rays as f64 / RAYS_PER_CAMERA_SAMPLE - pixels).max(0.0);
    let (sd, sd_sum) = deviations(stats);
    for (e, s) in extra.iter_mut().zip(stats) {
        *e = if sd_sum > 0.0 && budget > 0.0 {
            let share = budget * sd(s) / sd_sum;
            // Whole samples, the fraction kept as the probability of one more would need a
            // random number: rounding is as good and stays deterministic.
            (share.round() as u32).min(MAX_EXTRA)
        } else {
            0
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equal samples never vary, whatever rounding leaves in `sum2 - sum^2 / n`; samples that
    /// differ in the fourth digit do.
    #[test]
    fn equal_samples_do_not_vary() {
        let mut rounding_left_some = false;
        for k in 1..400u32 {
            let v = 0.01 + f64::from(k) * 0.7377;
            let c = Vec3A::new(v as f32, (v * 0.31) as f32, (v * 1.7) as f32);
            for n in 2..40 {
                let mut s = SampleStats::default();
                (0..n).for_each(|_| s.add(c));
                rounding_left_some |= s.variance().is_some_and(|v| v > 0.0);
                assert!(!s.varies(), "{n} samples of {c}");
                let mut t = s;
                t.add(c * 1.001);
                assert!(t.varies(), "{n} samples of {c} and one 1e-3 brighter");
            }
        }
        // The case the threshold is for: without it some of these would vary.
        assert!(rounding_left_some);
    }

    /// Pixels share the budget in proportion to their standard deviations; constant pixels
    /// get none; without a photon ray there is no budget.
    #[test]
    fn the_budget_follows_the_standard_deviations() {
        let mut stats = vec![SampleStats::default(); 4];
        for (i, s) in stats.iter_mut().enumerate() {
            for k in 0..4 {
                // Pixel i alternates between 0 and i: standard deviation proportional to i.
                s.add(Vec3A::splat(if k % 2 == 0 { 0.0 } else { i as f32 }));
            }
        }
        let mut extra = vec![0; 4];
        // 4 pixels, 3 rays per sample: 36 rays are 12 samples, 8 extra.
        allocate(&stats, 36, &mut extra);
        assert_eq!(extra[0], 0);
        assert!(extra[1] < extra[2] && extra[2] < extra[3], "{extra:?}");
        let total: u32 = extra.iter().sum();
        assert!((7..=9).contains(&total), "{extra:?}");
        allocate(&stats, 0, &mut extra);
        assert_eq!(extra, [0; 4]);
    }
}
