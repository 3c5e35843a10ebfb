//! Closed glass surfaces face out: a closed mesh whose triangles wind inward (negative signed
//! volume) or a closed revolve whose profile runs clockwise in the (radius, height) plane has
//! its normals pointing in, and glass reads "entering" and "leaving" from the normal's side, so
//! such glass would render inside out. Top-level glass objects of these two kinds are turned
//! outward before they are built (the mesh's triangles rewound, the profile run backwards); the
//! shapes of a CSG object are turned by the CSG's own leaves. Only glass: no other material
//! depends on the side a normal points to, and an emitting surface's winding says which side
//! emits. The check costs a closed-mesh test (one pass over the edges) per glass mesh of at
//! most 2^20 triangles; a larger one keeps its winding.

use std::collections::HashMap;
use std::sync::Arc;

use glam::DVec2;

use crate::scene::{self, MeshData, Object, Profile, Scene, ShapeDecl};

/// Six times the volume a closed mesh encloses, positive when its triangles wind
/// counter-clockwise seen from outside (normals outward).
pub(super) fn signed_volume(mesh: &MeshData) -> f64 {
    let p = |i: u32| mesh.positions.get(i as usize).copied().unwrap_or_default();
    mesh.indices
        .iter()
        .map(|t| p(t[0]).dot(p(t[1]).cross(p(t[2]))))
        .sum()
}

/// Twice the signed area the profile encloses in the (radius, height) plane, closed along the
/// axis or onto itself: positive when it runs counter-clockwise, which puts the revolve's
/// normals (to the right of the profile's direction) outside.
pub(super) fn profile_area(profile: &Profile) -> f64 {
    const STEPS: usize = 64;
    let mut pts = Vec::new();
    for seg in &profile.segments {
        for k in 0..STEPS {
            pts.push(de_casteljau(seg, k as f64 / STEPS as f64));
        }
    }
    if let Some(last) = profile.segments.last().and_then(|s| s.last()) {
        pts.push(*last);
    }
    let n = pts.len();
    (0..n).map(|i| pts[i].perp_dot(pts[(i + 1) % n])).sum()
}

fn de_casteljau(points: &[DVec2], s: f64) -> DVec2 {
    let mut p = points.to_vec();
    for k in (1..p.len()).rev() {
        for i in 0..k {
            p[i] = p[i].lerp(p[i + 1], s);
        }
    }
    p.first().copied().unwrap_or_default()
}

/// Which glass objects of a scene face in, each mesh tested once.
#[derive(Default)]
pub(super) struct Orientation {
    inward_meshes: HashMap<usize, bool>,
    /// Per material, whether it is a glass or blends one (filled on first use).
    glass: Option<Vec<bool>>,
}

impl Orientation {
    /// Whether `obj`'s surface is closed glass whose normals point in (a mesh: its triangles
    /// are to be rewound; a revolve: see [`outward_revolve`]).
    pub(super) fn faces_in(&mut self, scene: &Scene, obj: &Object) -> bool {
        let glass = self
            .glass
            .get_or_insert_with(|| crate::materials::eval::glass_parts(scene))
            .get(obj.material.0 as usize)
            .copied()
            .unwrap_or(false);
        if !glass || obj.emission.is_some() {
            return false;
        }
        match &obj.shape {
            ShapeDecl::Mesh { mesh } => *self
                .inward_meshes
                .entry(Arc::as_ptr(mesh) as usize)
                .or_insert_with(|| inward_mesh(mesh)),
            ShapeDecl::Revolve { profile, .. } => {
                scene::why_open(&obj.shape).is_none() && profile_area(profile) < 0.0
            }
            _ => false,
        }
    }
}

/// Largest glass mesh whose orientation is checked: the closed-mesh test keeps a map of every
/// edge (about 100 bytes per triangle, which the memory estimate does not count), so a larger
/// mesh keeps its file's winding.
const MAX_CHECKED_TRIANGLES: usize = 1 << 20;

fn inward_mesh(mesh: &Arc<MeshData>) -> bool {
    if mesh.indices.len() > MAX_CHECKED_TRIANGLES {
        return false;
    }
    let shape = ShapeDecl::Mesh { mesh: mesh.clone() };
    scene::why_open(&shape).is_none() && signed_volume(mesh) < 0.0
}

/// The revolve `obj` with its profile run backwards (the same surface, normals reversed;
/// its texture `v` runs the other way).
pub(super) fn outward_revolve(obj: &Object) -> Option<Object> {
    let ShapeDecl::Revolve {
        profile,
        sweep,
        method,
    } = &obj.shape
    else {
        return None;
    };
    let segments = profile
        .segments
        .iter()
        .rev()
        .map(|s| s.iter().rev().copied().collect())
        .collect();
    Some(Object {
        shape: ShapeDecl::Revolve {
            profile: Profile { segments },
            sweep: *sweep,
            method: *method,
        },
        transform: obj.transform,
        material: obj.material,
        emission: obj.emission,
        span: obj.span,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_orientation() {
        // Up the outside from the bottom of the axis to its top: counter-clockwise.
        let out = Profile {
            segments: vec![vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(1.0, 0.0),
                DVec2::new(1.0, 1.0),
                DVec2::new(0.0, 1.0),
            ]],
        };
        assert!(profile_area(&out) > 0.0);
        let mut back = out.clone();
        back.segments[0].reverse();
        assert!(profile_area(&back) < 0.0);
    }
}
