//! The set-up of a large mesh, step by step: wall time and CPU time (all threads) of reading
//! an OBJ file with `tobj` alone (the baseline), with `load_obj` (the product's reader), of
//! turning the mesh into world-space triangles, and of building the BVH over them, each in a
//! rayon pool of a given number of threads. `sppm-measure setup <file.obj> --threads 1,2`.

use std::path::Path;
use std::time::Instant;

use glam::DAffine3;
use sppm_lang::accel::Bvh;
use sppm_lang::scene::load_obj;
use sppm_lang::shapes::mesh::mesh_triangles;
use sppm_lang::shapes::primitive::AnyShape;

/// One step: its name, wall seconds and CPU seconds (summed over the process's threads).
#[derive(Debug, Clone)]
pub struct Step {
    pub name: &'static str,
    pub wall: f64,
    pub cpu: f64,
}

/// CPU time (user and system) of the whole process in seconds, threads that have ended
/// included: `/proc/self/stat`, in clock ticks of 10 ms (Linux; NaN elsewhere).
pub fn process_cpu() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // The fields after the command name (which is in parentheses and may hold spaces).
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(vec![], |(_, rest)| rest.split_whitespace().collect());
    let tick = |i: usize| fields.get(i).and_then(|f| f.parse::<u64>().ok());
    match (tick(11), tick(12)) {
        (Some(user), Some(system)) => (user + system) as f64 / 100.0,
        _ => f64::NAN,
    }
}

fn timed<T>(name: &'static str, steps: &mut Vec<Step>, f: impl FnOnce() -> T) -> T {
    let (c0, t0) = (process_cpu(), Instant::now());
    let out = f();
    steps.push(Step {
        name,
        wall: t0.elapsed().as_secs_f64(),
        cpu: process_cpu() - c0,
    });
    out
}

/// The steps for `obj` on `threads` threads.
pub fn run(obj: &Path, threads: usize) -> Result<Vec<Step>, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    pool.install(|| {
        let mut steps = Vec::new();
        let bytes = timed("read the file", &mut steps, || std::fs::read(obj))
            .map_err(|e| format!("{}: {e}", obj.display()))?;
        let options = tobj::LoadOptions {
            single_index: true,
            triangulate: true,
            ignore_points: true,
            ignore_lines: true,
        };
        let baseline = timed("tobj alone (baseline, not used)", &mut steps, || {
            tobj::load_obj_buf(&mut std::io::Cursor::new(&bytes[..]), &options, |_| {
                Err(tobj::LoadError::OpenFileFailed)
            })
        });
        drop(baseline);
        let mesh = timed("load_obj (read, parse, checks)", &mut steps, || {
            load_obj(obj)
        })?;
        let tris = timed("mesh_triangles", &mut steps, || {
            mesh_triangles(&mesh, &DAffine3::IDENTITY)
        })?;
        let shapes: Vec<(AnyShape, u32)> = timed("shapes for the BVH", &mut steps, || {
            tris.into_iter()
                .map(|t| (AnyShape::Triangle(t), 0))
                .collect()
        });
        let bvh = timed("Bvh::new", &mut steps, || Bvh::new(shapes));
        timed("drop the BVH and mesh", &mut steps, || drop((bvh, mesh)));
        Ok(steps)
    })
}
