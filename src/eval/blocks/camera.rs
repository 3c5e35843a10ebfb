//! `camera { ... }`.

use super::Sink;
use crate::diag::short_number;
use crate::diag::{Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, num, positive, range_error, vec3};
use crate::eval::props::{PropSpec, p};
use crate::eval::value::Value;
use crate::scene::Camera;
use crate::span::Span;
use crate::syntax::ast::Name;

/// Starts from the current camera (a declared one: from the defaults): a `camera { ... }`
/// block changes what it names.
pub(super) struct CameraBuilder {
    pub(super) camera: Camera,
    /// Whether a property or a declared camera was given yet: a declared camera sets every
    /// property, so it must come first.
    given: bool,
    /// Whether this block gave `fov`: an orthographic camera then shows what a perspective one
    /// with that field of view shows at `look_at` (POV-Ray's rule for `angle`).
    fov_given: bool,
}

static CAMERA_PROPS: [PropSpec; 8] = [
    p("orthographic", 0, 0, "nothing", ""),
    p("location", 1, 1, "a point", "<0, 1, -5>"),
    p("look_at", 1, 1, "a point", "<0, 1, 0>"),
    p("up", 1, 1, "a vector", "<0, 1, 0>"),
    p("fov", 1, 1, "an angle in degrees", "40"),
    p("aperture", 1, 1, "a lens radius", "0.05"),
    p("focus_distance", 1, 1, "a distance", "4"),
    p("right", 1, 1, "a vector", "<-1.33, 0, 0>"),
];

impl CameraBuilder {
    pub(super) fn new(camera: Camera) -> Self {
        Self {
            camera,
            given: false,
            fov_given: false,
        }
    }

    pub(super) fn finish(mut self, span: Span) -> SourceResult<Value> {
        let c = &mut self.camera;
        if c.orthographic && self.fov_given {
            // The view's height becomes the perspective view's at `look_at`; a `right` keeps
            // its ratio to `up`.
            let h = 2.0 * (0.5 * c.fov.to_radians()).tan() * (c.look_at - c.location).length();
            let k = h / c.up.length();
            if k.is_finite() && k > 0.0 {
                c.up *= k;
                c.right = c.right.map(|r| r * k);
            }
        }
        // The scene's own check (the one `prepare` runs), reported here at the block.
        if let Err(e) = self.camera.validate() {
            return Err(vec![e.at(span)]);
        }
        Ok(Value::Camera(Box::new(self.camera)))
    }
}

impl Sink for CameraBuilder {
    fn kind(&self) -> String {
        "a camera".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &CAMERA_PROPS
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        self.given = true;
        let c = &mut self.camera;
        match kw.text.as_str() {
            "orthographic" => c.orthographic = true,
            "location" => c.location = vec3(&args[0])?,
            "look_at" => c.look_at = vec3(&args[0])?,
            "up" => {
                let u = vec3(&args[0])?;
                if u.length_squared() == 0.0 {
                    return Err(vec![
                        Error::new("`up` is a zero vector")
                            .label("zero vector")
                            .help("give the direction that is up in the image, e.g. `up <0, 1, 0>`")
                            .at(args[0].span),
                    ]);
                }
                c.up = u;
            }
            "fov" => {
                let f = num(&args[0])?;
                if !(f > 0.0 && f < 180.0) {
                    return Err(range_error(
                        args[0].span,
                        format!(
                            "fov must be between 0 and 180 degrees, found {}",
                            short_number(f)
                        ),
                        "e.g. `fov 40`",
                    ));
                }
                c.fov = f;
                self.fov_given = true;
            }
            "aperture" => {
                let a = num(&args[0])?;
                if a < 0.0 {
                    return Err(range_error(
                        args[0].span,
                        format!("aperture must not be negative, found {}", short_number(a)),
                        "0 is a pinhole",
                    ));
                }
                c.aperture = a;
            }
            "focus_distance" => c.focus_distance = Some(positive(&args[0], "focus distance")?),
            // POV-Ray's `right`: the sign of its x component says which way the picture faces;
            // its length is an orthographic view's width (a perspective view's aspect ratio is
            // the resolution's).
            "right" => {
                let r = vec3(&args[0])?;
                if !(r.x.is_finite() && r.x != 0.0) {
                    return Err(range_error(
                        args[0].span,
                        format!(
                            "`right` needs a non-zero x component, found {}",
                            short_number(r.x)
                        ),
                        "`right <1.33, 0, 0>` is POV-Ray's left-handed camera, \
                         `right <-1.33, 0, 0>` a right-handed one; the aspect ratio is the \
                         resolution's",
                    ));
                }
                c.right = Some(r);
            }
            _ => unreachable!(),
        }
        Ok(())
    }
    /// A declared camera (`camera { Cam fov 30 }`, as in POV-Ray): every property is taken
    /// from it, and the properties after it change them.
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::Camera(_) if self.given => Err(vec![
                Error::new("a declared camera comes first in a camera block")
                    .label("after other properties or another camera")
                    .help(
                        "it sets every property, so what comes before it would be lost: move \
                         it to the start of the block (`camera { Cam fov 30 }`)",
                    )
                    .at(span),
            ]),
            Value::Camera(c) => {
                self.camera = *c;
                self.given = true;
                Ok(())
            }
            v => Err(super::unexpected(self, &v, span, self.positional_help())),
        }
    }
    fn positional_help(&self) -> &'static str {
        "a camera takes a declared camera (first: it sets every property), `orthographic`, \
         `location`, `look_at`, `up`, `fov`, `aperture`, `focus_distance`, `right`"
    }
}
