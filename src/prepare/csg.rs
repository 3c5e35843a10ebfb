//! Baking a scene CSG object into one renderer primitive: every closed shape below it becomes a
//! leaf of world-space surfaces (transforms composed from the root down), with outward normals
//! and a primitive id of its own, so that a hit reports the material and texture space of the
//! shape it is on.

use glam::{DAffine3, DVec2};

use super::shapes::build_shapes;
use crate::scene::{self, MaterialId, MeshData, Object, Profile};
use crate::shapes::csg::{Csg, CsgLeaf, CsgNode};
use crate::shapes::primitive::AnyShape;

/// A leaf's material and object-to-world transform (for its texture lookups).
pub(super) struct LeafPart {
    pub material: MaterialId,
    pub transform: DAffine3,
}

/// The primitive of CSG object `obj`; its leaves get ids `first_id`, `first_id + 1`, ... in the
/// order of the returned parts.
pub(super) fn build_csg(obj: &Object, first_id: u32) -> Result<(AnyShape, Vec<LeafPart>), String> {
    let mut parts = Vec::new();
    let root = node(obj, &DAffine3::IDENTITY, first_id, &mut parts)?;
    Ok((AnyShape::Csg(Box::new(Csg::new(root)?)), parts))
}

fn node(
    obj: &Object,
    parent: &DAffine3,
    first_id: u32,
    parts: &mut Vec<LeafPart>,
) -> Result<CsgNode, String> {
    let transform = *parent * obj.transform;
    if let scene::Shape::Csg(csg) = &obj.shape {
        let kids = csg
            .children
            .iter()
            .map(|c| node(c, &transform, first_id, parts))
            .collect::<Result<Vec<_>, _>>()?;
        return Ok(CsgNode::Op(csg.op, kids));
    }
    if let Some(why) = scene::why_open(&obj.shape) {
        return Err(format!(
            "a {} in a CSG must be closed: {why}",
            obj.shape.kind()
        ));
    }
    let leaf = Object {
        shape: obj.shape.clone(),
        transform,
        material: obj.material,
        emission: None,
        span: obj.span,
    };
    let shapes = build_shapes(&leaf)?;
    let flip = match &obj.shape {
        scene::Shape::Mesh { mesh } => signed_volume(mesh) < 0.0,
        scene::Shape::Revolve { profile, .. } => profile_area(profile) < 0.0,
        _ => false,
    };
    let id = first_id + parts.len() as u32;
    parts.push(LeafPart {
        material: obj.material,
        transform,
    });
    Ok(CsgNode::Leaf(CsgLeaf { shapes, flip, id }))
}

/// Six times the volume a closed mesh encloses, positive when its triangles wind
/// counter-clockwise seen from outside (normals outward).
fn signed_volume(mesh: &MeshData) -> f64 {
    let p = |i: u32| mesh.positions.get(i as usize).copied().unwrap_or_default();
    mesh.indices
        .iter()
        .map(|t| p(t[0]).dot(p(t[1]).cross(p(t[2]))))
        .sum()
}

/// Twice the signed area the profile encloses in the (radius, height) plane, closed along the
/// axis or onto itself: positive when it runs counter-clockwise, which puts the revolve's
/// normals (to the right of the profile's direction) outside.
fn profile_area(profile: &Profile) -> f64 {
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
