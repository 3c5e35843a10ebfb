//! A scene's twin with every `revolve` replaced by a triangle mesh of the same surface at a
//! given silhouette accuracy (`cargo run --release -p sppm-measure -- twin examples/goblet.scn`):
//! the meshes are written as OBJ files beside the twin scene (under `target/` by default), so the
//! analytic surfaces and the meshes can be rendered and timed side by side.
//!
//! Each revolve block is found in the scene's text (it must be written out, not made by a macro)
//! and replaced by `mesh { "<file>.obj" ... }` with the block's own material and transforms.

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;

use sppm_lang::internals::bezier::lathe::Lathe;
use sppm_lang::internals::eval::{EvalOptions, load_file};
use sppm_lang::internals::scene::{MeshData, ShapeDecl};

use crate::tessellate::lathe_mesh;

/// Largest distance between the mesh and the surface along the profile (chord midpoints against
/// the curve) and around the axis (`r (1 - cos(pi / cols))`), in the lathe's own units.
fn deviation(lathe: &Lathe, rows: usize, cols: usize) -> f64 {
    let m = lathe_mesh(lathe, rows, 0);
    let rmax = lathe.bounds().1.x;
    let around = rmax * (1.0 - (std::f64::consts::PI / cols as f64).cos());
    // Profile samples are the mesh's first column (phi = 0): (x, y) = (r, h).
    let col: Vec<DVec3> = m.positions.iter().step_by(4).copied().collect();
    let mut along: f64 = 0.0;
    for w in col.windows(2) {
        let mid = 0.5 * (w[0] + w[1]);
        // Distance from the chord midpoint to the nearest profile point, by dense sampling.
        let mut best = f64::INFINITY;
        for seg in lathe.segments() {
            for k in 0..=512 {
                let p = seg.point(k as f64 / 512.0);
                best = best.min(((p.x - mid.x).powi(2) + (p.y - mid.y).powi(2)).sqrt());
            }
        }
        along = along.max(best);
    }
    around.max(along)
}

/// The coarsest mesh (rows and columns doubling from 8 x 16) within `tol` of the surface.
pub fn mesh_within(lathe: &Lathe, tol: f64) -> (MeshData, usize, usize) {
    let (mut rows, mut cols) = (8, 16);
    let rmax = lathe.bounds().1.x;
    while rmax * (1.0 - (std::f64::consts::PI / cols as f64).cos()) > tol && cols < 1 << 16 {
        cols *= 2;
    }
    while deviation(lathe, rows, cols) > tol && rows < 1 << 14 {
        rows *= 2;
    }
    (lathe_mesh(lathe, rows, cols), rows, cols)
}

fn obj_text(m: &MeshData) -> String {
    let mut s = String::new();
    for p in &m.positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for n in &m.normals {
        let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
    }
    let with_normals = m.normals.len() == m.positions.len();
    for t in &m.indices {
        let [a, b, c] = t.map(|i| i + 1);
        if with_normals {
            let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
        } else {
            let _ = writeln!(s, "f {a} {b} {c}");
        }
    }
    s
}

/// The end (exclusive) of the brace block opening at `open` (the index of its `{`).
fn block_end(text: &str, open: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (i, ch) in text[open..].char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(open + i + 1);
                }
            }
            _ => {}
        }
    }
    None
}

/// Writes `<out>/<stem>_mesh.scn` and one OBJ per revolve; returns a line per revolve (file,
/// rows x cols, triangles) and the twin's path. `tol` is in world units (each revolve's own
/// tolerance is divided by its largest scale factor).
pub fn write_twin(scene: &Path, out: &Path, tol: f64) -> Result<(Vec<String>, String), String> {
    let loaded = load_file(scene, &EvalOptions::default()).map_err(|e| e.to_string())?;
    let sc = loaded
        .scene
        .ok_or_else(|| format!("{} has errors", scene.display()))?;
    let text = std::fs::read_to_string(scene).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    let stem = scene
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene");
    let mut lines = Vec::new();
    let mut twin = String::new();
    let mut rest = text.as_str();
    for (k, obj) in sc
        .objects
        .iter()
        .filter(|o| matches!(o.shape, ShapeDecl::Revolve { .. }))
        .enumerate()
    {
        let ShapeDecl::Revolve { profile, sweep, .. } = &obj.shape else {
            continue;
        };
        let lathe = Lathe::new(&profile.segments, *sweep)?;
        let m = obj.transform.matrix3;
        let scale = m
            .x_axis
            .length()
            .max(m.y_axis.length())
            .max(m.z_axis.length());
        let (mesh, rows, cols) = mesh_within(&lathe, tol / scale.max(1e-300));
        let file = format!("{stem}_revolve{k}.obj");
        std::fs::write(out.join(&file), obj_text(&mesh)).map_err(|e| e.to_string())?;
        lines.push(format!(
            "{file}: {rows} x {cols}, {} triangles",
            mesh.indices.len()
        ));
        // Replace the k-th `revolve {` block of the text.
        let start = rest
            .find("revolve {")
            .ok_or("fewer revolve blocks in the text than in the scene")?;
        let open = start + rest[start..].find('{').unwrap_or(0);
        let end = block_end(rest, open).ok_or("unbalanced braces")?;
        let body = &rest[open + 1..end - 1];
        let prof = body.find("profile").ok_or("revolve without profile")?;
        let p_open = prof + body[prof..].find('{').ok_or("profile without block")?;
        let p_end = block_end(body, p_open).ok_or("unbalanced braces")?;
        let after: String = body[p_end..]
            .lines()
            .filter(|l| l.trim() != "corner")
            .collect::<Vec<_>>()
            .join("\n");
        twin.push_str(&rest[..start]);
        let _ = write!(twin, "mesh {{ \"{file}\"{after}}}");
        rest = &rest[end..];
    }
    twin.push_str(rest);
    let path = out.join(format!("{stem}_mesh.scn"));
    std::fs::write(&path, twin).map_err(|e| e.to_string())?;
    Ok((lines, path.display().to_string()))
}
