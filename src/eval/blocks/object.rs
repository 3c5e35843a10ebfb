//! Object blocks: the primitives (in [`primitive`]), `prism` (in [`prism`]), `revolve`, Bezier patches, the
//! containers `union`, `group`, `object` and `area_light`, and the CSG operations (in [`csg`]).

mod blob;
mod csg;
pub(in crate::internals::eval) mod isosurface;

pub(super) use isosurface::ContainedBy;
mod height_field;
mod primitive;
mod prism;
mod sphere_sweep;
mod superellipsoid;
mod text;

use crate::diag::short_number;
use std::rc::Rc;

use glam::{DAffine3, DQuat, DVec3};

use super::{Sink, unexpected};
use crate::diag::{At, Diagnostic, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::args::{Arg, color, count, num, range_error, vec3, word};
use crate::eval::props::{PropSpec, p, transform_prop, w, with_transforms};
use crate::eval::value::{MaterialDef, ObjectDef, Part, ProfileDef, ShapeDef, Value};
use crate::scene::*;
use crate::span::Span;
use crate::syntax::ast::Name;

pub(super) struct ObjectBuilder {
    kind: &'static str,
    span: Span,
    values: Vec<(Value, Span)>,
    parts: Vec<Part>,
    transform: DAffine3,
    material: Option<Rc<MaterialDef>>,
    material_span: Span,
    radiance: Option<(Color, Span)>,
    two_sided: bool,
    open: bool,
    profile: Option<Rc<ProfileDef>>,
    corner: bool,
    axis: Option<(DVec3, Span)>,
    sweep: Option<(f64, f64)>,
    method: Option<String>,
    iterations: u32,
    starts: u32,
    inverse: bool,
    /// A prism's spline and sweep keywords.
    spline: Option<PrismSpline>,
    conic: bool,
    /// A curved sphere sweep's spline; `None`: straight segments.
    sweep_spline: Option<SweepSpline>,
    /// A `sphere` or `cylinder` written in a blob's body: a component of it.
    component: bool,
    /// A component's strength; a blob's or isosurface's threshold.
    strength: Option<(f64, Span)>,
    threshold: Option<(f64, Span)>,
    /// A blob's components so far.
    components: Vec<BlobComponent>,
    /// An isosurface's function, container, accuracy and `max_gradient`.
    function: Option<(std::sync::Arc<Function>, Span)>,
    container: Option<(Container, Span)>,
    accuracy: Option<(f64, Span)>,
    max_gradient: Option<Span>,
    /// A height field's image, its `smooth` and `water_level`.
    hf_file: Option<(std::path::PathBuf, Span)>,
    smooth: bool,
    water: Option<(f64, Span)>,
    /// A text's font: the resolved path, the name as written and its span.
    ttf: Option<(std::path::PathBuf, String, Span)>,
}

const INVERSE: PropSpec = p("inverse", 0, 0, "nothing", "");
static OBJ_PROPS: [PropSpec; 5] = with_transforms([INVERSE]);
static CYL_PROPS: [PropSpec; 6] = with_transforms([p("open", 0, 0, "nothing", ""), INVERSE]);
static AREA_PROPS: [PropSpec; 6] = with_transforms([
    p("radiance", 1, 1, "a color", "rgb <17, 12, 4>"),
    p("two_sided", 0, 0, "nothing", ""),
]);
static PATCH_PROPS: [PropSpec; 8] = with_transforms([
    INVERSE,
    w("method", "`robust` or `newton`", "newton"),
    p("iterations", 1, 1, "a number", "12"),
    p("starts", 1, 1, "a number", "8"),
]);
static PRISM_PROPS: [PropSpec; 12] = with_transforms([
    INVERSE,
    p("open", 0, 0, "nothing", ""),
    p("linear_spline", 0, 0, "nothing", ""),
    p("quadratic_spline", 0, 0, "nothing", ""),
    p("cubic_spline", 0, 0, "nothing", ""),
    p("bezier_spline", 0, 0, "nothing", ""),
    p("linear_sweep", 0, 0, "nothing", ""),
    p("conic_sweep", 0, 0, "nothing", ""),
]);
static HEIGHT_FIELD_PROPS: [PropSpec; 10] = with_transforms([
    INVERSE,
    p("png", 1, 1, "a file name", "\"terrain.png\""),
    p("exr", 1, 1, "a file name", "\"terrain.exr\""),
    p("jpeg", 1, 1, "a file name", "\"terrain.jpg\""),
    p("smooth", 0, 0, "nothing", ""),
    p("water_level", 1, 1, "a number in [0, 1)", "0.1"),
]);
static TEXT_PROPS: [PropSpec; 6] = with_transforms([
    INVERSE,
    p("ttf", 1, 1, "a font file name", "\"DejaVuSans.ttf\""),
]);
static SWEEP_PROPS: [PropSpec; 9] = with_transforms([
    INVERSE,
    p("linear_spline", 0, 0, "nothing", ""),
    p("cubic_spline", 0, 0, "nothing", ""),
    p("b_spline", 0, 0, "nothing", ""),
    p("tolerance", 1, 1, "a number", "1e-6"),
]);
static COMPONENT_PROPS: [PropSpec; 5] =
    with_transforms([p("strength", 1, 1, "a number", "strength 1")]);
static BLOB_PROPS: [PropSpec; 8] = with_transforms([
    p("threshold", 1, 1, "a positive number", "threshold 0.6"),
    p("sturm", 0, 0, "nothing", ""),
    w("hierarchy", "`on` or `off`", "hierarchy on"),
    INVERSE,
]);
static ISO_PROPS: [PropSpec; 11] = with_transforms([
    p("threshold", 1, 1, "a number", "threshold 0"),
    p("open", 0, 0, "nothing", ""),
    p("max_gradient", 1, 1, "a number", "max_gradient 4"),
    p("accuracy", 1, 1, "a positive number", "accuracy 1e-6"),
    p("max_trace", 1, 1, "a number", "max_trace 1"),
    p("all_intersections", 0, 0, "nothing", ""),
    INVERSE,
]);
static REVOLVE_PROPS: [PropSpec; 12] = with_transforms([
    INVERSE,
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

/// The blocks that make objects: shapes, then containers.
pub(super) const OBJECT_BLOCKS: &[&str] = &[
    "sphere",
    "plane",
    "quad",
    "box",
    "cylinder",
    "cone",
    "torus",
    "disk",
    "triangle",
    "mesh",
    "revolve",
    "prism",
    "superellipsoid",
    "sphere_sweep",
    "blob",
    "isosurface",
    "height_field",
    "text",
    "bezier_patch",
    "bezier_mesh",
    "union",
    "group",
    "object",
    "area_light",
    "merge",
    "intersection",
    "difference",
];

impl ObjectBuilder {
    pub(super) fn new(kind: &str, span: Span) -> Self {
        let kind = OBJECT_BLOCKS
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
            material_span: span,
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
            inverse: false,
            spline: None,
            conic: false,
            sweep_spline: None,
            component: false,
            strength: None,
            threshold: None,
            components: Vec::new(),
            function: None,
            container: None,
            accuracy: None,
            max_gradient: None,
            hf_file: None,
            smooth: false,
            water: None,
            ttf: None,
        }
    }

    /// A `sphere` or `cylinder` block written directly in a blob's body.
    pub(super) fn new_component(kind: &str, span: Span) -> Self {
        Self {
            component: true,
            ..Self::new(kind, span)
        }
    }

    fn is_container(&self) -> bool {
        matches!(self.kind, "union" | "group" | "object" | "area_light") || self.csg().is_some()
    }

    fn csg(&self) -> Option<CsgOp> {
        csg::csg_op(self.kind)
    }

    fn part(&self, shape: ShapeDecl) -> Part {
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
            Some(m) if m == "newton" => IntersectMethod::Newton {
                iterations: self.iterations,
                starts: self.starts,
            },
            _ => IntersectMethod::Robust,
        }
    }

    pub(super) fn finish(mut self, ev: &mut Evaluator) -> SourceResult<ObjectDef> {
        let mut parts = match self.kind {
            "union" | "group" | "object" => {
                if self.parts.is_empty() {
                    ev.warn(
                        Diagnostic::warning(self.span, format!("empty {}", self.kind))
                            .with_label("contains no objects")
                            .with_help(if self.kind == "object" {
                                "`object { Name ... }` places a declared object (`#declare Name \
                                 = sphere { ... }`); a declared material goes in `material { ... }`"
                            } else {
                                "put objects in it, or remove it"
                            }),
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
                            ShapeDecl::Quad { .. }
                                | ShapeDecl::Disk { .. }
                                | ShapeDecl::Sphere { .. }
                                | ShapeDecl::Triangle { .. }
                        )
                    {
                        return Err(vec![
                            Error::new(format!(
                                "an area light cannot be {} {}",
                                article(s.kind()),
                                s.kind()
                            ))
                            .label("unsupported emitter")
                            .help("use a quad, disk, sphere, triangle or mesh (or an `object` of one)")
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
                vec![self.part(ShapeDecl::Revolve {
                    profile: Profile {
                        segments: profile.segments.clone(),
                    },
                    sweep: self.sweep,
                    method: self.method(),
                })]
            }
            "prism" => vec![self.part(self.prism()?)],
            "superellipsoid" => vec![self.part(self.superellipsoid()?)],
            "blob" => vec![self.part(self.blob()?)],
            "isosurface" => vec![self.part(self.isosurface(ev)?)],
            "sphere" | "cylinder" if self.component => vec![self.blob_component()?],
            "height_field" => vec![self.part(self.height_field(ev)?)],
            "text" => self.text(ev)?,
            "sphere_sweep" => self.sphere_sweep()?,
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
                    parts.push(self.part(ShapeDecl::BezierPatch {
                        points: Box::new(pts),
                        method: self.method(),
                    }));
                }
                parts
            }
            k if csg::csg_op(k).is_some() => self.csg_finish(ev, csg::csg_op(k).unwrap())?,
            _ => vec![self.primitive(ev)?],
        };
        if self.inverse {
            parts = self.inverted(parts)?;
        }
        let mut t = self.transform;
        if let Some((axis, span)) = self.axis {
            let Some(dir) = crate::eval::builtins::unit(axis) else {
                return Err(vec![
                    Error::new("the axis has zero length")
                        .label("zero vector")
                        .help("give the axis a direction, e.g. `axis <0, 1, 0>` (the default)")
                        .at(span),
                ]);
            };
            t *= DAffine3::from_quat(DQuat::from_rotation_arc(DVec3::Y, dir));
        }
        if t.matrix3.determinant().abs() < 1e-300 {
            return Err(vec![
                Error::new("the transform is singular (it flattens the object to nothing)")
                    .label("its scales multiply to about 0")
                    .help("keep the product of the scales applied to the object above 1e-300")
                    .at(self.span),
            ]);
        }
        if matches!(self.kind, "union" | "group" | "object")
            && self.material.is_some()
            && !parts.is_empty()
            && parts.iter().all(|p| p.material.is_some())
        {
            ev.warn(
                Diagnostic::warning(
                    self.material_span,
                    format!("this material is used by no part of the {}", self.kind),
                )
                .with_label("every part has its own material")
                .with_help(
                    "a material here goes only to the parts without one (unlike POV-Ray's \
                     `object { Name pigment { ... } }`, it does not replace theirs): declare \
                     the object without a material and give one in each `object { ... }`, or \
                     remove this one",
                ),
            );
        }
        for part in &mut parts {
            part.transform = t * part.transform;
            if part.material.is_none() {
                part.material = self.material.clone();
            }
        }
        Ok(ObjectDef {
            parts,
            container: false,
        })
    }

    fn check_profile(&self, ev: &mut Evaluator, profile: &ProfileDef) -> SourceResult<()> {
        for seg in &profile.segments {
            for p in seg {
                if p.x < 0.0 {
                    return Err(range_error(
                        profile.span,
                        format!(
                            "profile point <{}, {}> has a negative radius",
                            short_number(p.x),
                            short_number(p.y)
                        ),
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
}

fn article(kind: &str) -> &'static str {
    // `union` begins with a vowel letter, not a vowel sound.
    if kind.starts_with(['a', 'e', 'i', 'o', 'u']) && !kind.starts_with("uni") {
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
            "sphere" | "cylinder" if self.component => &COMPONENT_PROPS,
            "cylinder" | "cone" => &CYL_PROPS,
            "area_light" => &AREA_PROPS,
            "revolve" => &REVOLVE_PROPS,
            "prism" => &PRISM_PROPS,
            "sphere_sweep" => &SWEEP_PROPS,
            "blob" => &BLOB_PROPS,
            "isosurface" => &ISO_PROPS,
            "height_field" => &HEIGHT_FIELD_PROPS,
            "text" => &TEXT_PROPS,
            "bezier_patch" | "bezier_mesh" => &PATCH_PROPS,
            _ => &OBJ_PROPS,
        }
    }
    fn property(&mut self, ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        if transform_prop(&kw.text, &args, &mut self.transform)? {
            return Ok(());
        }
        match kw.text.as_str() {
            "open" => self.open = true,
            // The last spline keyword of a sphere sweep counts, as in POV-Ray.
            "cubic_spline" if self.kind == "sphere_sweep" => {
                self.sweep_spline = Some(SweepSpline::CatmullRom)
            }
            "b_spline" => self.sweep_spline = Some(SweepSpline::BSpline),
            // A sphere sweep is exact: POV-Ray's root-finding tolerance has nothing to tune.
            "tolerance" => {}
            // A blob's roots are isolated exactly, over a hierarchy of its components always.
            "sturm" | "hierarchy" => {}
            "strength" => self.strength = Some((num(&args[0])?, args[0].span)),
            "threshold" => self.threshold = Some((num(&args[0])?, args[0].span)),
            "max_gradient" | "accuracy" | "max_trace" | "all_intersections" => {
                self.iso_property(ev, kw, &args)?
            }
            "linear_spline" => {
                self.spline = Some(PrismSpline::Linear);
                self.sweep_spline = None;
            }
            "quadratic_spline" => self.spline = Some(PrismSpline::Quadratic),
            "cubic_spline" => self.spline = Some(PrismSpline::Cubic),
            "bezier_spline" => self.spline = Some(PrismSpline::Bezier),
            "linear_sweep" => self.conic = false,
            "conic_sweep" => self.conic = true,
            "inverse" => self.inverse = true,
            "png" | "exr" | "jpeg" => {
                if let Some((_, first)) = &self.hf_file {
                    return Err(vec![
                        Error::new("a height field takes one image")
                            .label("a second image")
                            .help("remove one of them")
                            .at(kw.span.join(args[0].span))
                            .with_extra(*first, "the first one"),
                    ]);
                }
                let path = ev.resolve_path(crate::eval::args::file_name(&args[0])?, args[0].span);
                self.hf_file = Some((path, args[0].span));
            }
            "smooth" => self.smooth = true,
            "ttf" => {
                let written = crate::eval::args::file_name(&args[0])?.to_string();
                let path = ev.resolve_path(&written, args[0].span);
                self.ttf = Some((path, written, args[0].span));
            }
            "water_level" => {
                let w = num(&args[0])?;
                if !(0.0..1.0).contains(&w) {
                    return Err(range_error(
                        args[0].span,
                        format!(
                            "the water level must lie in [0, 1), found {}",
                            short_number(w)
                        ),
                        "heights run from 0 to 1: e.g. `water_level 0.2`",
                    ));
                }
                self.water = Some((w, args[0].span));
            }
            "two_sided" => self.two_sided = true,
            "corner" => self.corner = true,
            "radiance" => self.radiance = Some((color(&args[0])?, args[0].span)),
            "axis" => self.axis = Some((vec3(&args[0])?, args[0].span)),
            "method" => self.method = Some(word(&args[0], &["robust", "newton"])?),
            "iterations" => {
                self.iterations =
                    count(&args[0], "iterations", f64::from(MAX_NEWTON_ITERATIONS))? as u32
            }
            "starts" => {
                self.starts = count(&args[0], "starts", f64::from(MAX_NEWTON_STARTS))? as u32
            }
            "angle" => {
                let (a, b) = (num(&args[0])?, num(&args[1])?);
                if !(a < b && b - a <= 360.0) {
                    return Err(range_error(
                        args[0].span.join(args[1].span),
                        format!(
                            "sweep angles must satisfy start < end ≤ start + 360, found {}, {}",
                            short_number(a),
                            short_number(b)
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
    fn positional(&mut self, ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        match v {
            Value::Material(m) => {
                self.material = Some(m);
                self.material_span = span;
                Ok(())
            }
            Value::Object(o) if o.container && self.kind != "isosurface" => {
                Err(vec![isosurface::container_misplaced(span)])
            }
            Value::Object(o) if let Some(op) = self.csg() => self.csg_child(ev, op, &o, span),
            Value::Object(o) if self.kind == "blob" => self.blob_child(&o, span),
            Value::Function(f) if self.kind == "isosurface" => self.iso_function(&f, span),
            Value::Object(o) if self.kind == "isosurface" => {
                self.container = Some((isosurface::container_of(&o, span)?, span));
                Ok(())
            }
            Value::Object(o) if self.is_container() => {
                ev.count_parts(self.parts.len(), o.parts.len(), span)?;
                self.parts.extend(o.parts.iter().cloned());
                Ok(())
            }
            Value::Object(_) => Err(unexpected(
                self,
                &v,
                span,
                "only `union`, `group`, `object`, `area_light` and the CSG operations (`merge`, \
                 `intersection`, `difference`) contain objects",
            )),
            Value::Texture(_) => Err(unexpected(
                self,
                &v,
                span,
                "put the texture in a material: `material { diffuse texture { ... } }`",
            )),
            Value::Normal(_) => Err(unexpected(
                self,
                &v,
                span,
                "a normal belongs to a material: `material { diffuse rgb <...> normal { ... } }`",
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
