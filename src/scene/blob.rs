//! POV-Ray's `blob` and `isosurface` as the renderer takes them: shapes given by a field (a sum
//! of component densities, a user function) and a threshold.

use std::sync::Arc;

use glam::{DAffine3, DVec3};

use super::Function;

/// Most components one blob may have: its per-component hierarchy and data hold about 200
/// bytes each (50 MB at this bound).
pub const MAX_BLOB_COMPONENTS: usize = 1 << 18;

/// One component of a blob: a sphere (`a == b`) or a capsule around the segment `a`–`b`, of
/// radius `radius`, placed in the blob's space by `transform`. Its density at distance `d` from
/// the centre (segment) is `strength * (1 - (d / radius)^2)^2` within the radius, 0 beyond
/// (POV-Ray's field function).
#[derive(Debug, Clone, PartialEq)]
pub struct BlobComponent {
    pub a: DVec3,
    pub b: DVec3,
    pub radius: f64,
    pub strength: f64,
    /// From the component's own space to the blob's (the component's transforms).
    pub transform: DAffine3,
}

/// POV-Ray's `blob`: the points where the sum of the components' densities exceeds
/// `threshold` (> 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Blob {
    pub threshold: f64,
    pub components: Vec<BlobComponent>,
}

impl Blob {
    /// Why the blob cannot be rendered, if it cannot: the checks every blob passes (the
    /// evaluator reports them at their spans first; this guards the library's callers).
    pub fn check(&self) -> Result<(), String> {
        if !(self.threshold > 0.0 && self.threshold.is_finite()) {
            return Err(format!(
                "a blob's threshold must be a positive number, got {}",
                self.threshold
            ));
        }
        if self.components.is_empty() || self.components.len() > MAX_BLOB_COMPONENTS {
            return Err(format!(
                "a blob needs 1 to {MAX_BLOB_COMPONENTS} components, got {}",
                self.components.len()
            ));
        }
        for (i, c) in self.components.iter().enumerate() {
            let t = &c.transform;
            let finite = c.a.is_finite()
                && c.b.is_finite()
                && t.matrix3.is_finite()
                && t.translation.is_finite();
            if !(finite && c.radius > 0.0 && c.radius.is_finite() && c.strength.is_finite()) {
                return Err(format!(
                    "the blob's component {} is not finite or has no positive radius",
                    i + 1
                ));
            }
            if t.matrix3.determinant().abs() < 1e-300 {
                return Err(format!(
                    "the blob's component {} has a singular transform",
                    i + 1
                ));
            }
        }
        if !self.components.iter().any(|c| c.strength > 0.0) {
            return Err("a blob needs a component of positive strength".into());
        }
        Ok(())
    }
}

/// The region an isosurface is looked for in (POV-Ray's `contained_by`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Container {
    Box { min: DVec3, max: DVec3 },
    Sphere { center: DVec3, radius: f64 },
}

impl Container {
    /// The container's box.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match *self {
            Container::Box { min, max } => (min.min(max), min.max(max)),
            Container::Sphere { center, radius } => {
                (center - DVec3::splat(radius), center + DVec3::splat(radius))
            }
        }
    }

    /// Why the container holds no volume, if it holds none.
    pub fn check(&self) -> Result<(), String> {
        let (lo, hi) = self.bounds();
        if !(lo.is_finite() && hi.is_finite()) {
            return Err("the isosurface's container is not finite".into());
        }
        if (hi - lo).min_element() <= 0.0 {
            return Err("the isosurface's container holds no volume".into());
        }
        Ok(())
    }
}

/// An isosurface's default accuracy, relative to its container's diagonal.
pub const DEFAULT_ACCURACY: f64 = 1e-6;

/// POV-Ray's `isosurface`: the points of `container` where `function(x, y, z) < threshold`
/// (the surface where it equals the threshold), closed by the container's walls where the
/// function is below the threshold there, unless `open`.
#[derive(Debug, Clone, PartialEq)]
pub struct Isosurface {
    pub function: Arc<Function>,
    pub threshold: f64,
    pub container: Container,
    pub open: bool,
    /// Stretches of a ray narrower than this (in the function's units) are not split further:
    /// features thinner than it may be missed, none thicker.
    pub accuracy: f64,
}

impl Isosurface {
    /// Why the isosurface cannot be rendered, if it cannot.
    pub fn check(&self) -> Result<(), String> {
        self.container.check()?;
        if !self.threshold.is_finite() {
            return Err(format!(
                "an isosurface's threshold must be finite, got {}",
                self.threshold
            ));
        }
        if !(self.accuracy > 0.0 && self.accuracy.is_finite()) {
            return Err(format!(
                "an isosurface's accuracy must be a positive number, got {}",
                self.accuracy
            ));
        }
        if self.function.params() != 3 {
            return Err(format!(
                "an isosurface's function takes x, y, z, not {} parameters",
                self.function.params()
            ));
        }
        Ok(())
    }
}
