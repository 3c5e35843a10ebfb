//! `environment { ... }`: an image around the scene, as its background and a light.

use crate::diag::short_number;
use std::path::PathBuf;
use std::rc::Rc;

use glam::DAffine3;

use super::Sink;
use crate::diag::{Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, file_name, num, range_error, vec3};
use crate::eval::builtins::rotation;
use crate::eval::props::{PropSpec, p};
use crate::eval::value::{EnvDef, Value};
use crate::span::Span;
use crate::syntax::ast::Name;

#[derive(Default)]
pub(super) struct EnvBuilder {
    /// The resolved image path and where it was written.
    image: Option<(PathBuf, Span)>,
    intensity: Option<(f64, Span)>,
    rotation: Option<DAffine3>,
}

static ENV_PROPS: [PropSpec; 3] = [
    p("image", 1, 1, "a file name", "\"sky.hdr\""),
    p("intensity", 1, 1, "a number", "1"),
    p(
        "rotate",
        1,
        1,
        "a vector of angles in degrees",
        "<0, 90, 0>",
    ),
];

impl EnvBuilder {
    pub(super) fn finish(self, span: Span) -> SourceResult<Value> {
        let Some((path, path_span)) = self.image else {
            return Err(vec![
                Error::new("an environment needs an `image`")
                    .help("write e.g. `environment { image \"sky.hdr\" intensity 1 }`")
                    .at(span),
            ]);
        };
        // The image is loaded when the environment is used (by the top-level sink).
        Ok(Value::Environment(Rc::new(EnvDef {
            path,
            path_span,
            intensity: self.intensity.map_or(1.0, |(k, _)| k),
            intensity_span: self.intensity.map(|(_, s)| s),
            transform: self.rotation.unwrap_or(DAffine3::IDENTITY).inverse(),
        })))
    }
}

impl Sink for EnvBuilder {
    fn kind(&self) -> String {
        "an environment".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &ENV_PROPS
    }
    fn property(&mut self, ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        match kw.text.as_str() {
            "image" => {
                let path = ev.resolve_path(file_name(&args[0])?, args[0].span);
                self.image = Some((path, args[0].span));
            }
            "intensity" => {
                let k = num(&args[0])?;
                if k < 0.0 {
                    return Err(range_error(
                        args[0].span,
                        format!("intensity must not be negative, found {}", short_number(k)),
                        "e.g. `intensity 1`",
                    ));
                }
                if k > 1e9 || k.is_nan() {
                    return Err(range_error(
                        args[0].span,
                        format!("intensity {} is out of range", crate::diag::short_number(k)),
                        "use an intensity of at most 1e9",
                    ));
                }
                self.intensity = Some((k, args[0].span));
            }
            "rotate" => {
                self.rotation =
                    Some(rotation(vec3(&args[0])?) * self.rotation.unwrap_or(DAffine3::IDENTITY))
            }
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional_help(&self) -> &'static str {
        "an environment takes `image`, `intensity` and `rotate`"
    }
}
