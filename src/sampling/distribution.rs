//! A piecewise-constant 1-D distribution over discrete items (light selection by power).

/// Picks index `i` with probability `w[i] / sum(w)`.
#[derive(Debug, Clone, Default)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    pdf: Vec<f32>,
}

impl Distribution1D {
    /// Negative or non-finite weights count as 0; if all are 0 the choice is uniform.
    pub fn new(weights: &[f64]) -> Self {
        let clean: Vec<f64> = weights
            .iter()
            .map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
            .collect();
        let total: f64 = clean.iter().sum();
        let n = clean.len().max(1) as f64;
        let pdf: Vec<f64> = if total > 0.0 {
            clean.iter().map(|w| w / total).collect()
        } else {
            clean.iter().map(|_| 1.0 / n).collect()
        };
        let mut acc = 0.0;
        let cdf = pdf
            .iter()
            .map(|p| {
                acc += p;
                acc as f32
            })
            .collect();
        Self {
            cdf,
            pdf: pdf.iter().map(|&p| p as f32).collect(),
        }
    }

    pub fn len(&self) -> usize {
        self.pdf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pdf.is_empty()
    }

    /// Index chosen by `u` in [0,1) and its probability.
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        if self.cdf.is_empty() {
            return None;
        }
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1);
        // Skip zero-probability entries a rounding edge could land on.
        let i = (i..self.pdf.len())
            .chain((0..i).rev())
            .find(|&j| self.pdf[j] > 0.0)?;
        Some((i, self.pdf[i]))
    }

    pub fn pdf(&self, i: usize) -> f32 {
        self.pdf.get(i).copied().unwrap_or(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_in_proportion() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        let mut counts = [0usize; 3];
        for k in 0..4000 {
            let (i, _) = d.sample((k as f32 + 0.5) / 4000.0).unwrap();
            counts[i] += 1;
        }
        assert_eq!(counts, [1000, 0, 3000]);
        assert_eq!(d.pdf(2), 0.75);
    }
}
