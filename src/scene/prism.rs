//! POV-Ray's `prism`: a closed 2-D profile in the (x, z) plane swept along y, straight
//! (`linear_sweep`) or toward the origin (`conic_sweep`). The points given in the scene become
//! cubic Bezier segments here, by POV-Ray's rules for each spline kind, so that the renderer
//! sees one kind of curve.
//!
//! The profile may hold several sub-shapes (each closed); a point is inside by the even-odd
//! rule, so a sub-shape inside another is a hole.

use glam::DVec2;

/// How the points of a prism make its curve (POV-Ray's spline keywords).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PrismSpline {
    /// A polygon: a sub-shape closes when a point repeats its first point.
    Linear,
    /// Each segment runs between two points, shaped by the point before them (the first point
    /// of a sub-shape only shapes; it closes when a point repeats its second).
    Quadratic,
    /// Catmull-Rom: each segment runs between two points, shaped by one point on each side.
    Cubic,
    /// Groups of four control points, each a cubic Bezier segment.
    Bezier,
}

impl PrismSpline {
    pub fn keyword(self) -> &'static str {
        match self {
            PrismSpline::Linear => "linear_spline",
            PrismSpline::Quadratic => "quadratic_spline",
            PrismSpline::Cubic => "cubic_spline",
            PrismSpline::Bezier => "bezier_spline",
        }
    }
}

/// A prism as the renderer takes it (see [`prism_segments`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Prism {
    /// Cubic Bezier segments `[p0, p1, p2, p3]` in the (x, z) plane, in sub-shape order.
    pub segments: Vec<[DVec2; 4]>,
    /// The two heights as given (either may be the larger).
    pub heights: (f64, f64),
    /// The profile is scaled by the height (POV-Ray's `conic_sweep`: it is the given one at
    /// y = 1 and shrinks to the origin at y = 0).
    pub conic: bool,
    /// No caps (POV-Ray's `open`): a surface, not a solid.
    pub open: bool,
}

/// Why a list of points makes no prism profile; `at` is the index of the point the message is
/// about, when there is one.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileError {
    pub message: String,
    pub at: Option<usize>,
}

fn err(message: String, at: Option<usize>) -> ProfileError {
    ProfileError { message, at }
}

/// Whether two profile points are the same (POV-Ray compares within 1e-10; here relative to
/// the points' size too, so that a profile in large units closes as one in small units does).
fn same(a: DVec2, b: DVec2) -> bool {
    let scale = a.abs().max_element().max(b.abs().max_element()).max(1.0);
    (a - b).abs().max_element() <= 1e-10 * scale
}

/// The cubic Bezier form of `a s^3 + b s^2 + c s + d`.
fn bezier_of(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> [DVec2; 4] {
    [d, d + c / 3.0, d + c * (2.0 / 3.0) + b / 3.0, a + b + c + d]
}

/// The segments of the profile through `points` by `spline`'s rules (POV-Ray's own: see
/// [`PrismSpline`]), every sub-shape closed. Refused: a non-finite point, too few points for
/// the spline, a sub-shape left open, and a profile that encloses no area.
pub fn prism_segments(
    spline: PrismSpline,
    points: &[DVec2],
) -> Result<Vec<[DVec2; 4]>, ProfileError> {
    if let Some(i) = points.iter().position(|p| !p.is_finite()) {
        return Err(err(
            format!("point {} is not a finite number", i + 1),
            Some(i),
        ));
    }
    let n = points.len();
    let (least, what) = match spline {
        PrismSpline::Linear => (4, "3 corners and the first repeated"),
        PrismSpline::Quadratic => (
            5,
            "a control point, 3 points and the first of them repeated",
        ),
        PrismSpline::Cubic => (
            6,
            "a control point, 3 points, the first of them repeated and a control point",
        ),
        PrismSpline::Bezier => (4, "a segment of 4 control points"),
    };
    if n < least {
        return Err(err(
            format!(
                "a {} prism needs at least {least} points ({what}), found {n}",
                spline.keyword()
            ),
            None,
        ));
    }
    let mut segs = Vec::new();
    // The sub-shape's first point on the curve, and the index its points start at.
    let mut start = 0;
    let mut first = match spline {
        PrismSpline::Linear | PrismSpline::Bezier => points[0],
        _ => points[1],
    };
    let mut closed = false;
    let mut i = 0;
    while i + 1 < n {
        let p = |k: usize| points.get(k).copied();
        let lacking = || {
            err(
                format!(
                    "the sub-shape that starts at point {} is not closed: its curve must come \
                     back to its first point",
                    start + 1
                ),
                Some(start),
            )
        };
        closed = false;
        // The segment, and the point whose return to `first` closes the sub-shape.
        let (seg, end) = match spline {
            PrismSpline::Linear => {
                let (a, b) = (points[i], points[i + 1]);
                ([a, a + (b - a) / 3.0, a + (b - a) * (2.0 / 3.0), b], i + 1)
            }
            PrismSpline::Quadratic => {
                let (Some(p0), Some(p1), Some(p2)) = (p(i), p(i + 1), p(i + 2)) else {
                    return Err(lacking());
                };
                let b = 0.5 * p0 - p1 + 0.5 * p2;
                let c = -0.5 * p0 + 0.5 * p2;
                (bezier_of(DVec2::ZERO, b, c, p1), i + 2)
            }
            PrismSpline::Cubic => {
                let (Some(p0), Some(p1), Some(p2), Some(p3)) = (p(i), p(i + 1), p(i + 2), p(i + 3))
                else {
                    return Err(lacking());
                };
                let a = -0.5 * p0 + 1.5 * p1 - 1.5 * p2 + 0.5 * p3;
                let b = p0 - 2.5 * p1 + 2.0 * p2 - 0.5 * p3;
                let c = -0.5 * p0 + 0.5 * p2;
                (bezier_of(a, b, c, p1), i + 2)
            }
            PrismSpline::Bezier => {
                let (Some(p0), Some(p1), Some(p2), Some(p3)) = (p(i), p(i + 1), p(i + 2), p(i + 3))
                else {
                    return Err(err(
                        format!(
                            "a bezier_spline prism takes its points in groups of 4, found {n} \
                             ({} left over)",
                            n % 4
                        ),
                        Some(i),
                    ));
                };
                if let Some(last) = segs.last().map(|s: &[DVec2; 4]| s[3])
                    && i != start
                    && !same(last, p0)
                {
                    return Err(err(
                        format!(
                            "segment {} starts at point {} away from where the segment before \
                             it ends",
                            i / 4 + 1,
                            i + 1
                        ),
                        Some(i),
                    ));
                }
                ([p0, p1, p2, p3], i + 3)
            }
        };
        segs.push(seg);
        if same(points[end], first) {
            closed = true;
            // The next sub-shape starts after this one's points (its trailing control point).
            i = match spline {
                PrismSpline::Linear => i + 2,
                PrismSpline::Quadratic => i + 3,
                PrismSpline::Cubic => i + 4,
                PrismSpline::Bezier => i + 4,
            };
            start = i;
            let lead = match spline {
                PrismSpline::Linear | PrismSpline::Bezier => i,
                _ => i + 1,
            };
            match points.get(lead) {
                Some(&q) => first = q,
                None => break,
            }
            // Points left over that cannot make a sub-shape of their own.
            if i + 1 >= n {
                return Err(err(
                    format!(
                        "point {} is left over after the last closed sub-shape",
                        i + 1
                    ),
                    Some(i),
                ));
            }
        } else {
            i = match spline {
                PrismSpline::Bezier => i + 4,
                _ => i + 1,
            };
        }
    }
    if !closed {
        return Err(err(
            format!(
                "the sub-shape that starts at point {} is not closed: its curve must come back \
                 to its first point",
                start + 1
            ),
            Some(start),
        ));
    }
    let area: f64 = segs.iter().map(|s| segment_area(s).abs()).sum::<f64>();
    let extent = segs
        .iter()
        .flatten()
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let encloses = area > 1e-12 * extent * extent;
    if !encloses {
        return Err(err(
            "the profile encloses no area (its points lie on a line or on top of each other)"
                .into(),
            None,
        ));
    }
    Ok(segs)
}

/// The segment's share of its sub-shape's signed area, `∫ x dz` along it (Green's theorem; the
/// shares of a closed curve sum to its signed area). Exact: three-point Gauss-Legendre
/// integrates the degree-5 integrand exactly.
pub fn segment_area(s: &[DVec2; 4]) -> f64 {
    const NODES: [(f64, f64); 3] = [
        (0.112_701_665_379_258_3, 5.0 / 18.0),
        (0.5, 8.0 / 18.0),
        (0.887_298_334_620_741_7, 5.0 / 18.0),
    ];
    NODES
        .iter()
        .map(|&(t, w)| {
            let u = 1.0 - t;
            let x = u * u * u * s[0].x
                + 3.0 * u * u * t * s[1].x
                + 3.0 * u * t * t * s[2].x
                + t * t * t * s[3].x;
            let dz = 3.0
                * (u * u * (s[1].y - s[0].y)
                    + 2.0 * u * t * (s[2].y - s[1].y)
                    + t * t * (s[3].y - s[2].y));
            w * x * dz
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(v: &[(f64, f64)]) -> Vec<DVec2> {
        v.iter().map(|&(x, z)| DVec2::new(x, z)).collect()
    }

    #[test]
    fn a_square_with_a_square_hole_is_eight_segments() {
        let p = pts(&[
            (0.0, 0.0),
            (4.0, 0.0),
            (4.0, 4.0),
            (0.0, 4.0),
            (0.0, 0.0),
            (1.0, 1.0),
            (3.0, 1.0),
            (3.0, 3.0),
            (1.0, 3.0),
            (1.0, 1.0),
        ]);
        let s = prism_segments(PrismSpline::Linear, &p).unwrap();
        assert_eq!(s.len(), 8);
        let outer: f64 = s[..4].iter().map(segment_area).sum();
        assert!((outer.abs() - 16.0).abs() < 1e-12, "{outer}");
    }

    #[test]
    fn too_few_or_unclosed_or_flat_profiles_are_refused() {
        let open = pts(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
        assert!(prism_segments(PrismSpline::Linear, &open).is_err());
        let flat = pts(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (0.0, 0.0)]);
        assert!(prism_segments(PrismSpline::Linear, &flat).is_err());
        let nan = pts(&[(0.0, 0.0), (f64::NAN, 0.0), (1.0, 1.0), (0.0, 0.0)]);
        assert_eq!(
            prism_segments(PrismSpline::Linear, &nan).unwrap_err().at,
            Some(1)
        );
    }
}
