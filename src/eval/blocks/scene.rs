//! The top level: the scene itself as a sink (objects, lights, camera, settings, background).

use super::{Sink, unexpected};
use crate::diag::{Diagnostic, Error, SourceResult, short_number};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, color_def};
use crate::eval::props::{PropSpec, p};
use crate::eval::value::{ColorDef, Value};
use crate::scene::{Background, ColorParam, environment_too_bright};
use crate::span::Span;
use crate::syntax::ast::Name;

#[derive(Default)]
pub(crate) struct TopSink {
    /// Where the background (`background` or `environment`) was last set.
    background: Option<Span>,
    /// Where the backdrop was last set.
    backdrop: Option<Span>,
}

impl TopSink {
    /// Records a background set at `span`; one set before is replaced, with a warning.
    fn set_background(&mut self, ev: &mut Evaluator, span: Span) {
        if let Some(before) = self.background.replace(span) {
            ev.warn(
                Diagnostic::warning(span, "this background replaces an earlier one")
                    .with_label("this one is used")
                    .with_extra(before, "replaced")
                    .with_help(
                        "keep one `background rgb <...>` or `environment { ... }`: the scene has \
                         one background, and an environment lights the scene by itself",
                    ),
            );
        }
    }
}

static TOP_PROPS: [PropSpec; 2] = [
    p(
        "background",
        1,
        1,
        "a color or a texture",
        "rgb <0.1, 0.1, 0.2>",
    ),
    p(
        "backdrop",
        1,
        1,
        "a color or a texture",
        "rgb <0.1, 0.1, 0.2>",
    ),
];

impl Sink for TopSink {
    fn kind(&self) -> String {
        "the scene".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &TOP_PROPS
    }
    fn property(&mut self, ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        // A colour or a texture over directions, as a surface colour is checked (in range,
        // not negative; a colour map's entries were checked where it was written).
        let param = match color_def(&args[0])? {
            ColorDef::Const(c) => ColorParam::Const(c),
            ColorDef::Tex(t) => ColorParam::Texture(ev.texture_id(&t)?),
        };
        let span = kw.span.join(args[0].span);
        if kw.text == "backdrop" {
            ev.scene.backdrop = Some(param);
            if let Some(before) = self.backdrop.replace(span) {
                ev.warn(
                    Diagnostic::warning(span, "this backdrop replaces an earlier one")
                        .with_label("this one is used")
                        .with_extra(before, "replaced")
                        .with_help("keep one `backdrop`: the scene has one"),
                );
            }
            return Ok(());
        }
        ev.scene.background = match param {
            ColorParam::Const(c) => Background::Color(c),
            ColorParam::Texture(id) => Background::Texture(id),
        };
        self.set_background(ev, span);
        Ok(())
    }
    fn positional(&mut self, ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::Object(o) if o.container => Err(vec![
                crate::eval::blocks::object::isosurface::container_misplaced(span),
            ]),
            Value::Object(o) => ev.emit(&o, span),
            Value::Settings(s) => {
                ev.scene.settings = *s;
                Ok(())
            }
            Value::Camera(c) => {
                ev.scene.camera = *c;
                Ok(())
            }
            Value::Light(l) => {
                ev.scene.lights.push(*l);
                Ok(())
            }
            Value::Environment(e) => {
                // Colour, as an image texture's: PNG and JPEG are sRGB-decoded (as Mitsuba's
                // `envmap` and pbrt's `imagemap` light read them); EXR and HDR are linear.
                let image = ev.image(&e.path, false, e.path_span)?;
                // The radiance is pixel times intensity: each within the colour limit, as an
                // emission's is (beyond it, f32 products overflow to infinity).
                if let Some((message, most)) = environment_too_bright(&image, e.intensity) {
                    let at = e.intensity_span.unwrap_or(e.path_span);
                    return Err(vec![
                        Error::new(message)
                            .label(if e.intensity_span.is_some() {
                                "too bright for this image"
                            } else {
                                "this image is too bright"
                            })
                            .help(format!(
                                "use an intensity of at most {} with this image (write \
                                 `intensity ...` in the environment), or scale the image down",
                                short_number(most)
                            ))
                            .at(at),
                    ]);
                }
                ev.scene.background = Background::Environment {
                    image,
                    intensity: e.intensity,
                    transform: e.transform,
                };
                self.set_background(ev, span);
                Ok(())
            }
            v => Err(unexpected(
                self,
                &v,
                span,
                "a statement is an object, a light, `camera { ... }`, `settings { ... }`, a directive or a macro call",
            )),
        }
    }
}
