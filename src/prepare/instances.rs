//! Meshes placed more than once are stored once: their triangles go into one object-space BVH,
//! and each placement becomes a single primitive of the scene's BVH that carries its transform
//! (a two-level hierarchy). A mesh placed once, and every emissive mesh (its triangles are
//! sampled as lights), is baked into world-space triangles as before, so a scene without
//! repeated meshes does not change at all.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::DAffine3;

use crate::accel::Bvh;
use crate::scene::{MeshData, Object, Scene, ShapeDecl};
use crate::shapes::mesh::TriangleMesh;
use crate::shapes::primitive::AnyShape;
use crate::shapes::transformed::Transformed;

/// The identity of a loaded mesh (meshes loaded from the same file share their data).
fn key(mesh: &Arc<MeshData>) -> usize {
    Arc::as_ptr(mesh) as usize
}

/// The mesh an object places, when it may be instanced (not emissive).
fn placed_mesh(obj: &Object) -> Option<&Arc<MeshData>> {
    match &obj.shape {
        ShapeDecl::Mesh { mesh } if obj.emission.is_none() => Some(mesh),
        _ => None,
    }
}

/// The meshes stored once: those placed by more than one non-emissive object.
pub(super) fn shared_meshes(scene: &Scene) -> HashSet<usize> {
    let mut seen = HashSet::new();
    let mut shared = HashSet::new();
    for mesh in scene.objects.iter().filter_map(placed_mesh) {
        if !seen.insert(key(mesh)) {
            shared.insert(key(mesh));
        }
    }
    shared
}

/// The identity of the shared mesh `obj` places, if it places one.
pub(super) fn shared_key(obj: &Object, shared: &HashSet<usize>) -> Option<usize> {
    placed_mesh(obj).map(key).filter(|k| shared.contains(k))
}

/// Builds the placements of shared meshes, each mesh's BVH once.
pub(super) struct Instancer {
    shared: HashSet<usize>,
    /// Each shared mesh's BVH, by the mesh and whether its triangles are rewound.
    built: HashMap<(usize, bool), Arc<Bvh>>,
}

impl Instancer {
    pub(super) fn new(scene: &Scene) -> Self {
        Self {
            shared: shared_meshes(scene),
            built: HashMap::new(),
        }
    }

    /// The one primitive that places `obj`'s mesh, or `None` when the object is not a shared
    /// mesh (or its transform is too close to singular for an f32 inverse: it is then baked);
    /// its triangles rewound if `reverse`.
    pub(super) fn placement(
        &mut self,
        obj: &Object,
        reverse: bool,
    ) -> Result<Option<AnyShape>, String> {
        let (Some(mesh), Some(id)) = (placed_mesh(obj), shared_key(obj, &self.shared)) else {
            return Ok(None);
        };
        let bvh = match self.built.get(&(id, reverse)) {
            Some(b) => b.clone(),
            None => {
                let tris = TriangleMesh::with_winding(mesh, &DAffine3::IDENTITY, reverse)?;
                if tris.is_empty() {
                    return Err(format!("mesh `{}` has no triangles", mesh.path.display()));
                }
                let bvh = Bvh::with_meshes(Vec::new(), vec![(tris, 0)])
                    .map_err(|e| format!("mesh `{}`: {e}", mesh.path.display()))?;
                let bvh = Arc::new(bvh);
                self.built.insert((id, reverse), bvh.clone());
                bvh
            }
        };
        Ok(Transformed::new(bvh, obj.transform.as_affine3a())
            .ok()
            .map(|t| AnyShape::Other(Box::new(t))))
    }
}
