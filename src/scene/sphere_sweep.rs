//! POV-Ray's curved `sphere_sweep` (`cubic_spline`, `b_spline`) as the renderer takes it: the
//! spheres a cubic spline of centres and radii passes through or near, and their cubic segments
//! in Bernstein (Bezier) form. (A `linear_spline` sweep is built as a merge of spheres and cones
//! by the evaluator and never reaches this type.)

use glam::DVec3;

/// Most spheres one sweep may have: each segment holds about 300 bytes in the renderer (its
/// control points, box and hierarchy node; 80 MB at this bound).
pub const MAX_SWEEP_SPHERES: usize = 1 << 18;

/// The spline a curved sweep follows; both need 4 spheres or more and make `N - 3` segments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SweepSpline {
    /// Catmull-Rom (POV-Ray's `cubic_spline`): through spheres 2 to N-1; the first and the
    /// last only steer the ends.
    CatmullRom,
    /// Uniform cubic B-spline (`b_spline`): near the spheres, through none of them.
    BSpline,
}

/// One cubic segment in Bernstein form on `s` in [0, 1]: centre `c(s) = sum B_j(s) centres[j]`
/// and radius `r(s) = sum B_j(s) radii[j]`, `B_j` the cubic Bernstein basis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepSegment {
    pub centres: [DVec3; 4],
    pub radii: [f64; 4],
}

/// A curved sphere sweep: the union of the spheres `(c(s), r(s))` along the spline, where
/// `r(s) > 0` (a stretch where the interpolated radius is not positive is absent).
#[derive(Debug, Clone, PartialEq)]
pub struct SphereSweep {
    pub spline: SweepSpline,
    pub centres: Vec<DVec3>,
    pub radii: Vec<f64>,
}

impl SphereSweep {
    /// The sweep's `N - 3` segments in Bernstein form.
    pub fn segments(&self) -> Vec<SweepSegment> {
        let n = self.centres.len().min(self.radii.len());
        (0..n.saturating_sub(3))
            .map(|i| {
                let c = &self.centres[i..i + 4];
                let r = &self.radii[i..i + 4];
                SweepSegment {
                    centres: bezier(self.spline, [c[0], c[1], c[2], c[3]]),
                    radii: bezier(self.spline, [r[0], r[1], r[2], r[3]]),
                }
            })
            .collect()
    }

    /// Why the sweep cannot be rendered, if it cannot: the checks every sweep passes (the
    /// evaluator reports them at their spans first; this guards the library's callers).
    pub fn check(&self) -> Result<(), String> {
        let n = self.centres.len();
        if n != self.radii.len() {
            return Err("a sphere_sweep needs one radius per centre".into());
        }
        if !(4..=MAX_SWEEP_SPHERES).contains(&n) {
            return Err(format!(
                "a curved sphere_sweep needs 4 to {MAX_SWEEP_SPHERES} spheres, got {n}"
            ));
        }
        if let Some(i) =
            (0..n).find(|&i| !(self.centres[i].is_finite() && self.radii[i].is_finite()))
        {
            return Err(format!("the sphere_sweep's sphere {} is not finite", i + 1));
        }
        if !self.segments().iter().any(SweepSegment::somewhere_positive) {
            return Err(
                "the sphere_sweep's radius is nowhere positive along its curve (a stretch whose \
                 radius is 0 or less is absent)"
                    .into(),
            );
        }
        Ok(())
    }
}

impl SweepSegment {
    /// The centre and radius at `s`.
    pub fn at(&self, s: f64) -> (DVec3, f64) {
        let w = bernstein(s);
        let c = self.centres;
        let r = self.radii;
        (
            c[0] * w[0] + c[1] * w[1] + c[2] * w[2] + c[3] * w[3],
            r[0] * w[0] + r[1] * w[1] + r[2] * w[2] + r[3] * w[3],
        )
    }

    /// The derivatives of the centre and the radius at `s`.
    pub fn derivative(&self, s: f64) -> (DVec3, f64) {
        let (a, b, c) = ((1.0 - s) * (1.0 - s), 2.0 * s * (1.0 - s), s * s);
        let p = self.centres;
        let r = self.radii;
        (
            3.0 * ((p[1] - p[0]) * a + (p[2] - p[1]) * b + (p[3] - p[2]) * c),
            3.0 * ((r[1] - r[0]) * a + (r[2] - r[1]) * b + (r[3] - r[2]) * c),
        )
    }

    /// Whether the radius is positive at one of 33 evenly spread parameters (a stretch of
    /// positive radius narrower than that spacing adds a sliver the check may not see).
    pub fn somewhere_positive(&self) -> bool {
        (0..=32).any(|k| self.at(f64::from(k) / 32.0).1 > 0.0)
    }
}

/// The cubic Bernstein basis at `s`.
fn bernstein(s: f64) -> [f64; 4] {
    let t = 1.0 - s;
    [t * t * t, 3.0 * s * t * t, 3.0 * s * s * t, s * s * s]
}

/// The Bezier control values of the segment between `p[1]` and `p[2]` of the spline.
fn bezier<T>(spline: SweepSpline, p: [T; 4]) -> [T; 4]
where
    T: Copy
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f64, Output = T>,
{
    match spline {
        // Tangent (p[2] - p[0]) / 2 at p[1], a third of it to the inner control point.
        SweepSpline::CatmullRom => [
            p[1],
            p[1] + (p[2] - p[0]) * (1.0 / 6.0),
            p[2] - (p[3] - p[1]) * (1.0 / 6.0),
            p[2],
        ],
        SweepSpline::BSpline => [
            (p[0] + p[1] * 4.0 + p[2]) * (1.0 / 6.0),
            (p[1] * 2.0 + p[2]) * (1.0 / 3.0),
            (p[1] + p[2] * 2.0) * (1.0 / 3.0),
            (p[1] + p[2] * 4.0 + p[3]) * (1.0 / 6.0),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spline's value by POV-Ray's basis matrices in power form, for comparison.
    fn power_form(spline: SweepSpline, p: [f64; 4], s: f64) -> f64 {
        let m: [[f64; 4]; 4] = match spline {
            SweepSpline::CatmullRom => [
                [0.0, 1.0, 0.0, 0.0],
                [-0.5, 0.0, 0.5, 0.0],
                [1.0, -2.5, 2.0, -0.5],
                [-0.5, 1.5, -1.5, 0.5],
            ],
            SweepSpline::BSpline => [
                [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0, 0.0],
                [-0.5, 0.0, 0.5, 0.0],
                [0.5, -1.0, 0.5, 0.0],
                [-1.0 / 6.0, 0.5, -0.5, 1.0 / 6.0],
            ],
        };
        let pow = [1.0, s, s * s, s * s * s];
        (0..4)
            .map(|i| pow[i] * (0..4).map(|j| m[i][j] * p[j]).sum::<f64>())
            .sum()
    }

    #[test]
    fn the_bezier_form_is_the_splines_basis_matrix() {
        let p = [0.3, -1.2, 2.5, 0.7];
        for spline in [SweepSpline::CatmullRom, SweepSpline::BSpline] {
            let seg = SweepSegment {
                centres: p.map(|x| DVec3::new(x, 0.0, 0.0)),
                radii: p,
            };
            let seg = SweepSegment {
                centres: bezier(spline, seg.centres),
                radii: bezier(spline, seg.radii),
            };
            for k in 0..=10 {
                let s = f64::from(k) / 10.0;
                let want = power_form(spline, p, s);
                let (c, r) = seg.at(s);
                assert!(
                    (c.x - want).abs() < 1e-12 && (r - want).abs() < 1e-12,
                    "{s}"
                );
            }
        }
    }

    #[test]
    fn the_catmull_rom_passes_through_the_inner_spheres_and_segments_join() {
        let sweep = SphereSweep {
            spline: SweepSpline::CatmullRom,
            centres: (0..6)
                .map(|i| DVec3::new(f64::from(i), f64::from(i * i), 0.0))
                .collect(),
            radii: vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
        };
        let segs = sweep.segments();
        assert_eq!(segs.len(), 3);
        for (i, s) in segs.iter().enumerate() {
            assert_eq!(s.at(0.0), (sweep.centres[i + 1], sweep.radii[i + 1]));
        }
        for w in segs.windows(2) {
            let (a, b) = (w[0].derivative(1.0), w[1].derivative(0.0));
            assert!((a.0 - b.0).length() < 1e-12 && (a.1 - b.1).abs() < 1e-12);
        }
        assert!(sweep.check().is_ok());
    }

    #[test]
    fn the_checks_refuse_what_cannot_be_swept() {
        let good = SphereSweep {
            spline: SweepSpline::BSpline,
            centres: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            radii: vec![0.1; 4],
        };
        assert!(good.check().is_ok());
        let mut three = good.clone();
        three.centres.pop();
        three.radii.pop();
        assert!(three.check().is_err());
        let mut nan = good.clone();
        nan.radii[2] = f64::NAN;
        assert!(nan.check().is_err());
        let mut negative = good.clone();
        negative.radii = vec![-1.0, 0.0, -0.5, 0.0];
        assert!(negative.check().unwrap_err().contains("nowhere positive"));
    }
}
