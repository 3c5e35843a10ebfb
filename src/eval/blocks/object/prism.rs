//! `prism { [spline] [sweep] height1, height2, N, <x, z>... [open] }` as POV-Ray writes it: the
//! count and the points checked here, the profile built by [`prism_segments`].

use glam::DVec2;

use super::ObjectBuilder;
use crate::diag::{At, Error, SourceResult, short_number};
use crate::scene::{Prism, PrismSpline, ShapeDecl, prism_segments};

const EXAMPLE: &str = "prism { linear_sweep 0, 1, 4, <0, 0>, <1, 0>, <0, 1>, <0, 0> }";

impl ObjectBuilder {
    pub(super) fn prism(&self) -> SourceResult<ShapeDecl> {
        let spline = self.spline.unwrap_or(PrismSpline::Linear);
        if self.values.len() < 3 {
            return Err(vec![
                Error::new(format!(
                    "a prism needs two heights, a point count and the points, found {} value{}",
                    self.values.len(),
                    if self.values.len() == 1 { "" } else { "s" }
                ))
                .label("too few values")
                .help(format!("e.g. `{EXAMPLE}`"))
                .at(self.span),
            ]);
        }
        let number = |k: usize, what: &str| -> SourceResult<f64> {
            let (v, span) = &self.values[k];
            let x = v
                .num()
                .map_err(|e| e.help(format!("the prism's {what} is a number: `{EXAMPLE}`")))
                .at(*span)?;
            if !x.is_finite() {
                return Err(vec![
                    Error::new(format!("the prism's {what} is {}", short_number(x)))
                        .label("not a finite number")
                        .help(format!("e.g. `{EXAMPLE}`"))
                        .at(*span),
                ]);
            }
            Ok(x)
        };
        let (h1, h2) = (number(0, "first height")?, number(1, "second height")?);
        if h1 == h2 {
            return Err(vec![
                Error::new(format!(
                    "the prism's two heights are both {}: it has no thickness",
                    short_number(h1)
                ))
                .label("equal heights")
                .help("give the heights the prism spans along y, e.g. `0, 1`")
                .at(self.values[0].1.join(self.values[1].1)),
            ]);
        }
        let count = number(2, "point count")?;
        let points = &self.values[3..];
        if count != points.len() as f64 {
            return Err(vec![
                Error::new(format!(
                    "the prism says it has {} points, but {} follow",
                    short_number(count),
                    points.len()
                ))
                .label("the count")
                .help("the third value is the number of points after it (as in POV-Ray)")
                .at(self.values[2].1),
            ]);
        }
        let pts: Vec<DVec2> = points
            .iter()
            .map(|(v, span)| {
                v.vec2()
                    .map_err(|e| e.help("prism points are 2-D: `<x, z>`"))
                    .at(*span)
            })
            .collect::<SourceResult<_>>()?;
        let segments = prism_segments(spline, &pts).map_err(|e| {
            let at = match e.at {
                Some(i) => points[i].1,
                None => points[0].1.join(points[points.len() - 1].1),
            };
            vec![
                Error::new(e.message)
                    .label("the profile")
                    .help(
                        "a sub-shape closes when its curve comes back to its first point \
                         (linear_spline: repeat the first point; quadratic_spline and \
                         cubic_spline: repeat the second, the first only shapes the curve; \
                         bezier_spline: 4 control points per segment)",
                    )
                    .at(at),
            ]
        })?;
        if self.conic && h1.min(h2) < 0.0 && h1.max(h2) > 0.0 {
            return Err(vec![
                Error::new("a conic prism's heights lie on both sides of 0".to_string())
                    .label("the heights")
                    .help(
                        "a conic sweep shrinks the profile to a point at y = 0: give heights on \
                         one side of it, e.g. `0, 1`",
                    )
                    .at(self.values[0].1.join(self.values[1].1)),
            ]);
        }
        Ok(ShapeDecl::Prism(Prism {
            segments,
            heights: (h1, h2),
            conic: self.conic,
            open: self.open,
        }))
    }
}
