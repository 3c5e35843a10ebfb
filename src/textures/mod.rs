//! Texture evaluation: patterns, mappings, image lookup.
//!
//! The renderer calls [`evaluate`] with a [`TexCoord`] built at a surface hit; everything a
//! texture needs to know about the hit is in it.

use glam::{Vec2, Vec3A};

use crate::scene::{Pattern, Texture};

/// Where a texture is looked up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TexCoord {
    /// The hit point in the object's own space (before its transform).
    pub p: Vec3A,
    /// Unit shading normal in object space.
    pub n: Vec3A,
    /// The shape's surface (u, v).
    pub uv: Vec2,
}

/// The linear RGB value of `texture` at `at`.
pub fn evaluate(texture: &Texture, at: &TexCoord) -> Vec3A {
    // Placeholder until the textures module lands: a solid checker, mean color elsewhere.
    let p = texture.transform.transform_point3(at.p.as_dvec3());
    match &texture.pattern {
        Pattern::Checker { a, b } => {
            let s = p.x.floor() + p.y.floor() + p.z.floor();
            if s.rem_euclid(2.0) < 1.0 {
                a.as_vec3a()
            } else {
                b.as_vec3a()
            }
        }
        _ => Vec3A::splat(0.5),
    }
}
