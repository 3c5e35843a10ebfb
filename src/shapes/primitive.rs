//! Enum dispatch over the renderer's shapes (no virtual call for the common ones).

use glam::Vec2;

use super::{
    AreaSample, Shape, cylinder::Cylinder, disk::Disk, plane::Plane, quad::Quad, sphere::Sphere,
    triangle::Triangle,
};
use crate::geometry::{Aabb, Hit, Ray};

pub enum AnyShape {
    Sphere(Sphere),
    Quad(Quad),
    Disk(Disk),
    Cylinder(Cylinder),
    Triangle(Triangle),
    Plane(Plane),
    Other(Box<dyn Shape>),
}

macro_rules! dispatch {
    ($self:ident, $s:ident => $e:expr) => {
        match $self {
            AnyShape::Sphere($s) => $e,
            AnyShape::Quad($s) => $e,
            AnyShape::Disk($s) => $e,
            AnyShape::Cylinder($s) => $e,
            AnyShape::Triangle($s) => $e,
            AnyShape::Plane($s) => $e,
            AnyShape::Other($s) => $e,
        }
    };
}

impl Shape for AnyShape {
    fn bounds(&self) -> Aabb {
        dispatch!(self, s => s.bounds())
    }
    #[inline]
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        dispatch!(self, s => s.intersect(ray, t_min, t_max))
    }
    #[inline]
    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        dispatch!(self, s => s.occluded(ray, t_min, t_max))
    }
    fn area(&self) -> f32 {
        dispatch!(self, s => s.area())
    }
    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        dispatch!(self, s => s.sample(u))
    }
}
