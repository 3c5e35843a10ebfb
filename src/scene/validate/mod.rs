//! The one validation of an evaluated [`Scene`]: what the renderer relies on and the language
//! cannot see value by value (where a transformed object ends up, whether the camera can be
//! oriented, whether sizes and positions stay inside what f32 rendering can represent).
//!
//! `prepare` runs it before building anything, so `check` (which prepares the scene) and
//! `render` accept exactly the same scenes, and a `Scene` built by hand through the library API
//! is refused with a message instead of rendering NaN or panicking. The evaluator calls
//! [`Camera::validate`] too, to report a bad camera at its block as soon as it is written.

use glam::{DAffine3, DVec3};
use rayon::prelude::*;

use super::{
    Background, CLOSED_HELP, Camera, ColorParam, Csg, CsgOp, IntersectMethod, LightDecl,
    MAX_BLEND_DEPTH, MAX_CSG_DEPTH, MAX_CSG_LEAVES, MAX_NEWTON_ITERATIONS, MAX_NEWTON_STARTS,
    Material, NormalKind, Object, ScalarParam, Scene, Settings, ShapeDecl, why_open,
};
use crate::diag::Diagnostic;
use crate::span::Span;

mod appearance;

pub use appearance::{
    COAT_IOR_RANGE, IOR_RANGE, MAX_COLOR, MAX_OCTAVES, MIN_ROUGHNESS, color_problem,
    environment_too_bright,
};

/// Largest coordinate or size in world space. Squares of it (distances, areas) stay far inside
/// f32, the renderer's precision along rays.
pub const MAX_COORD: f64 = 1e12;
/// Largest image side in pixels (the evaluator and `prepare` use the same bound).
pub const MAX_RESOLUTION_SIDE: u32 = 16_384;
/// Largest image in pixels.
pub const MAX_PIXELS: u64 = 1 << 27;

/// Most iterations a render may be asked for (by the scene's settings or the render's
/// options) without a time limit.
pub const MAX_ITERATIONS: u32 = 100_000_000;
/// Most photons per iteration (memory is checked again by the render's estimate).
pub const MAX_PHOTONS: u64 = 100_000_000_000;

/// Smallest radius, length or side in world space.
pub const MIN_SIZE: f64 = 1e-9;

/// Why a scene cannot be rendered, at the declaration at fault (detached when the scene was
/// built by hand).
fn invalid(span: Span, message: String, label: &str, help: &str) -> Diagnostic {
    Diagnostic::error(span, message)
        .with_label(label)
        .with_help(help)
}

fn fmt(x: f64) -> String {
    crate::diag::short_number(x)
}

/// A point or vector that must be finite and within [`MAX_COORD`].
fn point(p: DVec3, what: &str, span: Span) -> Result<(), Diagnostic> {
    let m = p.abs().max_element();
    if m.is_nan() || m > MAX_COORD {
        return Err(invalid(
            span,
            format!("{what} is out of range ({} from the origin)", fmt(m)),
            "too far away",
            "keep coordinates within 1e12 of the origin (scale the whole scene down)",
        ));
    }
    Ok(())
}

/// A world-space size that must lie in [`MIN_SIZE`, `MAX_COORD`].
fn size(x: f64, what: &str, span: Span) -> Result<(), Diagnostic> {
    if x.is_nan() || x > MAX_COORD {
        return Err(invalid(
            span,
            format!("{what} is {} in world space, too large", fmt(x)),
            "too large",
            "keep sizes (after every scale) at most 1e12",
        ));
    }
    if x.is_nan() || x < MIN_SIZE {
        return Err(invalid(
            span,
            format!("{what} is {} in world space, too small to render", fmt(x)),
            "too small",
            "keep sizes (after every scale) at least 1e-9",
        ));
    }
    Ok(())
}

impl Camera {
    /// Whether the camera can be built: finite, in range, oriented.
    pub fn validate(&self) -> Result<(), Diagnostic> {
        let span = self.span;
        point(self.location, "the camera's location", span)?;
        point(self.look_at, "the camera's look_at", span)?;
        if !(self.up.is_finite() && self.up.length_squared() > 0.0) {
            return Err(invalid(
                span,
                "the camera's `up` must be a finite, non-zero vector".into(),
                "cannot orient the camera",
                "e.g. `up <0, 1, 0>`",
            ));
        }
        let dir = self.look_at - self.location;
        if dir.length_squared() == 0.0 {
            return Err(invalid(
                span,
                "the camera looks at its own location".into(),
                "location == look_at",
                "move `look_at` away from `location`",
            ));
        }
        if dir.cross(self.up).length_squared()
            < 1e-18 * dir.length_squared() * self.up.length_squared().max(1e-300)
        {
            // Suggest an axis across the view direction.
            let across = if dir.z.abs() >= dir.x.abs().max(dir.y.abs()) {
                "`up <0, 1, 0>`"
            } else {
                "`up <0, 0, 1>`"
            };
            return Err(invalid(
                span,
                "the camera's `up` is parallel to its view direction".into(),
                "cannot orient the camera",
                &format!("choose another `up`, e.g. {across}"),
            ));
        }
        if !(self.fov > 0.0 && self.fov < 180.0) {
            return Err(invalid(
                span,
                format!(
                    "fov must be between 0 and 180 degrees, found {}",
                    fmt(self.fov)
                ),
                "out of range",
                "e.g. `fov 40`",
            ));
        }
        if !(self.aperture >= 0.0 && self.aperture <= MAX_COORD) {
            return Err(invalid(
                span,
                format!("the aperture {} is out of range", fmt(self.aperture)),
                "out of range",
                "use a lens radius from 0 (pinhole) to 1e12",
            ));
        }
        if let Some(f) = self.focus_distance {
            size(f, "the focus distance", span)?;
        } else if self.aperture > 0.0 {
            // A lens focuses at `look_at` unless told otherwise: the same bounds apply.
            size(
                (self.look_at - self.location).length(),
                "the focus distance (from `location` to `look_at`, no `focus_distance` given)",
                span,
            )?;
        }
        if self.orthographic {
            size(
                self.up.length(),
                "the orthographic view's height (the length of `up`)",
                span,
            )?;
            if let Some(r) = self.right {
                size(
                    r.length(),
                    "the orthographic view's width (the length of `right`)",
                    span,
                )?;
            }
        }
        if let Some(r) = self.right
            && !(r.x.is_finite() && r.x != 0.0)
        {
            return Err(invalid(
                span,
                "the camera's `right` has no x component to tell its handedness".into(),
                "x component 0 or not finite",
                "`right` says only which way the picture faces: `right <1.33, 0, 0>` is \
                 POV-Ray's left-handed camera, `right <-1.33, 0, 0>` a right-handed one",
            ));
        }
        Ok(())
    }
}

impl Settings {
    /// The numbers a render computes with; the resolution and counts are checked by `prepare`
    /// against the limits of the run.
    pub fn validate(&self) -> Result<(), Diagnostic> {
        let span = self.span;
        if let Some(r) = self.radius {
            size(r, "the initial radius", span)?;
        }
        if let Some(t) = self.antialias_threshold {
            if self.antialias != super::Antialias::Adaptive {
                return Err(invalid(
                    span,
                    "`threshold` is given but anti-aliasing is not adaptive".into(),
                    "threshold without `antialias adaptive`",
                    "write `antialias adaptive threshold 0.1`, or drop the threshold",
                ));
            }
            if !(t > 0.0 && t.is_finite()) {
                return Err(invalid(
                    span,
                    format!("anti-aliasing threshold {} is out of range", fmt(t)),
                    "out of range",
                    "use a positive colour difference, e.g. `threshold 0.1`",
                ));
            }
        }
        if !(self.exposure > 0.0 && self.exposure <= 1e9) {
            return Err(invalid(
                span,
                format!("exposure {} is out of range", fmt(self.exposure)),
                "out of range",
                "use an exposure above 0 and at most 1e9",
            ));
        }
        if !(self.radius_scale > 0.0 && self.radius_scale.is_finite()) {
            return Err(invalid(
                span,
                format!("radius scale {} is out of range", fmt(self.radius_scale)),
                "out of range",
                "use a positive, finite scale of the initial radius (1: as chosen)",
            ));
        }
        if !(self.alpha > 0.0 && self.alpha <= 1.0) {
            return Err(invalid(
                span,
                format!("alpha must be in (0, 1], got {}", fmt(self.alpha)),
                "out of range",
                "the usual value is 2/3",
            ));
        }
        if let Some(t) = self.time_limit
            && !(t > 0.0 && t.is_finite())
        {
            return Err(invalid(
                span,
                format!(
                    "time limit must be a positive number of seconds, got {}",
                    fmt(t)
                ),
                "out of range",
                "e.g. `time_limit 30`",
            ));
        }
        Ok(())
    }
}

/// Largest column norm of the linear part: how much the transform can stretch a length.
fn stretch(t: &DAffine3) -> f64 {
    let m = t.matrix3;
    m.x_axis
        .length()
        .max(m.y_axis.length())
        .max(m.z_axis.length())
}

/// Smallest column norm: how much it can shrink one.
fn shrink(t: &DAffine3) -> f64 {
    let m = t.matrix3;
    m.x_axis
        .length()
        .min(m.y_axis.length())
        .min(m.z_axis.length())
}

impl Scene {
    /// Checks the whole scene; the first problem found.
    pub fn validate(&self) -> Result<(), Diagnostic> {
        self.camera.validate()?;
        self.settings.validate()?;
        for (i, m) in self.materials.iter().enumerate() {
            textures_exist(m, i, self.textures.len())?;
        }
        blends_bounded(self)?;
        sky_textures_exist(self)?;
        appearance::validate(self)?;
        for obj in &self.objects {
            if let ShapeDecl::Csg(csg) = &obj.shape {
                csg_limits(csg, obj.span)?;
                if obj.emission.is_some() {
                    return Err(invalid(
                        obj.span,
                        format!("{} cannot emit light", csg.op.a_name()),
                        "emissive",
                        "place an area light beside the CSG object",
                    ));
                }
            }
            validate_object(obj, &DAffine3::IDENTITY)?;
        }
        for light in &self.lights {
            let (position, span) = match light {
                LightDecl::Point { position, span, .. }
                | LightDecl::Spot { position, span, .. } => (*position, *span),
            };
            point(position, "the light's position", span)?;
        }
        if let Background::Environment { intensity, .. } = &self.background
            && !(*intensity >= 0.0 && *intensity <= 1e9)
        {
            return Err(invalid(
                Span::detached(),
                format!("environment intensity {} is out of range", fmt(*intensity)),
                "out of range",
                "use an intensity from 0 to 1e9",
            ));
        }
        if let Background::Environment {
            image, intensity, ..
        } = &self.background
            && let Some((message, most)) = environment_too_bright(image, *intensity)
        {
            return Err(invalid(
                Span::detached(),
                message,
                "out of range",
                &format!("use an intensity of at most {} with this image", fmt(most)),
            ));
        }
        Ok(())
    }
}

/// One object under its parent's transform (identity at the top level).
fn validate_object(obj: &Object, parent: &DAffine3) -> Result<(), Diagnostic> {
    let span = obj.span;
    let t = &(*parent * obj.transform);
    let kind = obj.shape.kind();
    if !(t.matrix3.is_finite() && t.translation.is_finite()) {
        return Err(invalid(
            span,
            format!("the {kind}'s transform is not finite"),
            "transforms overflow",
            "check the chain of scale, translate and matrix applied to it",
        ));
    }
    let (hi, lo) = (stretch(t), shrink(t));
    let at = |p: DVec3| point(t.transform_point3(p), &format!("this {kind}"), span);
    let len = |x: f64, what: &str| {
        size(x * hi, &format!("the {kind}'s {what}"), span)?;
        size(x * lo, &format!("the {kind}'s {what}"), span)
    };
    match &obj.shape {
        ShapeDecl::Sphere { center, radius } => {
            at(*center)?;
            len(*radius, "radius")?;
        }
        ShapeDecl::Plane { normal, offset } => {
            // Only the distance from the origin matters: a plane moved along itself is
            // the same plane.
            let n = t.matrix3.inverse().transpose() * *normal;
            let p = t.transform_point3(*normal * *offset);
            let d = if n.length_squared() > 0.0 {
                n.normalize().dot(p)
            } else {
                f64::NAN
            };
            point(DVec3::splat(d), &format!("this {kind}"), span)?;
        }
        ShapeDecl::Quad {
            origin,
            edge_u,
            edge_v,
        } => {
            for p in [*origin, *origin + *edge_u, *origin + *edge_v] {
                at(p)?;
            }
            at(*origin + *edge_u + *edge_v)?;
        }
        ShapeDecl::Box { min, max } => {
            for i in 0..8 {
                let pick = |bit: i32, a: f64, b: f64| if i & bit == 0 { a } else { b };
                at(DVec3::new(
                    pick(1, min.x, max.x),
                    pick(2, min.y, max.y),
                    pick(4, min.z, max.z),
                ))?;
            }
        }
        ShapeDecl::Cylinder {
            base, cap, radius, ..
        } => {
            at(*base)?;
            at(*cap)?;
            len(*radius, "radius")?;
            len((*cap - *base).length(), "length")?;
        }
        ShapeDecl::Cone {
            base,
            base_radius,
            cap,
            cap_radius,
            ..
        } => {
            at(*base)?;
            at(*cap)?;
            // One radius may be 0 (a pointed cone): the larger one sets the size.
            len(base_radius.max(*cap_radius), "radius")?;
            len((*cap - *base).length(), "length")?;
        }
        ShapeDecl::Torus { major, minor } => {
            at(DVec3::ZERO)?;
            len(*major + *minor, "size")?;
            len(*minor, "minor radius")?;
        }
        ShapeDecl::Disk { center, radius, .. } => {
            // A disk may be squashed along its own normal: only its largest stretch.
            at(*center)?;
            size(*radius * hi, &format!("the {kind}'s radius"), span)?;
        }
        ShapeDecl::Triangle { vertices } => {
            for v in vertices {
                at(*v)?;
            }
        }
        ShapeDecl::Mesh { mesh } => {
            // A mesh may have millions of vertices: looked at in parallel, the first one out of
            // range reported.
            let far = |p: &DVec3| {
                let m = t.transform_point3(*p).abs().max_element();
                m.is_nan() || m > MAX_COORD
            };
            if let Some(p) = mesh.positions.par_iter().find_first(|p| far(p)) {
                at(*p)?;
            }
        }
        ShapeDecl::Superellipsoid { e, n } => {
            let (lo, hi) = super::SUPERELLIPSOID_EXPONENTS;
            if !(*e >= lo && *e <= hi && *n >= lo && *n <= hi) {
                return Err(invalid(
                    span,
                    format!(
                        "the superellipsoid's exponents <{}, {}> lie outside [{}, {}]",
                        fmt(*e),
                        fmt(*n),
                        fmt(lo),
                        fmt(hi)
                    ),
                    "out of range",
                    "near 0 a box, 1 a sphere, 2 an octahedron, beyond 2 a pinched star",
                ));
            }
            len(1.0, "size")?;
            for c in [DVec3::splat(-1.0), DVec3::splat(1.0)] {
                at(c)?;
            }
        }
        ShapeDecl::Blob(b) => {
            b.check().map_err(|m| {
                invalid(span, m, "here", "see the blob section of docs/language.md")
            })?;
            for c in &b.components {
                let place = *t * c.transform;
                for q in [c.a, c.b] {
                    point(place.transform_point3(q), &format!("this {kind}"), span)?;
                }
                len(c.radius * stretch(&c.transform), "component radius")?;
            }
        }
        ShapeDecl::Isosurface(i) => {
            i.check().map_err(|m| {
                invalid(
                    span,
                    m,
                    "here",
                    "see the isosurface section of docs/language.md",
                )
            })?;
            let (lo, hi) = i.container.bounds();
            len((hi - lo).max_element(), "container")?;
            at(lo)?;
            at(hi)?;
        }
        ShapeDecl::SphereSweep(s) => {
            s.check().map_err(|m| {
                invalid(
                    span,
                    m,
                    "here",
                    "see the sphere sweep section of docs/language.md",
                )
            })?;
            for (c, r) in s.centres.iter().zip(&s.radii) {
                at(*c)?;
                if *r > 0.0 {
                    len(*r, "radius")?;
                }
            }
        }
        ShapeDecl::HeightField(_) => {
            len(1.0, "size")?;
            for c in [DVec3::ZERO, DVec3::ONE] {
                at(c)?;
            }
        }
        ShapeDecl::Prism(p) => {
            // The corners of its box: the profile's rectangle at both heights (scaled by the
            // height for a conic sweep).
            let (lo, hi) = p.heights;
            len((hi - lo).abs(), "height")?;
            for q in p.segments.iter().flatten() {
                for h in [lo, hi] {
                    let w = if p.conic { h } else { 1.0 };
                    at(DVec3::new(q.x * w, h, q.y * w))?;
                }
            }
        }
        ShapeDecl::Revolve {
            profile, method, ..
        } => {
            newton_bounds(*method, kind, span)?;
            for p in profile.segments.iter().flatten() {
                at(DVec3::new(p.x, p.y, p.x))?;
            }
        }
        ShapeDecl::BezierPatch { points, method } => {
            newton_bounds(*method, kind, span)?;
            for p in points.iter() {
                at(*p)?;
            }
            // The surface lies in the control net's convex hull: a net whose points all lie
            // on one line (or at one point) draws nothing, as a zero-area quad would.
            let w: Vec<DVec3> = points.iter().map(|p| t.transform_point3(*p)).collect();
            let area: f64 = (0..3)
                .flat_map(|i| (0..3).map(move |j| (i, j)))
                .map(|(i, j)| {
                    let q = |a: usize, b: usize| w[4 * a + b];
                    0.5 * (q(i + 1, j + 1) - q(i, j))
                        .cross(q(i, j + 1) - q(i + 1, j))
                        .length()
                })
                .sum();
            if area.is_nan() || area <= MIN_SIZE * MIN_SIZE {
                return Err(invalid(
                    span,
                    "this bezier_patch has no area: its control points all lie on one line \
                     or at one point"
                        .into(),
                    "no area",
                    "spread the 16 points over a surface, e.g. a 4 x 4 grid",
                ));
            }
        }
        ShapeDecl::Csg(csg) => validate_csg(csg, t, span)?,
    }
    Ok(())
}

/// Newton's iterations and starts within the language's bounds (each ray pays their product).
fn newton_bounds(method: IntersectMethod, kind: &str, span: Span) -> Result<(), Diagnostic> {
    match method {
        IntersectMethod::Newton { iterations, starts }
            if iterations > MAX_NEWTON_ITERATIONS || starts > MAX_NEWTON_STARTS =>
        {
            Err(invalid(
                span,
                format!(
                    "this {kind}'s Newton method asks for {iterations} iterations from {starts} \
                     starts, more than {MAX_NEWTON_ITERATIONS} and {MAX_NEWTON_STARTS}"
                ),
                "too many iterations",
                "use at most `iterations 1000 starts 64`, or `method robust`",
            ))
        }
        _ => Ok(()),
    }
}

/// Every blend's parts come before it in `Scene::materials` (so that following them ends) and
/// blends nest at most `MAX_BLEND_DEPTH` deep.
fn blends_bounded(scene: &Scene) -> Result<(), Diagnostic> {
    let depths = scene.blend_depths();
    match depths
        .iter()
        .position(|d| d.is_none_or(|d| d > MAX_BLEND_DEPTH))
    {
        Some(i) => Err(invalid(
            Span::detached(),
            format!(
                "material {i} blends materials that do not come before it, or nests blends \
                 more than {MAX_BLEND_DEPTH} deep"
            ),
            "blend out of order",
            "push a blend's two materials before it, and nest at most 16 blends",
        )),
        None => Ok(()),
    }
}

/// Every texture material `index` refers to is one of the scene's `count` textures.
fn textures_exist(m: &Material, index: usize, count: usize) -> Result<(), Diagnostic> {
    let color = |p: &ColorParam| match p {
        ColorParam::Texture(t) => Some(t.0),
        ColorParam::Const(_) => None,
    };
    let ids = match m {
        Material::Diffuse { albedo } => [color(albedo), None, None],
        Material::Mirror { tint } => [color(tint), None, None],
        Material::Glass {
            absorb, roughness, ..
        } => [
            color(absorb),
            None,
            match roughness {
                ScalarParam::Texture(t) => Some(t.0),
                ScalarParam::Const(_) => None,
            },
        ],
        Material::ThinGlass { .. } => [None, None, None],
        Material::Conductor { .. } => [None, None, None],
        Material::Bumped { normal, .. } => match normal.kind {
            NormalKind::Height(t) | NormalKind::Map(t) => [Some(t.0), None, None],
            _ => [None, None, None],
        },
        Material::Blend { weight, .. } => [
            None,
            None,
            match weight {
                ScalarParam::Texture(t) => Some(t.0),
                ScalarParam::Const(_) => None,
            },
        ],
        Material::Coated {
            albedo, roughness, ..
        } => [
            color(albedo),
            None,
            match roughness {
                ScalarParam::Texture(t) => Some(t.0),
                ScalarParam::Const(_) => None,
            },
        ],
        Material::Glossy {
            albedo,
            specular,
            roughness,
        } => [
            color(albedo),
            color(specular),
            match roughness {
                ScalarParam::Texture(t) => Some(t.0),
                ScalarParam::Const(_) => None,
            },
        ],
    };
    match ids.into_iter().flatten().find(|&t| t as usize >= count) {
        Some(t) => Err(invalid(
            Span::detached(),
            format!("material {index} uses texture {t}, but the scene has {count} textures"),
            "unknown texture",
            "push the texture onto `Scene::textures` and refer to it by its index",
        )),
        None => Ok(()),
    }
}

/// The background's and the backdrop's textures are among the scene's.
fn sky_textures_exist(scene: &Scene) -> Result<(), Diagnostic> {
    let count = scene.textures.len();
    let background = match scene.background {
        Background::Texture(t) => Some(("the background", t.0)),
        _ => None,
    };
    let backdrop = match scene.backdrop {
        Some(ColorParam::Texture(t)) => Some(("the backdrop", t.0)),
        _ => None,
    };
    match [background, backdrop]
        .into_iter()
        .flatten()
        .find(|&(_, t)| t as usize >= count)
    {
        Some((what, t)) => Err(invalid(
            Span::detached(),
            format!("{what} uses texture {t}, but the scene has {count} textures"),
            "unknown texture",
            "push the texture onto `Scene::textures` and refer to it by its index",
        )),
        None => Ok(()),
    }
}

/// The size of a CSG tree; checked before anything walks it recursively.
fn csg_limits(csg: &Csg, span: Span) -> Result<(), Diagnostic> {
    if csg.depth(MAX_CSG_DEPTH) > MAX_CSG_DEPTH {
        return Err(invalid(
            span,
            format!("CSG operations are nested more than {MAX_CSG_DEPTH} deep"),
            "too deep",
            "flatten the tree: a merge, union or intersection takes any number of children",
        ));
    }
    let n = csg.leaves().len();
    if n > MAX_CSG_LEAVES {
        return Err(invalid(
            span,
            format!(
                "this {} holds {n} shapes, more than {MAX_CSG_LEAVES}",
                csg.op.name()
            ),
            "too many shapes",
            "every ray into a CSG tests its shapes one by one: split it, or use `union` \
             (flattened into the scene) where inner surfaces may stay",
        ));
    }
    Ok(())
}

/// The children of a CSG node: closed, not emissive, each valid under `t`.
fn validate_csg(csg: &Csg, t: &DAffine3, span: Span) -> Result<(), Diagnostic> {
    if csg.op == CsgOp::Inverse && csg.children.len() != 1 {
        return Err(invalid(
            span,
            format!("inverse takes one object, found {}", csg.children.len()),
            "not one object",
            "write `inverse` inside the object to turn inside out",
        ));
    }
    for child in &csg.children {
        if let Some(why) = why_open(&child.shape) {
            return Err(invalid(
                child.span,
                format!(
                    "this {} has no inside, so it cannot be part of {}: {why}",
                    child.shape.kind(),
                    csg.op.a_name()
                ),
                "not a closed shape",
                CLOSED_HELP,
            ));
        }
        if child.emission.is_some() {
            return Err(invalid(
                child.span,
                format!("an area light cannot be part of {}", csg.op.a_name()),
                "emissive",
                "place the area light beside the CSG object",
            ));
        }
        validate_object(child, t)?;
    }
    Ok(())
}
