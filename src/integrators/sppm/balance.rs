//! The balance of camera samples against photons. Each SPPM iteration gives every pixel one
//! camera path (its visible point, with the emitted and directly lit light it meets); the
//! photon pass usually costs far more. Where the camera part's own variance is large (a
//! directly visible light's edge, a small light's soft shadow) one sample per iteration starves
//! it: at equal time a path tracer gives such a pixel many more samples. So every iteration
//! also traces extra camera samples, for the emitted and direct part only (their visible points
//! are not kept), shared among the pixels in proportion to the standard deviation of their
//! camera samples so far (Neyman allocation: it minimises the summed variance for a given
//! number of samples).
//!
//! How many: the camera pass casts `ratio` times the photon pass's rays, and the automatic
//! photon count (`photon_count.rs`) gives the photons their share of the same total. The ratio
//! is 1 until both parts' noise is known, then the one that minimises the image's summed
//! variance at equal time, [`camera_share`], from the camera samples' deviations and the
//! photons' counting noise ([`PhotonNoise`]), within 2 to 8 ([`SPLIT_RANGE`]: the lower
//! bound measured): a scene lit mostly directly (an environment map's sun) moves more of its
//! casts to the camera pass.
//!
//! VCM shares its extra camera paths among the pixels with the same [`SampleStats`] and
//! [`allocate`] (`integrators/vcm/mod.rs`), for a fixed budget.
//!
//! Every count comes from deterministic quantities: the photon pass's traced segments (a count
//! of ray casts, the same on any thread count and machine load), each pixel's own samples and
//! the photons it gathered, summed in pixel order; never from the clock.

use std::f64::consts::PI;

use glam::{DVec3, Vec3A};

use super::pixels::Pixel;

/// Rays per camera sample: the eye ray, the shadow ray of the light sample and the BSDF
/// sample's ray (specular bounces add a few; the photon side's gathers are not counted either,
/// so the two omissions roughly cancel).
pub(crate) const RAYS_PER_CAMERA_SAMPLE: f64 = 3.0;

/// The most extra camera samples one pixel takes in one iteration.
pub(super) const MAX_EXTRA: u32 = 63;

/// One pixel's camera samples so far: their number and the sums of their luminance and of its
/// square, for the variance.
#[derive(Clone, Copy, Default)]
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

    /// The sample variance; `None` with fewer than two samples.
    fn variance(&self) -> Option<f64> {
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
fn deviations(stats: &[SampleStats]) -> (impl Fn(&SampleStats) -> f64, f64) {
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

/// The noise of the photon part: `V`, the sum over the pixels of `v_i`, where pixel `i`'s
/// photon estimate from one iteration of `M` photons (the luminance of its gathered flux times
/// its visible point's throughput, over `M pi r^2`) has variance `v_i / M`. The estimate is a
/// sum of the photons' contributions `c_j`, each found near the point by chance, so its
/// variance is about `sum c_j^2 / (M pi r^2)^2` (the photons' counting noise alone: where the
/// visible point itself moves from iteration to iteration, over texture or edges, that part of
/// the noise falls with the iterations, not with the photons). The estimates are averaged over
/// the iterations with a weight of [`NOISE_WEIGHT`] for the newest, since `v_i` grows as the
/// radius shrinks.
#[derive(Default)]
pub(super) struct PhotonNoise {
    v: Option<f64>,
}

/// The weight of the newest iteration in [`PhotonNoise`]'s average.
const NOISE_WEIGHT: f64 = 0.3;

impl PhotonNoise {
    /// One iteration of `photons` photons: for the visible points (and with final gathering
    /// the gather points), each pixel's point with its radius before the update and its sum
    /// of squared contributions (zeroed here). Pixels without a point count 0.
    pub(super) fn observe(&mut self, parts: [(&[Pixel], &mut [f64]); 2], photons: u64) {
        let m = photons as f64;
        // Pixel order: the same sum on every thread count.
        let mut v = 0.0;
        for (pixels, phi2) in parts {
            for (px, q) in pixels.iter().zip(phi2.iter_mut()) {
                let area = PI * px.radius * px.radius;
                if px.vp.is_some() && area > 0.0 && photons > 0 {
                    let vi = *q / (m * area * area);
                    if vi.is_finite() {
                        v += vi;
                    }
                }
                *q = 0.0;
            }
        }
        if photons > 0 {
            self.add(v);
        }
    }

    /// One iteration's estimate of `V`.
    fn add(&mut self, v: f64) {
        self.v = Some(match self.v {
            Some(old) => (1.0 - NOISE_WEIGHT) * old + NOISE_WEIGHT * v,
            None => v,
        });
    }
}

/// The bounds of [`camera_share`]'s ratio. The lower bound is measured, not modelled: where
/// the model asks for fewer camera casts (the Cornell box 0.8, the teapot 1, `smallppm_far`
/// 0.4, the furnace 0.125) it leaves out what the iterations buy (the radius shrinks by
/// iteration, and the visible points move) and the photon pass's costs beyond its rays. At
/// equal CPU time on every example a forced 2 was as good as 1 within the runs' scatter and
/// better on the teapot, and going below 1 made `smallppm_far` worse (figures in
/// docs/integrators.md, "Camera samples and photons").
const SPLIT_RANGE: (f64, f64) = (2.0, 8.0);

/// The ratio of the camera pass's ray casts to the photon pass's that minimises the image's
/// summed variance for a given time, or `None` before both parts' noise is known. With `S`
/// camera samples per iteration shared by Neyman allocation, the camera part's summed
/// variance is `Q^2 / S` (`Q` the sum of the pixels' standard deviations of one sample); with
/// `M` photons the photon part's is `V / M` ([`PhotonNoise`]). An iteration costs
/// `a S + b M` ray casts (`a` = [`RAYS_PER_CAMERA_SAMPLE`], `b` the segments per photon), and
/// the iterations in a given time are inversely proportional to it, so the product
/// `(Q^2 / S + V / M)(a S + b M)` is to be minimised: at `a S / (b M) = Q sqrt(a) / sqrt(V b)`.
/// Bounded to [`SPLIT_RANGE`]: the estimates are noisy, and the model leaves out what more
/// iterations buy.
pub(super) fn camera_share(
    stats: &[SampleStats],
    noise: &PhotonNoise,
    segments_per_photon: f64,
) -> Option<f64> {
    let v = noise.v?;
    let (_, q) = deviations(stats);
    let ratio = q * RAYS_PER_CAMERA_SAMPLE.sqrt() / (v * segments_per_photon.max(1.0)).sqrt();
    // No photon noise: the camera part takes all it may (NaN: neither part has noise).
    (!ratio.is_nan()).then(|| ratio.clamp(SPLIT_RANGE.0, SPLIT_RANGE.1))
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// The photon noise of one gather: photons of contribution `c` found at random, `k` on
    /// average per point, give an estimate whose variance over many draws is what
    /// `PhotonNoise` predicts from one draw's sum of squares.
    #[test]
    fn photon_noise_predicts_the_variance_of_the_gather() {
        let mut rng = crate::sampling::Rng::new(11);
        let (m, area, c, k) = (1000.0f64, 0.01f64, 0.5f64, 20.0f64);
        // Each of `m` photons lands in the disk with probability k / m.
        let mut draw = || {
            let hits = (0..m as u32)
                .filter(|_| f64::from(rng.f32()) < k / m)
                .count() as f64;
            (hits * c / (m * area), hits * c * c)
        };
        let draws: Vec<(f64, f64)> = (0..4000).map(|_| draw()).collect();
        let n = draws.len() as f64;
        let mean = draws.iter().map(|d| d.0).sum::<f64>() / n;
        let var = draws.iter().map(|d| (d.0 - mean).powi(2)).sum::<f64>() / (n - 1.0);
        // What one iteration's `observe` gives, v / M, averaged over the draws.
        let predicted = draws.iter().map(|d| d.1 / (m * area).powi(2)).sum::<f64>() / n;
        assert!(
            (predicted / var - 1.0).abs() < 0.08,
            "{predicted} against {var}"
        );
        let mut noise = PhotonNoise::default();
        noise.add(1.0);
        noise.add(2.0);
        assert!((noise.v.unwrap() - 1.3).abs() < 1e-12);
    }

    /// The ratio minimises the variance-time product of the model, is bounded, and follows
    /// the two parts: no photon noise gives the camera part all it may.
    #[test]
    fn the_split_minimises_variance_times_cost() {
        let mut stats = vec![SampleStats::default(); 3];
        for (i, s) in stats.iter_mut().enumerate() {
            for k in 0..8 {
                s.add(Vec3A::splat(if k % 2 == 0 { 0.0 } else { (i + 1) as f32 }));
            }
        }
        let (_, q) = deviations(&stats);
        let b = 2.5;
        let a = RAYS_PER_CAMERA_SAMPLE;
        let product = |v: f64, ratio: f64| {
            // A fixed budget of casts split as `ratio` : 1.
            let (cam, ph) = (ratio / (1.0 + ratio), 1.0 / (1.0 + ratio));
            let (s, m) = (cam / a, ph / b);
            q * q / s + v / m
        };
        let mut interior = 0;
        for v in [0.01, 0.3, 1.0] {
            let noise = PhotonNoise { v: Some(v) };
            let r = camera_share(&stats, &noise, b).unwrap();
            if r > SPLIT_RANGE.0 && r < SPLIT_RANGE.1 {
                interior += 1;
                for other in [0.5 * r, 0.9 * r, 1.1 * r, 2.0 * r] {
                    assert!(product(v, r) < product(v, other), "v {v}: {r} vs {other}");
                }
            }
        }
        assert_eq!(interior, 2);
        let none = PhotonNoise { v: Some(0.0) };
        assert_eq!(camera_share(&stats, &none, b), Some(SPLIT_RANGE.1));
        let huge = PhotonNoise { v: Some(1e12) };
        assert_eq!(camera_share(&stats, &huge, b), Some(SPLIT_RANGE.0));
        assert_eq!(camera_share(&stats, &PhotonNoise::default(), b), None);
        let flat = vec![SampleStats::default(); 3];
        assert_eq!(camera_share(&flat, &none, b), None);
    }
}
