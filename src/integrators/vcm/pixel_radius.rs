//! Each pixel's radius schedule, SPPM's (Hachisuka & Jensen 2009): a pixel's camera paths
//! merge with `r_0` (their footprint rule) times the pixel's own scale `s`, and after each
//! iteration the count `M` of light vertices its first camera path found within its radius at
//! its first merge updates it as SPPM's pixel: `s^2 <- s^2 (N + alpha M) / (N + M)`,
//! `N <- N + alpha M`. `M` is counted per pixel's worth of light paths (times the pixels over
//! the iteration's light paths), so that an iteration with a quarter as many light paths
//! shrinks as one with as many as pixels would. A pixel that found none keeps its scale.
//!
//! The scales an iteration uses are those after the earlier iterations only (updated between
//! iterations, in pixel order): each iteration's weights use a radius fixed before it, and
//! stay those of a valid estimator for that radius; the same on any thread count.

/// The per-pixel scales and counts.
#[derive(Debug, Default)]
pub(super) struct PixelRadii {
    /// Each pixel's scale of `r_0` (1 until it found light vertices).
    scales: Vec<f64>,
    /// Each pixel's accumulated count `N`.
    counts: Vec<f64>,
}

impl PixelRadii {
    /// Every pixel's scale at 1, its count at 0.
    pub(super) fn new(pixels: usize) -> Self {
        Self {
            scales: vec![1.0; pixels],
            counts: vec![0.0; pixels],
        }
    }

    /// The pixels' scales for the next iteration.
    pub(super) fn scales(&self) -> &[f64] {
        &self.scales
    }

    /// Updates each pixel with the light vertices `found` by its first camera path (one entry
    /// per pixel) in an iteration of `light_paths` light paths.
    pub(super) fn observe(&mut self, found: &[u32], light_paths: usize, alpha: f64) {
        let per_pixel = self.scales.len() as f64 / light_paths.max(1) as f64;
        let alpha = alpha.clamp(0.0, 1.0);
        for ((s, n), &m) in self.scales.iter_mut().zip(&mut self.counts).zip(found) {
            if m == 0 {
                continue;
            }
            let m = f64::from(m) * per_pixel;
            let n_new = *n + alpha * m;
            let shrink = n_new / (*n + m);
            if shrink.is_finite() && shrink > 0.0 {
                *s *= shrink.sqrt();
                *n = n_new;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::PixelRadii;

    /// A pixel that finds light vertices shrinks by SPPM's rule, one that finds none keeps
    /// its scale; a quarter as many light paths count four times.
    #[test]
    fn pixels_shrink_by_the_light_vertices_they_found() {
        let mut r = PixelRadii::new(4);
        r.observe(&[10, 0, 10, 1], 4, 0.5);
        let s = r.scales();
        assert!((s[0] * s[0] - 0.5).abs() < 1e-12);
        assert_eq!(s[1], 1.0);
        // N = 5: 5 + 0.5 * 10 over 5 + 10.
        r.observe(&[10, 0, 0, 0], 4, 0.5);
        assert!((r.scales()[0].powi(2) - 0.5 * 10.0 / 15.0).abs() < 1e-12);
        assert!((r.scales()[2].powi(2) - 0.5).abs() < 1e-12);
        let mut q = PixelRadii::new(4);
        q.observe(&[0, 0, 0, 1], 1, 0.5);
        q.observe(&[0, 0, 0, 1], 1, 0.5);
        let mut full = PixelRadii::new(4);
        full.observe(&[0, 0, 0, 4], 4, 0.5);
        full.observe(&[0, 0, 0, 4], 4, 0.5);
        assert!((q.scales()[3] - full.scales()[3]).abs() < 1e-12);
    }
}
