//! The scale bench's files (the mesh and rays for `benches/scale_embree.py`, the OBJ for the
//! render) and its CPU clocks.

use std::io::Write as _;
use std::path::Path;

use sppm_lang::internals::geometry::Ray;

use super::displaced::Mesh;

pub fn write_mesh(path: &Path, mesh: &Mesh) {
    let mut out = Vec::with_capacity(8 + mesh.vertices.len() * 12 + mesh.triangles.len() * 12);
    out.extend((mesh.vertices.len() as u32).to_le_bytes());
    out.extend((mesh.triangles.len() as u32).to_le_bytes());
    for v in mesh.vertices.iter().flatten() {
        out.extend(v.to_le_bytes());
    }
    for i in mesh.triangles.iter().flatten() {
        out.extend(i.to_le_bytes());
    }
    std::fs::write(path, out).unwrap();
}

pub fn write_rays(path: &Path, rays: &[Ray]) {
    let mut out = Vec::with_capacity(4 + rays.len() * 24);
    out.extend((rays.len() as u32).to_le_bytes());
    for r in rays {
        for c in r.o.to_array().into_iter().chain(r.d.to_array()) {
            out.extend(c.to_le_bytes());
        }
    }
    std::fs::write(path, out).unwrap();
}

pub fn write_obj(path: &Path, mesh: &Mesh) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for v in &mesh.vertices {
        writeln!(f, "v {} {} {}", v[0], v[1], v[2]).unwrap();
    }
    for t in &mesh.triangles {
        writeln!(f, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).unwrap();
    }
    f.flush().unwrap();
}

/// CPU time of the calling thread in seconds (Linux: `/proc/thread-self/schedstat`, in ns).
pub fn thread_cpu() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(f64::NAN, |ns| ns as f64 * 1e-9)
}

/// CPU time of the process's live threads in seconds (Linux: the sum of
/// `/proc/self/task/*/schedstat`; rayon's pool threads live as long as the process).
pub fn process_cpu() -> f64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return f64::NAN;
    };
    dir.filter_map(|e| {
        let s = std::fs::read_to_string(e.ok()?.path().join("schedstat")).ok()?;
        s.split_whitespace().next()?.parse::<u64>().ok()
    })
    .map(|ns| ns as f64 * 1e-9)
    .sum()
}
