//! Baking a scene CSG object into one renderer primitive: every closed shape below it becomes a
//! leaf of world-space surfaces (transforms composed from the root down), with outward normals
//! and a primitive id of its own, so that a hit reports the material and texture space of the
//! shape it is on.

use glam::DAffine3;

use super::orient::{profile_area, signed_volume};
use super::shapes::build_shapes;
use crate::scene::{self, MaterialId, Object};
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
