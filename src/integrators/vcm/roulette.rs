//! Russian roulette of the connections' shadow rays. A connection of a camera vertex to a light
//! vertex whose weighted contribution (both paths' throughput included) is below its pixel's
//! floor goes on with probability `y / floor` and then counts `floor / y` times, before its
//! shadow ray is traced: the estimate stays unbiased and the MIS weights are untouched. Where a
//! pixel's connections add little to it (most of room's, whose shadow rays are a sixth of the
//! render's CPU), most of those rays are saved.
//!
//! A pixel's floor is `CONNECT_ROULETTE` times the mean, over its camera paths so far (the
//! full ones), of their non-delta part: what next-event estimation, connections and merges add
//! and the emission a path reaches after a non-delta bounce. Not of the whole pixel: where a
//! light is seen directly (its edge, `cornell`'s pixels beside the lamp) its emission made the
//! floor ten or more times what any connection there adds, so that 2 % of those pixels'
//! connections survived, each counting fifty times. The floors are set before each pass from
//! the earlier ones (a pass's own paths never move its floors), in pixel order, and only once a
//! pixel has `CONNECT_ROULETTE_SAMPLES` camera paths: a mean of a few, raised by one bright
//! path, would make the floor follow the noise. Each draw comes from the pixel's own stream,
//! so the image is the same on any thread count.

use crate::integrators::common::camera_samples::SampleStats;
use crate::sampling::Rng;

/// A pixel's floor as a share of the mean of its camera paths' non-delta part so far.
const CONNECT_ROULETTE: f64 = 0.1;

/// The full camera paths a pixel needs before its mean sets a floor.
const CONNECT_ROULETTE_SAMPLES: u32 = 32;

/// Every pixel's floor for the next pass, from the non-delta part of its camera paths so far
/// (`rest`); 0 (no roulette) for a pixel with fewer than `CONNECT_ROULETTE_SAMPLES` of them or
/// a mean that is not finite.
pub(super) fn floors<'a>(rest: impl Iterator<Item = &'a SampleStats>, out: &mut Vec<f32>) {
    out.clear();
    out.extend(rest.map(|s| {
        let floor = (s.mean_of(CONNECT_ROULETTE_SAMPLES).unwrap_or(0.0) * CONNECT_ROULETTE) as f32;
        if floor.is_finite() && floor > 0.0 {
            floor
        } else {
            0.0
        }
    }));
}

/// Russian roulette of a connection of luminance `y` (before its shadow ray) against the
/// pixel's `floor`: below it the connection goes on with probability `y / floor` and counts
/// `floor / y` times (its expectation unchanged); at or above it, or without a floor, it goes
/// on with factor 1 and draws nothing. `None`: dropped. The probability is rounded up to a
/// multiple of 2^-24, the steps of [`Rng::f32`], so that a draw below it has exactly that
/// probability and the factor (its inverse, at most 2^24, never infinite) keeps the
/// expectation exactly.
pub(super) fn connection_roulette(y: f32, floor: f32, rng: &mut Rng) -> Option<f32> {
    if !(floor > 0.0 && y < floor) {
        return Some(1.0);
    }
    const STEPS: f32 = (1u32 << 24) as f32;
    let p = ((y / floor) * STEPS).ceil() / STEPS;
    (p > 0.0 && rng.f32() < p).then(|| 1.0 / p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    /// The roulette keeps a connection's expectation: below the floor the mean of its factor
    /// over many draws is 1 (and each survivor counts up to the floor); at or above it, or
    /// without a floor, the factor is 1 and no number is drawn.
    #[test]
    fn connection_roulette_keeps_the_expectation() {
        for &(y, floor) in &[(0.01f32, 0.1f32), (0.05, 0.1), (0.099, 0.1), (1e-4, 2.0)] {
            let mut rng = Rng::new(7);
            let n = 400_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                if let Some(k) = connection_roulette(y, floor, &mut rng) {
                    // A survivor adds up to its floor: `floor / y` within the rounding of
                    // the probability to the generator's steps.
                    assert!(
                        k * y <= floor * (1.0 + 1e-6) && k * y >= floor * (1.0 - 1e-3),
                        "{k} {y} {floor}"
                    );
                    sum += f64::from(k);
                }
            }
            let mean = sum / f64::from(n);
            // The factor is floor / y with probability y / floor: its standard error.
            let sd = (f64::from(floor / y) - 1.0).sqrt() / f64::from(n).sqrt();
            assert!(
                (mean - 1.0).abs() < 5.0 * sd,
                "y {y}: mean {mean} (sd {sd})"
            );
        }
        for &(y, floor) in &[(0.2f32, 0.1f32), (0.1, 0.1), (0.3, 0.0), (f32::NAN, 0.1)] {
            let mut rng = Rng::new(3);
            let before = rng.clone().f32();
            assert_eq!(connection_roulette(y, floor, &mut rng), Some(1.0));
            assert_eq!(rng.f32(), before, "drew a number at y {y}, floor {floor}");
        }
        let mut rng = Rng::new(5);
        assert_eq!(connection_roulette(0.0, 0.1, &mut rng), None);
        // A contribution far below the floor (a subnormal one too) keeps a finite factor: the
        // probability's least step.
        for y in [1e-12f32, 1e-40] {
            let p = 1.0 / (1u32 << 24) as f32;
            let mut rng = Rng::new(13);
            let k = (0..1 << 28)
                .find_map(|_| connection_roulette(y, 0.1, &mut rng))
                .expect("a survivor in 2^28 draws at probability 2^-24");
            assert_eq!(k, 1.0 / p, "y {y}");
        }
    }

    /// A sum of connections, some below the floor, keeps its mean under the roulette: the
    /// estimate a camera path adds (luminance values as `camera_path::connect` sees them).
    #[test]
    fn a_camera_paths_connections_keep_their_sum() {
        let ys = [0.003f32, 0.02, 0.07, 0.15, 0.5];
        let floor = 0.1;
        let exact: f64 = ys.iter().map(|&y| f64::from(y)).sum();
        let mut rng = Rng::new(11);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let v: f64 = ys
                .iter()
                .map(|&y| connection_roulette(y, floor, &mut rng).map_or(0.0, |k| f64::from(k * y)))
                .sum();
            sum += v;
            sum2 += v * v;
        }
        let mean = sum / f64::from(n);
        let sd = ((sum2 / f64::from(n) - mean * mean) / f64::from(n)).sqrt();
        assert!(sd > 0.0);
        assert!(
            (mean - exact).abs() < 5.0 * sd,
            "mean {mean}, exact {exact}, sd {sd}"
        );
    }

    /// A floor only from `CONNECT_ROULETTE_SAMPLES` camera paths on, a share of their mean;
    /// none for a mean of zero or one that is not finite.
    #[test]
    fn floors_wait_for_their_samples() {
        let mut stats = [SampleStats::default(); 4];
        for k in 0..CONNECT_ROULETTE_SAMPLES {
            let v = if k % 2 == 0 { 1.0 } else { 3.0 };
            stats[0].add(Vec3A::splat(v));
            stats[2].add(Vec3A::ZERO);
            stats[3].add(Vec3A::splat(f32::INFINITY));
            if k + 1 < CONNECT_ROULETTE_SAMPLES {
                stats[1].add(Vec3A::splat(v));
            }
        }
        let mut out = vec![9.0];
        floors(stats.iter(), &mut out);
        assert_eq!(out.len(), 4);
        assert!(
            (out[0] - 2.0 * CONNECT_ROULETTE as f32).abs() < 1e-5,
            "{out:?}"
        );
        assert_eq!(out[1..], [0.0, 0.0, 0.0]);
    }
}
