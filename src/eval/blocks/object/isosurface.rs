//! `isosurface { function { f(x, y, z) } threshold t contained_by { box { a, b } } open
//! accuracy a }` as POV-Ray writes it. `max_gradient` is accepted and ignored, with a warning
//! that says why: the surface is found by interval arithmetic, which needs no bound on the
//! gradient. `max_trace` and `all_intersections` are accepted and ignored (a ray takes its
//! nearest hit). The function is checked over its container before it renders: one that gives
//! no finite value there is refused.

use glam::DVec3;

use super::ObjectBuilder;
use crate::diag::{Diagnostic, Error, SourceResult, short_number};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, num};
use crate::eval::blocks::{Sink, unexpected};
use crate::eval::props::PropSpec;
use crate::eval::value::{FunctionValue, ObjectDef, ShapeDef, Value};
use crate::scene::blob::DEFAULT_ACCURACY;
use crate::scene::interval::Interval;
use crate::scene::{Container, Isosurface, ShapeDecl};
use crate::span::Span;
use crate::syntax::ast::Name;

const EXAMPLE: &str = "isosurface { function { x*x + y*y + z*z - 1 } \
                       contained_by { box { <-2, -2, -2>, <2, 2, 2> } } }";

/// Samples per axis of the check that the function gives numbers in its container.
const CHECK_SAMPLES: usize = 9;

impl ObjectBuilder {
    pub(super) fn iso_function(&mut self, f: &FunctionValue, span: Span) -> SourceResult<()> {
        if self.function.is_some() {
            return Err(vec![
                Error::new("an isosurface takes one function")
                    .label("a second function")
                    .help("combine them in one: `function { min(F1(x, y, z), F2(x, y, z)) }`")
                    .at(span),
            ]);
        }
        if f.code.params() != 3 {
            return Err(vec![
                Error::new(format!(
                    "an isosurface's function takes x, y, z, this one takes {} parameter{}",
                    f.code.params(),
                    if f.code.params() == 1 { "" } else { "s" }
                ))
                .label("here")
                .help("write `function { ... }` (x, y, z) or `function(x, y, z) { ... }`")
                .at(span),
            ]);
        }
        self.function = Some((f.code.clone(), span));
        Ok(())
    }

    pub(super) fn iso_property(
        &mut self,
        ev: &mut Evaluator,
        kw: &Name,
        args: &[Arg],
    ) -> SourceResult<()> {
        match kw.text.as_str() {
            "accuracy" => {
                let a = num(&args[0])?;
                if !(a > 0.0 && a.is_finite()) {
                    return Err(vec![
                        Error::new(format!(
                            "an isosurface's accuracy must be a positive number, found {}",
                            short_number(a)
                        ))
                        .label("not positive")
                        .help("the width below which a stretch of a ray is not split, e.g. `accuracy 1e-6`")
                        .at(args[0].span),
                    ]);
                }
                self.accuracy = Some((a, args[0].span));
            }
            "max_gradient" => {
                num(&args[0])?;
                ev.warn(
                    Diagnostic::warning(kw.span, "`max_gradient` is ignored here")
                        .with_label("not needed")
                        .with_help(
                            "the isosurface is found by interval arithmetic on the function, \
                             which cannot step over a thin feature and needs no bound on the \
                             gradient; remove it",
                        ),
                );
                self.max_gradient = Some(kw.span);
            }
            // A ray takes its nearest hit: POV-Ray's count of hits to keep has nothing to set.
            _ => {}
        }
        Ok(())
    }

    pub(super) fn isosurface(&self, ev: &mut Evaluator) -> SourceResult<ShapeDecl> {
        if let Some((v, s)) = self.values.first() {
            return Err(unexpected(
                self,
                v,
                *s,
                "an isosurface takes a `function { ... }`, `threshold`, `contained_by { ... }`, \
                 `open` and `accuracy`",
            ));
        }
        let Some((function, fspan)) = self.function.clone() else {
            return Err(vec![
                Error::new("an isosurface needs a function")
                    .label("no function")
                    .help(format!("e.g. `{EXAMPLE}`"))
                    .at(self.span),
            ]);
        };
        let (threshold, tspan) = self.threshold.unwrap_or((0.0, self.span));
        if !threshold.is_finite() {
            return Err(vec![
                Error::new(format!(
                    "an isosurface's threshold must be a finite number, found {}",
                    short_number(threshold)
                ))
                .label("here")
                .at(tspan),
            ]);
        }
        // POV-Ray's default container: the box from <-1, -1, -1> to <1, 1, 1>.
        let (container, cspan) = self.container.unwrap_or((
            Container::Box {
                min: DVec3::splat(-1.0),
                max: DVec3::splat(1.0),
            },
            self.span,
        ));
        if let Err(m) = container.check() {
            return Err(vec![
                Error::new(m)
                    .label("an empty container")
                    .help("give the box two opposite corners apart on every axis, or the sphere a positive radius")
                    .at(cspan),
            ]);
        }
        let (lo, hi) = container.bounds();
        let accuracy = self
            .accuracy
            .map_or(DEFAULT_ACCURACY * (hi - lo).length(), |a| a.0);
        // The function over the container: a grid of points, and its interval over the box.
        let mut finite = false;
        let n = CHECK_SAMPLES;
        for i in 0..n * n * n {
            let f = |k: usize| k as f64 / (n - 1) as f64;
            let u = DVec3::new(f(i % n), f(i / n % n), f(i / (n * n)));
            if function.eval_point(lo + u * (hi - lo)).is_finite() {
                finite = true;
                break;
            }
        }
        if !finite {
            return Err(vec![
                Error::new("the isosurface's function gives no finite value in its container")
                    .label("infinite or not a number everywhere tried")
                    .help(
                        "check for a division by zero or a root or logarithm of a negative \
                         number; the function is sampled on a 9×9×9 grid over the container",
                    )
                    .at(fspan),
            ]);
        }
        let range = function.eval_interval(&[0, 1, 2].map(|k| Interval::new(lo[k], hi[k])));
        if !range.contains(threshold) {
            ev.warn(
                Diagnostic::warning(fspan, "this isosurface is empty")
                    .with_label(format!(
                        "the function stays {} the threshold {} in its container",
                        if range.lo > threshold {
                            "above"
                        } else {
                            "below"
                        },
                        short_number(threshold)
                    ))
                    .with_help(
                        "move the threshold or the container to where the function meets it",
                    ),
            );
        }
        Ok(ShapeDecl::Isosurface(Isosurface {
            function,
            threshold,
            container,
            open: self.open,
            accuracy,
        }))
    }
}

/// The body of `contained_by { ... }`: one box or sphere.
#[derive(Default)]
pub(in crate::internals::eval::blocks) struct ContainedBy {
    container: Option<(Container, Span)>,
}

static NO_PROPS: [PropSpec; 0] = [];

impl ContainedBy {
    pub(in crate::internals::eval::blocks) fn finish(self, span: Span) -> SourceResult<Value> {
        let Some((c, _)) = self.container else {
            return Err(vec![
                Error::new("`contained_by` needs a box or a sphere")
                    .label("empty")
                    .help("e.g. `contained_by { box { <-1, -1, -1>, <1, 1, 1> } }`")
                    .at(span),
            ]);
        };
        let shape = match c {
            Container::Box { min, max } => ShapeDecl::Box { min, max },
            Container::Sphere { center, radius } => ShapeDecl::Sphere { center, radius },
        };
        Ok(Value::Object(std::rc::Rc::new(ObjectDef {
            parts: vec![crate::eval::value::Part {
                shape: ShapeDef::Ready(shape),
                transform: glam::DAffine3::IDENTITY,
                material: None,
                emission: None,
                span,
            }],
            container: true,
        })))
    }
}

/// A `contained_by { ... }` anywhere but inside an isosurface (POV-Ray refuses it too).
pub(in crate::internals::eval) fn container_misplaced(span: Span) -> Diagnostic {
    Error::new("`contained_by` belongs inside an `isosurface`")
        .label("not inside an isosurface")
        .help(
            "write it in the isosurface it bounds: `isosurface { function { ... } contained_by \
             { box { <-1, -1, -1>, <1, 1, 1> } } }`; to place a box, write `box { ... }`",
        )
        .at(span)
}

/// The container an object given to `contained_by` (or to an isosurface) stands for.
pub(super) fn container_of(o: &ObjectDef, span: Span) -> SourceResult<Container> {
    let refuse = || {
        vec![
            Error::new("an isosurface is contained by a box or a sphere")
                .label("not a box or a sphere")
                .help("e.g. `contained_by { box { <-1, -1, -1>, <1, 1, 1> } }` (transform the isosurface, not its container)")
                .at(span),
        ]
    };
    let [part] = o.parts.as_slice() else {
        return Err(refuse());
    };
    if part.transform != glam::DAffine3::IDENTITY {
        return Err(refuse());
    }
    match &part.shape {
        ShapeDef::Ready(ShapeDecl::Box { min, max }) => Ok(Container::Box {
            min: *min,
            max: *max,
        }),
        ShapeDef::Ready(ShapeDecl::Sphere { center, radius }) => Ok(Container::Sphere {
            center: *center,
            radius: *radius,
        }),
        _ => Err(refuse()),
    }
}

impl Sink for ContainedBy {
    fn kind(&self) -> String {
        "a `contained_by`".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &NO_PROPS
    }
    fn property(&mut self, _ev: &mut Evaluator, _kw: &Name, _args: Vec<Arg>) -> SourceResult<()> {
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match &v {
            Value::Object(o) if self.container.is_none() => {
                self.container = Some((container_of(o, span)?, span));
                Ok(())
            }
            _ => Err(unexpected(
                self,
                &v,
                span,
                "`contained_by` takes one `box { ... }` or `sphere { ... }`",
            )),
        }
    }
}
