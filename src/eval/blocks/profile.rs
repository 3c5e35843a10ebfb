//! Profiles for `revolve`: `bezier { ... }` (control points) and `spline { ... }` (points a
//! Catmull-Rom curve passes through), both made of Bezier segments.

use crate::diag::short_number;
use std::rc::Rc;

use glam::DVec2;

use super::Sink;
use crate::diag::{At, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, num, range_error};
use crate::eval::props::{PropSpec, p};
use crate::eval::value::{ProfileDef, Value};
use crate::span::Span;
use crate::syntax::ast::Name;

/// A `bezier { ... }` or (with `spline`) a `spline { ... }` profile.
pub(super) struct ProfileBuilder {
    spline: bool,
    degree: Option<u32>,
    points: Vec<(DVec2, Span)>,
}

static BEZIER_PROPS: [PropSpec; 1] = [p("degree", 1, 1, "a number from 1 to 7", "3")];

impl ProfileBuilder {
    pub(super) fn new(spline: bool) -> Self {
        Self {
            spline,
            degree: None,
            points: Vec::new(),
        }
    }

    pub(super) fn finish(self, span: Span) -> SourceResult<Value> {
        let pts: Vec<DVec2> = self.points.iter().map(|p| p.0).collect();
        let d = if self.spline {
            1
        } else {
            self.degree.unwrap_or(3) as usize
        };
        let joints: Vec<Span> = self.points.iter().step_by(d.max(1)).map(|p| p.1).collect();
        let segments = if self.spline {
            if pts.len() < 2 {
                return Err(vec![
                    Error::new(format!(
                        "a spline needs at least 2 points, found {}",
                        pts.len()
                    ))
                    .label("too few points")
                    .help("give the points the curve passes through, e.g. `spline { <0.5, 0>, <0.5, 1> }`")
                    .at(span),
                ]);
            }
            // Catmull-Rom through the points, as cubic Bezier segments.
            let n = pts.len();
            (0..n - 1)
                .map(|i| {
                    let p0 = pts[i.saturating_sub(1)];
                    let (p1, p2) = (pts[i], pts[i + 1]);
                    let p3 = pts[(i + 2).min(n - 1)];
                    vec![p1, p1 + (p2 - p0) / 6.0, p2 - (p3 - p1) / 6.0, p2]
                })
                .collect()
        } else {
            if pts.len() < d + 1 || !(pts.len() - 1).is_multiple_of(d) {
                return Err(vec![
                    Error::new(format!("a degree-{d} Bezier profile needs {d}·k + 1 points (k segments sharing end points), found {}", pts.len()))
                        .label("wrong number of points")
                        .help(format!("use {} or {} points, or set `degree`", d + 1, 2 * d + 1))
                        .at(span),
                ]);
            }
            pts.windows(d + 1).step_by(d).map(|w| w.to_vec()).collect()
        };
        Ok(Value::Profile(Rc::new(ProfileDef {
            segments,
            span,
            joints,
        })))
    }
}

impl Sink for ProfileBuilder {
    fn kind(&self) -> String {
        if self.spline {
            "a spline profile".into()
        } else {
            "a Bezier profile".into()
        }
    }
    fn props(&self) -> &'static [PropSpec] {
        if self.spline { &[] } else { &BEZIER_PROPS }
    }
    fn property(&mut self, _ev: &mut Evaluator, _kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        let d = num(&args[0])?;
        if !(1.0..=7.0).contains(&d) || d.fract() != 0.0 {
            return Err(range_error(
                args[0].span,
                format!(
                    "degree must be a whole number from 1 to 7, found {}",
                    short_number(d)
                ),
                "e.g. `degree 3`",
            ));
        }
        self.degree = Some(d as u32);
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        let p = v
            .vec2()
            .map_err(|e| e.help("profile points are 2-D: `<radius, height>`"))
            .at(span)?;
        self.points.push((p, span));
        Ok(())
    }
}
