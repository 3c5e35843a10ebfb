use glam::{Vec2, Vec3A};

/// A ray `o + t d`. `d` need not be unit length; `t` is in units of `d`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub o: Vec3A,
    pub d: Vec3A,
}

impl Ray {
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        Self { o, d }
    }

    pub fn at(&self, t: f32) -> Vec3A {
        self.o + self.d * t
    }
}

/// A ray–surface intersection, in the space of the ray that produced it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Hit point.
    pub p: Vec3A,
    /// Unit geometric normal (the shape's outward side; not flipped toward the ray).
    pub n: Vec3A,
    /// Unit shading normal (interpolated / from the exact surface), same hemisphere as `n`.
    pub ns: Vec3A,
    /// Surface (u, v) texture coordinates.
    pub uv: Vec2,
    /// Partial derivative of the surface point along u (tangent), not necessarily unit.
    pub dpdu: Vec3A,
}
