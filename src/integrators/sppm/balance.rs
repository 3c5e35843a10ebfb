//! The balance of camera samples against photons. Each SPPM iteration gives every pixel one
//! camera path (its visible point, with the emitted and directly lit light it meets); the
//! photon pass usually costs far more. Where the camera part's own variance is large (a
//! directly visible light's edge, a small light's soft shadow) one sample per iteration starves
//! it: at equal time a path tracer gives such a pixel many more samples. So every iteration
//! also traces extra camera samples, for the emitted and direct part only (their visible points
//! are not kept), shared among the pixels by `common/camera_samples.rs`.
//!
//! How many: the camera pass casts `ratio` times the photon pass's rays, and the automatic
//! photon count (`photon_count.rs`) gives the photons their share of the same total. The ratio
//! is 1 until both parts' noise is known, then the one that minimises the image's summed
//! variance at equal time, [`camera_share`], from the camera samples' deviations and the
//! photons' counting noise ([`PhotonNoise`]), within 2 to 8 ([`SPLIT_RANGE`]: the lower
//! bound measured): a scene lit mostly directly (an environment map's sun) moves more of its
//! casts to the camera pass.
//!
//! Every count comes from deterministic quantities: the photon pass's traced segments (a count
//! of ray casts, the same on any thread count and machine load), each pixel's own samples and
//! the photons it gathered, summed in pixel order; never from the clock.

use std::f64::consts::PI;

use super::pixels::Pixel;
use crate::integrators::common::camera_samples::{RAYS_PER_CAMERA_SAMPLE, SampleStats, deviations};

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
    use glam::Vec3A;

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
