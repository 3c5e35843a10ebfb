//! Renderer-side shapes: intersection, bounds and area sampling.
//!
//! Each shape implements [`Shape`] in its own space; the renderer wraps shapes that carry a
//! non-trivial transform. Numerical cores that are more than a few lines (the Bezier root finder)
//! live in their own modules with their own tests.

use glam::{Vec2, Vec3A};

use crate::bezier::Solver;
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::IntersectMethod;

/// A point sampled uniformly by area on a shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaSample {
    pub p: Vec3A,
    /// Unit geometric normal at `p` (outward side).
    pub n: Vec3A,
    /// Probability density with respect to area (1 / area for uniform sampling).
    pub pdf: f32,
}

/// A point on a shape sampled for a receiver by the directions it subtends there
/// ([`sphere::Sphere::sample_toward`], [`quad::Quad::sample_toward`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidAngleSample {
    pub p: Vec3A,
    /// Unit geometric normal at `p` (outward side).
    pub n: Vec3A,
    /// Unit direction from the receiver to `p`.
    pub wi: Vec3A,
    /// Probability density with respect to solid angle at the receiver.
    pub pdf: f32,
}

/// The uniform-area density `1 / area` at the point `pl` (normal `nl`) as a density per solid
/// angle at `p`; 0 where the conversion is undefined (grazing or coincident points).
#[inline]
pub(crate) fn area_pdf_to_solid_angle(p: Vec3A, pl: Vec3A, nl: Vec3A, area: f32) -> f32 {
    let d = pl - p;
    let d2 = d.length_squared();
    let cos = nl.dot(d).abs() / d2.sqrt();
    if !(cos > 0.0 && d2 > 0.0) {
        return 0.0;
    }
    d2 / (cos * area)
}

/// An area sample `pl` (normal `nl`, uniform over `area`) seen from `p`, with its density per
/// solid angle; `None` where it is undefined.
#[inline]
pub(crate) fn area_to_solid_angle(
    p: Vec3A,
    pl: Vec3A,
    nl: Vec3A,
    area: f32,
) -> Option<SolidAngleSample> {
    let d = pl - p;
    let d2 = d.length_squared();
    if d2.is_nan() || d2 <= 0.0 {
        return None;
    }
    let wi = d / d2.sqrt();
    let cos = nl.dot(wi).abs();
    if cos.is_nan() || cos <= 0.0 {
        return None;
    }
    let pdf = d2 / (cos * area);
    pdf.is_finite().then_some(SolidAngleSample {
        p: pl,
        n: nl,
        wi,
        pdf,
    })
}

/// What a shape keeps of a hit whose surface data it computes later ([`Shape::complete`]):
/// two numbers and an index for the shape's own use (a revolve: the hit's ray parameter along
/// the unit direction, its profile parameter and its part).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Deferred {
    pub a: f64,
    pub b: f64,
    pub k: u32,
}

/// The result of [`Shape::intersect_boxed`].
#[derive(Debug, Clone, Copy)]
pub enum BoxedHit {
    Full(Hit),
    /// The hit's `t` and what [`Shape::complete`] needs for the rest.
    Deferred(f32, Deferred),
}

pub trait Shape: Send + Sync {
    /// Bounds in the same space as the rays it is given.
    fn bounds(&self) -> Aabb;
    /// Nearest intersection with `t_min < t < t_max`.
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit>;
    /// Whether anything is hit with `t_min < t < t_max` (shadow rays); may be faster.
    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.intersect(ray, t_min, t_max).is_some()
    }
    /// [`Shape::intersect`] as a [`BoxedHit`]: shapes whose surface data is costly may give
    /// only the hit's `t` and a [`Deferred`] record, from which [`Shape::complete`] builds the
    /// hit later (the BVH does so once, for the nearest hit). The default gives the full hit.
    fn intersect_boxed(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<BoxedHit> {
        self.intersect(ray, t_min, t_max).map(BoxedHit::Full)
    }
    /// The hit for a [`BoxedHit::Deferred`] this shape returned for `ray`: what
    /// [`Shape::intersect`] gives, except that `uv: false` lets the shape leave `uv` NaN (for
    /// primitives whose material reads no texture). Shapes that never defer need not
    /// implement it: the default intersects again just before `t`.
    fn complete(&self, ray: &Ray, t: f32, _rec: Deferred, _uv: bool) -> Hit {
        self.intersect(ray, t * (1.0 - 1e-6), f32::INFINITY)
            .unwrap_or(Hit {
                t,
                p: ray.at(t),
                n: Vec3A::Z,
                ns: Vec3A::Z,
                uv: Vec2::ZERO,
                dpdu: Vec3A::X,
            })
    }
    /// Surface area (for emissive shapes).
    fn area(&self) -> f32;
    /// A uniformly distributed point on the surface, from `u` in [0,1)^2.
    /// Shapes that cannot be sampled (infinite planes) return `None`.
    fn sample(&self, u: Vec2) -> Option<AreaSample>;
}

/// A shape whose intersection splits into a cheap search for the hit distance ([`hit_t`]) and
/// the surface data at that distance ([`hit_at`]). Every `SplitShape` is a [`Shape`]: the
/// intersection is `hit_t` followed by `hit_at`, and a shadow ray needs only `hit_t`. The BVH
/// uses the split to build the surface data once, for the nearest hit only.
///
/// [`hit_t`]: SplitShape::hit_t
/// [`hit_at`]: SplitShape::hit_at
pub trait SplitShape: Send + Sync {
    /// Nearest `t` with `t_min < t < t_max`, without the surface data.
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32>;
    /// The full surface data at ray parameter `t` (a value [`SplitShape::hit_t`] returned).
    fn hit_at(&self, ray: &Ray, t: f32) -> Hit;
    /// See [`Shape::bounds`].
    fn bounds(&self) -> Aabb;
    /// See [`Shape::area`].
    fn area(&self) -> f32;
    /// See [`Shape::sample`].
    fn sample(&self, u: Vec2) -> Option<AreaSample>;
}

impl<S: SplitShape> Shape for S {
    #[inline]
    fn bounds(&self) -> Aabb {
        SplitShape::bounds(self)
    }

    #[inline]
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let t = self.hit_t(ray, t_min, t_max)?;
        Some(self.hit_at(ray, t))
    }

    #[inline]
    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.hit_t(ray, t_min, t_max).is_some()
    }

    #[inline]
    fn area(&self) -> f32 {
        SplitShape::area(self)
    }

    #[inline]
    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        SplitShape::sample(self, u)
    }
}

/// Helpers of the shapes' sampling tests.
#[cfg(test)]
pub(crate) mod sampling_tests {
    use super::Shape;
    use crate::geometry::Ray;
    use crate::sampling::{Rng, uniform_sphere};
    use glam::Vec3A;

    /// Mean and standard error of `n` draws of `f`, in f64.
    pub(crate) fn mean_se(n: usize, mut f: impl FnMut() -> f64) -> (f64, f64) {
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let v = f();
            s += v;
            s2 += v * v;
        }
        let mean = s / n as f64;
        let var = (s2 / n as f64 - mean * mean).max(0.0);
        (mean, (var / n as f64).sqrt())
    }

    /// Asserts a Monte Carlo mean `got` (standard error `se`) is `want` within five standard
    /// errors plus `rel` of `want` (f32 rounding).
    pub(crate) fn assert_estimate(what: &str, (got, se): (f64, f64), want: f64, rel: f64) {
        let tol = 5.0 * se + rel * want;
        assert!(
            (got - want).abs() <= tol,
            "{what}: {got} vs {want} (tolerance {tol})"
        );
    }

    /// Asserts that `pdf(p, hit point, hit normal)` integrates to one over the directions from
    /// `p` that hit `shape` (uniform directions, 400 000 of them): a normalized density, as MIS
    /// needs when a BSDF sample hits the light.
    pub(crate) fn assert_density_integrates_to_one(
        shape: &dyn Shape,
        p: Vec3A,
        pdf: impl Fn(Vec3A, Vec3A, Vec3A) -> f32,
        rng: &mut Rng,
    ) {
        let (got, se) = mean_se(400_000, || {
            let d = uniform_sphere(rng.vec2());
            shape
                .intersect(&Ray::new(p, d), 0.0, f32::INFINITY)
                .map_or(0.0, |h| {
                    f64::from(pdf(p, h.p, h.n) * 4.0 * std::f32::consts::PI)
                })
        });
        assert!((got - 1.0).abs() <= 5.0 * se + 1e-3, "{p}: {got} (se {se})");
    }
}

/// The f64 range of ray parameters whose f32 rounding lies strictly inside `(t_min, t_max)`:
/// an f64 search over it never returns a hit that rounds onto `t_min` (the hit a CSG or a
/// bounce just left) and so hides the hits beyond it.
pub(crate) fn f64_range(t_min: f32, t_max: f32) -> (f64, f64) {
    let lo = 0.5 * (f64::from(t_min) + f64::from(t_min.next_up()));
    let hi = 0.5 * (f64::from(t_max) + f64::from(t_max.next_down()));
    (lo, if t_max.is_finite() { hi } else { f64::INFINITY })
}

/// The root finder of the curved shapes for the scene's choice of method.
pub(crate) fn solver_of(method: IntersectMethod) -> Solver {
    match method {
        IntersectMethod::Robust => Solver::Robust,
        IntersectMethod::Newton { iterations, starts } => Solver::Newton { iterations, starts },
    }
}

pub mod blob;
pub mod cone;
pub mod csg;
pub mod cuboid;
pub mod cylinder;
pub mod disk;
pub mod height_field;
pub mod isosurface;
pub mod mesh;
pub mod patch;
pub mod plane;
pub mod primitive;
pub mod prism;
pub mod quad;
pub mod revolve;
pub mod sphere;
pub mod sphere_sweep;
pub mod superellipsoid;
pub mod torus;
pub mod transformed;
pub mod triangle;
