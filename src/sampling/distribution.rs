//! Piecewise-constant distributions: over discrete items (light selection by power) and over
//! the bins of [0, 1) or [0, 1)² (environment-map texels).

/// A piecewise-constant function of `n` equal bins, sampled in proportion to its values.
///
/// Negative or non-finite values count as 0; if all are 0 the choice is uniform. A bin of value
/// 0 is never chosen (unless all are 0).
#[derive(Debug, Clone, Default)]
pub struct PiecewiseConstant1D {
    /// The bins' values (cleaned).
    func: Vec<f32>,
    /// `n + 1` non-decreasing entries from 0 to 1.
    cdf: Vec<f32>,
    /// Probability of each bin, `func[i] / sum(func)`.
    pmf: Vec<f32>,
    /// Sum of the values (f64 before rounding).
    sum: f64,
}

impl PiecewiseConstant1D {
    pub fn new(weights: &[f64]) -> Self {
        let clean: Vec<f64> = weights
            .iter()
            .map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
            .collect();
        let total: f64 = clean.iter().sum();
        let n = clean.len().max(1) as f64;
        let pmf: Vec<f64> = if total > 0.0 {
            clean.iter().map(|w| w / total).collect()
        } else {
            clean.iter().map(|_| 1.0 / n).collect()
        };
        let mut cdf = Vec::with_capacity(pmf.len() + 1);
        cdf.push(0.0f32);
        let mut acc = 0.0;
        cdf.extend(pmf.iter().map(|p| {
            acc += p;
            acc as f32
        }));
        Self {
            func: clean.iter().map(|&w| w as f32).collect(),
            cdf,
            pmf: pmf.iter().map(|&p| p as f32).collect(),
            sum: total,
        }
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Bin chosen by `u` in [0,1) and its probability (discrete use: one item of `n`).
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        // One item (a scene with one light, chosen once per photon and per light sample): the
        // search below would find it whatever `u` is.
        if let [p] = self.pmf[..] {
            return (p > 0.0).then_some((0, p));
        }
        if self.pmf.is_empty() {
            return None;
        }
        let i = self.cdf[1..]
            .partition_point(|&c| c <= u)
            .min(self.pmf.len() - 1);
        // Skip zero-probability entries a rounding edge could land on.
        let i = (i..self.pmf.len())
            .chain((0..i).rev())
            .find(|&j| self.pmf[j] > 0.0)?;
        Some((i, self.pmf[i]))
    }

    /// Probability of bin `i` (0 outside).
    pub fn pdf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Bin chosen by `u` in [0, 1] and the fraction of `u` within it (continuous use: the point
    /// `(i + fraction) / n` of [0, 1) has density `func[i] / mean(func)`).
    ///
    /// # Panics
    /// If the distribution is empty.
    pub fn sample_continuous(&self, u: f32) -> (usize, f32) {
        sample_cdf(&self.cdf, u)
    }

    /// The value of bin `i` (cleaned, as f32).
    pub fn func(&self, i: usize) -> f32 {
        self.func[i]
    }

    /// Sum of the bins' values.
    pub fn sum(&self) -> f64 {
        self.sum
    }
}

/// A piecewise-constant function on a `width x height` grid of equal bins (row-major), sampled
/// in proportion to its values: a row by the rows' sums, then a column within that row.
#[derive(Debug, Clone)]
pub struct PiecewiseConstant2D {
    width: usize,
    rows: Vec<PiecewiseConstant1D>,
    marginal: PiecewiseConstant1D,
}

impl PiecewiseConstant2D {
    /// `values` has `width * height` entries, row-major; `width` and `height` must be > 0.
    pub fn new(values: &[f64], width: usize, height: usize) -> Self {
        assert!(width > 0 && height > 0 && values.len() == width * height);
        let rows: Vec<PiecewiseConstant1D> =
            values.chunks(width).map(PiecewiseConstant1D::new).collect();
        let marginal = PiecewiseConstant1D::new(&rows.iter().map(|r| r.sum()).collect::<Vec<_>>());
        Self {
            width,
            rows,
            marginal,
        }
    }

    /// Bin `(column, row)` chosen by `u` and the fractions of `u` within it.
    pub fn sample(&self, u: glam::Vec2) -> ((usize, usize), glam::Vec2) {
        let (row, dv) = self.marginal.sample_continuous(u.y);
        let (col, du) = self.rows[row].sample_continuous(u.x);
        ((col, row), glam::Vec2::new(du, dv))
    }

    /// The value of bin `(column, row)`.
    pub fn func(&self, col: usize, row: usize) -> f32 {
        self.rows[row].func(col)
    }

    /// Sum of all values.
    pub fn sum(&self) -> f64 {
        self.marginal.sum()
    }

    /// Mean of all values (the normaliser of the continuous density on [0, 1)²).
    pub fn mean(&self) -> f64 {
        self.sum() / (self.width * self.rows.len()) as f64
    }
}

/// Index `i` with `cdf[i] <= u < cdf[i + 1]` and the fraction of `u` within it. `cdf` has
/// `n + 1` non-decreasing entries from 0 to 1; an entry of zero width is never chosen.
#[inline]
fn sample_cdf(cdf: &[f32], u: f32) -> (usize, f32) {
    let n = cdf.len() - 1;
    let u = if u.is_finite() {
        u.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let i = cdf.partition_point(|&c| c <= u).saturating_sub(1);
    // u = 1 (or a last run of zero-width entries) lands past the end: step back to the last
    // entry with width.
    let mut i = i.min(n - 1);
    while i > 0 && cdf[i + 1] <= cdf[i] {
        i -= 1;
    }
    let width = cdf[i + 1] - cdf[i];
    let frac = if width > 0.0 {
        ((u - cdf[i]) / width).clamp(0.0, 1.0 - f32::EPSILON)
    } else {
        0.5
    };
    (i, frac)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_in_proportion() {
        let d = PiecewiseConstant1D::new(&[1.0, 0.0, 3.0]);
        let mut counts = [0usize; 3];
        for k in 0..4000 {
            let (i, _) = d.sample((k as f32 + 0.5) / 4000.0).unwrap();
            counts[i] += 1;
        }
        assert_eq!(counts, [1000, 0, 3000]);
        assert_eq!(d.pdf(2), 0.75);
    }

    /// One item: chosen with probability 1 for every `u` (the edges and beyond included),
    /// whatever its weight (none usable: the choice is uniform); no item: none chosen.
    #[test]
    fn one_item_is_always_chosen() {
        let us = [0.0, 0.25, 0.5, 1.0 - f32::EPSILON, 1.0, -1.0, 2.0];
        let one = PiecewiseConstant1D::new(&[0.3]);
        for u in us {
            assert_eq!(one.sample(u), Some((0, 1.0)), "u {u}");
        }
        for w in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            // All weights zero: the choice is uniform, so the one item is still chosen.
            assert_eq!(
                PiecewiseConstant1D::new(&[w]).sample(0.5),
                Some((0, 1.0)),
                "w {w}"
            );
        }
        assert_eq!(PiecewiseConstant1D::new(&[]).sample(0.5), None);
    }

    #[test]
    fn sample_cdf_skips_empty_entries() {
        let cdf = [0.0, 0.0, 0.5, 0.5, 1.0, 1.0];
        assert_eq!(sample_cdf(&cdf, 0.0).0, 1);
        assert_eq!(sample_cdf(&cdf, 0.25), (1, 0.5));
        assert_eq!(sample_cdf(&cdf, 0.5).0, 3);
        assert_eq!(sample_cdf(&cdf, 0.75), (3, 0.5));
        assert_eq!(sample_cdf(&cdf, 1.0).0, 3);
    }

    /// The continuous density `func / mean` integrates to 1 over [0, 1), and the known
    /// histogram `[1, 0, 2, 1]` is reproduced by stratified samples; the empty bin never is.
    #[test]
    fn continuous_density_integrates_to_one_and_matches_a_histogram() {
        let w = [1.0, 0.0, 2.0, 1.0];
        let d = PiecewiseConstant1D::new(&w);
        let mean = d.sum() / w.len() as f64;
        let integral: f64 = (0..w.len())
            .map(|i| d.func(i) as f64 / mean / w.len() as f64)
            .sum();
        assert!((integral - 1.0).abs() < 1e-12, "{integral}");
        let n = 4000;
        let mut counts = [0usize; 4];
        for k in 0..n {
            let (i, f) = d.sample_continuous((k as f32 + 0.5) / n as f32);
            assert!((0.0..1.0).contains(&f));
            counts[i] += 1;
        }
        assert_eq!(counts, [1000, 0, 2000, 1000]);
        for u in [0.0, 0.25, 0.2500001, 1.0, f32::NAN, -1.0] {
            assert_ne!(d.sample_continuous(u).0, 1, "{u}");
            assert_ne!(d.sample(u).map(|s| s.0), Some(1), "{u}");
        }
        // All zero: uniform.
        let z = PiecewiseConstant1D::new(&[0.0, f64::NAN, -1.0]);
        assert_eq!(z.sample_continuous(0.5).0, 1);
        assert_eq!(z.pdf(0), 1.0 / 3.0);
    }

    /// Rows are chosen by their sums, columns within a row by its values; empty bins never.
    #[test]
    fn two_d_matches_a_known_histogram() {
        // Row sums 4 and 4 (equal rows), columns [3, 1] and [0, 4].
        let d = PiecewiseConstant2D::new(&[3.0, 1.0, 0.0, 4.0], 2, 2);
        assert_eq!(d.sum(), 8.0);
        assert_eq!(d.mean(), 2.0);
        let n = 64;
        let mut counts = [[0usize; 2]; 2];
        for a in 0..n {
            for b in 0..n {
                let u = glam::Vec2::new((a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32);
                let ((col, row), _) = d.sample(u);
                counts[row][col] += 1;
            }
        }
        let total = (n * n) as f64;
        for (row, cols) in counts.iter().enumerate() {
            for (col, &c) in cols.iter().enumerate() {
                let want = d.func(col, row) as f64 / d.sum();
                assert!((c as f64 / total - want).abs() < 1e-9, "{row} {col}: {c}");
            }
        }
        assert_eq!(counts[1][0], 0);
    }
}
