//! The evaluated scene: plain data, the boundary between the language and the renderer.
//!
//! Everything here is what a `.scn` file declared, with explicit defaults filled in by the
//! evaluator (see `docs/language.md`). No rendering state lives here: the renderer builds its own
//! prepared structures (BVH, light sampler) from a `Scene` and never writes back.
//!
//! Geometry is in f64 (`glam::DVec3`) so that the renderer chooses where precision matters.
//! Colors are linear RGB.

pub mod animation;
mod assets;
pub mod blob;
mod csg;
pub mod function;
pub mod height_field;
pub mod interval;
pub mod metals;
pub mod noise;
mod obj;
mod obj_errors;
pub mod pattern_value;
pub mod prism;
pub mod slope;
pub mod sphere_sweep;
pub mod text;
mod validate;

pub use animation::{ANIMATION_NAMES, Frame, FrameRange, MAX_FRAME, animation_value};
pub use assets::{
    AssetError, ColorSpace, IMAGE_BYTES_PER_PIXEL, ImageData, ImageRoom, MAX_TOTAL_IMAGE_PIXELS,
    MeshData, brightest_pixel, load_image, load_image_within, load_obj, load_obj_in,
    srgb_to_linear,
};
pub use blob::{Blob, BlobComponent, Container, Isosurface, MAX_BLOB_COMPONENTS};
pub use csg::{CLOSED_HELP, Csg, CsgOp, MAX_CSG_DEPTH, MAX_CSG_LEAVES, why_open};
pub use function::{Function, FunctionError, Op};
pub use height_field::{HeightField, HeightGrid, MAX_HEIGHT_FIELD_SIDE};
pub use pattern_value::{PatternFn, PatternKind};
pub use prism::{Prism, PrismSpline, ProfileError, prism_segments};
pub use sphere_sweep::{MAX_SWEEP_SPHERES, SphereSweep, SweepSegment, SweepSpline};
pub use validate::{
    COAT_IOR_RANGE, IOR_RANGE, MAX_COLOR, MAX_COORD, MAX_ITERATIONS, MAX_OCTAVES, MAX_PHOTONS,
    MAX_PIXELS, MAX_RESOLUTION_SIDE, MIN_ROUGHNESS, MIN_SIZE, color_problem,
    environment_too_bright,
};

use std::sync::Arc;

/// The unit vector along `v` (f64), scaled by its largest component first so that neither its
/// squared length overflows (`<1e160, 0, 0>`) nor underflows (`<1e-160, 0, 0>`); `None` for a
/// zero vector (or one with a component that is not finite).
pub fn scaled_unit(v: glam::DVec3) -> Option<glam::DVec3> {
    let m = v.abs().max_element();
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    let s = v / m;
    Some(s / s.length())
}

/// The length of `v` (f64), scaled by its largest component first: `<1e-200, 1e-200, 0>` has a length, though its squared length
/// underflows.
pub fn scaled_length_f64(v: glam::DVec3) -> f64 {
    let m = v.abs().max_element();
    if m > 0.0 && m.is_finite() {
        m * (v / m).length()
    } else {
        v.length()
    }
}

use glam::{DAffine3, DVec2, DVec3};

use crate::span::Span;

/// Linear RGB color.
pub type Color = DVec3;

/// Index into [`Scene::materials`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MaterialId(pub u32);

/// Index into [`Scene::textures`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TextureId(pub u32);

/// The whole evaluated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    pub settings: Settings,
    pub camera: Camera,
    /// Every object, flattened (groups and unions resolved, transforms composed); a CSG
    /// operation is one object holding its children.
    pub objects: Vec<Object>,
    /// Lights that are not shapes (point, spot). Emissive objects are lights too.
    pub lights: Vec<LightDecl>,
    pub materials: Vec<Material>,
    /// Only textures some material, the background or the backdrop actually uses.
    pub textures: Vec<Texture>,
    pub background: Background,
    /// What camera rays that leave the scene show, directly or through mirrors and glass
    /// alone, in place of the background; it lights nothing. `None`: they show the background.
    pub backdrop: Option<ColorParam>,
}

impl Scene {
    pub fn material(&self, id: MaterialId) -> &Material {
        &self.materials[id.0 as usize]
    }

    pub fn texture(&self, id: TextureId) -> &Texture {
        &self.textures[id.0 as usize]
    }
}

/// Photons per pass of `photon_map` when the scene does not set `photons`.
pub const DEFAULT_PHOTONS: u64 = 200_000;

/// Render settings (`settings { ... }`).
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Width and height in pixels.
    pub resolution: (u32, u32),
    /// Number of SPPM iterations (camera pass + photon pass).
    pub iterations: u32,
    /// Photons traced per iteration; `None`: SPPM and PPM choose it every iteration
    /// (`integrators::sppm` `photon_count`), photon mapping traces [`DEFAULT_PHOTONS`].
    pub photons: Option<u64>,
    /// Initial gather radius in scene units; `None`: chosen from the scene's size.
    pub radius: Option<f64>,
    /// Scale of the initial radius (the scene's `radius` or the default rule): 1 unless a tool
    /// varies it (`sppm-lang chart`); not part of the language.
    pub radius_scale: f64,
    /// SPPM radius reduction parameter, in (0, 1].
    pub alpha: f64,
    /// Maximum path depth for camera paths and photon paths.
    pub max_depth: u32,
    pub seed: u64,
    /// The method the scene names (`integrator NAME`); `None`: it names none, and the render
    /// runs the default rule's (`prepare::default_method`: `sppm` with `final_gather on`).
    pub integrator: Option<Integrator>,
    /// Exposure multiplier applied before tone mapping to PNG (linear outputs are unscaled).
    pub exposure: f64,
    /// Stop after this many seconds even if iterations remain.
    pub time_limit: Option<f64>,
    /// How `whitted` anti-aliases (`antialias jitter|adaptive`); other integrators ignore it.
    pub antialias: Antialias,
    /// `threshold t` of `antialias adaptive`; `None`: [`Antialias::DEFAULT_THRESHOLD`].
    pub antialias_threshold: Option<f64>,
    /// SPPM's final gathering (`final_gather on`): a visible point gathers only caustic
    /// photons, and one BSDF-sampled gather path per pixel and iteration brings the rest from
    /// the next diffuse surface. `vcm` merges at a camera path's second vertex (after a
    /// non-specular first) with the gather's wider radius, as a technique of its own in its
    /// weights. Other integrators ignore it.
    pub final_gather: bool,
    /// How the scene's coordinates are read (`handedness left`: POV-Ray's).
    pub handedness: Handedness,
    /// The animation's frames (`frames first, last`); `None`: a still unless the caller gives
    /// a range.
    pub frames: Option<(u32, u32)>,
    /// The clock over the frames (`clock_range initial, final`); `None`: 0 to 1.
    pub clock_range: Option<(f64, f64)>,
    /// `cyclic on`: the frame after the last is the first again ([`FrameRange::cyclic`]).
    pub cyclic: bool,
    /// The last `settings` block (detached when the file gave none): where errors about the
    /// settings point.
    pub span: Span,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            resolution: (512, 512),
            iterations: 64,
            photons: None,
            radius: None,
            radius_scale: 1.0,
            alpha: 2.0 / 3.0,
            max_depth: 16,
            seed: 0,
            integrator: None,
            exposure: 1.0,
            time_limit: None,
            antialias: Antialias::Jitter,
            antialias_threshold: None,
            final_gather: false,
            handedness: Handedness::Right,
            frames: None,
            clock_range: None,
            cyclic: false,
            span: Span::detached(),
        }
    }
}

/// The coordinate system a scene's numbers are written in. A camera looking along +z with +y
/// up sees +x on its left in a right-handed system and on its right in a left-handed one
/// (POV-Ray's). Reading a scene as left-handed mirrors only the camera's screen x axis: every
/// other number keeps its meaning, so the picture is the mirror image of the right-handed
/// reading, as if every x coordinate (and every rotation, pattern, uv and winding with it) had
/// been mirrored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Handedness {
    #[default]
    Right,
    Left,
}

impl Handedness {
    pub const ALL: [Handedness; 2] = [Handedness::Right, Handedness::Left];

    pub fn name(self) -> &'static str {
        match self {
            Handedness::Right => "right",
            Handedness::Left => "left",
        }
    }
}

/// Anti-aliasing of `whitted`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Antialias {
    /// One jittered sample per pixel per iteration.
    #[default]
    Jitter,
    /// As `Jitter`, plus a 4x4 rotated-grid supersample of every pixel whose sample differs
    /// from a neighbour's (in colour by more than the threshold, or in the objects its eye
    /// path met).
    Adaptive,
}

impl Antialias {
    /// The colour difference above which `Adaptive` supersamples a pixel.
    pub const DEFAULT_THRESHOLD: f64 = 0.1;
    pub const ALL: [Antialias; 2] = [Antialias::Jitter, Antialias::Adaptive];

    pub fn name(self) -> &'static str {
        match self {
            Antialias::Jitter => "jitter",
            Antialias::Adaptive => "adaptive",
        }
    }
}

/// Which light-transport algorithm renders the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Integrator {
    Whitted,
    PhotonMap,
    Ppm,
    Sppm,
    Path,
    /// Vertex connection and merging.
    Vcm,
    /// Bidirectional path tracing (VCM's connections only).
    Bpt,
    /// Light tracing (light paths connected to the camera only).
    Lt,
}

impl Integrator {
    pub const ALL: [Integrator; 8] = [
        Integrator::Whitted,
        Integrator::PhotonMap,
        Integrator::Ppm,
        Integrator::Sppm,
        Integrator::Path,
        Integrator::Vcm,
        Integrator::Bpt,
        Integrator::Lt,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Integrator::Whitted => "whitted",
            Integrator::PhotonMap => "photon_map",
            Integrator::Ppm => "ppm",
            Integrator::Sppm => "sppm",
            Integrator::Path => "path",
            Integrator::Vcm => "vcm",
            Integrator::Bpt => "bpt",
            Integrator::Lt => "lt",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|i| i.name() == name)
    }
}

/// Pinhole or thin-lens camera, perspective or orthographic.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    pub location: DVec3,
    pub look_at: DVec3,
    /// Which way is up in the picture; for an orthographic camera its length is also the
    /// height of the view in scene units (POV-Ray's rule).
    pub up: DVec3,
    /// Vertical field of view in degrees (perspective cameras).
    pub fov: f64,
    /// Parallel camera rays from a rectangle through `location` across the view direction,
    /// `|up|` high and `|right|` wide (the resolution's aspect without `right`).
    pub orthographic: bool,
    /// Lens radius; 0 is a pinhole.
    pub aperture: f64,
    /// Distance to the plane in focus; `None`: the distance to `look_at`.
    pub focus_distance: Option<f64>,
    /// POV-Ray's `right` vector as written: the sign of its x component is used, as POV-Ray
    /// tests it against its default `up y` and `direction z` (positive: +x shows on the right
    /// of the picture, as in a left-handed system; negative: a right-handed camera), and an
    /// orthographic camera takes its length as the view's width.
    /// `None`: the scene's [`Handedness`] decides.
    pub right: Option<DVec3>,
    /// The last `camera` block (detached when the file gave none).
    pub span: Span,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            location: DVec3::new(0.0, 0.0, -5.0),
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov: 40.0,
            orthographic: false,
            aperture: 0.0,
            focus_distance: None,
            right: None,
            span: Span::detached(),
        }
    }
}

impl Camera {
    /// The width and height of an orthographic camera's view in scene units for an image of
    /// `width` x `height` pixels: `|right|` (else the image's aspect times the height) by
    /// `|up|`.
    pub fn view_size(&self, width: u32, height: u32) -> (f64, f64) {
        let h = self.up.length();
        let w = match self.right {
            Some(r) => r.length(),
            None => h * f64::from(width) / f64::from(height.max(1)),
        };
        (w, h)
    }

    /// Whether the picture's x axis is mirrored from the right-handed camera: the camera's own
    /// `right` decides when it has one (so a POV-Ray camera made right-handed with
    /// `right <-1.33, 0, 0>` is never mirrored twice), else the scene's `handedness`.
    pub fn mirrored(&self, handedness: Handedness) -> bool {
        match self.right {
            Some(r) => r.x > 0.0,
            None => handedness == Handedness::Left,
        }
    }
}

/// What a ray that leaves the scene sees: the sky, which lights the scene.
#[derive(Debug, Clone)]
pub enum Background {
    Color(Color),
    /// A texture over directions (looked up as `textures::sky` describes), baked into an
    /// environment map when the scene is prepared.
    Texture(TextureId),
    /// Equirectangular image that also lights the scene.
    Environment {
        image: Arc<ImageData>,
        intensity: f64,
        /// World-to-environment rotation.
        transform: DAffine3,
    },
}

impl Default for Background {
    fn default() -> Self {
        Background::Color(Color::ZERO)
    }
}

/// One object: a shape in object space, its object-to-world transform, and its appearance.
#[derive(Debug, Clone)]
pub struct Object {
    pub shape: ShapeDecl,
    /// Object-to-world transform (identity when the file gave none).
    pub transform: DAffine3,
    pub material: MaterialId,
    /// Emitted radiance; an emissive object is an area light.
    pub emission: Option<Emission>,
    /// Where the object was declared.
    pub span: Span,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Emission {
    /// Radiance leaving the surface (W / (m^2 sr) per channel).
    pub radiance: Color,
    /// Emit from both sides; otherwise only on the side the geometric normal faces.
    pub two_sided: bool,
}

/// Shapes in object space.
#[derive(Debug, Clone)]
pub enum ShapeDecl {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// All points `p` with `dot(normal, p) = offset` (normal is unit length).
    Plane {
        normal: DVec3,
        offset: f64,
    },
    /// Parallelogram `origin + s*edge_u + t*edge_v`, s,t in \[0,1\]; normal `edge_u x edge_v`.
    Quad {
        origin: DVec3,
        edge_u: DVec3,
        edge_v: DVec3,
    },
    Box {
        min: DVec3,
        max: DVec3,
    },
    Cylinder {
        base: DVec3,
        cap: DVec3,
        radius: f64,
        /// No end caps.
        open: bool,
    },
    /// A cone frustum (POV-Ray's `cone`): radius `base_radius` at `base`, `cap_radius` at
    /// `cap`, either 0 for a point.
    Cone {
        base: DVec3,
        base_radius: f64,
        cap: DVec3,
        cap_radius: f64,
        /// No end caps.
        open: bool,
    },
    Disk {
        center: DVec3,
        normal: DVec3,
        radius: f64,
    },
    /// A torus about the object-space y axis (POV-Ray's `torus`): `major` from the axis to the
    /// tube's centre, `minor` the tube's radius; `minor < major <= TORUS_MAX_ASPECT * minor`.
    Torus {
        major: f64,
        minor: f64,
    },
    Triangle {
        vertices: [DVec3; 3],
    },
    Mesh {
        mesh: Arc<MeshData>,
    },
    /// A profile curve `(radius, height)` swept around the object-space y axis.
    Revolve {
        profile: Profile,
        /// Partial sweep `(start, end)` in degrees with flat side caps; `None`: full turn.
        sweep: Option<(f64, f64)>,
        method: IntersectMethod,
    },
    /// Bicubic Bezier patch, control points row-major (`points[4*i + j]`, i along u).
    BezierPatch {
        points: Box<[DVec3; 16]>,
        method: IntersectMethod,
    },
    /// POV-Ray's `prism`: a closed profile swept along y (see [`Prism`]).
    Prism(Prism),
    /// POV-Ray's `superellipsoid { <e, n> }` in the cube [-1, 1]^3, the exponents within
    /// [`SUPERELLIPSOID_EXPONENTS`].
    Superellipsoid {
        e: f64,
        n: f64,
    },
    /// POV-Ray's `blob`: spheres and capsules of density, the surface where their sum meets
    /// a threshold (see [`Blob`]).
    Blob(Blob),
    /// POV-Ray's `isosurface`: where a user function meets a threshold in a container (see
    /// [`Isosurface`]).
    Isosurface(Isosurface),
    /// POV-Ray's `height_field`: a grid of heights over the unit square (see [`HeightField`]).
    HeightField(HeightField),
    /// POV-Ray's `sphere_sweep` along a `cubic_spline` or `b_spline` (see [`SphereSweep`]; a
    /// `linear_spline` sweep is a merge of spheres and cones).
    SphereSweep(SphereSweep),
    /// Constructive solid geometry over closed child objects (see [`Csg`]).
    Csg(Csg),
}

/// The range of a superellipsoid's exponents: below it the shape is a box, above it a set of
/// needles, to within rounding.
pub const SUPERELLIPSOID_EXPONENTS: (f64, f64) = (1e-3, 10.0);

/// The most a torus's major radius may exceed its minor radius (see `shapes::torus`: beyond
/// it the intersector's quartic loses the precision to place hits on the surface).
pub const TORUS_MAX_ASPECT: f64 = 1000.0;

impl ShapeDecl {
    /// The keyword that declares this shape, for messages and summaries.
    pub fn kind(&self) -> &'static str {
        match self {
            ShapeDecl::Sphere { .. } => "sphere",
            ShapeDecl::Plane { .. } => "plane",
            ShapeDecl::Quad { .. } => "quad",
            ShapeDecl::Box { .. } => "box",
            ShapeDecl::Cylinder { .. } => "cylinder",
            ShapeDecl::Cone { .. } => "cone",
            ShapeDecl::Torus { .. } => "torus",
            ShapeDecl::Disk { .. } => "disk",
            ShapeDecl::Triangle { .. } => "triangle",
            ShapeDecl::Mesh { .. } => "mesh",
            ShapeDecl::Revolve { .. } => "revolve",
            ShapeDecl::BezierPatch { .. } => "bezier_patch",
            ShapeDecl::Prism(_) => "prism",
            ShapeDecl::Superellipsoid { .. } => "superellipsoid",
            ShapeDecl::Blob(_) => "blob",
            ShapeDecl::Isosurface(_) => "isosurface",
            ShapeDecl::HeightField(_) => "height_field",
            ShapeDecl::SphereSweep(_) => "sphere_sweep",
            ShapeDecl::Csg(c) => c.op.name(),
        }
    }
}

/// A piecewise Bezier profile in the (radius, height) half-plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// Segments in order; each has 2..=8 control points (degree 1..=7), and each segment starts
    /// where the previous one ended.
    pub segments: Vec<Vec<DVec2>>,
}

/// Most iterations of [`IntersectMethod::Newton`] per start, and most starts (the language's
/// bounds; each ray pays their product).
pub const MAX_NEWTON_ITERATIONS: u32 = 1000;
pub const MAX_NEWTON_STARTS: u32 = 64;

/// How curved surfaces are intersected.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum IntersectMethod {
    /// Root isolation that cannot miss a root (the default).
    #[default]
    Robust,
    /// Newton's method from several starting guesses; it can miss roots (for comparison only).
    /// The renderer maps this enum to `bezier::Solver`.
    Newton { iterations: u32, starts: u32 },
}

/// Lights that are not shapes.
#[derive(Debug, Clone, PartialEq)]
pub enum LightDecl {
    Point {
        position: DVec3,
        /// Radiant intensity (W/sr per channel).
        intensity: Color,
        span: Span,
    },
    Spot {
        position: DVec3,
        /// Unit direction the spot points in.
        direction: DVec3,
        intensity: Color,
        /// Total cone half-angle in degrees: no light outside it.
        cone_angle: f64,
        /// Half-angle in degrees where the falloff to the cone edge starts.
        falloff_angle: f64,
        span: Span,
    },
}

/// A color-valued material parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ColorParam {
    Const(Color),
    Texture(TextureId),
}

/// A scalar material parameter (a texture contributes its luminance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScalarParam {
    Const(f64),
    Texture(TextureId),
}

#[derive(Debug, Clone, PartialEq)]
pub enum Material {
    /// Lambertian reflection.
    Diffuse { albedo: ColorParam },
    /// Perfect specular reflection scaled by `tint`.
    Mirror { tint: ColorParam },
    /// Dielectric: Fresnel reflection and refraction, Beer–Lambert absorption inside; smooth
    /// (`roughness` 0) or frosted (a GGX microfacet surface).
    Glass {
        ior: f64,
        /// Absorption coefficient per unit length inside the medium.
        absorb: ColorParam,
        /// Multiplies both reflection and transmission.
        tint: Color,
        roughness: ScalarParam,
    },
    /// A thin pane or film: reflection and straight transmission, the bounces between its two
    /// faces summed; encloses no medium.
    ThinGlass { ior: f64, tint: Color },
    /// A GGX microfacet lobe (metal-like, tinted by `specular`) over a Lambertian base.
    Glossy {
        albedo: ColorParam,
        specular: ColorParam,
        roughness: ScalarParam,
    },
    /// A metal: Fresnel reflection for the complex index of refraction `eta + i k` per
    /// channel, smooth (`roughness` 0, a perfect mirror) or a GGX microfacet lobe.
    Conductor {
        eta: Color,
        k: Color,
        roughness: f64,
    },
    /// A dielectric coat of index `ior` over a Lambertian base (plastic, varnish); a roughness
    /// of zero is a smooth coat.
    Coated {
        albedo: ColorParam,
        ior: f64,
        roughness: ScalarParam,
    },
    /// Material `a` or `b` at each shading point, `b` with probability `weight` (a number or
    /// a texture's luminance, clamped to [0, 1]): the mix of the two in expectation (see
    /// `materials::eval::choose`). Both come earlier in [`Scene::materials`], so blends nest
    /// without cycles, at most [`MAX_BLEND_DEPTH`] deep.
    Blend {
        a: MaterialId,
        b: MaterialId,
        weight: ScalarParam,
    },
    /// Material `base` with its shading normal perturbed by a bump or normal map
    /// (`materials::bump`); `base` comes earlier in [`Scene::materials`] and counts as a level
    /// of [`MAX_BLEND_DEPTH`].
    Bumped { base: MaterialId, normal: Normal },
}

/// A bump or normal map (`normal { ... }`): how a material's shading normal leans.
#[derive(Debug, Clone, PartialEq)]
pub struct Normal {
    pub kind: NormalKind,
    /// How strongly the height's slope tilts the normal (POV-Ray's bump amount, `bump_size`),
    /// or how far a normal map leans (1 as the map says).
    pub amount: f64,
    /// Object space to the built-in pattern's space (a texture carries its own transform).
    pub transform: DAffine3,
}

/// Where a [`Normal`]'s perturbation comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormalKind {
    /// POV-Ray's normal patterns, heights from noise or from waves.
    Bumps,
    Dents,
    Wrinkles,
    Ripples,
    Waves,
    /// A texture's luminance is the height (any pattern, or an image: `bump_map`).
    Height(TextureId),
    /// A texture's colour is a tangent-space normal (`normal_map`): x along the shape's u,
    /// y along its normal crossed with u, z along its normal, each from `2 c - 1`.
    Map(TextureId),
}

/// The deepest blends nest (a blend of blends of ...): each level is one hash and one lookup
/// per hit.
pub const MAX_BLEND_DEPTH: u32 = 16;

impl Scene {
    /// How deep the blends under each material nest (0: not a blend), in one pass over
    /// [`Scene::materials`]; `None` for a blend whose parts do not come before it (which could
    /// loop) or are not valid themselves.
    pub fn blend_depths(&self) -> Vec<Option<u32>> {
        let mut depths: Vec<Option<u32>> = Vec::with_capacity(self.materials.len());
        for (i, m) in self.materials.iter().enumerate() {
            let d = match m {
                Material::Blend { a, b, .. } => {
                    let part = |id: MaterialId| {
                        let k = id.0 as usize;
                        if k < i { depths[k] } else { None }
                    };
                    part(*a).zip(part(*b)).map(|(x, y)| 1 + x.max(y))
                }
                Material::Bumped { base, .. } => {
                    let k = base.0 as usize;
                    if k < i {
                        depths[k].map(|d| d + 1)
                    } else {
                        None
                    }
                }
                _ => Some(0),
            };
            depths.push(d);
        }
        depths
    }
}

/// A texture: a pattern evaluated at mapped coordinates.
#[derive(Debug, Clone)]
pub struct Texture {
    pub pattern: Pattern,
    pub mapping: Mapping,
    /// Texture-space transform applied to the mapped coordinates (the inverse of the
    /// `scale`/`rotate`/`translate` the file gave, so that `scale 2` makes the pattern larger).
    pub transform: DAffine3,
    pub span: Span,
}

/// Where a texture's coordinates come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mapping {
    /// Solid texturing: the object-space point (default for procedural patterns).
    #[default]
    Solid,
    /// The shape's own (u, v) (default for image textures).
    Uv,
    Planar,
    Spherical,
    Cylindrical,
}

/// Wrapping of image coordinates outside [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wrap {
    #[default]
    Repeat,
    Clamp,
    Mirror,
}

/// A piecewise-linear color map over [0, 1]: `(position, color)` sorted by position.
#[derive(Debug, Clone, PartialEq)]
pub struct ColorMap(pub Vec<(f64, Color)>);

#[derive(Debug, Clone)]
pub enum Pattern {
    Checker {
        a: Color,
        b: Color,
    },
    Stripes {
        a: Color,
        b: Color,
    },
    Gradient {
        direction: DVec3,
        map: ColorMap,
    },
    Noise {
        map: ColorMap,
        octaves: u32,
    },
    Marble {
        map: ColorMap,
        turbulence: f64,
        octaves: u32,
    },
    Wood {
        map: ColorMap,
        turbulence: f64,
        octaves: u32,
    },
    Brick {
        brick: Color,
        mortar: Color,
        size: DVec3,
        mortar_width: f64,
    },
    Image {
        image: Arc<ImageData>,
        wrap: Wrap,
        /// Bilinear filtering (otherwise nearest texel).
        bilinear: bool,
    },
}
