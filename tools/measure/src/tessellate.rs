//! Tessellation of the Bezier surfaces into triangle meshes (the renderer's [`MeshData`]), for
//! comparing the analytic intersectors with the mesh a user could use instead.
//!
//! Both grids put their vertices on the exact surface (the mesh is inscribed), with the exact
//! surface normal per vertex and the surface parameters as `uv`. Triangles that collapse (at a
//! pole of a revolve, where a whole grid row is one point) come out degenerate and are dropped by
//! [`sppm_lang::internals::shapes::mesh::mesh_triangles`], as for any mesh file.

use std::f64::consts::TAU;
use std::path::PathBuf;

use glam::{DVec2, DVec3};

use sppm_lang::internals::bezier::lathe::Lathe;
use sppm_lang::internals::bezier::patch::Patch;
use sppm_lang::internals::scene::MeshData;

/// Samples per segment used to estimate its arc length (for sharing rows between segments).
const LENGTH_SAMPLES: usize = 64;

/// Indices of a `rows x cols` grid of quads over `(rows + 1) x (cols + 1)` vertices (row-major),
/// two triangles each.
fn grid_indices(rows: usize, cols: usize) -> Vec<[u32; 3]> {
    let w = cols + 1;
    let mut out = Vec::with_capacity(2 * rows * cols);
    for i in 0..rows {
        for j in 0..cols {
            let a = (i * w + j) as u32;
            let b = a + 1;
            let c = a + w as u32;
            let d = c + 1;
            out.push([a, c, b]);
            out.push([b, c, d]);
        }
    }
    out
}

/// How many of `rows` grid rows each segment gets: in proportion to its arc length, at least one.
fn rows_per_segment(lathe: &Lathe, rows: usize) -> Vec<usize> {
    let lengths: Vec<f64> = lathe
        .segments()
        .iter()
        .map(|seg| {
            (0..LENGTH_SAMPLES)
                .map(|k| {
                    let a = seg.point(k as f64 / LENGTH_SAMPLES as f64);
                    let b = seg.point((k + 1) as f64 / LENGTH_SAMPLES as f64);
                    (b - a).length()
                })
                .sum()
        })
        .collect();
    let total: f64 = lengths.iter().sum();
    lengths
        .iter()
        .map(|l| {
            if total > 0.0 {
                ((rows as f64 * l / total).round() as usize).max(1)
            } else {
                1
            }
        })
        .collect()
}

/// A revolve as a `rows x cols` grid in (profile parameter, angle): `rows` shared between the
/// profile's segments by arc length (uniform in `s` within a segment, at least one per segment),
/// `cols` uniform in the angle of the sweep. Caps of a partial sweep are not tessellated.
pub fn lathe_mesh(lathe: &Lathe, rows: usize, cols: usize) -> MeshData {
    let cols = cols.max(3);
    let (a0, span) = lathe.sweep().unwrap_or((0.0, TAU));
    let per_seg = rows_per_segment(lathe, rows.max(1));
    let size = lathe.size();
    // Profile samples (segment, s) in order; a segment's first sample is the previous one's last.
    let mut samples: Vec<(usize, f64)> = Vec::new();
    for (i, &n) in per_seg.iter().enumerate() {
        let first = if i == 0 { 0 } else { 1 };
        for k in first..=n {
            samples.push((i, k as f64 / n as f64));
        }
    }
    let total_rows = samples.len() - 1;
    let mut positions = Vec::with_capacity(samples.len() * (cols + 1));
    let mut normals = Vec::with_capacity(positions.capacity());
    let mut uvs = Vec::with_capacity(positions.capacity());
    for (row, &(i, s)) in samples.iter().enumerate() {
        let seg = &lathe.segments()[i];
        let dr = seg.r.eval_with_derivative(s).1;
        let dh = seg.h.eval_with_derivative(s).1;
        for j in 0..=cols {
            let frac = j as f64 / cols as f64;
            let phi = a0 + span * frac;
            let p = lathe.surface_point(i, s, phi);
            // Outward normal (h' cos phi, -r', h' sin phi); left empty where P' vanishes.
            let n = DVec3::new(dh * phi.cos(), -dr, dh * phi.sin());
            positions.push(p);
            normals.push(if n.length() > 1e-12 * size {
                n.normalize()
            } else {
                DVec3::ZERO
            });
            uvs.push(DVec2::new(row as f64 / total_rows as f64, frac));
        }
    }
    MeshData {
        path: PathBuf::from("<tessellated revolve>"),
        positions,
        normals,
        uvs,
        indices: grid_indices(total_rows, cols),
    }
}

/// A bicubic patch as a `rows x cols` grid uniform in `(u, v)`.
pub fn patch_mesh(patch: &Patch, rows: usize, cols: usize) -> MeshData {
    let (rows, cols) = (rows.max(1), cols.max(1));
    let mut positions = Vec::with_capacity((rows + 1) * (cols + 1));
    let mut normals = Vec::with_capacity(positions.capacity());
    let mut uvs = Vec::with_capacity(positions.capacity());
    for i in 0..=rows {
        for j in 0..=cols {
            let (u, v) = (i as f64 / rows as f64, j as f64 / cols as f64);
            positions.push(patch.eval(u, v).0);
            normals.push(patch.normal(u, v));
            uvs.push(DVec2::new(u, v));
        }
    }
    MeshData {
        path: PathBuf::from("<tessellated patch>"),
        positions,
        normals,
        uvs,
        indices: grid_indices(rows, cols),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DAffine3;
    use sppm_lang::internals::shapes::mesh::mesh_triangles;

    fn cylinder() -> Lathe {
        Lathe::new(&[vec![DVec2::new(1.0, 0.0), DVec2::new(1.0, 2.0)]], None).unwrap()
    }

    #[test]
    fn lathe_grid_lies_on_the_surface_and_closes_the_turn() {
        let m = lathe_mesh(&cylinder(), 4, 16);
        assert_eq!(m.positions.len(), 5 * 17);
        assert_eq!(m.indices.len(), 2 * 4 * 16);
        for p in &m.positions {
            assert!((p.x.hypot(p.z) - 1.0).abs() < 1e-12 && (0.0..=2.0).contains(&p.y));
        }
        // The last column meets the first (a closed turn).
        assert!((m.positions[16] - m.positions[0]).length() < 1e-12);
        // Outward normals.
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((DVec3::new(p.x, 0.0, p.z) - *n).length() < 1e-12);
        }
        let tris = mesh_triangles(&m, &DAffine3::IDENTITY).unwrap();
        assert_eq!(tris.len(), 128);
    }

    #[test]
    fn rows_follow_arc_length_and_poles_collapse() {
        // A disk (length 1 from the axis) then a wall of length 3.
        let l = Lathe::new(
            &[
                vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0)],
                vec![DVec2::new(1.0, 0.0), DVec2::new(1.0, 3.0)],
            ],
            None,
        )
        .unwrap();
        assert_eq!(rows_per_segment(&l, 8), vec![2, 6]);
        let m = lathe_mesh(&l, 8, 8);
        assert_eq!(m.indices.len(), 2 * 8 * 8);
        // The first row is the pole: its triangles are degenerate and dropped.
        let tris = mesh_triangles(&m, &DAffine3::IDENTITY).unwrap();
        assert_eq!(tris.len(), 2 * 8 * 8 - 8);
    }

    #[test]
    fn patch_grid_corners_are_the_control_corners() {
        let pts: [DVec3; 16] = std::array::from_fn(|k| {
            DVec3::new((k / 4) as f64, (k % 4) as f64, ((k * 7) % 5) as f64 * 0.1)
        });
        let p = Patch::new(&pts).unwrap();
        let m = patch_mesh(&p, 3, 5);
        assert_eq!(m.positions.len(), 4 * 6);
        assert_eq!(m.indices.len(), 30);
        assert!((m.positions[0] - pts[0]).length() < 1e-12);
        assert!((m.positions[5] - pts[3]).length() < 1e-12);
        assert!((m.positions[23] - pts[15]).length() < 1e-12);
    }
}
