//! The set-up of a large mesh, step by step, as a render does it: wall time and CPU time (all
//! threads) of reading an OBJ file with `tobj` alone (the baseline, not used), of loading a
//! scene that places the mesh once (evaluation, the parallel OBJ reader), of the scene's
//! validation, of the world-space compact mesh (`TriangleMesh::new`, what `prepare` builds for
//! a mesh that is neither instanced nor a light), of the BVH over it (`Bvh::with_meshes`) and of
//! dropping it all; then the whole `PreparedScene::new` once more as a check that the steps add
//! up. Each in a rayon pool of a given number of threads.
//! `sppm-measure setup <file.obj> --threads 1,2`.

use std::path::Path;
use std::time::Instant;

use sppm_lang::internals::accel::Bvh;
use sppm_lang::internals::render::PreparedScene;
use sppm_lang::internals::scene::ShapeDecl;
use sppm_lang::internals::shapes::mesh::TriangleMesh;

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

/// Steps whose time is part of a render's set-up (the others, in parentheses, are baselines
/// and checks).
pub fn counted(step: &Step) -> bool {
    !step.name.starts_with('(')
}

/// The steps for `obj` on `threads` threads.
pub fn run(obj: &Path, threads: usize) -> Result<Vec<Step>, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let obj = obj
        .canonicalize()
        .map_err(|e| format!("{}: {e}", obj.display()))?;
    let text = format!("mesh {{ {:?} }}\n", obj.display().to_string());
    pool.install(|| {
        let mut steps = Vec::new();
        let options = tobj::LoadOptions {
            single_index: true,
            triangulate: true,
            ignore_points: true,
            ignore_lines: true,
        };
        let baseline = timed("(baseline) tobj alone, not used", &mut steps, || {
            let bytes = std::fs::read(&obj).map_err(|e| format!("{}: {e}", obj.display()))?;
            tobj::load_obj_buf(&mut std::io::Cursor::new(&bytes[..]), &options, |_| {
                Err(tobj::LoadError::OpenFileFailed)
            })
            .map_err(|e| e.to_string())
        })?;
        drop(baseline);
        let loaded = timed("load the scene (eval, load_obj)", &mut steps, || {
            sppm_lang::internals::eval::load_source("setup.scn", &text, &Default::default())
        });
        let scene = loaded
            .scene
            .ok_or_else(|| format!("{} does not load: {:?}", obj.display(), loaded.diagnostics))?;
        timed("validate the scene", &mut steps, || scene.validate())
            .map_err(|e| format!("{e:?}"))?;
        let object = &scene.objects[0];
        let ShapeDecl::Mesh { mesh } = &object.shape else {
            return Err("the scene holds no mesh".into());
        };
        let compact = timed("TriangleMesh::new", &mut steps, || {
            TriangleMesh::new(mesh, &object.transform)
        })?;
        let bvh = timed("Bvh::with_meshes", &mut steps, || {
            Bvh::with_meshes(Vec::new(), vec![(compact, 0)])
        })
        .map_err(|e| e.to_string())?;
        timed("drop the BVH", &mut steps, || drop(bvh));
        let prepared = timed("(check) PreparedScene::new", &mut steps, || {
            PreparedScene::new(&scene)
        })
        .map_err(|e| e.message)?;
        timed("(check) drop it", &mut steps, || drop(prepared));
        timed("drop the scene", &mut steps, || drop(scene));
        Ok(steps)
    })
}
