//! Triangle meshes: expanded into world-space triangles for the BVH.

use glam::{DAffine3, Vec2};
use rayon::prelude::*;

use super::triangle::Triangle;
use crate::scene::MeshData;

/// The mesh's triangles in world space; smooth normals and uvs when the file has them.
/// Degenerate triangles are skipped (OBJ files often contain a few).
pub fn mesh_triangles(mesh: &MeshData, xf: &DAffine3) -> Result<Vec<Triangle>, String> {
    let n = mesh.positions.len();
    let nmat = xf.matrix3.inverse().transpose();
    let mirrored = xf.matrix3.determinant() < 0.0;
    let has_n = mesh.normals.len() == n;
    let has_uv = mesh.uvs.len() == n;
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
    // In parallel, into a list of the file's length (so that the threads write their parts of
    // it in place), and the degenerate triangles left out after.
    let tris: Vec<Option<Triangle>> = mesh
        .indices
        .par_iter()
        .map(|tri| {
            let mut idx = tri.map(|i| i as usize);
            if mirrored {
                idx.swap(1, 2); // keep the winding (and so the normal) consistent under a mirror
            }
            let p = idx.map(|i| xf.transform_point3(mesh.positions[i]).as_vec3a());
            let normals = has_n.then(|| idx.map(|i| (nmat * mesh.normals[i]).as_vec3a()));
            let uvs = has_uv.then(|| idx.map(|i| mesh.uvs[i].as_vec2()));
            Triangle::new(p, normals, uvs.map(|u| u.map(Vec2::from))).ok()
        })
        .collect();
    if tris.par_iter().all(Option::is_some) {
        // The usual case, moved in parallel too.
        return Ok(tris
            .into_par_iter()
            .map(|t| t.expect("checked just above"))
            .collect());
    }
    Ok(tris.into_iter().flatten().collect())
}
