//! Bicubic Bezier patch (scene glue).
//! Placeholder: the robust intersector replaces this file.

use glam::{DVec3, Vec2};

use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::IntersectMethod;

pub struct BezierPatch {
    bounds: Aabb,
}

impl BezierPatch {
    /// Builds the renderer shape; the error is a message fit for a diagnostic.
    pub fn new(points: &[DVec3; 16], _method: IntersectMethod) -> Result<Self, String> {
        Ok(Self {
            bounds: Aabb::from_points(points.iter().map(|p| p.as_vec3a())),
        })
    }
}

impl Shape for BezierPatch {
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
