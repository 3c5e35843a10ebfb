//! `sphere_sweep { linear_spline N, <c1>, r1, ..., <cN>, rN [tolerance t] }` as POV-Ray writes
//! it: a sphere moved along straight segments, its radius changing linearly. The swept solid
//! is exactly the `merge` of the spheres at the points and, per segment, the cone frustum
//! tangent to its two spheres (the rest of their convex hull), so it is built as that merge:
//! exact, closed, and a CSG child like any other.
//!
//! With `cubic_spline` or `b_spline` the sweep is the renderer's own primitive
//! ([`crate::scene::SphereSweep`]): at least 4 spheres, radii of any sign (a stretch where the
//! interpolated radius is not positive is absent), positive somewhere.

use glam::DVec3;

use super::ObjectBuilder;
use super::csg::node;
use crate::diag::{At, Error, SourceResult, short_number};
use crate::eval::value::{Part, Value};
use crate::scene::{CsgOp, MAX_SWEEP_SPHERES, ShapeDecl, SphereSweep, SweepSpline};
use crate::span::Span;

const EXAMPLE: &str =
    "sphere_sweep { linear_spline 3, <0, 0, 0>, 0.1, <1, 1, 0>, 0.2, <2, 0, 0>, 0.1 }";
const CURVED_EXAMPLE: &str = "sphere_sweep { b_spline 4, <0, 0, 0>, 0.1, <1, 1, 0>, 0.2, \
                              <2, 0, 0>, 0.2, <3, 1, 0>, 0.1 }";

impl ObjectBuilder {
    pub(super) fn sphere_sweep(&self) -> SourceResult<Vec<Part>> {
        let Some((count, count_span)) = self.values.first() else {
            return Err(vec![
                Error::new("a sphere_sweep needs a point count and its spheres")
                    .label("no values")
                    .help(format!("e.g. `{EXAMPLE}`"))
                    .at(self.span),
            ]);
        };
        let count = count.num().at(*count_span)?;
        let rest = &self.values[1..];
        if count != (rest.len() / 2) as f64 || !rest.len().is_multiple_of(2) {
            return Err(vec![
                Error::new(format!(
                    "the sphere_sweep says it has {} spheres, but {} value{} follow (a centre \
                     and a radius each)",
                    short_number(count),
                    rest.len(),
                    if rest.len() == 1 { "" } else { "s" }
                ))
                .label("the count")
                .help(format!(
                    "e.g. `{}`",
                    if self.sweep_spline.is_some() {
                        CURVED_EXAMPLE
                    } else {
                        EXAMPLE
                    }
                ))
                .at(*count_span),
            ]);
        }
        if let Some(spline) = self.sweep_spline {
            return self.curved_sweep(spline, rest, *count_span);
        }
        if rest.len() < 4 {
            return Err(vec![
                Error::new("a linear sphere_sweep needs at least 2 spheres")
                    .label("the count")
                    .help(format!("e.g. `{EXAMPLE}`"))
                    .at(*count_span),
            ]);
        }
        let mut spheres: Vec<(DVec3, f64)> = Vec::new();
        for pair in rest.chunks(2) {
            let (c, r) = sweep_sphere(pair, EXAMPLE)?;
            if !(r > 0.0 && r.is_finite()) {
                return Err(vec![
                    Error::new(format!(
                        "a sphere_sweep's radius must be positive, found {}",
                        short_number(r)
                    ))
                    .label("not a positive radius")
                    .help(format!("e.g. `{EXAMPLE}`"))
                    .at(pair[1].1),
                ]);
            }
            spheres.push((c, r));
        }
        let mut parts: Vec<Part> = spheres
            .iter()
            .map(|&(center, radius)| self.part(ShapeDecl::Sphere { center, radius }))
            .collect();
        for w in spheres.windows(2) {
            let ((c1, r1), (c2, r2)) = (w[0], w[1]);
            let axis = c2 - c1;
            let len = axis.length();
            // One sphere inside the other: the segment adds nothing to them.
            if len <= (r1 - r2).abs() {
                continue;
            }
            // The frustum touches each sphere on a circle where the cone's slope, sin a =
            // (r1 - r2) / len, meets it: shifted along the axis by r sin a, of radius r cos a.
            let u = axis / len;
            let sin = (r1 - r2) / len;
            let cos = (1.0 - sin * sin).max(0.0).sqrt();
            if cos < 1e-6 {
                continue;
            }
            parts.push(self.part(ShapeDecl::Cone {
                base: c1 + u * (r1 * sin),
                base_radius: r1 * cos,
                cap: c2 + u * (r2 * sin),
                cap_radius: r2 * cos,
                open: false,
            }));
        }
        Ok(vec![node(CsgOp::Merge, parts, self.span)?])
    }

    /// A sweep along a `cubic_spline` or `b_spline` of the spheres in `rest` (pairs of a
    /// centre and a radius, as many as the count says).
    fn curved_sweep(
        &self,
        spline: SweepSpline,
        rest: &[(crate::eval::value::Value, crate::span::Span)],
        count_span: crate::span::Span,
    ) -> SourceResult<Vec<Part>> {
        let name = match spline {
            SweepSpline::CatmullRom => "cubic_spline",
            SweepSpline::BSpline => "b_spline",
        };
        let n = rest.len() / 2;
        if n < 4 {
            return Err(vec![
                Error::new(format!(
                    "a `{name}` sphere_sweep needs at least 4 spheres, found {n}"
                ))
                .label("the count")
                .help(format!(
                    "the first and the last sphere only steer the curve's ends; e.g. \
                     `{CURVED_EXAMPLE}`"
                ))
                .at(count_span),
            ]);
        }
        if n > MAX_SWEEP_SPHERES {
            return Err(vec![
                Error::new(format!(
                    "a sphere_sweep may have at most {MAX_SWEEP_SPHERES} spheres, found {n}"
                ))
                .label("the count")
                .help("split the sweep into several")
                .at(count_span),
            ]);
        }
        let (mut centres, mut radii) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for pair in rest.chunks(2) {
            let (c, r) = sweep_sphere(pair, CURVED_EXAMPLE)?;
            if !r.is_finite() {
                return Err(vec![
                    Error::new(format!(
                        "a sphere_sweep's radius must be finite, found {}",
                        short_number(r)
                    ))
                    .label("not a finite radius")
                    .help(format!("e.g. `{CURVED_EXAMPLE}`"))
                    .at(pair[1].1),
                ]);
            }
            centres.push(c);
            radii.push(r);
        }
        let sweep = SphereSweep {
            spline,
            centres,
            radii,
        };
        if let Err(m) = sweep.check() {
            return Err(vec![
                Error::new(m)
                    .label("this sweep")
                    .help("give the spheres positive radii")
                    .at(self.span),
            ]);
        }
        Ok(vec![self.part(ShapeDecl::SphereSweep(sweep))])
    }
}

/// One sphere of a sweep: its centre (finite, or an error naming `example`) and its radius
/// (a number; each spline checks its range).
fn sweep_sphere(pair: &[(Value, Span)], example: &str) -> SourceResult<(DVec3, f64)> {
    let c = pair[0]
        .0
        .vec3()
        .map_err(|e| e.help("each sphere is a centre `<x, y, z>` and a radius"))
        .at(pair[0].1)?;
    let r = pair[1].0.num().at(pair[1].1)?;
    if !c.is_finite() {
        return Err(vec![
            Error::new("a sphere_sweep's centre must be finite")
                .label("not a finite point")
                .help(format!("e.g. `{example}`"))
                .at(pair[0].1),
        ]);
    }
    Ok((c, r))
}
