//! Blocks (`sphere { ... }`, `material { ... }`, `settings { ... }`, ...): each kind has a
//! builder that is the [`Sink`] of its body, checks its properties and builds a [`Value`].

mod camera;
mod environment;
mod light;
mod material;
mod normal;
mod object;
mod profile;
mod scene;
mod settings;
mod texture;
mod transparency;

use std::rc::Rc;

use super::Evaluator;
use super::args::Arg;
use super::props::PropSpec;
use super::value::Value;
use crate::diag::{Diagnostic, Error, SourceResult, suggest};
use crate::span::Span;
use crate::syntax::ast::{Item, Name};
use camera::CameraBuilder;
use environment::EnvBuilder;
use light::LightBuilder;
use material::MaterialBuilder;
use normal::NormalBuilder;
use object::{OBJECT_BLOCKS, ObjectBuilder};

use profile::ProfileBuilder;
pub(super) use scene::TopSink;
use settings::SettingsBuilder;
use texture::{ColorMapBuilder, TextureBuilder};

/// Receives the items of a body.
pub(crate) trait Sink {
    /// The block's name with an article, for messages ("a sphere").
    fn kind(&self) -> String;
    fn props(&self) -> &'static [PropSpec];
    fn prop_spec(&self, name: &str) -> Option<&'static PropSpec> {
        self.props().iter().find(|p| p.name == name)
    }
    fn property(&mut self, ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()>;
    /// A value written without a property name; refused unless the block takes one.
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        Err(unexpected(self, &v, span, self.positional_help()))
    }
    /// The help of the default [`Sink::positional`] refusal: what the block takes instead.
    fn positional_help(&self) -> &'static str {
        "this block takes properties only"
    }
}

/// The label of [`unexpected`]'s refusal: a macro call standing as a statement recognises it
/// (see `macros`).
pub(super) const UNEXPECTED_VALUE: &str = "unexpected value";

pub(super) fn unexpected<S: Sink + ?Sized>(
    sink: &S,
    v: &Value,
    span: Span,
    help: &str,
) -> Vec<Diagnostic> {
    vec![
        Error::new(format!(
            "{} does not take {} here",
            sink.kind(),
            v.type_name()
        ))
        .label(UNEXPECTED_VALUE)
        .help(help.to_string())
        .at(span),
    ]
}

/// Whether `name` is the name of a kind of block (`material`, `sphere`, ...).
/// `colour_map` is POV-Ray's other spelling of `color_map` (not listed with the blocks).
pub(super) fn is_block_name(name: &str) -> bool {
    OBJECT_BLOCKS.contains(&name) || VALUE_BLOCKS.contains(&name) || name == "colour_map"
}

/// The blocks that are not objects (those are [`OBJECT_BLOCKS`]).
const VALUE_BLOCKS: &[&str] = &[
    "material",
    "texture",
    "normal",
    "bump_map",
    "color_map",
    "bezier",
    "spline",
    "settings",
    "camera",
    "light",
    "spotlight",
    "environment",
    "contained_by",
];

/// A property keyword as the evaluator checks it (its name, what it takes and an example): what
/// an editor offers inside a block. Read from the builders' own tables, so the two cannot drift.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PropertyInfo {
    pub name: &'static str,
    /// What the arguments are ("a vector", "nothing").
    pub hint: &'static str,
    /// An argument as written (empty when it takes none).
    pub example: &'static str,
}

impl From<&PropSpec> for PropertyInfo {
    fn from(p: &PropSpec) -> Self {
        Self {
            name: p.name,
            hint: p.hint,
            example: p.example,
        }
    }
}

/// Every kind of block: the objects, then the others (`material`, `camera`, ...).
pub fn block_names() -> impl Iterator<Item = &'static str> {
    OBJECT_BLOCKS.iter().chain(VALUE_BLOCKS).copied()
}

/// The properties a block of kind `kind` takes (`None`: not a kind of block), from the builder
/// that evaluates its body.
pub fn block_properties(kind: &str) -> Option<Vec<PropertyInfo>> {
    let sink: Box<dyn Sink> = match kind {
        _ if OBJECT_BLOCKS.contains(&kind) => Box::new(ObjectBuilder::new(kind, Span::detached())),
        "material" => Box::new(MaterialBuilder::default()),
        // A texture's `size` is known to its `prop_spec` only (the pattern that uses it).
        "texture" => {
            let b = TextureBuilder::default();
            let mut all: Vec<PropertyInfo> = b.props().iter().map(PropertyInfo::from).collect();
            all.extend(texture::TEX_PROPS_SIZE.iter().map(PropertyInfo::from));
            return Some(all);
        }
        "normal" | "bump_map" => Box::new(NormalBuilder::new(kind == "bump_map")),
        "color_map" | "colour_map" => Box::new(ColorMapBuilder::default()),
        "bezier" | "spline" => Box::new(ProfileBuilder::new(kind == "spline")),
        "settings" => Box::new(SettingsBuilder(crate::scene::Settings::default())),
        "camera" => Box::new(CameraBuilder::new(crate::scene::Camera::default())),
        "light" | "spotlight" => Box::new(LightBuilder::new(kind == "spotlight")),
        "environment" => Box::new(EnvBuilder::default()),
        _ => return None,
    };
    Some(sink.props().iter().map(PropertyInfo::from).collect())
}

/// The properties of the scene's top level (`background`, `backdrop`).
pub fn top_level_properties() -> Vec<PropertyInfo> {
    TopSink::default()
        .props()
        .iter()
        .map(PropertyInfo::from)
        .collect()
}

impl Evaluator {
    pub(crate) fn eval_block(
        &mut self,
        kind: &Name,
        items: &Rc<Vec<Item>>,
        span: Span,
    ) -> SourceResult<Value> {
        self.check_nesting(kind.span)?;
        self.block_depth += 1;
        // A `#break` in the body cannot leave a `#switch` or loop around the block.
        let outer = std::mem::take(&mut self.break_targets);
        // A `sphere` or `cylinder` directly in a blob's body is a component of it; the body of
        // any other block is not a blob's.
        let component = self.in_blob && matches!(kind.text.as_str(), "sphere" | "cylinder");
        let outer_blob = std::mem::replace(&mut self.in_blob, kind.text == "blob");
        let r = self.eval_block_body(kind, items, span, component);
        self.in_blob = outer_blob;
        self.break_targets = outer;
        self.block_depth -= 1;
        r
    }

    fn eval_block_body(
        &mut self,
        kind: &Name,
        items: &Rc<Vec<Item>>,
        span: Span,
        component: bool,
    ) -> SourceResult<Value> {
        let k = kind.text.as_str();
        match k {
            _ if OBJECT_BLOCKS.contains(&k) => {
                let mut b = if component {
                    ObjectBuilder::new_component(k, span)
                } else {
                    ObjectBuilder::new(k, span)
                };
                self.run_items(items, &mut b)?;
                b.finish(self).map(|o| Value::Object(Rc::new(o)))
            }
            "material" => {
                let mut b = MaterialBuilder::default();
                self.run_items(items, &mut b)?;
                b.finish(self, span)
            }
            "texture" => {
                let mut b = TextureBuilder::default();
                self.run_items(items, &mut b)?;
                b.finish(self, span)
            }
            "normal" | "bump_map" => {
                let mut b = NormalBuilder::new(k == "bump_map");
                self.run_items(items, &mut b)?;
                b.finish(self, span)
            }
            "color_map" | "colour_map" => {
                let mut b = ColorMapBuilder::default();
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            "bezier" | "spline" => {
                let mut b = ProfileBuilder::new(k == "spline");
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            "settings" => {
                let mut b = SettingsBuilder(self.scene.settings.clone());
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            "camera" => {
                let start = if std::mem::take(&mut self.camera_from_defaults) {
                    crate::scene::Camera::default()
                } else {
                    self.scene.camera.clone()
                };
                let mut b = CameraBuilder::new(start);
                self.run_items(items, &mut b)?;
                b.camera.span = span;
                b.finish(span)
            }
            "light" | "spotlight" => {
                let mut b = LightBuilder::new(k == "spotlight");
                self.run_items(items, &mut b)?;
                b.finish(self, span)
            }
            "contained_by" => {
                let mut b = object::ContainedBy::default();
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            "environment" => {
                let mut b = EnvBuilder::default();
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            _ => {
                let mut e = Error::new(format!("unknown block `{k}`")).label("not a kind of block");
                let blocks = OBJECT_BLOCKS.iter().chain(VALUE_BLOCKS).copied();
                if let Some(hint) = crate::syntax::povray_hint(k, "") {
                    e = e.help(hint);
                } else if let Some(s) = suggest(k, blocks.clone()) {
                    e = e.help(format!("did you mean `{s}`?"));
                } else {
                    let names: Vec<String> = blocks.map(|b| format!("`{b}`")).collect();
                    e = e.help(format!("the blocks are {}", names.join(", ")));
                }
                Err(vec![e.at(kind.span)])
            }
        }
    }
}
