//! Baking a scene CSG object into one renderer primitive: every closed shape below it becomes a
//! leaf of world-space surfaces (transforms composed from the root down), with outward normals
//! and a primitive id of its own, so that a hit reports the material and texture space of the
//! shape it is on.
//!
//! Before anything is built, each CSG object's cost per ray is estimated from counts
//! ([`ray_cost`]) and refused past [`MAX_CSG_RAY_COST`]: the renderer tests a CSG's surfaces
//! one by one, so a merge of many placements of a large mesh would make every ray into it
//! test millions of triangles.

use glam::DAffine3;

use super::budget::primitives;
use super::orient::{profile_area, signed_volume};
use super::shapes::{Isosurfaces, build_shapes};
use crate::diag::Diagnostic;
use crate::scene::{self, MAX_CSG_DEPTH, MaterialId, Object, Scene};
use crate::shapes::csg::{Csg, CsgLeaf, CsgNode};
use crate::shapes::primitive::AnyShape;

/// Most work one ray into a CSG object may cost, in tests of one surface ([`ray_cost`]). A
/// test of a sphere or a triangle takes some 10 ns, so this is about 10 ms a ray at worst:
/// 4 096 spheres (the most a CSG holds) cost 127 000, a mesh of 300 000 triangles 900 000.
pub const MAX_CSG_RAY_COST: u64 = 1 << 20;

/// The most work one ray into CSG `csg` may cost, in tests of one surface, from counts alone
/// (nothing is built): a ray tests each shape's surfaces (a box's six, a mesh's triangles)
/// once at the start and again after each of its hits (taken as two: in and out), and
/// classifies each hit with a heap step and a test per level of the tree.
pub fn ray_cost(csg: &scene::Csg) -> u64 {
    let leaves = csg.leaves();
    let count = leaves.len() as u64;
    let per_hit = csg.depth(MAX_CSG_DEPTH) as u64 + u64::from(u64::BITS - count.leading_zeros());
    leaves
        .iter()
        .map(|o| {
            primitives(&o.shape)
                .saturating_mul(3)
                .saturating_add(2 * per_hit)
        })
        .fold(0u64, u64::saturating_add)
}

/// Refuses a CSG object whose [`ray_cost`] passes [`MAX_CSG_RAY_COST`], at its span.
pub(super) fn check_costs(scene: &Scene) -> Result<(), Diagnostic> {
    for obj in &scene.objects {
        let scene::ShapeDecl::Csg(csg) = &obj.shape else {
            continue;
        };
        let cost = ray_cost(csg);
        if cost <= MAX_CSG_RAY_COST {
            continue;
        }
        let leaves = csg.leaves();
        let surfaces = leaves
            .iter()
            .map(|o| primitives(&o.shape))
            .fold(0u64, u64::saturating_add);
        return Err(Diagnostic::error(
            obj.span,
            format!(
                "this {} would cost up to {cost} surface tests for every ray that meets it \
                 ({} shapes with {surfaces} surfaces), more than the {MAX_CSG_RAY_COST} a CSG \
                 may cost",
                csg.op.name(),
                leaves.len(),
            ),
        )
        .with_label("too costly to intersect")
        .with_help(
            "a CSG tests the surfaces of its shapes one by one (every triangle of a mesh): use \
             `union` where inner surfaces may stay (its shapes go into the scene's acceleration \
             structure), split the object into smaller CSGs, or use meshes with fewer triangles",
        ));
    }
    Ok(())
}

/// A leaf's material and object-to-world transform (for its texture lookups).
pub(super) struct LeafPart {
    pub material: MaterialId,
    pub transform: DAffine3,
}

/// The primitive of CSG object `obj`; its leaves get ids `first_id`, `first_id + 1`, ... in the
/// order of the returned parts.
/// Its isosurfaces go into `isos`.
pub(super) fn build_csg(
    obj: &Object,
    first_id: u32,
    isos: &mut Isosurfaces,
) -> Result<(AnyShape, Vec<LeafPart>), String> {
    let mut parts = Vec::new();
    let root = node(obj, &DAffine3::IDENTITY, first_id, &mut parts, isos)?;
    Ok((AnyShape::Csg(Box::new(Csg::new(root)?)), parts))
}

fn node(
    obj: &Object,
    parent: &DAffine3,
    first_id: u32,
    parts: &mut Vec<LeafPart>,
    isos: &mut Isosurfaces,
) -> Result<CsgNode, String> {
    let transform = *parent * obj.transform;
    if let scene::ShapeDecl::Csg(csg) = &obj.shape {
        let kids = csg
            .children
            .iter()
            .map(|c| node(c, &transform, first_id, parts, isos))
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
    let shapes = build_shapes(&leaf, isos)?;
    let flip = match &obj.shape {
        scene::ShapeDecl::Mesh { mesh } => signed_volume(mesh) < 0.0,
        scene::ShapeDecl::Revolve { profile, .. } => profile_area(profile) < 0.0,
        _ => false,
    };
    let id = first_id + parts.len() as u32;
    parts.push(LeafPart {
        material: obj.material,
        transform,
    });
    Ok(CsgNode::Leaf(CsgLeaf { shapes, flip, id }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{MeshData, ShapeDecl};
    use std::sync::Arc;

    fn scene(text: &str) -> Scene {
        let l = crate::eval::load_source("cost.scn", text, &Default::default());
        l.scene.expect("a valid scene")
    }

    fn cost_of(s: &Scene) -> u64 {
        match &s.objects[0].shape {
            ShapeDecl::Csg(c) => ray_cost(c),
            _ => panic!("not a CSG"),
        }
    }

    /// The estimate counts each shape's surfaces three times and two classified hits per
    /// shape, each a step per level and per bit of the shape count: 4 096 spheres in one
    /// operation cost 4 096 x (3 + 2 x (1 + 13)); a box's six faces count six; each level of
    /// nesting adds two steps per shape.
    #[test]
    fn the_estimate_follows_the_counts() {
        let spheres = |op: &str, n: u32| {
            scene(&format!(
                "{op} {{ #for (I, 1, {n}) sphere {{ <0, 0, 0>, I }} #end }}"
            ))
        };
        assert_eq!(cost_of(&spheres("intersection", 4096)), 4096 * (3 + 2 * 14));
        assert_eq!(cost_of(&spheres("merge", 2)), 2 * (3 + 2 * (1 + 2)));
        let boxes = scene("merge { box { <0,0,0>, <1,1,1> } box { <1,0,0>, <2,1,1> } }");
        assert_eq!(cost_of(&boxes), 2 * (18 + 2 * (1 + 2)));
        let nested = scene(
            "difference { sphere { <0,0,0>, 1 } intersection { sphere { <0,0,0>, 1 } \
             sphere { <1,0,0>, 1 } } }",
        );
        // Three shapes (2 bits), two levels.
        assert_eq!(cost_of(&nested), 3 * (3 + 2 * (2 + 2)));
    }

    /// A mesh counts its triangles: 100 placements of a mesh of 10 000 triangles pass the
    /// budget's 1 048 576 and are refused, with the CSG's span, a message with the counts and a
    /// help naming `union`; 30 placements (900 000 and the classification) are accepted.
    #[test]
    fn many_placements_of_a_mesh_are_refused_from_counts() {
        let mut s = scene("merge { sphere { <0,0,0>, 1 } sphere { <1,0,0>, 1 } }");
        let mesh = Arc::new(MeshData {
            indices: vec![[0, 1, 2]; 10_000],
            ..Default::default()
        });
        let ShapeDecl::Csg(csg) = &mut s.objects[0].shape else {
            unreachable!()
        };
        let template = csg.children[0].clone();
        let placements = |n: usize| {
            (0..n)
                .map(|_| Object {
                    shape: ShapeDecl::Mesh { mesh: mesh.clone() },
                    ..template.clone()
                })
                .collect::<Vec<_>>()
        };
        csg.children = placements(30);
        assert!(check_costs(&s).is_ok(), "{}", cost_of(&s));
        let ShapeDecl::Csg(csg) = &mut s.objects[0].shape else {
            unreachable!()
        };
        csg.children = placements(100);
        let cost = cost_of(&s);
        assert!(cost >= 3_000_000, "{cost}");
        let e = check_costs(&s).unwrap_err();
        assert_eq!(e.span, s.objects[0].span);
        assert!(
            e.message
                .contains(&format!("would cost up to {cost} surface tests"))
                && e.message.contains("(100 shapes with 1000000 surfaces)"),
            "{}",
            e.message
        );
        assert!(e.help.unwrap().contains("use `union`"));
    }
}
