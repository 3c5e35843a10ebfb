//! Scale benchmark: triangle meshes of 10^4 to 10^7 triangles, the project's BVH against Embree 4
//! on exactly the same triangles and rays.
//!
//! Run: `cargo bench --bench scale` (sizes: `SCALE_SIZES=1e4,1e5,1e6,1e7`, the default;
//! rounds: `SCALE_ROUNDS=2`; `SCALE_RENDER=0` leaves out the SPPM render, for quicker runs of
//! the BVH alone). For each size it makes a displaced sphere (a UV sphere with bumps, so the
//! BVH sees neither a flat nor a regular surface), writes the triangles and two fixed ray sets
//! to `target/scale/` (coherent: a 1024x1024 pinhole camera that the mesh fills;
//! incoherent: cosine-distributed diffuse bounces from the camera rays' hits), and measures:
//!
//! - BVH build time (wall, and CPU time of all the process's threads: the build runs on rayon's
//!   global pool, all cores);
//! - memory per triangle (`Bvh::memory_bytes`: nodes, leaves, triangle packets, the mesh's
//!   vertex and index buffers);
//! - closest-hit (the record Embree returns: see `closest_record`) and any-hit rays/s on both
//!   ray sets, 1 thread (CPU time of the tracing thread)
//!   and 2 threads (wall and the threads' summed CPU time);
//! - photons/s of an SPPM render of the mesh from an OBJ written to `target/scale/`, and the time
//!   from loading that scene to its first finished iteration.
//!
//! Embree runs in the same run, alternating with this project round by round, through
//! `benches/scale_embree.py` (pip package `embreex`, Embree 4.4) with the Python found in
//! `SCALE_PYTHON`, the repository's `.venv/bin/python` or `python3`; without `embreex` the Embree columns
//! are left out and the bench says so. embreex traces from a Cython loop that reads numpy
//! arrays per ray; the script measures that loop's cost on a scene of one far-away triangle and
//! reports Embree's rays/s both raw and with the loop's cost taken out. Its build uses all the
//! cores it sees (TBB), and so does the project's (rayon).
//!
//! Knobs for measuring one effect at a time: `SCALE_QUERIES=closest` (or `any`) traces only
//! those queries, `SCALE_ONE_THREAD=1` leaves out the two-thread runs, and
//! `SCALE_STACK_PAD=n` calls the traversals `n` frames deeper on the stack, printing the
//! tracing thread's stack offset modulo 4096 (`stack ...` on stderr); with any of them set
//! the results files are not written.
//!
//! Results: a table on stdout, `target/scale/results.json`, and the curves drawn by the
//! project's chart code into `target/scale/scale.png`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use sppm_lang::EvalOptions;
use sppm_lang::internals::accel::{Bvh, Surface};
use sppm_lang::internals::chart::{ChartSpec, Dash, Series, draw_panels};
use sppm_lang::internals::eval::load_file;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::render::{RenderOptions, render};

#[path = "support/displaced.rs"]
mod displaced;
use displaced::{Mesh, bounce_rays, camera_rays, displaced_sphere, mesh_bvh, triangle_mesh};
#[path = "support/scale_files.rs"]
mod scale_files;
use scale_files::{process_cpu, thread_cpu, write_mesh, write_obj, write_rays};

const CAMERA_SIDE: u32 = 1024;
const BOUNCE_RAYS: usize = 1 << 20;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Query {
    Closest,
    Any,
}

/// Whether `ray` hits the mesh, with the closest hit's record as Embree's `rtcIntersect1`
/// makes it (`t`, the barycentric `u` and `v`, the triangle's index, the geometry's id and the
/// unnormalised geometric normal `Ng`), so that both sides give the same information out:
/// [`Bvh::intersect_ng`] (`Ng` from the triangle packet the hit was found in, as Embree's
/// leaf intersector has it), not the shading record (point, unit and shading normals, uv,
/// dp/du) of [`Bvh::intersect`], which Embree leaves to its caller.
#[inline]
fn closest_record(bvh: &Bvh, ray: &Ray) -> bool {
    match bvh.intersect_ng(ray, 0.0, f32::INFINITY) {
        Some((lazy, Surface::MeshTriangle(_, k, uv), id, ng)) => {
            std::hint::black_box((lazy.t(), uv, k, id, ng));
            true
        }
        // (The bench's trees hold mesh triangles only.)
        Some((lazy, Surface::Shape(_), id, _)) => {
            std::hint::black_box((lazy.t(), id));
            true
        }
        None => false,
    }
}

/// Runs `f` `n` frames deeper on the stack, to measure how the traversals' speed depends on
/// the stack pointer they are called with (`SCALE_STACK_PAD`).
#[inline(never)]
fn padded(n: usize, f: &mut dyn FnMut() -> (f64, usize)) -> (f64, usize) {
    if n == 0 {
        return f();
    }
    let buf = [0u8; 1];
    std::hint::black_box(&buf);
    let r = padded(n - 1, f);
    std::hint::black_box(r)
}

/// Traces `rays` on `threads` threads; returns (wall seconds, summed CPU seconds, hits).
fn trace(bvh: &Bvh, rays: &[Ray], query: Query, threads: usize) -> (f64, f64, usize) {
    let start = Instant::now();
    let chunk = rays.len().div_ceil(threads);
    let results: Vec<(f64, usize)> = std::thread::scope(|s| {
        let handles: Vec<_> = rays
            .chunks(chunk)
            .map(|part| {
                s.spawn(move || {
                    let pad: usize = std::env::var("SCALE_STACK_PAD")
                        .ok()
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(0);
                    padded(pad, &mut || {
                        let probe = 0u8;
                        if std::env::var_os("SCALE_STACK_PAD").is_some() {
                            eprintln!("stack {}", (&raw const probe as usize) & 4095);
                        }
                        std::hint::black_box(&probe);
                        let c0 = thread_cpu();
                        let hits = part
                            .iter()
                            .filter(|r| match query {
                                Query::Closest => closest_record(bvh, r),
                                Query::Any => bvh.occluded(r, 0.0, f32::INFINITY),
                            })
                            .count();
                        (thread_cpu() - c0, hits)
                    })
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let wall = start.elapsed().as_secs_f64();
    let cpu = results.iter().map(|r| r.0).sum();
    let hits = results.iter().map(|r| r.1).sum();
    (wall, cpu, hits)
}

/// Figures of one renderer at one size; rays/s keyed by "set/query/threads".
#[derive(Default, Clone)]
struct Figures {
    build_wall: f64,
    build_cpu: f64,
    bytes_per_triangle: f64,
    rays: Vec<(String, f64)>,
    /// Embree only: rays/s with the Python loop's cost taken out.
    rays_net: Vec<(String, f64)>,
}

impl Figures {
    fn best(&mut self, other: &Figures) {
        let min = |a: f64, b: f64| if a == 0.0 || b < a { b } else { a };
        self.build_wall = min(self.build_wall, other.build_wall);
        self.build_cpu = min(self.build_cpu, other.build_cpu);
        self.bytes_per_triangle = other.bytes_per_triangle;
        for (list, new) in [
            (&mut self.rays, &other.rays),
            (&mut self.rays_net, &other.rays_net),
        ] {
            for (k, v) in new {
                match list.iter_mut().find(|(key, _)| key == k) {
                    Some((_, old)) => *old = old.max(*v),
                    None => list.push((k.clone(), *v)),
                }
            }
        }
    }

    fn get(&self, key: &str) -> Option<f64> {
        self.rays.iter().find(|(k, _)| k == key).map(|r| r.1)
    }

    fn get_net(&self, key: &str) -> Option<f64> {
        self.rays_net.iter().find(|(k, _)| k == key).map(|r| r.1)
    }
}

fn ours(mesh: &Mesh, camera: &[Ray], bounce: &[Ray]) -> Figures {
    let prims = triangle_mesh(mesh);
    let n = prims.len();
    let (c0, t0) = (process_cpu(), Instant::now());
    let bvh = mesh_bvh(prims);
    let mut f = Figures {
        build_wall: t0.elapsed().as_secs_f64(),
        build_cpu: process_cpu() - c0,
        bytes_per_triangle: bvh.memory_bytes() as f64 / n as f64,
        ..Figures::default()
    };
    let parts: Vec<String> = bvh
        .memory_parts()
        .iter()
        .filter(|p| p.1 > 0)
        .map(|(what, b)| format!("{what} {:.1}", *b as f64 / n as f64))
        .collect();
    println!("  (ours, bytes/triangle: {})", parts.join(", "));
    let only = std::env::var("SCALE_QUERIES").unwrap_or_default();
    if !matches!(only.as_str(), "" | "closest" | "any") {
        eprintln!("SCALE_QUERIES={only}: `closest` or `any`");
        std::process::exit(2);
    }
    let one_thread = std::env::var("SCALE_ONE_THREAD").is_ok_and(|v| v == "1");
    for (set, rays) in [("camera", camera), ("bounce", bounce)] {
        for (q, query) in [("closest", Query::Closest), ("any", Query::Any)] {
            if !only.is_empty() && only != q {
                continue;
            }
            let (_, cpu, _) = trace(&bvh, rays, query, 1);
            f.rays
                .push((format!("{set}/{q}/1"), rays.len() as f64 / cpu));
            if one_thread {
                continue;
            }
            let (wall, _, _) = trace(&bvh, rays, query, 2);
            f.rays
                .push((format!("{set}/{q}/2"), rays.len() as f64 / wall));
        }
    }
    f
}

fn python() -> Option<PathBuf> {
    let candidates = [
        std::env::var_os("SCALE_PYTHON").map(PathBuf::from),
        Some(Path::new(env!("CARGO_MANIFEST_DIR")).join(".venv/bin/python")),
        Some(PathBuf::from("python3")),
    ];
    candidates.into_iter().flatten().find(|p| {
        Command::new(p)
            .args(["-c", "import embreex, numpy"])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

fn embree(python: &Path, dir: &Path, size: usize) -> Option<Figures> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/scale_embree.py");
    let out = Command::new(python)
        .arg(script)
        .arg(dir)
        .arg(size.to_string())
        .output()
        .ok()?;
    if !out.status.success() {
        eprintln!("embree: {}", String::from_utf8_lossy(&out.stderr));
        return None;
    }
    // Lines `key value [net]`.
    let mut f = Figures::default();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let parts: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| parts.get(i).and_then(|s| s.parse::<f64>().ok());
        match parts.first() {
            Some(&"build_wall") => f.build_wall = num(1)?,
            Some(&"build_cpu") => f.build_cpu = num(1)?,
            Some(&"bytes_per_triangle") => f.bytes_per_triangle = num(1)?,
            Some(key) if key.contains('/') => {
                f.rays.push((key.to_string(), num(1)?));
                f.rays_net.push((key.to_string(), num(2)?));
            }
            _ => {}
        }
    }
    Some(f)
}

/// Photons/s of a short SPPM render of the mesh read from an OBJ, and the time from loading the
/// scene to its first finished iteration.
fn render_figures(dir: &Path, mesh: &Mesh) -> (f64, f64) {
    let obj = dir.join("mesh.obj");
    write_obj(&obj, mesh);
    let scene_path = dir.join("mesh.scn");
    std::fs::write(
        &scene_path,
        "settings { resolution <256, 256> photons 500000 iterations 3 }\n\
         camera { location <0, 0.3, -2.4> look_at <0, 0, 0> fov 50 }\n\
         light { <2, 4, -3> intensity rgb 30 }\n\
         plane { <0, 1, 0>, -1.3 }\n\
         mesh { \"mesh.obj\" material { diffuse rgb 0.7 } }\n",
    )
    .unwrap();
    let start = Instant::now();
    let loaded = load_file(&scene_path, &EvalOptions::default()).expect("scene file");
    let scene = loaded.scene.expect("the scale scene evaluates");
    let mut first = None;
    let options = RenderOptions {
        integrator: Some(sppm_lang::Integrator::Sppm),
        memory_limit: Some(16 << 30),
        ..RenderOptions::default()
    };
    let out = render(&scene, &options, &AtomicBool::new(false), &mut |_| {
        first.get_or_insert(start.elapsed().as_secs_f64());
    })
    .expect("the scale scene renders");
    let photons_per_s = out.stats.photons as f64 / out.stats.photon_time.as_secs_f64();
    (photons_per_s, first.unwrap_or(f64::NAN))
}

fn parse_sizes() -> Vec<usize> {
    let text = std::env::var("SCALE_SIZES").unwrap_or_else(|_| "1e4,1e5,1e6,1e7".into());
    text.split(',')
        .filter_map(|s| s.trim().parse::<f64>().ok())
        .filter(|n| (100.0..=1e8).contains(n))
        .map(|n| n as usize)
        .collect()
}

/// Everything measured at one size.
struct Row {
    triangles: usize,
    ours: Figures,
    embree: Option<Figures>,
    /// Photons/s and seconds to the first image of the SPPM render.
    render: (f64, f64),
}

const KEYS: [&str; 8] = [
    "camera/closest/1",
    "camera/closest/2",
    "camera/any/1",
    "camera/any/2",
    "bounce/closest/1",
    "bounce/closest/2",
    "bounce/any/1",
    "bounce/any/2",
];

fn main() {
    // `cargo test --benches` lists tests with `--list`: there are none.
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/scale");
    std::fs::create_dir_all(&root).unwrap();
    let rounds: usize = std::env::var("SCALE_ROUNDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2)
        .clamp(1, 10);
    // `SCALE_RENDER=0` leaves out the SPPM render (quicker A/B runs of the BVH alone).
    let skip_render = std::env::var("SCALE_RENDER").is_ok_and(|v| v == "0");
    let py = python();
    if py.is_none() {
        println!(
            "embreex not found (pip install embreex; SCALE_PYTHON=<python>): Embree columns left out"
        );
    }
    let mut json = String::from("[\n");
    let mut table = String::new();
    let mut rows: Vec<Row> = Vec::new();
    for size in parse_sizes() {
        let dir = root.join(format!("n{size}"));
        std::fs::create_dir_all(&dir).unwrap();
        let mesh = displaced_sphere(size);
        let n = mesh.triangles.len();
        let camera = camera_rays(CAMERA_SIDE);
        let probe = mesh_bvh(triangle_mesh(&mesh));
        let bounce = bounce_rays(&probe, &camera, BOUNCE_RAYS);
        drop(probe);
        write_mesh(&dir.join("mesh.bin"), &mesh);
        write_rays(&dir.join("camera.bin"), &camera);
        write_rays(&dir.join("bounce.bin"), &bounce);
        let mut mine = Figures::default();
        let mut theirs: Option<Figures> = None;
        for _ in 0..rounds {
            mine.best(&ours(&mesh, &camera, &bounce));
            if let Some(p) = &py
                && let Some(f) = embree(p, &dir, n)
            {
                theirs.get_or_insert_with(Figures::default).best(&f);
            }
        }
        let render = if skip_render {
            (f64::NAN, f64::NAN)
        } else {
            render_figures(&dir, &mesh)
        };
        let _ = writeln!(table, "\n{n} triangles");
        let ratio = |a: f64, b: Option<f64>| b.map_or("-".into(), |b| format!("{:.2}x", a / b));
        let _ = writeln!(
            table,
            "  build: {:.3} s wall, {:.3} s CPU; Embree {}; speed ratio (Embree time / ours, wall) {}",
            mine.build_wall,
            mine.build_cpu,
            theirs.as_ref().map_or("-".into(), |t| format!(
                "{:.3} s wall, {:.3} s CPU",
                t.build_wall, t.build_cpu
            )),
            ratio(
                1.0 / mine.build_wall,
                theirs.as_ref().map(|t| 1.0 / t.build_wall)
            ),
        );
        let _ = writeln!(
            table,
            "  memory: {:.0} bytes/triangle; Embree {}; ratio {}",
            mine.bytes_per_triangle,
            theirs
                .as_ref()
                .map_or("-".into(), |t| format!("{:.0}", t.bytes_per_triangle)),
            ratio(
                mine.bytes_per_triangle,
                theirs.as_ref().map(|t| t.bytes_per_triangle)
            ),
        );
        for key in KEYS {
            let m = mine.get(key).unwrap_or(f64::NAN);
            let t = theirs.as_ref().and_then(|t| t.get(key));
            let tn = theirs.as_ref().and_then(|t| t.get_net(key));
            let _ = writeln!(
                table,
                "  {key:18} {:7.2} M rays/s; Embree {} (loop cost out: {}); ratio {} ({})",
                m * 1e-6,
                t.map_or("-".into(), |t| format!("{:.2} M", t * 1e-6)),
                tn.map_or("-".into(), |t| format!("{:.2} M", t * 1e-6)),
                ratio(m, t),
                ratio(m, tn),
            );
        }
        let _ = writeln!(
            table,
            "  render: {:.2} M photons/s, first image after {:.2} s (OBJ read, BVH, one iteration)",
            render.0 * 1e-6,
            render.1
        );
        print!("{table}");
        table.clear();
        let _ = writeln!(
            json,
            "  {{\"triangles\": {n}, \"build_s\": {}, \"bytes_per_triangle\": {}, \"rays\": {{{}}}, \
             \"embree\": {}, \"photons_per_s\": {}, \"first_image_s\": {}}},",
            mine.build_wall,
            mine.bytes_per_triangle,
            mine.rays
                .iter()
                .map(|(k, v)| format!("\"{k}\": {v}"))
                .collect::<Vec<_>>()
                .join(", "),
            theirs.as_ref().map_or("null".into(), |t| format!(
                "{{\"build_s\": {}, \"bytes_per_triangle\": {}, \"rays\": {{{}}}, \"rays_net\": {{{}}}}}",
                t.build_wall,
                t.bytes_per_triangle,
                t.rays
                    .iter()
                    .map(|(k, v)| format!("\"{k}\": {v}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                t.rays_net
                    .iter()
                    .map(|(k, v)| format!("\"{k}\": {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
            render.0,
            render.1
        );
        rows.push(Row {
            triangles: n,
            ours: mine,
            embree: theirs,
            render,
        });
    }
    if json.ends_with(",\n") {
        json.truncate(json.len() - 2);
        json.push('\n');
    }
    json.push_str("]\n");
    if ["SCALE_QUERIES", "SCALE_ONE_THREAD", "SCALE_STACK_PAD"]
        .iter()
        .any(|k| std::env::var_os(k).is_some())
    {
        println!("\n(a SCALE_ knob set: results.json and scale.png left as they were)");
        return;
    }
    std::fs::write(root.join("results.json"), json).unwrap();
    chart(&root.join("scale.png"), &rows);
    println!("\nwrote {}", root.join("results.json").display());
}

fn chart(path: &Path, rows: &[Row]) {
    let series = |label: &str, colour: usize, dash: Dash, f: &dyn Fn(&Row) -> Option<f64>| Series {
        label: label.into(),
        colour: Some(colour),
        dash,
        points: rows
            .iter()
            .filter_map(|r| Some((r.triangles as f64, f(r)?)))
            .filter(|p| p.1.is_finite() && p.1 > 0.0)
            .collect(),
    };
    let spec = |title: &str, y: &str| ChartSpec {
        title: title.into(),
        x_label: "triangles".into(),
        y_label: y.into(),
        log_x: true,
        log_y: true,
        floor: None,
    };
    let mut rays = Vec::new();
    for (k, key) in ["camera/closest/1", "bounce/closest/1", "bounce/any/1"]
        .into_iter()
        .enumerate()
    {
        rays.push(series(&format!("sppm-lang {key}"), k, Dash::Solid, &|c| {
            c.ours.get(key).map(|v| v * 1e-6)
        }));
        rays.push(series(
            &format!("Embree {key} (loop cost out)"),
            k,
            Dash::Dashed,
            &|c| c.embree.as_ref()?.get_net(key).map(|v| v * 1e-6),
        ));
    }
    let panels = vec![
        (spec("Rays per second, 1 thread", "M rays/s"), rays),
        (
            spec("BVH build", "seconds"),
            vec![
                series("sppm-lang (1 thread)", 0, Dash::Solid, &|c| {
                    Some(c.ours.build_wall)
                }),
                series("Embree (all cores)", 0, Dash::Dashed, &|c| {
                    Some(c.embree.as_ref()?.build_wall)
                }),
            ],
        ),
        (
            spec("Memory", "bytes per triangle"),
            vec![
                series("sppm-lang", 0, Dash::Solid, &|c| {
                    Some(c.ours.bytes_per_triangle)
                }),
                series("Embree", 0, Dash::Dashed, &|c| {
                    Some(c.embree.as_ref()?.bytes_per_triangle)
                }),
            ],
        ),
        (
            spec("SPPM render of the mesh", "M photons/s; s to first image"),
            vec![
                series("M photons/s", 0, Dash::Solid, &|c| Some(c.render.0 * 1e-6)),
                series("seconds to first image", 1, Dash::Solid, &|c| {
                    Some(c.render.1)
                }),
            ],
        ),
    ];
    if let Err(e) = draw_panels(&panels, 2, path) {
        eprintln!("chart: {e}");
    }
}
