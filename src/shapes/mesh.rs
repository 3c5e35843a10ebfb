//! Triangle meshes: one shared vertex buffer (and normal and uv buffers, only when the file has
//! them) with three vertex indices per triangle. The BVH stores a mesh this way; CSG leaves
//! and emissive meshes (sampled as lights) expand it into world-space [`Triangle`]s.

use glam::{DAffine3, Vec2, Vec3A};
use rayon::prelude::*;

use super::triangle::{Triangle, shading_normal, uv_and_dpdu};
use crate::geometry::{Aabb, Hit};
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

    /// Triangle `k`'s geometric normal, not normalised: the cross product of its edges from the
    /// first vertex to the second and to the third (the direction [`TriangleMesh::hit_at`]'s
    /// `n` has; its length is twice the triangle's area). For a caller that needs a hit's
    /// triangle and orientation but not its shading record (what Embree's closest hit returns
    /// as `Ng`).
    #[inline]
    pub fn geometric_normal(&self, k: usize) -> Vec3A {
        let p = self.indices[k].map(|i| Vec3A::from(self.positions[i as usize]));
        (p[1] - p[0]).cross(p[2] - p[0])
    }

    /// The full hit on triangle `k` at ray parameter `t` with barycentric coordinates `b`
    /// (of its second and third vertex), the values its intersection test returned: read from
    /// the buffers, with the operations of the stand-alone triangle's `hit_at` in the same
    /// order, so the same bits, without building the triangle (its area, its normals' checks
    /// and the intersection test over again).
    pub fn hit_at(&self, k: usize, t: f32, b: [f32; 2]) -> Hit {
        let idx = self.indices[k].map(|i| i as usize);
        let p = idx.map(|i| Vec3A::from(self.positions[i]));
        let e1 = p[1] - p[0];
        let e2 = p[2] - p[0];
        let c = e1.cross(e2);
        // (Stored triangles are not degenerate: the length is finite and positive.)
        let n = c / crate::geometry::scaled_length(c);
        let [b1, b2] = b;
        let b0 = 1.0 - b1 - b2;
        let point = p[0] * b0 + p[1] * b1 + p[2] * b2;
        let ns = shading_normal(self.vertex_normals(idx), [b0, b1, b2], n);
        // Without uvs, the default parameterisation's constants go through the same operations
        // (what they fold away is exact: products and a quotient by one); no buffer is read.
        let (uv, dpdu) = if self.uvs.is_empty() {
            uv_and_dpdu([Vec2::ZERO, Vec2::X, Vec2::Y], [b0, b1, b2], e1, e2)
        } else {
            uv_and_dpdu(idx.map(|i| self.uvs[i]), [b0, b1, b2], e1, e2)
        };
        Hit {
            t,
            p: point,
            n,
            ns,
            uv,
            dpdu,
        }
    }

    /// The vertex normals `idx` name, normalised, when the mesh has normals and all three are
    /// usable (as [`Triangle::new`] takes them).
    #[inline]
    fn vertex_normals(&self, idx: [usize; 3]) -> Option<[Vec3A; 3]> {
        if self.normals.is_empty() {
            return None;
        }
        let ns = idx.map(|i| Vec3A::from(self.normals[i]));
        ns.iter()
            .all(|v| v.is_finite() && v.length() > 0.0)
            .then(|| ns.map(|v| v.normalize()))
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
