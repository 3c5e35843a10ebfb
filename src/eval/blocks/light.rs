//! `light { ... }` (a point light) and `spotlight { ... }`.

use crate::diag::short_number;
use glam::DVec3;

use super::{Sink, unexpected};
use crate::diag::{At, Diagnostic, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, color, num, range_error, vec3};
use crate::eval::props::{PropSpec, p};
use crate::eval::value::Value;
use crate::scene::{Color, LightDecl};
use crate::span::Span;
use crate::syntax::ast::Name;

pub(super) struct LightBuilder {
    spot: bool,
    position: Option<DVec3>,
    intensity: Option<(Color, Span)>,
    point_at: Option<DVec3>,
    angle: Option<(f64, Span)>,
    falloff: Option<(f64, Span)>,
}

static LIGHT_PROPS: [PropSpec; 1] = [p("intensity", 1, 1, "a color", "rgb <10, 10, 10>")];
static SPOT_PROPS: [PropSpec; 4] = [
    p("intensity", 1, 1, "a color", "rgb <10, 10, 10>"),
    p("point_at", 1, 1, "a point", "<0, 0, 0>"),
    p("angle", 1, 1, "the cone half-angle in degrees", "30"),
    p("falloff", 1, 1, "the half-angle where falloff starts", "25"),
];

impl LightBuilder {
    pub(super) fn new(spot: bool) -> Self {
        Self {
            spot,
            position: None,
            intensity: None,
            point_at: None,
            angle: None,
            falloff: None,
        }
    }

    pub(super) fn finish(self, ev: &mut Evaluator, span: Span) -> SourceResult<Value> {
        let what = if self.spot { "spotlight" } else { "light" };
        let Some(position) = self.position else {
            return Err(vec![
                Error::new(format!("a {what} needs a position"))
                    .label("no position")
                    .help(format!(
                        "write e.g. `{what} {{ <0, 1.9, 0> intensity rgb <10, 10, 10> }}`"
                    ))
                    .at(span),
            ]);
        };
        let Some((intensity, ispan)) = self.intensity else {
            return Err(vec![
                Error::new(format!("a {what} needs `intensity`"))
                    .label("no intensity")
                    .help("add e.g. `intensity rgb <10, 10, 10>`")
                    .at(span),
            ]);
        };
        if intensity.min_element() < 0.0 {
            return Err(range_error(
                ispan,
                "intensity must not be negative".into(),
                "use components ≥ 0",
            ));
        }
        if intensity.max_element() == 0.0 {
            ev.warn(
                Diagnostic::warning(ispan, format!("this {what} has zero power"))
                    .with_label("zero intensity")
                    .with_help("remove the light or give it a positive intensity"),
            );
        }
        if !self.spot {
            return Ok(Value::Light(Box::new(LightDecl::Point {
                position,
                intensity,
                span,
            })));
        }
        let Some(target) = self.point_at else {
            return Err(vec![
                Error::new("a spotlight needs `point_at`")
                    .label("no direction")
                    .help("add e.g. `point_at <0, 0, 0>`")
                    .at(span),
            ]);
        };
        // (Scaled before it is normalised: a `point_at` 1e-300 away still gives a direction.)
        let Some(direction) = crate::eval::builtins::unit(target - position) else {
            return Err(vec![
                Error::new("the spotlight points at its own position")
                    .label("`point_at` is the light's position")
                    .help("point it at what it lights, e.g. `point_at <0, 0, 0>` for a light above")
                    .at(span),
            ]);
        };
        let (cone, cspan) = self.angle.unwrap_or((30.0, span));
        if !(cone > 0.0 && cone <= 90.0) {
            return Err(range_error(
                cspan,
                format!(
                    "the cone angle must be in (0, 90] degrees, found {}",
                    short_number(cone)
                ),
                "e.g. `angle 30`",
            ));
        }
        let (fall, fspan) = self.falloff.unwrap_or((cone * 0.8, span));
        if !(0.0..=cone).contains(&fall) {
            return Err(range_error(
                fspan,
                format!(
                    "falloff must be between 0 and the cone angle ({}), found {}",
                    short_number(cone),
                    short_number(fall)
                ),
                "e.g. `falloff 25` with `angle 30`",
            ));
        }
        Ok(Value::Light(Box::new(LightDecl::Spot {
            position,
            direction,
            intensity,
            cone_angle: cone,
            falloff_angle: fall,
            span,
        })))
    }
}

impl Sink for LightBuilder {
    fn kind(&self) -> String {
        if self.spot {
            "a spotlight".into()
        } else {
            "a light".into()
        }
    }
    fn props(&self) -> &'static [PropSpec] {
        if self.spot { &SPOT_PROPS } else { &LIGHT_PROPS }
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        match kw.text.as_str() {
            "intensity" => self.intensity = Some((color(&args[0])?, args[0].span)),
            "point_at" => self.point_at = Some(vec3(&args[0])?),
            "angle" => self.angle = Some((num(&args[0])?, args[0].span)),
            "falloff" => self.falloff = Some((num(&args[0])?, args[0].span)),
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        if self.position.is_some() {
            let help = match v {
                Value::Color(_) => "a light has one position; its colour is `intensity <color>`",
                _ => "a light has one position",
            };
            return Err(unexpected(self, &v, span, help));
        }
        self.position = Some(v.vec3().at(span)?);
        Ok(())
    }
}
