//! Blocks (`sphere { ... }`, `material { ... }`, `settings { ... }`, ...): their properties,
//! validation, and how they reach the [`Scene`].

use std::collections::HashMap;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::Arc;

use glam::{DAffine3, DQuat, DVec2, DVec3};

use super::Evaluator;
use super::builtins::rotation;
use super::value::Value;
use crate::diag::{At, Diagnostic, Error, SourceResult, suggest};
use crate::scene::*;
use crate::span::Span;
use crate::syntax::ast::{Item, Name};

/// One argument of a property: its value and where it was written.
pub(crate) struct Arg {
    pub value: Value,
    pub span: Span,
}

/// How a property keyword takes its arguments.
#[derive(Clone, Copy)]
pub(crate) struct PropSpec {
    pub name: &'static str,
    pub min: u8,
    pub max: u8,
    /// The argument is a bare word (`wrap repeat`), not an expression.
    pub word: bool,
    /// What the arguments are, for "needs ..." messages.
    pub hint: &'static str,
    pub example: &'static str,
}

const fn p(
    name: &'static str,
    min: u8,
    max: u8,
    hint: &'static str,
    example: &'static str,
) -> PropSpec {
    PropSpec {
        name,
        min,
        max,
        word: false,
        hint,
        example,
    }
}

const fn w(name: &'static str, hint: &'static str, example: &'static str) -> PropSpec {
    PropSpec {
        name,
        min: 1,
        max: 1,
        word: true,
        hint,
        example,
    }
}

/// Receives the items of a body.
pub(crate) trait Sink {
    /// The block's name with an article, for messages ("a sphere").
    fn kind(&self) -> String;
    fn props(&self) -> &'static [PropSpec];
    fn prop_spec(&self, name: &str) -> Option<&'static PropSpec> {
        self.props().iter().find(|p| p.name == name)
    }
    fn property(&mut self, ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()>;
    fn positional(&mut self, ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()>;
}

fn unexpected(sink: &dyn Sink, v: &Value, span: Span, help: &str) -> Vec<Diagnostic> {
    vec![
        Error::new(format!(
            "{} does not take {} here",
            sink.kind(),
            v.type_name()
        ))
        .label("unexpected value")
        .help(help.to_string())
        .at(span),
    ]
}

// ------------------------------------------------------------------ definitions (values)

#[derive(Debug, Clone)]
pub enum ColorDef {
    Const(Color),
    Tex(Rc<TextureDef>),
}

#[derive(Debug)]
pub struct MaterialDef {
    pub kind: MatKind,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub enum MatKind {
    Diffuse(ColorDef),
    Mirror(ColorDef),
    Glass {
        ior: f64,
        absorb: ColorDef,
        tint: Color,
    },
    Glossy {
        albedo: ColorDef,
        specular: ColorDef,
        roughness: ColorDef,
    },
}

#[derive(Debug)]
pub struct TextureDef {
    pub pattern: PatternDef,
    pub mapping: Mapping,
    pub transform: DAffine3,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub enum PatternDef {
    Ready(Pattern),
    Image {
        path: PathBuf,
        linear: bool,
        wrap: Wrap,
        bilinear: bool,
        span: Span,
    },
}

#[derive(Debug, Clone)]
pub enum ShapeDef {
    Ready(Shape),
    Mesh { path: PathBuf, span: Span },
}

#[derive(Debug, Clone)]
pub struct Part {
    pub shape: ShapeDef,
    pub transform: DAffine3,
    pub material: Option<Rc<MaterialDef>>,
    pub emission: Option<Emission>,
    pub span: Span,
}

#[derive(Debug)]
pub struct ObjectDef {
    pub parts: Vec<Part>,
}

#[derive(Debug)]
pub struct ProfileDef {
    pub segments: Vec<Vec<DVec2>>,
    pub span: Span,
    /// Span of each segment's first point.
    pub joints: Vec<Span>,
}

#[derive(Debug)]
pub struct EnvDef {
    pub path: PathBuf,
    pub path_span: Span,
    pub intensity: f64,
    pub transform: DAffine3,
}

/// Loaded assets and the ids given to declared materials and textures.
#[derive(Default)]
pub(crate) struct Assets {
    materials: HashMap<*const MaterialDef, (Rc<MaterialDef>, MaterialId)>,
    textures: HashMap<*const TextureDef, (Rc<TextureDef>, TextureId)>,
    images: HashMap<(PathBuf, bool), Arc<ImageData>>,
    meshes: HashMap<PathBuf, Arc<MeshData>>,
    default_material: Option<MaterialId>,
    black_material: Option<MaterialId>,
}

pub(crate) fn empty_scene() -> Scene {
    Scene {
        settings: Settings::default(),
        camera: Camera::default(),
        objects: Vec::new(),
        lights: Vec::new(),
        materials: Vec::new(),
        textures: Vec::new(),
        background: Background::default(),
        dependencies: Vec::new(),
    }
}

// ------------------------------------------------------------------ block dispatch

/// Every block name, for "did you mean".
pub(crate) const BLOCKS: &[&str] = &[
    "sphere",
    "plane",
    "quad",
    "box",
    "cylinder",
    "disk",
    "triangle",
    "mesh",
    "revolve",
    "bezier_patch",
    "bezier_mesh",
    "union",
    "group",
    "object",
    "area_light",
    "material",
    "texture",
    "color_map",
    "bezier",
    "spline",
    "settings",
    "camera",
    "light",
    "spotlight",
    "environment",
];

const SHAPES: &[&str] = &[
    "sphere",
    "plane",
    "quad",
    "box",
    "cylinder",
    "disk",
    "triangle",
    "mesh",
    "revolve",
    "bezier_patch",
    "bezier_mesh",
];

impl Evaluator {
    pub(crate) fn eval_block(
        &mut self,
        kind: &Name,
        items: &Rc<Vec<Item>>,
        span: Span,
    ) -> SourceResult<Value> {
        let k = kind.text.as_str();
        match k {
            _ if SHAPES.contains(&k)
                || matches!(k, "union" | "group" | "object" | "area_light") =>
            {
                let mut b = ObjectBuilder::new(k, span);
                self.run_items(items, &mut b)?;
                b.finish(self).map(|o| Value::Object(Rc::new(o)))
            }
            "material" => {
                let mut b = MaterialBuilder::default();
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            "texture" => {
                let mut b = TextureBuilder::default();
                self.run_items(items, &mut b)?;
                b.finish(self, span)
            }
            "color_map" => {
                let mut b = ColorMapBuilder::default();
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            "bezier" | "spline" => {
                let mut b = ProfileBuilder {
                    spline: k == "spline",
                    degree: None,
                    points: Vec::new(),
                };
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            "settings" => {
                let mut b = SettingsBuilder(self.scene.settings.clone());
                self.run_items(items, &mut b)?;
                Ok(Value::Settings(Box::new(b.0)))
            }
            "camera" => {
                let mut b = CameraBuilder {
                    cam: self.scene.camera.clone(),
                    focus: None,
                };
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            "light" | "spotlight" => {
                let mut b = LightBuilder::new(k == "spotlight");
                self.run_items(items, &mut b)?;
                b.finish(self, span)
            }
            "environment" => {
                let mut b = EnvBuilder::default();
                self.run_items(items, &mut b)?;
                b.finish(span)
            }
            _ => {
                let mut e = Error::new(format!("unknown block `{k}`")).label("not a kind of block");
                if let Some(s) = suggest(k, BLOCKS.iter().copied()) {
                    e = e.help(format!("did you mean `{s}`?"));
                }
                Err(vec![e.at(kind.span)])
            }
        }
    }

    /// Adds an object's parts to the scene.
    fn emit(&mut self, obj: &ObjectDef, span: Span) -> SourceResult<()> {
        for part in &obj.parts {
            self.check_object_budget(span)?;
            let material = match (&part.material, part.emission) {
                (Some(m), _) => self.material_id(m)?,
                (None, Some(_)) => self.black_material(),
                (None, None) => self.default_material(),
            };
            let shape = match &part.shape {
                ShapeDef::Ready(s) => s.clone(),
                ShapeDef::Mesh { path, span } => Shape::Mesh {
                    mesh: self.mesh(path, *span)?,
                },
            };
            self.scene.objects.push(Object {
                shape,
                transform: part.transform,
                material,
                emission: part.emission,
                span: part.span,
            });
        }
        Ok(())
    }

    fn push_material(&mut self, m: Material) -> MaterialId {
        self.scene.materials.push(m);
        MaterialId(self.scene.materials.len() as u32 - 1)
    }

    fn default_material(&mut self) -> MaterialId {
        if let Some(id) = self.assets.default_material {
            return id;
        }
        let id = self.push_material(Material::Diffuse {
            albedo: ColorParam::Const(Color::splat(0.5)),
        });
        self.assets.default_material = Some(id);
        id
    }

    fn black_material(&mut self) -> MaterialId {
        if let Some(id) = self.assets.black_material {
            return id;
        }
        let id = self.push_material(Material::Diffuse {
            albedo: ColorParam::Const(Color::ZERO),
        });
        self.assets.black_material = Some(id);
        id
    }

    fn material_id(&mut self, m: &Rc<MaterialDef>) -> SourceResult<MaterialId> {
        let key = Rc::as_ptr(m);
        if let Some((_, id)) = self.assets.materials.get(&key) {
            return Ok(*id);
        }
        let material = match &m.kind {
            MatKind::Diffuse(a) => Material::Diffuse {
                albedo: self.color_param(a)?,
            },
            MatKind::Mirror(t) => Material::Mirror {
                tint: self.color_param(t)?,
            },
            MatKind::Glass { ior, absorb, tint } => Material::Glass {
                ior: *ior,
                absorb: self.color_param(absorb)?,
                tint: *tint,
            },
            MatKind::Glossy {
                albedo,
                specular,
                roughness,
            } => Material::Glossy {
                albedo: self.color_param(albedo)?,
                specular: self.color_param(specular)?,
                roughness: match self.color_param(roughness)? {
                    ColorParam::Const(c) => ScalarParam::Const(c.x),
                    ColorParam::Texture(t) => ScalarParam::Texture(t),
                },
            },
        };
        let id = self.push_material(material);
        self.assets.materials.insert(key, (m.clone(), id));
        Ok(id)
    }

    fn color_param(&mut self, c: &ColorDef) -> SourceResult<ColorParam> {
        Ok(match c {
            ColorDef::Const(c) => ColorParam::Const(*c),
            ColorDef::Tex(t) => ColorParam::Texture(self.texture_id(t)?),
        })
    }

    fn texture_id(&mut self, t: &Rc<TextureDef>) -> SourceResult<TextureId> {
        let key = Rc::as_ptr(t);
        if let Some((_, id)) = self.assets.textures.get(&key) {
            return Ok(*id);
        }
        let pattern = match &t.pattern {
            PatternDef::Ready(p) => p.clone(),
            PatternDef::Image {
                path,
                linear,
                wrap,
                bilinear,
                span,
            } => Pattern::Image {
                image: self.image(path, *linear, *span)?,
                wrap: *wrap,
                bilinear: *bilinear,
            },
        };
        self.scene.textures.push(Texture {
            pattern,
            mapping: t.mapping,
            transform: t.transform,
            span: t.span,
        });
        let id = TextureId(self.scene.textures.len() as u32 - 1);
        self.assets.textures.insert(key, (t.clone(), id));
        Ok(id)
    }

    fn image(
        &mut self,
        path: &std::path::Path,
        linear: bool,
        span: Span,
    ) -> SourceResult<Arc<ImageData>> {
        let key = (path.to_path_buf(), linear);
        if let Some(img) = self.assets.images.get(&key) {
            return Ok(img.clone());
        }
        let space = if linear {
            ColorSpace::Linear
        } else {
            ColorSpace::Srgb
        };
        // Recorded before the read so that `watch` also waits for a file that is missing.
        self.scene.dependencies.push(path.to_path_buf());
        let img = load_image(path, space).map_err(|e| {
            vec![
                Error::new(e)
                    .label("cannot load this image")
                    .help("the path is resolved relative to the scene file")
                    .at(span),
            ]
        })?;
        let img = Arc::new(img);
        self.assets.images.insert(key, img.clone());
        Ok(img)
    }

    fn mesh(&mut self, path: &PathBuf, span: Span) -> SourceResult<Arc<MeshData>> {
        if let Some(m) = self.assets.meshes.get(path) {
            return Ok(m.clone());
        }
        self.scene.dependencies.push(path.clone());
        let m = load_obj(path).map_err(|e| {
            vec![
                Error::new(e)
                    .label("cannot load this mesh")
                    .help("the path is resolved relative to the scene file")
                    .at(span),
            ]
        })?;
        let m = Arc::new(m);
        self.assets.meshes.insert(path.clone(), m.clone());
        Ok(m)
    }

    pub(crate) fn finish_scene(&mut self) {}
}

// ------------------------------------------------------------------ argument helpers

fn num(a: &Arg) -> SourceResult<f64> {
    a.value.num().at(a.span)
}

fn vec3(a: &Arg) -> SourceResult<DVec3> {
    a.value.vec3().at(a.span)
}

fn color(a: &Arg) -> SourceResult<Color> {
    a.value.color().at(a.span)
}

fn word(a: &Arg, choices: &[&str]) -> SourceResult<String> {
    let s = match &a.value {
        Value::Str(s) => s.to_string(),
        v => {
            return Err(vec![
                Error::new(format!(
                    "expected one of {}, found {}",
                    choices.join(", "),
                    v.type_name()
                ))
                .at(a.span),
            ]);
        }
    };
    if choices.contains(&s.as_str()) {
        return Ok(s);
    }
    let mut e =
        Error::new(format!("`{s}` is not one of {}", choices.join(", "))).label("unknown choice");
    if let Some(c) = suggest(&s, choices.iter().copied()) {
        e = e.help(format!("did you mean `{c}`?"));
    }
    Err(vec![e.at(a.span)])
}

fn range_error(span: Span, msg: String, help: &str) -> Vec<Diagnostic> {
    vec![
        Error::new(msg)
            .label("out of range")
            .help(help.to_string())
            .at(span),
    ]
}

fn positive(a: &Arg, what: &str) -> SourceResult<f64> {
    let x = num(a)?;
    if x <= 0.0 {
        return Err(range_error(
            a.span,
            format!("{what} must be positive, found {x}"),
            "use a number greater than 0",
        ));
    }
    Ok(x)
}

fn count(a: &Arg, what: &str, max: f64) -> SourceResult<f64> {
    let x = num(a)?;
    if x < 1.0 || x.fract() != 0.0 || x > max {
        return Err(range_error(
            a.span,
            format!("{what} must be a whole number from 1 to {max}, found {x}"),
            "use a whole number in range",
        ));
    }
    Ok(x)
}

fn color_def(a: &Arg) -> SourceResult<ColorDef> {
    match &a.value {
        Value::Texture(t) => Ok(ColorDef::Tex(t.clone())),
        v => Ok(ColorDef::Const(
            v.color()
                .map_err(|e| {
                    e.help("give a color `rgb <r, g, b>`, a number or a `texture { ... }`")
                })
                .at(a.span)?,
        )),
    }
}

/// Applies a transform property to `t` (each applied after the previous one).
fn transform_prop(kw: &str, args: &[Arg], t: &mut DAffine3) -> SourceResult<bool> {
    let m = match kw {
        "translate" => DAffine3::from_translation(vec3(&args[0])?),
        "rotate" => rotation(vec3(&args[0])?),
        "scale" => {
            let s = match &args[0].value {
                Value::Num(n) => DVec3::splat(*n),
                _ => vec3(&args[0])?,
            };
            if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 {
                return Err(vec![
                    Error::new("scale by zero flattens the object")
                        .label("a zero component")
                        .help("use a small non-zero scale")
                        .at(args[0].span),
                ]);
            }
            DAffine3::from_scale(s)
        }
        "matrix" => {
            let mut xs = Vec::new();
            for a in args {
                match &a.value {
                    Value::Array(v) => {
                        for x in v.iter() {
                            xs.push(x.num().at(a.span)?);
                        }
                    }
                    Value::Vec3(v) => xs.extend(v.to_array()),
                    _ => xs.push(num(a)?),
                }
            }
            let span = args[0].span.join(args[args.len() - 1].span);
            if xs.len() != 12 {
                return Err(vec![
                    Error::new(format!("`matrix` needs 12 numbers, found {}", xs.len()))
                        .label("wrong count")
                        .help("write `matrix <a,b,c, d,e,f, g,h,i, tx,ty,tz>` as in POV-Ray")
                        .at(span),
                ]);
            }
            let m = DAffine3::from_cols(
                DVec3::new(xs[0], xs[1], xs[2]),
                DVec3::new(xs[3], xs[4], xs[5]),
                DVec3::new(xs[6], xs[7], xs[8]),
                DVec3::new(xs[9], xs[10], xs[11]),
            );
            if m.matrix3.determinant().abs() < 1e-12 {
                return Err(vec![
                    Error::new("this matrix is singular (it flattens the object)")
                        .label("determinant 0")
                        .at(span),
                ]);
            }
            m
        }
        _ => return Ok(false),
    };
    *t = m * *t;
    Ok(true)
}

const TRANSFORMS: [PropSpec; 4] = [
    p("translate", 1, 1, "a vector", "<1, 0, 0>"),
    p(
        "rotate",
        1,
        1,
        "a vector of angles in degrees",
        "<0, 30, 0>",
    ),
    p("scale", 1, 1, "a number or a vector", "2"),
    p(
        "matrix",
        1,
        12,
        "12 numbers",
        "<1,0,0, 0,1,0, 0,0,1, 0,0,0>",
    ),
];

/// `TRANSFORMS` followed by `extra` (`M` must be `N + 4`: checked when the static is built).
const fn with_transforms<const N: usize, const M: usize>(extra: [PropSpec; N]) -> [PropSpec; M] {
    assert!(M == N + TRANSFORMS.len());
    let mut out = [TRANSFORMS[0]; M];
    let mut i = 0;
    while i < M {
        out[i] = if i < TRANSFORMS.len() {
            TRANSFORMS[i]
        } else {
            extra[i - TRANSFORMS.len()]
        };
        i += 1;
    }
    out
}

// ------------------------------------------------------------------ top level

pub(crate) struct TopSink;

static TOP_PROPS: [PropSpec; 1] = [p("background", 1, 1, "a color", "rgb <0.1, 0.1, 0.2>")];

impl Sink for TopSink {
    fn kind(&self) -> String {
        "the scene".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &TOP_PROPS
    }
    fn property(&mut self, ev: &mut Evaluator, _kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        ev.scene.background = Background::Color(color(&args[0])?);
        Ok(())
    }
    fn positional(&mut self, ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
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
                let image = ev.image(&e.path, true, e.path_span)?;
                ev.scene.background = Background::Environment {
                    image,
                    intensity: e.intensity,
                    transform: e.transform,
                };
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

// ------------------------------------------------------------------ objects

struct ObjectBuilder {
    kind: &'static str,
    span: Span,
    values: Vec<(Value, Span)>,
    parts: Vec<Part>,
    transform: DAffine3,
    material: Option<Rc<MaterialDef>>,
    radiance: Option<(Color, Span)>,
    two_sided: bool,
    open: bool,
    profile: Option<Rc<ProfileDef>>,
    corner: bool,
    axis: Option<(DVec3, Span)>,
    sweep: Option<(f64, f64)>,
    method: Option<(String, Span)>,
    iterations: u32,
    starts: u32,
}

static OBJ_PROPS: [PropSpec; 4] = TRANSFORMS;
static CYL_PROPS: [PropSpec; 5] = with_transforms([p("open", 0, 0, "nothing", "")]);
static AREA_PROPS: [PropSpec; 6] = with_transforms([
    p("radiance", 1, 1, "a color", "rgb <17, 12, 4>"),
    p("two_sided", 0, 0, "nothing", ""),
]);
static PATCH_PROPS: [PropSpec; 7] = with_transforms([
    w("method", "`robust` or `newton`", "newton"),
    p("iterations", 1, 1, "a number", "12"),
    p("starts", 1, 1, "a number", "8"),
]);
static REVOLVE_PROPS: [PropSpec; 11] = with_transforms([
    w("method", "`robust` or `newton`", "newton"),
    p("iterations", 1, 1, "a number", "12"),
    p("starts", 1, 1, "a number", "8"),
    p(
        "profile",
        1,
        1,
        "a `bezier { ... }` or `spline { ... }` block",
        "bezier { <0, 0>, <0.3, 0>, <0.3, 0.5>, <0, 0.5> }",
    ),
    p("corner", 0, 0, "nothing", ""),
    p("axis", 1, 1, "a vector", "<0, 0, 1>"),
    p("angle", 2, 2, "two angles in degrees", "0, 270"),
]);

/// What each primitive's positional values are: (name, kind) with kind `v` vector, `n` number,
/// `s` string.
fn signature(kind: &str) -> &'static [(&'static str, char)] {
    match kind {
        "sphere" => &[("center", 'v'), ("radius", 'n')],
        "plane" => &[("normal", 'v'), ("offset", 'n')],
        "quad" => &[("corner", 'v'), ("first edge", 'v'), ("second edge", 'v')],
        "box" => &[("first corner", 'v'), ("opposite corner", 'v')],
        "cylinder" => &[("base point", 'v'), ("cap point", 'v'), ("radius", 'n')],
        "disk" => &[("center", 'v'), ("normal", 'v'), ("radius", 'n')],
        "triangle" => &[
            ("first vertex", 'v'),
            ("second vertex", 'v'),
            ("third vertex", 'v'),
        ],
        "mesh" => &[("OBJ file name", 's')],
        _ => &[],
    }
}

fn example(kind: &str) -> &'static str {
    match kind {
        "sphere" => "sphere { <0, 1, 0>, 0.5 }",
        "plane" => "plane { <0, 1, 0>, 0 }",
        "quad" => "quad { <-1, 0, -1>, <2, 0, 0>, <0, 0, 2> }",
        "box" => "box { <-1, 0, -1>, <1, 1, 1> }",
        "cylinder" => "cylinder { <0, 0, 0>, <0, 1, 0>, 0.1 }",
        "disk" => "disk { <0, 0, 0>, <0, 1, 0>, 1 }",
        "triangle" => "triangle { <0, 0, 0>, <1, 0, 0>, <0, 1, 0> }",
        "mesh" => "mesh { \"bunny.obj\" }",
        _ => "",
    }
}

impl ObjectBuilder {
    fn new(kind: &str, span: Span) -> Self {
        let kind = BLOCKS
            .iter()
            .find(|k| **k == kind)
            .copied()
            .unwrap_or("object");
        Self {
            kind,
            span,
            values: Vec::new(),
            parts: Vec::new(),
            transform: DAffine3::IDENTITY,
            material: None,
            radiance: None,
            two_sided: false,
            open: false,
            profile: None,
            corner: false,
            axis: None,
            sweep: None,
            method: None,
            iterations: 12,
            starts: 8,
        }
    }

    fn is_container(&self) -> bool {
        matches!(self.kind, "union" | "group" | "object" | "area_light")
    }

    fn part(&self, shape: Shape) -> Part {
        Part {
            shape: ShapeDef::Ready(shape),
            transform: DAffine3::IDENTITY,
            material: None,
            emission: None,
            span: self.span,
        }
    }

    fn method(&self) -> IntersectMethod {
        match &self.method {
            Some((m, _)) if m == "newton" => IntersectMethod::Newton {
                iterations: self.iterations,
                starts: self.starts,
            },
            _ => IntersectMethod::Robust,
        }
    }

    fn finish(mut self, ev: &mut Evaluator) -> SourceResult<ObjectDef> {
        let mut parts = match self.kind {
            "union" | "group" | "object" => {
                if self.parts.is_empty() {
                    ev.warn(
                        Diagnostic::warning(self.span, format!("empty {}", self.kind))
                            .with_label("contains no objects"),
                    );
                }
                std::mem::take(&mut self.parts)
            }
            "area_light" => {
                let Some((radiance, rspan)) = self.radiance else {
                    return Err(vec![
                        Error::new("an area light needs `radiance`")
                            .label("no radiance given")
                            .help("add e.g. `radiance rgb <17, 12, 4>`")
                            .at(self.span),
                    ]);
                };
                if self.parts.len() != 1 {
                    return Err(vec![Error::new(format!("an area light needs exactly one shape, found {}", self.parts.len())).label("here").help("write e.g. `area_light { quad { <-0.25, 1.98, -0.25>, <0.5, 0, 0>, <0, 0, 0.5> } radiance rgb <17, 12, 4> }`").at(self.span)]);
                }
                if radiance.max_element() <= 0.0 {
                    ev.warn(
                        Diagnostic::warning(rspan, "this area light emits no light")
                            .with_label("zero radiance")
                            .with_help("give a positive radiance, or use a plain object"),
                    );
                }
                if radiance.min_element() < 0.0 {
                    return Err(range_error(
                        rspan,
                        "radiance must not be negative".into(),
                        "use components ≥ 0",
                    ));
                }
                let mut parts = std::mem::take(&mut self.parts);
                let emission = Emission {
                    radiance,
                    two_sided: self.two_sided,
                };
                for p in &mut parts {
                    if let ShapeDef::Ready(s) = &p.shape
                        && !matches!(
                            s,
                            Shape::Quad { .. }
                                | Shape::Disk { .. }
                                | Shape::Sphere { .. }
                                | Shape::Triangle { .. }
                        )
                    {
                        return Err(vec![
                            Error::new(format!(
                                "an area light cannot be {} {}",
                                if s.kind().starts_with(['a', 'e', 'i', 'o', 'u']) {
                                    "an"
                                } else {
                                    "a"
                                },
                                s.kind()
                            ))
                            .label("unsupported emitter")
                            .help("use a quad, disk, sphere or triangle")
                            .at(p.span),
                        ]);
                    }
                    p.emission = Some(emission);
                }
                parts
            }
            "revolve" => {
                let Some(profile) = self.profile.clone() else {
                    return Err(vec![Error::new("a revolve needs a `profile`").label("no profile").help("add e.g. `profile bezier { <0, 0>, <0.35, 0>, <0.4, 0.3>, <0.15, 0.6> }`").at(self.span)]);
                };
                self.check_profile(ev, &profile)?;
                vec![self.part(Shape::Revolve {
                    profile: Profile {
                        segments: profile.segments.clone(),
                    },
                    sweep: self.sweep,
                    method: self.method(),
                })]
            }
            "bezier_patch" | "bezier_mesh" => {
                let n = self.values.len();
                if n == 0 || !n.is_multiple_of(16) || (self.kind == "bezier_patch" && n != 16) {
                    return Err(vec![
                        Error::new(format!(
                            "{} needs {} control points, found {n}",
                            self.kind,
                            if self.kind == "bezier_patch" {
                                "16"
                            } else {
                                "a multiple of 16"
                            }
                        ))
                        .label("wrong number of points")
                        .help("give 4 rows of 4 points `<x, y, z>`, row by row")
                        .at(self.span),
                    ]);
                }
                let mut parts = Vec::new();
                for chunk in self.values.chunks(16) {
                    let mut pts = [DVec3::ZERO; 16];
                    for (i, (v, s)) in chunk.iter().enumerate() {
                        pts[i] = v.vec3().at(*s)?;
                    }
                    parts.push(self.part(Shape::BezierPatch {
                        points: Box::new(pts),
                        method: self.method(),
                    }));
                }
                parts
            }
            _ => vec![self.primitive(ev)?],
        };
        let mut t = self.transform;
        if let Some((axis, span)) = self.axis {
            if axis.length_squared() == 0.0 {
                return Err(vec![
                    Error::new("the axis has zero length")
                        .label("zero vector")
                        .at(span),
                ]);
            }
            t *= DAffine3::from_quat(DQuat::from_rotation_arc(DVec3::Y, axis.normalize()));
        }
        if t.matrix3.determinant().abs() < 1e-300 {
            return Err(vec![Error::new("the transform is singular").at(self.span)]);
        }
        for part in &mut parts {
            part.transform = t * part.transform;
            if part.material.is_none() {
                part.material = self.material.clone();
            }
        }
        Ok(ObjectDef { parts })
    }

    fn check_profile(&self, ev: &mut Evaluator, profile: &ProfileDef) -> SourceResult<()> {
        for seg in &profile.segments {
            for p in seg {
                if p.x < 0.0 {
                    return Err(range_error(
                        profile.span,
                        format!("profile point <{}, {}> has a negative radius", p.x, p.y),
                        "radii (the first component) must be ≥ 0",
                    ));
                }
            }
        }
        if self.corner {
            return Ok(());
        }
        for (k, pair) in profile.segments.windows(2).enumerate() {
            let (a, b) = (&pair[0], &pair[1]);
            let at = profile.joints.get(k + 1).copied().unwrap_or(profile.span);
            let t0 = a[a.len() - 1] - a[a.len() - 2];
            let t1 = b[1] - b[0];
            if t0.length() > 0.0 && t1.length() > 0.0 {
                let cos = t0.normalize().dot(t1.normalize());
                if cos < 0.9998 {
                    let j = b[0];
                    ev.warn(
                        Diagnostic::warning(
                            at,
                            format!(
                                "the profile has a kink at <{}, {}> ({:.1}° turn)",
                                j.x,
                                j.y,
                                cos.clamp(-1.0, 1.0).acos().to_degrees()
                            ),
                        )
                        .with_label("the segments meet at an angle here")
                        .with_help("add `corner` to the revolve if the kink is intended"),
                    );
                }
            }
        }
        Ok(())
    }

    fn primitive(&mut self, ev: &mut Evaluator) -> SourceResult<Part> {
        let sig = signature(self.kind);
        let names: Vec<&str> = sig.iter().map(|(n, _)| *n).collect();
        if self.values.len() != sig.len() {
            let span = if self.values.len() > sig.len() {
                self.values[sig.len()].1
            } else {
                self.span
            };
            return Err(vec![
                Error::new(format!(
                    "{} needs {} value{} ({}), found {}",
                    self.kind,
                    sig.len(),
                    if sig.len() == 1 { "" } else { "s" },
                    names.join(", "),
                    self.values.len()
                ))
                .label(if self.values.len() > sig.len() {
                    "one value too many"
                } else {
                    "missing values"
                })
                .help(format!("write e.g. `{}`", example(self.kind)))
                .at(span),
            ]);
        }
        let mut vs = Vec::new();
        let mut ns = Vec::new();
        let mut strs = Vec::new();
        for ((name, k), (v, s)) in sig.iter().zip(&self.values) {
            match k {
                'v' => vs.push((
                    v.vec3()
                        .map_err(|e| Error {
                            message: format!(
                                "the {name} of {} {}: {}",
                                article(self.kind),
                                self.kind,
                                e.message
                            ),
                            ..e
                        })
                        .at(*s)?,
                    *s,
                )),
                'n' => ns.push((
                    v.num()
                        .map_err(|e| Error {
                            message: format!(
                                "the {name} of {} {}: {}",
                                article(self.kind),
                                self.kind,
                                e.message
                            ),
                            ..e
                        })
                        .at(*s)?,
                    *s,
                )),
                _ => match v {
                    Value::Str(p) => strs.push((p.to_string(), *s)),
                    v => {
                        return Err(vec![
                            Error::new(format!(
                                "expected a file name string, found {}",
                                v.type_name()
                            ))
                            .at(*s),
                        ]);
                    }
                },
            }
        }
        let radius = |(r, s): (f64, Span)| -> SourceResult<f64> {
            if r <= 0.0 {
                return Err(range_error(
                    s,
                    format!("radius must be positive, found {r}"),
                    "use a radius greater than 0",
                ));
            }
            Ok(r)
        };
        let nonzero = |(v, s): (DVec3, Span), what: &str| -> SourceResult<DVec3> {
            if v.length_squared() == 0.0 {
                return Err(vec![
                    Error::new(format!("the {what} is a zero vector"))
                        .label("zero length")
                        .at(s),
                ]);
            }
            Ok(v)
        };
        let shape = match self.kind {
            "sphere" => Shape::Sphere {
                center: vs[0].0,
                radius: radius(ns[0])?,
            },
            "plane" => Shape::Plane {
                normal: nonzero(vs[0], "normal")?.normalize(),
                offset: ns[0].0,
            },
            "quad" => {
                let (u, v) = (
                    nonzero(vs[1], "first edge")?,
                    nonzero(vs[2], "second edge")?,
                );
                if u.cross(v).length_squared() < 1e-24 {
                    return Err(vec![
                        Error::new("the quad's edges are parallel (it has no area)")
                            .label("parallel to the first edge")
                            .at(vs[2].1),
                    ]);
                }
                Shape::Quad {
                    origin: vs[0].0,
                    edge_u: u,
                    edge_v: v,
                }
            }
            "box" => Shape::Box {
                min: vs[0].0.min(vs[1].0),
                max: vs[0].0.max(vs[1].0),
            },
            "cylinder" => {
                if vs[0].0 == vs[1].0 {
                    return Err(vec![
                        Error::new("the cylinder's base and cap are the same point")
                            .label("zero height")
                            .at(vs[1].1),
                    ]);
                }
                Shape::Cylinder {
                    base: vs[0].0,
                    cap: vs[1].0,
                    radius: radius(ns[0])?,
                    open: self.open,
                }
            }
            "disk" => Shape::Disk {
                center: vs[0].0,
                normal: nonzero(vs[1], "normal")?.normalize(),
                radius: radius(ns[0])?,
            },
            "triangle" => {
                let [a, b, c] = [vs[0].0, vs[1].0, vs[2].0];
                if (b - a).cross(c - a).length_squared() < 1e-24 {
                    ev.warn(
                        Diagnostic::warning(self.span, "this triangle has no area")
                            .with_label("degenerate triangle"),
                    );
                }
                Shape::Triangle {
                    vertices: [a, b, c],
                }
            }
            "mesh" => {
                let (path, span) = &strs[0];
                let part = Part {
                    shape: ShapeDef::Mesh {
                        path: ev.resolve_path(path, *span),
                        span: *span,
                    },
                    transform: DAffine3::IDENTITY,
                    material: None,
                    emission: None,
                    span: self.span,
                };
                return Ok(part);
            }
            k => unreachable!("primitive {k}"),
        };
        Ok(self.part(shape))
    }
}

fn article(kind: &str) -> &'static str {
    if kind.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    }
}

impl Sink for ObjectBuilder {
    fn kind(&self) -> String {
        format!("{} {}", article(self.kind), self.kind)
    }
    fn props(&self) -> &'static [PropSpec] {
        match self.kind {
            "cylinder" => &CYL_PROPS,
            "area_light" => &AREA_PROPS,
            "revolve" => &REVOLVE_PROPS,
            "bezier_patch" | "bezier_mesh" => &PATCH_PROPS,
            _ => &OBJ_PROPS,
        }
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        if transform_prop(&kw.text, &args, &mut self.transform)? {
            return Ok(());
        }
        match kw.text.as_str() {
            "open" => self.open = true,
            "two_sided" => self.two_sided = true,
            "corner" => self.corner = true,
            "radiance" => self.radiance = Some((color(&args[0])?, args[0].span)),
            "axis" => self.axis = Some((vec3(&args[0])?, args[0].span)),
            "method" => self.method = Some((word(&args[0], &["robust", "newton"])?, args[0].span)),
            "iterations" => self.iterations = count(&args[0], "iterations", 1000.0)? as u32,
            "starts" => self.starts = count(&args[0], "starts", 64.0)? as u32,
            "angle" => {
                let (a, b) = (num(&args[0])?, num(&args[1])?);
                if !(a < b && b - a <= 360.0) {
                    return Err(range_error(
                        args[0].span.join(args[1].span),
                        format!(
                            "sweep angles must satisfy start < end ≤ start + 360, found {a}, {b}"
                        ),
                        "e.g. `angle 0, 270`",
                    ));
                }
                self.sweep = Some((a, b));
            }
            "profile" => match &args[0].value {
                Value::Profile(p) => self.profile = Some(p.clone()),
                v => {
                    return Err(vec![
                        Error::new(format!("expected a profile, found {}", v.type_name()))
                            .help("write `profile bezier { <r, h>, ... }`")
                            .at(args[0].span),
                    ]);
                }
            },
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::Material(m) => {
                self.material = Some(m);
                Ok(())
            }
            Value::Object(o) if self.is_container() => {
                self.parts.extend(o.parts.iter().cloned());
                Ok(())
            }
            Value::Object(_) => Err(unexpected(
                self,
                &v,
                span,
                "only `union`, `group`, `object` and `area_light` contain objects",
            )),
            Value::Texture(_) => Err(unexpected(
                self,
                &v,
                span,
                "put the texture in a material: `material { diffuse texture { ... } }`",
            )),
            v if self.is_container() => Err(unexpected(
                self,
                &v,
                span,
                "this block takes objects, a material and transforms",
            )),
            v if self.kind == "revolve" => Err(unexpected(
                self,
                &v,
                span,
                "a revolve takes `profile bezier { ... }`",
            )),
            v => {
                self.values.push((v, span));
                Ok(())
            }
        }
    }
}

// ------------------------------------------------------------------ materials

#[derive(Default)]
struct MaterialBuilder {
    kind: Option<(&'static str, Span)>,
    base: Option<Rc<MaterialDef>>,
    albedo: Option<ColorDef>,
    ior: Option<(f64, Span)>,
    absorb: Option<ColorDef>,
    tint: Option<(Color, Span)>,
    tint_def: Option<ColorDef>,
    specular: Option<ColorDef>,
    roughness: Option<ColorDef>,
    touched: bool,
}

static MAT_PROPS: [PropSpec; 9] = [
    p("diffuse", 1, 1, "a color or texture", "rgb <0.8, 0.8, 0.8>"),
    p("mirror", 0, 1, "a color (optional)", "rgb <0.9, 0.9, 0.9>"),
    p("glass", 0, 0, "nothing", ""),
    p("glossy", 1, 1, "a color or texture", "rgb <0.5, 0.5, 0.5>"),
    p("ior", 1, 1, "a number", "1.5"),
    p("absorb", 1, 1, "a color", "rgb <0.1, 0.02, 0.02>"),
    p("tint", 1, 1, "a color", "rgb <1, 1, 1>"),
    p("specular", 1, 1, "a color", "rgb <0.04, 0.04, 0.04>"),
    p("roughness", 1, 1, "a number in (0, 1]", "0.2"),
];

impl MaterialBuilder {
    fn set_kind(&mut self, k: &'static str, span: Span) -> SourceResult<()> {
        if let Some((old, old_span)) = self.kind {
            return Err(vec![
                Error::new(format!("a material is either {old} or {k}, not both"))
                    .label("second kind")
                    .help("use one of diffuse, mirror, glass, glossy per material")
                    .at(span)
                    .with_extra(old_span, "first kind here"),
            ]);
        }
        self.kind = Some((k, span));
        Ok(())
    }

    fn finish(self, span: Span) -> SourceResult<Value> {
        if !self.touched
            && let Some(base) = self.base
        {
            return Ok(Value::Material(base));
        }
        let kind_name = self.kind.map(|k| k.0).or_else(|| {
            self.base.as_ref().map(|b| match b.kind {
                MatKind::Diffuse(_) => "diffuse",
                MatKind::Mirror(_) => "mirror",
                MatKind::Glass { .. } => "glass",
                MatKind::Glossy { .. } => "glossy",
            })
        });
        let Some(kind_name) = kind_name else {
            return Err(vec![
                Error::new("a material needs a kind: diffuse, mirror, glass or glossy")
                    .label("no kind given")
                    .help("write e.g. `material { diffuse rgb <0.8, 0.8, 0.8> }`")
                    .at(span),
            ]);
        };
        let base = self.base.as_ref().map(|b| b.kind.clone());
        let misplaced = |what: &str, s: Option<Span>| -> SourceResult<()> {
            match s {
                Some(s) => Err(vec![
                    Error::new(format!("`{what}` does not apply to a {kind_name} material"))
                        .label("not used by this kind")
                        .at(s),
                ]),
                None => Ok(()),
            }
        };
        let one = ColorDef::Const(Color::ONE);
        let kind = match kind_name {
            "diffuse" => {
                misplaced("ior", self.ior.map(|i| i.1))?;
                let base_albedo = match base {
                    Some(MatKind::Diffuse(a)) => Some(a),
                    _ => None,
                };
                MatKind::Diffuse(
                    self.albedo
                        .or(base_albedo)
                        .unwrap_or(ColorDef::Const(Color::splat(0.5))),
                )
            }
            "mirror" => {
                misplaced("ior", self.ior.map(|i| i.1))?;
                MatKind::Mirror(self.tint_def.or(self.albedo).unwrap_or(one))
            }
            "glass" => {
                let (mut ior, mut absorb, mut tint) =
                    (1.5, ColorDef::Const(Color::ZERO), Color::ONE);
                if let Some(MatKind::Glass {
                    ior: i,
                    absorb: a,
                    tint: t,
                }) = base
                {
                    (ior, absorb, tint) = (i, a, t);
                }
                if let Some((i, s)) = self.ior {
                    if i < 1.0 {
                        return Err(range_error(
                            s,
                            format!("ior must be at least 1, found {i}"),
                            "glass has an index of refraction ≥ 1 (1.5 for window glass)",
                        ));
                    }
                    ior = i;
                }
                MatKind::Glass {
                    ior,
                    absorb: self.absorb.unwrap_or(absorb),
                    tint: self.tint.map_or(tint, |t| t.0),
                }
            }
            _ => MatKind::Glossy {
                albedo: self.albedo.unwrap_or(ColorDef::Const(Color::splat(0.5))),
                specular: self.specular.unwrap_or(ColorDef::Const(Color::splat(0.04))),
                roughness: self.roughness.unwrap_or(ColorDef::Const(Color::splat(0.2))),
            },
        };
        Ok(Value::Material(Rc::new(MaterialDef { kind, span })))
    }
}

impl Sink for MaterialBuilder {
    fn kind(&self) -> String {
        "a material".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &MAT_PROPS
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        self.touched = true;
        match kw.text.as_str() {
            "diffuse" => {
                self.set_kind("diffuse", kw.span)?;
                self.albedo = Some(color_def(&args[0])?);
            }
            "mirror" => {
                self.set_kind("mirror", kw.span)?;
                if let Some(a) = args.first() {
                    self.tint_def = Some(color_def(a)?);
                }
            }
            "glass" => self.set_kind("glass", kw.span)?,
            "glossy" => {
                self.set_kind("glossy", kw.span)?;
                self.albedo = Some(color_def(&args[0])?);
            }
            "ior" => self.ior = Some((num(&args[0])?, args[0].span)),
            "absorb" => {
                let c = color_def(&args[0])?;
                if let ColorDef::Const(c) = c
                    && c.min_element() < 0.0
                {
                    return Err(range_error(
                        args[0].span,
                        "absorption must not be negative".into(),
                        "use components ≥ 0",
                    ));
                }
                self.absorb = Some(c);
            }
            "tint" => {
                self.tint = Some((color(&args[0])?, args[0].span));
                self.tint_def = Some(ColorDef::Const(color(&args[0])?));
            }
            "specular" => self.specular = Some(color_def(&args[0])?),
            "roughness" => {
                if let Value::Num(r) = args[0].value
                    && !(r > 0.0 && r <= 1.0)
                {
                    return Err(range_error(
                        args[0].span,
                        format!("roughness must be in (0, 1], found {r}"),
                        "e.g. `roughness 0.2`",
                    ));
                }
                self.roughness = Some(color_def(&args[0])?);
            }
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::Material(m) if self.base.is_none() => {
                self.base = Some(m);
                Ok(())
            }
            v => Err(unexpected(
                self,
                &v,
                span,
                "a material takes a declared material and properties, e.g. `material { diffuse rgb <0.8, 0.8, 0.8> }`",
            )),
        }
    }
}

// ------------------------------------------------------------------ textures

#[derive(Default)]
struct TextureBuilder {
    pattern: Option<(&'static str, Span)>,
    a: Color,
    b: Color,
    direction: Option<DVec3>,
    map: Option<Rc<ColorMap>>,
    octaves: Option<u32>,
    turbulence: Option<f64>,
    mortar: Option<f64>,
    size: Option<DVec3>,
    image: Option<(String, Span)>,
    wrap: Wrap,
    bilinear: bool,
    mapping: Option<Mapping>,
    linear: bool,
    transform: DAffine3,
}

static TEX_PROPS: [PropSpec; 19] = with_transforms([
    p(
        "checker",
        2,
        2,
        "two colors",
        "rgb <1, 1, 1>, rgb <0, 0, 0>",
    ),
    p(
        "stripes",
        2,
        2,
        "two colors",
        "rgb <1, 1, 1>, rgb <0, 0, 0>",
    ),
    p("gradient", 0, 1, "a direction (optional)", "<0, 1, 0>"),
    p("noise", 0, 0, "nothing", ""),
    p("marble", 0, 0, "nothing", ""),
    p("wood", 0, 0, "nothing", ""),
    p(
        "brick",
        2,
        2,
        "two colors (brick, mortar)",
        "rgb <0.6, 0.2, 0.1>, rgb <0.8, 0.8, 0.8>",
    ),
    p("image", 1, 1, "a file name", "\"wood.png\""),
    w("wrap", "`repeat`, `clamp` or `mirror`", "repeat"),
    p("interpolate", 0, 0, "nothing", ""),
    w(
        "map",
        "`uv`, `planar`, `spherical`, `cylindrical` or `solid`",
        "uv",
    ),
    p("linear", 0, 0, "nothing", ""),
    p("octaves", 1, 1, "a number", "6"),
    p("turbulence", 1, 1, "a number", "1"),
    p("mortar", 1, 1, "a number", "0.01"),
]);
static TEX_PROPS_SIZE: [PropSpec; 1] = [p("size", 1, 1, "a vector", "<0.2, 0.075, 0.1>")];

impl TextureBuilder {
    fn set(&mut self, k: &'static str, span: Span) -> SourceResult<()> {
        if let Some((old, old_span)) = self.pattern {
            return Err(vec![
                Error::new(format!("a texture has one pattern: {old} or {k}, not both"))
                    .label("second pattern")
                    .at(span)
                    .with_extra(old_span, "first pattern here"),
            ]);
        }
        self.pattern = Some((k, span));
        Ok(())
    }

    fn finish(self, ev: &mut Evaluator, span: Span) -> SourceResult<Value> {
        let Some((kind, _)) = self.pattern else {
            return Err(vec![
                Error::new("a texture needs a pattern")
                    .label("no pattern")
                    .help("e.g. `texture { checker rgb <1, 1, 1>, rgb <0, 0, 0> scale 0.1 }`")
                    .at(span),
            ]);
        };
        let map = self
            .map
            .map(|m| (*m).clone())
            .unwrap_or_else(|| ColorMap(vec![(0.0, Color::ZERO), (1.0, Color::ONE)]));
        let octaves = self.octaves.unwrap_or(6);
        let turbulence = self.turbulence.unwrap_or(1.0);
        let pattern = match kind {
            "checker" => PatternDef::Ready(Pattern::Checker {
                a: self.a,
                b: self.b,
            }),
            "stripes" => PatternDef::Ready(Pattern::Stripes {
                a: self.a,
                b: self.b,
            }),
            "gradient" => PatternDef::Ready(Pattern::Gradient {
                direction: self.direction.unwrap_or(DVec3::Y),
                map,
            }),
            "noise" => PatternDef::Ready(Pattern::Noise { map, octaves }),
            "marble" => PatternDef::Ready(Pattern::Marble {
                map,
                turbulence,
                octaves,
            }),
            "wood" => PatternDef::Ready(Pattern::Wood {
                map,
                turbulence,
                octaves,
            }),
            "brick" => PatternDef::Ready(Pattern::Brick {
                brick: self.a,
                mortar: self.b,
                size: self.size.unwrap_or(DVec3::new(0.2, 0.075, 0.1)),
                mortar_width: self.mortar.unwrap_or(0.01),
            }),
            _ => {
                let (path, pspan) = self.image.expect("image path");
                PatternDef::Image {
                    path: ev.resolve_path(&path, pspan),
                    linear: self.linear,
                    wrap: self.wrap,
                    bilinear: self.bilinear,
                    span: pspan,
                }
            }
        };
        let mapping = self.mapping.unwrap_or(if kind == "image" {
            Mapping::Uv
        } else {
            Mapping::Solid
        });
        Ok(Value::Texture(Rc::new(TextureDef {
            pattern,
            mapping,
            transform: self.transform.inverse(),
            span,
        })))
    }
}

impl Sink for TextureBuilder {
    fn kind(&self) -> String {
        "a texture".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &TEX_PROPS
    }
    fn prop_spec(&self, name: &str) -> Option<&'static PropSpec> {
        TEX_PROPS
            .iter()
            .chain(TEX_PROPS_SIZE.iter())
            .find(|p| p.name == name)
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        if transform_prop(&kw.text, &args, &mut self.transform)? {
            return Ok(());
        }
        match kw.text.as_str() {
            k @ ("checker" | "stripes" | "brick") => {
                self.set(
                    if k == "checker" {
                        "checker"
                    } else if k == "stripes" {
                        "stripes"
                    } else {
                        "brick"
                    },
                    kw.span,
                )?;
                self.a = color(&args[0])?;
                self.b = color(&args[1])?;
            }
            "gradient" => {
                self.set("gradient", kw.span)?;
                if let Some(a) = args.first() {
                    match &a.value {
                        Value::ColorMap(m) => self.map = Some(m.clone()),
                        _ => {
                            let d = vec3(a)?;
                            if d.length_squared() == 0.0 {
                                return Err(vec![
                                    Error::new("the gradient direction is a zero vector")
                                        .at(a.span),
                                ]);
                            }
                            self.direction = Some(d);
                        }
                    }
                }
            }
            "noise" => self.set("noise", kw.span)?,
            "marble" => self.set("marble", kw.span)?,
            "wood" => self.set("wood", kw.span)?,
            "image" => {
                self.set("image", kw.span)?;
                match &args[0].value {
                    Value::Str(s) => self.image = Some((s.to_string(), args[0].span)),
                    v => {
                        return Err(vec![
                            Error::new(format!(
                                "expected a file name string, found {}",
                                v.type_name()
                            ))
                            .at(args[0].span),
                        ]);
                    }
                }
            }
            "wrap" => {
                self.wrap = match word(&args[0], &["repeat", "clamp", "mirror"])?.as_str() {
                    "repeat" => Wrap::Repeat,
                    "clamp" => Wrap::Clamp,
                    _ => Wrap::Mirror,
                }
            }
            "interpolate" => self.bilinear = true,
            "linear" => self.linear = true,
            "map" => {
                self.mapping = Some(
                    match word(
                        &args[0],
                        &["uv", "planar", "spherical", "cylindrical", "solid"],
                    )?
                    .as_str()
                    {
                        "uv" => Mapping::Uv,
                        "planar" => Mapping::Planar,
                        "spherical" => Mapping::Spherical,
                        "cylindrical" => Mapping::Cylindrical,
                        _ => Mapping::Solid,
                    },
                )
            }
            "octaves" => self.octaves = Some(count(&args[0], "octaves", 16.0)? as u32),
            "turbulence" => {
                let t = num(&args[0])?;
                if t < 0.0 {
                    return Err(range_error(
                        args[0].span,
                        format!("turbulence must not be negative, found {t}"),
                        "use a number ≥ 0",
                    ));
                }
                self.turbulence = Some(t);
            }
            "mortar" => self.mortar = Some(positive(&args[0], "mortar width")?),
            "size" => {
                let s = vec3(&args[0])?;
                if s.min_element() <= 0.0 {
                    return Err(range_error(
                        args[0].span,
                        "brick size components must be positive".into(),
                        "e.g. `size <0.2, 0.075, 0.1>`",
                    ));
                }
                self.size = Some(s);
            }
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::ColorMap(m) => {
                self.map = Some(m);
                Ok(())
            }
            v => Err(unexpected(
                self,
                &v,
                span,
                "a texture takes a pattern keyword, `color_map { ... }` and transforms",
            )),
        }
    }
}

#[derive(Default)]
struct ColorMapBuilder(Vec<(f64, Color)>);

impl ColorMapBuilder {
    fn finish(mut self, span: Span) -> SourceResult<Value> {
        if self.0.len() < 2 {
            return Err(vec![
                Error::new("a color map needs at least two entries")
                    .help("e.g. `color_map { [0, rgb <0, 0, 0>] [1, rgb <1, 1, 1>] }`")
                    .at(span),
            ]);
        }
        self.0.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(Value::ColorMap(Rc::new(ColorMap(self.0))))
    }
}

impl Sink for ColorMapBuilder {
    fn kind(&self) -> String {
        "a color map".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &[]
    }
    fn property(&mut self, _ev: &mut Evaluator, _kw: &Name, _args: Vec<Arg>) -> SourceResult<()> {
        unreachable!()
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        let entry = match &v {
            Value::Array(a) if a.len() == 2 => (a[0].num(), a[1].color()),
            _ => {
                return Err(unexpected(
                    self,
                    &v,
                    span,
                    "entries look like `[0.5, rgb <1, 0, 0>]`",
                ));
            }
        };
        let pos = entry.0.at(span)?;
        let c = entry.1.at(span)?;
        if !(0.0..=1.0).contains(&pos) {
            return Err(range_error(
                span,
                format!("color map positions must be in [0, 1], found {pos}"),
                "use a position from 0 to 1",
            ));
        }
        self.0.push((pos, c));
        Ok(())
    }
}

// ------------------------------------------------------------------ profiles

struct ProfileBuilder {
    spline: bool,
    degree: Option<(u32, Span)>,
    points: Vec<(DVec2, Span)>,
}

static BEZIER_PROPS: [PropSpec; 1] = [p("degree", 1, 1, "a number from 1 to 7", "3")];

impl ProfileBuilder {
    fn finish(self, span: Span) -> SourceResult<Value> {
        let pts: Vec<DVec2> = self.points.iter().map(|p| p.0).collect();
        let d = if self.spline {
            1
        } else {
            self.degree.map_or(3, |d| d.0) as usize
        };
        let joints: Vec<Span> = self.points.iter().step_by(d.max(1)).map(|p| p.1).collect();
        let segments = if self.spline {
            if pts.len() < 2 {
                return Err(vec![
                    Error::new(format!(
                        "a spline needs at least 2 points, found {}",
                        pts.len()
                    ))
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
            let d = self.degree.map_or(3, |d| d.0) as usize;
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
                format!("degree must be a whole number from 1 to 7, found {d}"),
                "e.g. `degree 3`",
            ));
        }
        self.degree = Some((d as u32, args[0].span));
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

// ------------------------------------------------------------------ settings, camera, lights

struct SettingsBuilder(Settings);

static SETTINGS_PROPS: [PropSpec; 10] = [
    p("resolution", 1, 2, "a width and height", "<512, 512>"),
    p("iterations", 1, 1, "a number", "64"),
    p("photons", 1, 1, "a number", "200000"),
    p("radius", 1, 1, "a number", "0.05"),
    p("alpha", 1, 1, "a number in (0, 1]", "0.7"),
    p("max_depth", 1, 1, "a number", "16"),
    p("seed", 1, 1, "a number", "7"),
    w(
        "integrator",
        "`sppm`, `ppm`, `photon_map`, `path` or `whitted`",
        "sppm",
    ),
    p("exposure", 1, 1, "a number", "1"),
    p("time_limit", 1, 1, "a number of seconds", "60"),
];

impl Sink for SettingsBuilder {
    fn kind(&self) -> String {
        "settings".into()
    }
    fn props(&self) -> &'static [PropSpec] {
        &SETTINGS_PROPS
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        let s = &mut self.0;
        match kw.text.as_str() {
            "resolution" => {
                let (w, h, span) = if args.len() == 2 {
                    (
                        num(&args[0])?,
                        num(&args[1])?,
                        args[0].span.join(args[1].span),
                    )
                } else {
                    let v = args[0].value.vec2().at(args[0].span)?;
                    (v.x, v.y, args[0].span)
                };
                for x in [w, h] {
                    if !(1.0..=16384.0).contains(&x) || x.fract() != 0.0 {
                        return Err(range_error(
                            span,
                            format!(
                                "resolution must be whole numbers from 1 to 16384, found {w} x {h}"
                            ),
                            "e.g. `resolution <512, 512>`",
                        ));
                    }
                }
                s.resolution = (w as u32, h as u32);
            }
            "iterations" => s.iterations = count(&args[0], "iterations", 1e7)? as u32,
            "photons" => s.photons = count(&args[0], "photons", 1e10)? as u64,
            "radius" => s.radius = Some(positive(&args[0], "radius")?),
            "alpha" => {
                let a = num(&args[0])?;
                if !(a > 0.0 && a <= 1.0) {
                    return Err(range_error(
                        args[0].span,
                        format!("alpha must be in (0, 1], found {a}"),
                        "SPPM uses 2/3 or 0.7",
                    ));
                }
                s.alpha = a;
            }
            "max_depth" => s.max_depth = count(&args[0], "max_depth", 1000.0)? as u32,
            "seed" => {
                let x = num(&args[0])?;
                if x < 0.0 || x.fract() != 0.0 || x > u64::MAX as f64 {
                    return Err(range_error(
                        args[0].span,
                        format!("seed must be a whole number ≥ 0, found {x}"),
                        "e.g. `seed 7`",
                    ));
                }
                s.seed = x as u64;
            }
            "integrator" => {
                let names: Vec<&str> = Integrator::ALL.iter().map(|i| i.name()).collect();
                s.integrator = Integrator::from_name(&word(&args[0], &names)?).expect("known name");
            }
            "exposure" => s.exposure = positive(&args[0], "exposure")?,
            "time_limit" => s.time_limit = Some(positive(&args[0], "time limit")?),
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        Err(unexpected(
            self,
            &v,
            span,
            "settings take properties only, e.g. `settings { iterations 64 }`",
        ))
    }
}

struct CameraBuilder {
    cam: Camera,
    focus: Option<Span>,
}

static CAMERA_PROPS: [PropSpec; 6] = [
    p("location", 1, 1, "a point", "<0, 1, -5>"),
    p("look_at", 1, 1, "a point", "<0, 1, 0>"),
    p("up", 1, 1, "a vector", "<0, 1, 0>"),
    p("fov", 1, 1, "an angle in degrees", "40"),
    p("aperture", 1, 1, "a lens radius", "0.05"),
    p("focus_distance", 1, 1, "a distance", "4"),
];

impl CameraBuilder {
    fn finish(self, span: Span) -> SourceResult<Value> {
        let c = &self.cam;
        let dir = c.look_at - c.location;
        if dir.length_squared() == 0.0 {
            return Err(vec![
                Error::new("the camera looks at its own location")
                    .label("location == look_at")
                    .help("move `look_at` away from `location`")
                    .at(span),
            ]);
        }
        if dir.cross(c.up).length_squared()
            < 1e-18 * dir.length_squared() * c.up.length_squared().max(1e-300)
        {
            return Err(vec![
                Error::new("the camera's `up` is parallel to its view direction")
                    .label("cannot orient the camera")
                    .help("choose another `up`, e.g. `up <0, 0, 1>`")
                    .at(span),
            ]);
        }
        let _ = self.focus;
        Ok(Value::Camera(Box::new(self.cam)))
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
        let c = &mut self.cam;
        match kw.text.as_str() {
            "location" => c.location = vec3(&args[0])?,
            "look_at" => c.look_at = vec3(&args[0])?,
            "up" => {
                let u = vec3(&args[0])?;
                if u.length_squared() == 0.0 {
                    return Err(vec![Error::new("`up` is a zero vector").at(args[0].span)]);
                }
                c.up = u;
            }
            "fov" => {
                let f = num(&args[0])?;
                if !(f > 0.0 && f < 180.0) {
                    return Err(range_error(
                        args[0].span,
                        format!("fov must be between 0 and 180 degrees, found {f}"),
                        "e.g. `fov 40`",
                    ));
                }
                c.fov = f;
            }
            "aperture" => {
                let a = num(&args[0])?;
                if a < 0.0 {
                    return Err(range_error(
                        args[0].span,
                        format!("aperture must not be negative, found {a}"),
                        "0 is a pinhole",
                    ));
                }
                c.aperture = a;
            }
            "focus_distance" => {
                c.focus_distance = Some(positive(&args[0], "focus distance")?);
                self.focus = Some(args[0].span);
            }
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        Err(unexpected(
            self,
            &v,
            span,
            "a camera takes `location`, `look_at`, `up`, `fov`, `aperture`, `focus_distance`",
        ))
    }
}

struct LightBuilder {
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
    fn new(spot: bool) -> Self {
        Self {
            spot,
            position: None,
            intensity: None,
            point_at: None,
            angle: None,
            falloff: None,
        }
    }

    fn finish(self, ev: &mut Evaluator, span: Span) -> SourceResult<Value> {
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
            return Ok(Value::Light(Box::new(Light::Point {
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
        if target == position {
            return Err(vec![
                Error::new("the spotlight points at its own position").at(span),
            ]);
        }
        let (cone, cspan) = self.angle.unwrap_or((30.0, span));
        if !(cone > 0.0 && cone <= 90.0) {
            return Err(range_error(
                cspan,
                format!("the cone angle must be in (0, 90] degrees, found {cone}"),
                "e.g. `angle 30`",
            ));
        }
        let (fall, fspan) = self.falloff.unwrap_or((cone * 0.8, span));
        if !(0.0..=cone).contains(&fall) {
            return Err(range_error(
                fspan,
                format!("falloff must be between 0 and the cone angle ({cone}), found {fall}"),
                "e.g. `falloff 25` with `angle 30`",
            ));
        }
        Ok(Value::Light(Box::new(Light::Spot {
            position,
            direction: (target - position).normalize(),
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
            return Err(unexpected(self, &v, span, "a light has one position"));
        }
        self.position = Some(v.vec3().at(span)?);
        Ok(())
    }
}

#[derive(Default)]
struct EnvBuilder {
    image: Option<(String, Span)>,
    intensity: Option<f64>,
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
    fn finish(self, span: Span) -> SourceResult<Value> {
        let Some((path, path_span)) = self.image else {
            return Err(vec![
                Error::new("an environment needs an `image`")
                    .help("write e.g. `environment { image \"sky.hdr\" intensity 1 }`")
                    .at(span),
            ]);
        };
        // The file is resolved when the environment is used (by the top-level sink).
        let dir_file = path_span;
        Ok(Value::Environment(Rc::new(EnvDef {
            path: PathBuf::from(path),
            path_span: dir_file,
            intensity: self.intensity.unwrap_or(1.0),
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
            "image" => match &args[0].value {
                Value::Str(s) => {
                    let resolved = ev.resolve_path(s, args[0].span);
                    self.image = Some((resolved.to_string_lossy().into_owned(), args[0].span));
                }
                v => {
                    return Err(vec![
                        Error::new(format!(
                            "expected a file name string, found {}",
                            v.type_name()
                        ))
                        .at(args[0].span),
                    ]);
                }
            },
            "intensity" => {
                let k = num(&args[0])?;
                if k < 0.0 {
                    return Err(range_error(
                        args[0].span,
                        format!("intensity must not be negative, found {k}"),
                        "e.g. `intensity 1`",
                    ));
                }
                self.intensity = Some(k);
            }
            "rotate" => {
                self.rotation =
                    Some(rotation(vec3(&args[0])?) * self.rotation.unwrap_or(DAffine3::IDENTITY))
            }
            _ => unreachable!(),
        }
        Ok(())
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        Err(unexpected(
            self,
            &v,
            span,
            "an environment takes `image`, `intensity` and `rotate`",
        ))
    }
}
