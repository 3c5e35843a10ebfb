//! Data loaded from files a scene names: images and OBJ meshes.
//!
//! Loading happens during evaluation, only for assets an object actually uses, so that a missing
//! file is reported at the span of its name and an unused one is never read.

use std::path::PathBuf;

use glam::{DVec2, DVec3};

/// How the stored values of an image are to be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorSpace {
    /// 8-bit color images: decode the sRGB transfer curve.
    Srgb,
    /// Data images and float formats (EXR, HDR): use the values as they are.
    Linear,
}

/// A decoded image in linear RGB, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageData {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

/// A triangle mesh as read from an OBJ file (all groups merged).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshData {
    pub path: PathBuf,
    pub positions: Vec<DVec3>,
    /// Per-vertex normals, same length as `positions`, or empty.
    pub normals: Vec<DVec3>,
    /// Per-vertex texture coordinates, same length as `positions`, or empty.
    pub uvs: Vec<DVec2>,
    /// Three vertex indices per triangle.
    pub indices: Vec<[u32; 3]>,
}
