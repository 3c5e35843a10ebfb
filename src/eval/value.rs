//! Runtime values of the scene language, and the definitions (materials, textures, objects,
//! profiles, environments) that values hold until they are lowered into the scene.

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::Arc;

use glam::{DAffine3, DVec2, DVec3};

use crate::diag::Error;
use crate::sampling::SplitMix64;
use crate::scene::{
    Camera, Color, ColorMap, CsgOp, Emission, Function, LightDecl, Mapping, NormalKind, Pattern,
    Settings, ShapeDecl, Wrap,
};
use crate::span::Span;
use crate::syntax::ast::MacroDef;

#[derive(Debug, Clone)]
pub enum Value {
    Num(f64),
    Bool(bool),
    Str(Rc<str>),
    Vec2(DVec2),
    Vec3(DVec3),
    /// A linear RGB color (`rgb <r, g, b>`).
    Color(DVec3),
    /// POV-Ray's colour with filter and transmit (`rgbf`, `rgbt`, `rgbft`): the colour, the
    /// filter and the transmit. Only a material's colour takes one (it makes the material a
    /// glass, with a warning).
    Filtered(DVec3, f64, f64),
    Array(Rc<Vec<Value>>),
    Object(Rc<ObjectDef>),
    Material(Rc<MaterialDef>),
    Texture(Rc<TextureDef>),
    /// A bump or normal map (`normal { ... }`, `bump_map { ... }`).
    Normal(Rc<NormalDef>),
    ColorMap(Rc<ColorMap>),
    Profile(Rc<ProfileDef>),
    Settings(Box<Settings>),
    Camera(Box<Camera>),
    Light(Box<LightDecl>),
    Environment(Rc<EnvDef>),
    Macro(Rc<MacroDef>),
    /// A random stream (`seed(n)`): every copy of the value draws from the same stream, as
    /// POV-Ray's stream handles do, so a macro given a stream advances the caller's.
    Stream(Rc<RefCell<SplitMix64>>),
    /// A user function (`function(x, y, z) { ... }`), compiled.
    Function(Rc<FunctionValue>),
}

/// A compiled user function with the names of its parameters (for messages) and where it was
/// defined.
#[derive(Debug)]
pub struct FunctionValue {
    pub code: Arc<Function>,
    pub params: Vec<String>,
    pub span: Span,
    /// The grid of POV-Ray's height field form `function W, H { ... }`: its sides as written
    /// and their span.
    pub grid: Option<(f64, f64, Span)>,
}

impl FunctionValue {
    /// How a call is written: `F(x, y, z)`.
    pub fn signature(&self, name: &str) -> String {
        format!("{name}({})", self.params.join(", "))
    }
}

impl Value {
    /// The type's name with an article, for messages ("a number").
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::Num(_) => "a number",
            Value::Bool(_) => "a boolean",
            Value::Str(_) => "a string",
            Value::Vec2(_) => "a 2-D vector",
            Value::Vec3(_) => "a vector",
            Value::Color(_) => "a color",
            Value::Filtered(..) => "a color with filter or transmit",
            Value::Array(_) => "an array",
            Value::Object(_) => "an object",
            Value::Material(_) => "a material",
            Value::Texture(_) => "a texture",
            Value::Normal(_) => "a normal",
            Value::ColorMap(_) => "a color map",
            Value::Profile(_) => "a profile",
            Value::Settings(_) => "a settings block",
            Value::Camera(_) => "a camera",
            Value::Light(_) => "a light",
            Value::Environment(_) => "an environment",
            Value::Macro(_) => "a macro",
            Value::Stream(_) => "a random stream",
            Value::Function(_) => "a function",
        }
    }

    /// The value as a message shows it (`#debug`): strings as they are, numbers, vectors,
    /// colors and booleans as written; `None` for the others.
    pub fn show(&self) -> Option<String> {
        let n = crate::diag::short_number;
        Some(match self {
            Value::Str(s) => s.to_string(),
            Value::Num(x) => n(*x),
            Value::Bool(b) => b.to_string(),
            Value::Vec2(v) => format!("<{}, {}>", n(v.x), n(v.y)),
            Value::Vec3(v) => format!("<{}, {}, {}>", n(v.x), n(v.y), n(v.z)),
            Value::Color(v) => format!("rgb <{}, {}, {}>", n(v.x), n(v.y), n(v.z)),
            _ => return None,
        })
    }

    fn mismatch(&self, expected: &str) -> Error {
        Error::new(format!("expected {expected}, found {}", self.type_name()))
            .label(format!("this is {}", self.type_name()))
    }

    pub fn num(&self) -> Result<f64, Error> {
        match self {
            Value::Num(n) => Ok(*n),
            Value::Vec2(_) | Value::Vec3(_) | Value::Color(_) => Err(self
                .mismatch("a number")
                .help("take one component (`V.x`) or the length (`vlength(V)`) of the vector")),
            Value::Str(_) => Err(self
                .mismatch("a number")
                .help("write the number without quotes, e.g. `1.5`")),
            Value::Function(f) => Err(self.mismatch("a number").help(format!(
                "a function stands for its value only when called: `{}` with numbers",
                f.signature("F")
            ))),
            v => Err(v.mismatch("a number").help("write a number, e.g. `1.5`")),
        }
    }

    pub fn vec3(&self) -> Result<DVec3, Error> {
        match self {
            Value::Vec3(v) | Value::Color(v) => Ok(*v),
            Value::Vec2(_) => Err(self
                .mismatch("a 3-D vector")
                .help("give three components: `<x, y, z>`")),
            Value::Num(n) => {
                let n = crate::diag::short_number(*n);
                Err(self.mismatch("a vector `<x, y, z>`").help(format!(
                    "write `<{n}, {n}, {n}>`: a number does not stand for a vector here (as \
                     POV-Ray's `{n}` does)"
                )))
            }
            Value::Array(a) if a.len() >= 4 && a.iter().all(|v| v.num().is_ok()) => {
                Err(Error::new(format!(
                    "expected a vector `<x, y, z>`, found {} components",
                    a.len()
                ))
                .label("a vector has three components")
                .help("write three components, e.g. `<0, 1, 0>`"))
            }
            v => Err(v
                .mismatch("a vector `<x, y, z>`")
                .help("write three components, e.g. `<0, 1, 0>`")),
        }
    }

    pub fn vec2(&self) -> Result<DVec2, Error> {
        match self {
            Value::Vec2(v) => Ok(*v),
            v => Err(v
                .mismatch("a 2-D vector `<u, v>`")
                .help("write two components, e.g. `<0.5, 1>`")),
        }
    }

    /// A color: `rgb <..>`, a plain vector, or a number (gray).
    pub fn color(&self) -> Result<DVec3, Error> {
        match self {
            Value::Color(c) | Value::Vec3(c) => Ok(*c),
            Value::Num(n) => Ok(DVec3::splat(*n)),
            Value::Array(a) if (4..=5).contains(&a.len()) && a.iter().all(|v| v.num().is_ok()) => {
                Err(Error::new(format!(
                    "expected a color `rgb <r, g, b>`, found {} components",
                    a.len()
                ))
                .label("a color has three components")
                .help(
                    "POV-Ray's filter and transmit components are not part of a colour here: \
                     write `rgb <r, g, b>`; transparency is a material, `material { glass ior \
                     1.5 tint rgb <...> }`",
                ))
            }
            v => Err(v
                .mismatch("a color `rgb <r, g, b>`")
                .help("write e.g. `rgb <1, 0.5, 0.2>`")),
        }
    }

    pub fn truthy(&self) -> Result<bool, Error> {
        match self {
            Value::Bool(b) => Ok(*b),
            Value::Num(n) => Ok(*n != 0.0),
            v => Err(v
                .mismatch("a boolean")
                .help("write a comparison such as `N > 0`, or `true` / `false`")),
        }
    }
}

// ------------------------------------------------------------------ definitions

#[derive(Debug, Clone)]
pub enum ColorDef {
    Const(Color),
    Tex(Rc<TextureDef>),
}

#[derive(Debug)]
pub struct MaterialDef {
    pub kind: MatKind,
    pub span: Span,
    /// A bump or normal map on the material.
    pub normal: Option<Rc<NormalDef>>,
}

/// A bump or normal map as written (lowered to `scene::Normal`).
#[derive(Debug)]
pub struct NormalDef {
    pub source: NormalSource,
    pub amount: f64,
    /// Object space to the pattern's (or the height texture's object) space.
    pub transform: DAffine3,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub enum NormalSource {
    Pattern(NormalKind),
    Height(Rc<TextureDef>),
    Map(Rc<TextureDef>),
}

#[derive(Debug, Clone)]
pub enum MatKind {
    Diffuse(ColorDef),
    Mirror(ColorDef),
    /// No roughness: smooth glass; `thin`: a pane (no absorption, no roughness).
    Glass {
        ior: f64,
        absorb: ColorDef,
        tint: Color,
        roughness: Option<ColorDef>,
        thin: bool,
    },
    Glossy {
        albedo: ColorDef,
        specular: ColorDef,
        roughness: ColorDef,
    },
    Conductor {
        eta: Color,
        k: Color,
        roughness: f64,
    },
    /// No roughness: a smooth coat.
    Coated {
        albedo: ColorDef,
        ior: f64,
        roughness: Option<ColorDef>,
    },
    /// `a` or `b` per point, `b` with probability `weight`; `depth`: how deep blends nest
    /// under this one (1 for a blend of two plain materials).
    Blend {
        a: Rc<MaterialDef>,
        b: Rc<MaterialDef>,
        weight: ColorDef,
        depth: u32,
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
    Ready(ShapeDecl),
    Mesh { path: PathBuf, span: Span },
    Csg(Rc<CsgDef>),
}

/// A CSG operation over its children, each one closed object (a child union is one part
/// holding a `Union` node).
#[derive(Debug)]
pub struct CsgDef {
    pub op: CsgOp,
    pub children: Vec<Part>,
    /// Shapes in the whole tree.
    pub leaves: usize,
    /// Nesting of operations (1: its children are shapes).
    pub depth: usize,
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
    /// The body of a `contained_by { ... }`: a region only an isosurface takes, never an object
    /// placed in the scene or in a CSG.
    pub container: bool,
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
    /// Where `intensity` was written (`None`: the default 1).
    pub intensity_span: Option<Span>,
    pub transform: DAffine3,
}
