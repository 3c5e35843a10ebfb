//! Surface of revolution of a Bezier profile around the y axis (scene glue).
//! Placeholder: the robust intersector replaces this file.

use glam::Vec2;

use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::{IntersectMethod, Profile};

pub struct Revolve {
    bounds: Aabb,
}

impl Revolve {
    /// Builds the renderer shape; the error is a message fit for a diagnostic.
    pub fn new(
        profile: &Profile,
        _sweep: Option<(f64, f64)>,
        _method: IntersectMethod,
    ) -> Result<Self, String> {
        let r = profile
            .segments
            .iter()
            .flatten()
            .map(|p| p.x.abs())
            .fold(0.0, f64::max) as f32;
        let (lo, hi) = profile
            .segments
            .iter()
            .flatten()
            .fold((f64::MAX, f64::MIN), |(lo, hi), p| {
                (lo.min(p.y), hi.max(p.y))
            });
        Ok(Self {
            bounds: Aabb::new(
                glam::Vec3A::new(-r, lo as f32, -r),
                glam::Vec3A::new(r, hi as f32, r),
            ),
        })
    }
}

impl Shape for Revolve {
    fn bounds(&self) -> Aabb {
        self.bounds
    }
    fn intersect(&self, _ray: &Ray, _t_min: f32, _t_max: f32) -> Option<Hit> {
        None
    }
    fn area(&self) -> f32 {
        0.0
    }
    fn sample(&self, _u: Vec2) -> Option<AreaSample> {
        None
    }
}
