//! Triangle meshes: one shared vertex buffer (and normal and uv buffers, only when the file has
//! them) with three vertex indices per triangle. The BVH stores a mesh this way; CSG leaves
//! and emissive meshes (sampled as lights) expand it into world-space [`Triangle`]s.

use glam::{DAffine3, Vec2, Vec3A};
use rayon::prelude::*;

use super::triangle::Triangle;
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::MeshData;

/// A mesh in the space its transform maps it to. Degenerate triangles are left out.
pub struct TriangleMesh {
    positions: Vec<[f32; 3]>,
    /// Per-vertex normals (transformed, not normalised), or empty.
    normals: Vec<[f32; 3]>,
    /// Per-vertex texture coordinates, or empty.
    uvs: Vec<Vec2>,
    indices: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// `mesh` under `xf`; a mirroring transform swaps two vertices of each triangle so that its
    /// winding (and so its normal) stays consistent.
    pub fn new(mesh: &MeshData, xf: &DAffine3) -> Result<Self, String> {
        Self::with_winding(mesh, xf, false)
    }

    /// [`TriangleMesh::new`], with every triangle's winding (and so its normal) reversed when
    /// `reverse` is set: a closed glass mesh wound inward is turned outward.
    pub fn with_winding(mesh: &MeshData, xf: &DAffine3, reverse: bool) -> Result<Self, String> {
        let n = mesh.positions.len();
        let nmat = xf.matrix3.inverse().transpose();
        // A mirroring transform reverses the winding as well.
        let rewind = (xf.matrix3.determinant() < 0.0) != reverse;
        // In parallel: a large mesh's set-up is part of the render's wall time.
        let positions: Vec<[f32; 3]> = mesh
            .positions
            .par_iter()
            .map(|&p| xf.transform_point3(p).as_vec3().to_array())
            .collect();
        let normals = if mesh.normals.len() == n {
            mesh.normals
                .par_iter()
                .map(|&v| (nmat * v).as_vec3().to_array())
                .collect()
        } else {
            Vec::new()
        };
        let uvs = if mesh.uvs.len() == n {
            mesh.uvs.par_iter().map(|uv| uv.as_vec2()).collect()
        } else {
            Vec::new()
        };
        if mesh
            .indices
            .par_iter()
            .any(|tri| tri.iter().any(|&i| i as usize >= n))
        {
            return Err(format!(
                "mesh `{}` has a vertex index out of range",
                mesh.path.display()
            ));
        }
        let mut out = Self {
            positions,
            normals,
            uvs,
            indices: Vec::new(),
        };
        // (rayon's collect keeps the file's order.)
        out.indices = mesh
            .indices
            .par_iter()
            .map(|tri| {
                let mut idx = *tri;
                if rewind {
                    idx.swap(1, 2);
                }
                idx
            })
            .filter(|&idx| out.triangle_of(idx).is_ok())
            .collect();
        Ok(out)
    }

    /// A mesh from raw buffers (no normals, no uvs); degenerate triangles and those with an
    /// index out of range are left out.
    pub fn from_buffers(positions: Vec<[f32; 3]>, indices: &[[u32; 3]]) -> Self {
        let mut out = Self {
            positions,
            normals: Vec::new(),
            uvs: Vec::new(),
            indices: Vec::with_capacity(indices.len()),
        };
        for tri in indices {
            if tri.iter().all(|&i| (i as usize) < out.positions.len()) {
                out.indices.push(*tri);
                if out.triangle(out.indices.len() - 1).is_err() {
                    out.indices.pop();
                }
            }
        }
        out.indices.shrink_to_fit();
        out
    }

    pub fn len(&self) -> usize {
        self.indices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The three vertices of triangle `k`.
    #[inline]
    pub fn vertices(&self, k: usize) -> [Vec3A; 3] {
        self.indices[k].map(|i| Vec3A::from(self.positions[i as usize]))
    }

    pub fn bounds(&self, k: usize) -> Aabb {
        Aabb::from_points(self.vertices(k))
    }

    /// Triangle `k` as a stand-alone shape (the same values the shape of an expanded mesh has).
    pub fn triangle(&self, k: usize) -> Result<Triangle, String> {
        self.triangle_of(self.indices[k])
    }

    /// The triangle of vertex indices `idx` (all in range).
    fn triangle_of(&self, idx: [u32; 3]) -> Result<Triangle, String> {
        let idx = idx.map(|i| i as usize);
        let normals = (!self.normals.is_empty()).then(|| idx.map(|i| Vec3A::from(self.normals[i])));
        let uvs = (!self.uvs.is_empty()).then(|| idx.map(|i| self.uvs[i]));
        Triangle::new(idx.map(|i| Vec3A::from(self.positions[i])), normals, uvs)
    }

    /// Every triangle as a stand-alone shape.
    pub fn triangles(&self) -> Vec<Triangle> {
        (0..self.len())
            .into_par_iter()
            .filter_map(|k| self.triangle(k).ok())
            .collect()
    }

    /// The full hit on triangle `k` at ray parameter `t` (a value its intersection returned):
    /// identical to the stand-alone triangle's.
    pub fn hit_at(&self, k: usize, ray: &Ray, t: f32) -> Hit {
        use super::SplitShape;
        match self.triangle(k) {
            Ok(tri) => tri.hit_at(ray, t),
            // Not reached: degenerate triangles are not stored.
            Err(_) => Hit {
                t,
                p: ray.at(t),
                n: Vec3A::Z,
                ns: Vec3A::Z,
                uv: Vec2::ZERO,
                dpdu: Vec3A::X,
            },
        }
    }

    /// Bytes of the buffers.
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.positions.capacity() * size_of::<[f32; 3]>()
            + self.normals.capacity() * size_of::<[f32; 3]>()
            + self.uvs.capacity() * size_of::<Vec2>()
            + self.indices.capacity() * size_of::<[u32; 3]>()
    }
}

/// The mesh's triangles in world space, as stand-alone shapes; smooth normals and uvs when the
/// file has them. Degenerate triangles are skipped (OBJ files often contain a few).
pub fn mesh_triangles(mesh: &MeshData, xf: &DAffine3) -> Result<Vec<Triangle>, String> {
    Ok(TriangleMesh::new(mesh, xf)?.triangles())
}
