//! Constructive solid geometry as plain data: an operation over child objects, and which
//! shapes enclose a volume (and so can take part in one).
//!
//! A CSG node is an [`Object`] whose shape is [`ShapeDecl::Csg`]: its transform applies to every
//! child (each child's own transform comes first), and each child keeps its own material. The
//! renderer intersects the whole tree as one primitive (`shapes::csg`).

use std::collections::HashMap;

use super::{MeshData, Object, ShapeDecl};
use crate::diag::short_number as short;

/// Deepest nesting of CSG operations: the renderer classifies a hit by walking the tree.
pub const MAX_CSG_DEPTH: usize = 64;
/// Most closed shapes in one CSG tree: a ray into the tree queries each one whose bounds it
/// meets, so a wide tree costs every such ray.
pub const MAX_CSG_LEAVES: usize = 4096;

/// The help of every "not closed" diagnostic.
pub const CLOSED_HELP: &str = "use closed shapes (sphere, box, torus, superellipsoid, blob, \
     height_field, text, cylinder, cone, prism or isosurface without `open`, a revolve whose \
     profile starts and ends on the axis, a \
     watertight mesh, a plane), or `union`, which needs no inside";

/// The operations, with POV-Ray's meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CsgOp {
    /// Inside any child; every child's whole surface is kept, inner parts too.
    Union,
    /// Inside any child; the surfaces inside another child are removed.
    Merge,
    /// Inside every child.
    Intersection,
    /// Inside the first child and no other; surfaces of the others are turned inside out.
    Difference,
    /// Inside where the one child is outside (its surface, turned inside out).
    Inverse,
}

impl CsgOp {
    pub fn name(self) -> &'static str {
        match self {
            CsgOp::Union => "union",
            CsgOp::Merge => "merge",
            CsgOp::Intersection => "intersection",
            CsgOp::Difference => "difference",
            CsgOp::Inverse => "inverse",
        }
    }

    /// The name with its article, for messages ("an intersection").
    pub fn a_name(self) -> &'static str {
        match self {
            CsgOp::Union => "a union",
            CsgOp::Merge => "a merge",
            CsgOp::Intersection => "an intersection",
            CsgOp::Difference => "a difference",
            CsgOp::Inverse => "an inverse",
        }
    }
}

/// One CSG operation over its children (objects: shapes or further operations).
#[derive(Debug, Clone)]
pub struct Csg {
    pub op: CsgOp,
    pub children: Vec<Object>,
}

impl Csg {
    /// Depth of the tree (1: children are all shapes), counted up to `limit + 1` only, so that
    /// a hand-built tree of any depth is measured without deep recursion.
    pub fn depth(&self, limit: usize) -> usize {
        if limit == 0 {
            return 1;
        }
        1 + self
            .children
            .iter()
            .map(|c| match &c.shape {
                ShapeDecl::Csg(inner) => inner.depth(limit - 1),
                _ => 0,
            })
            .max()
            .unwrap_or(0)
    }

    /// Every non-CSG object below this node (call only on a tree within [`MAX_CSG_DEPTH`]).
    pub fn leaves(&self) -> Vec<&Object> {
        let mut out = Vec::new();
        let mut stack = vec![self];
        while let Some(n) = stack.pop() {
            for c in &n.children {
                match &c.shape {
                    ShapeDecl::Csg(inner) => stack.push(inner),
                    _ => out.push(c),
                }
            }
        }
        out
    }
}

/// Why a shape does not enclose a volume, or `None` when it does.
pub fn why_open(shape: &ShapeDecl) -> Option<String> {
    match shape {
        ShapeDecl::Sphere { .. }
        | ShapeDecl::Box { .. }
        | ShapeDecl::Plane { .. }
        | ShapeDecl::Torus { .. }
        | ShapeDecl::Csg(_) => None,
        ShapeDecl::Cylinder { open: true, .. } => Some("an `open` cylinder has no caps".into()),
        ShapeDecl::Cylinder { .. } => None,
        ShapeDecl::Cone { open: true, .. } => Some("an `open` cone has no caps".into()),
        ShapeDecl::Cone { .. } => None,
        ShapeDecl::Quad { .. } | ShapeDecl::Disk { .. } | ShapeDecl::Triangle { .. } => {
            Some(format!("a {} is a flat surface", shape.kind()))
        }
        ShapeDecl::BezierPatch { .. } => Some("a single Bezier patch is an open surface".into()),
        ShapeDecl::Prism(p) if p.open => Some("an `open` prism has no caps".into()),
        ShapeDecl::Prism(_)
        | ShapeDecl::Superellipsoid { .. }
        | ShapeDecl::Blob(_)
        | ShapeDecl::HeightField(_)
        | ShapeDecl::SphereSweep(_) => None,
        ShapeDecl::Isosurface(i) if i.open => {
            Some("an `open` isosurface has no walls where its container cuts it".into())
        }
        ShapeDecl::Isosurface(_) => None,
        ShapeDecl::Revolve { profile, sweep, .. } => {
            if sweep.is_some() {
                return Some("a partial sweep (`angle`) is open".into());
            }
            let first = profile.segments.first().and_then(|s| s.first());
            let last = profile.segments.last().and_then(|s| s.last());
            match (first, last) {
                (Some(a), Some(b)) if a == b || (a.x == 0.0 && b.x == 0.0) => None,
                _ => Some(
                    "the profile neither starts and ends on the axis (radius 0) nor ends where \
                     it starts"
                        .into(),
                ),
            }
        }
        ShapeDecl::Mesh { mesh } => mesh_why_open(mesh),
    }
}

/// A mesh encloses a volume when it is a closed, consistently oriented surface: every directed
/// edge `a -> b` of a triangle is matched by exactly one `b -> a` of another. Vertices are
/// compared by position: an OBJ corner with its own normal or texture coordinate (a cube with
/// flat faces) is a vertex of its own in [`MeshData`], yet the same point of the surface.
fn mesh_why_open(mesh: &MeshData) -> Option<String> {
    let mut first_at: HashMap<[u64; 3], u32> = HashMap::with_capacity(mesh.positions.len());
    // `+ 0.0` makes -0 and 0 one key.
    let point: Vec<u32> = (0u32..)
        .zip(&mesh.positions)
        .map(|(i, p)| {
            *first_at
                .entry((*p + 0.0).to_array().map(f64::to_bits))
                .or_insert(i)
        })
        .collect();
    let corner = |i: u32| point.get(i as usize).copied().unwrap_or(i);
    let mut edges: HashMap<(u32, u32), i32> = HashMap::with_capacity(mesh.indices.len() * 3);
    for t in &mesh.indices {
        let t = t.map(corner);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a == b {
                continue;
            }
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    // The first bad edge in file order (a message that does not change from run to run).
    let bad = mesh
        .indices
        .iter()
        .map(|t| t.map(corner))
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .filter(|&(a, b)| a != b)
        .map(|e| (e, edges[&e]))
        .find(|&((a, b), n)| n != 1 || edges.get(&(b, a)) != Some(&1));
    match bad {
        None if !edges.is_empty() => None,
        None => Some(format!("mesh `{}` has no triangles", mesh.path.display())),
        Some(((a, b), _)) => {
            // The mesh's vertices are numbered as the faces use them, not as the file's `v`
            // lines: name the edge by its end points.
            let at = |i: u32| {
                let p = mesh.positions.get(i as usize).copied().unwrap_or_default();
                format!("<{}, {}, {}>", short(p.x), short(p.y), short(p.z))
            };
            Some(format!(
                "mesh `{}` is not watertight: its edge from {} to {} is not shared by exactly \
                 two consistently oriented triangles",
                mesh.path.display(),
                at(a),
                at(b)
            ))
        }
    }
}
