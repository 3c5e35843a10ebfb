//! Fixed workloads for counting instructions, the one speed measure that does not move with
//! the machine's load: run the binary under `valgrind --tool=callgrind` (or cachegrind) and
//! compare the totals of two builds. Timings on the shared 2-core machines move 10-40 % between
//! runs, which hides changes of a few percent; instruction counts repeat exactly.
//!
//! ```text
//! cargo bench --bench instructions --no-run     # prints the executable's path
//! valgrind --tool=callgrind <path> rays         # 200 000 BVH rays in the Cornell box
//! valgrind --tool=callgrind <path> photons      # one SPPM iteration, 1 thread: camera pass
//!                                               # (65 536 pixels) and 200 000 photons
//! ```
//!
//! Instructions per photon of the photon pass alone (tracing, filing, grid build, gathers;
//! not the camera pass), the photon pass's regression guard: collect only inside
//! `PhotonPass::run` and divide the total by the 200 000 photons it prints.
//!
//! ```text
//! valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*PhotonPass::run' \
//!     <path> photon-pass            # the default initial radius (1.5 pixel footprints)
//! valgrind ... <path> photon-pass-fixed   # radius 0.0111 (benches/pbrt_compare's)
//! ```
//!
//! Mesh rays, the scale bench's displaced sphere of 10^5 triangles (`benches/scale.rs`): 65 536
//! camera rays (a 256x256 view of it) or 65 536 diffuse bounces from their hits, each traced
//! for the closest hit (with the full hit record, as `Bvh::intersect` returns it; and, in
//! `trace_record`, with the record Embree returns, as the scale bench asks for it: `t`, the
//! barycentrics, the triangle and the geometric normal) and for any hit. The tracing loops are functions of their own: read their inclusive counts (the mesh's
//! build and the ray sets are left out).
//!
//! ```text
//! valgrind --tool=callgrind --callgrind-out-file=cg.out <path> mesh-camera   # or mesh-bounce
//! callgrind_annotate --inclusive=yes cg.out | grep trace_
//! ```
//!
//! `spheres`: 20 000 small spheres in the mesh's place, the same 65 536 camera rays, the same
//! tracing loops: a BVH whose leaves hold shapes (the mesh's hold only triangle packets).
//!
//! `benches/photon_rate.sh` times the same pass on two builds.
//!
//! Without valgrind (`cargo bench --bench instructions`) both run once and print their result,
//! so the bench stays built and working. Fewer instructions is not the same as faster (cache
//! misses cost more than instructions in the photon lookup): this complements the timed
//! `render` bench, it does not replace it.

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "support/displaced.rs"]
mod displaced;

use std::sync::atomic::AtomicBool;

use sppm_lang::internals::accel::Bvh;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::render::{PreparedScene, RenderOptions, render};

fn rays() {
    let scene = common::cornell_glass(256);
    let prepared = PreparedScene::new(&scene).expect("cornell scene");
    let hits = common::cornell_rays(200_000)
        .iter()
        .filter(|ray| prepared.intersect(ray, f32::INFINITY).is_some())
        .count();
    println!("rays: 200000 cast, {hits} hit");
}

/// One SPPM iteration of 200 000 photons on 1 thread, `radius` the initial radius (`None`: the
/// default rule): the workload of `photon-pass` and `photon-pass-fixed`.
fn photon_pass(radius: Option<f64>) {
    let mut scene = common::cornell_glass(256);
    scene.settings.radius = radius;
    let options = RenderOptions {
        integrator: Some(sppm_lang::Integrator::Sppm),
        iterations: Some(1),
        photons: Some(200_000),
        seed: Some(1),
        threads: Some(1),
        ..Default::default()
    };
    let cancel = AtomicBool::new(false);
    let out = render(&scene, &options, &cancel, &mut |_| {}).expect("render");
    println!(
        "photon pass (radius {}): {} photons, {} deposits",
        radius.map_or("default".to_string(), |r| r.to_string()),
        out.stats.photons,
        out.stats.deposits
    );
}

/// Closest hits (full records) of `rays`: how many hit, and a sum of their points and
/// normals (so that the record is computed, and two builds' results can be compared).
#[inline(never)]
fn trace_closest(bvh: &Bvh, rays: &[Ray]) -> (usize, f64) {
    let mut sum = 0.0f64;
    let mut hits = 0;
    for ray in rays {
        if let Some((h, _)) = bvh.intersect(ray, 0.0, f32::INFINITY) {
            hits += 1;
            sum += f64::from(h.t + h.p.element_sum() + h.n.element_sum() + h.ns.element_sum());
        }
    }
    (hits, sum)
}

/// Closest hits of `rays` with the record Embree returns (`Bvh::intersect_ng`: the triangle's
/// unnormalised geometric normal beside the lazy hit, as the scale bench's closest-hit query):
/// how many hit, and a sum of their `t`, barycentrics and normals.
#[inline(never)]
fn trace_record(bvh: &Bvh, rays: &[Ray]) -> (usize, f64) {
    use sppm_lang::internals::accel::Surface;
    let mut sum = 0.0f64;
    let mut hits = 0;
    for ray in rays {
        if let Some((lazy, Surface::MeshTriangle(_, _, b), _, ng)) =
            bvh.intersect_ng(ray, 0.0, f32::INFINITY)
        {
            hits += 1;
            sum += f64::from(lazy.t() + b[0] + b[1] + ng.element_sum());
        }
    }
    (hits, sum)
}

/// How many of `rays` hit anything.
#[inline(never)]
fn trace_any(bvh: &Bvh, rays: &[Ray]) -> usize {
    rays.iter()
        .filter(|ray| bvh.occluded(ray, 0.0, f32::INFINITY))
        .count()
}

/// The `mesh-camera` (`bounce` false) or `mesh-bounce` workload.
fn mesh_rays(bounce: bool) {
    let mesh = displaced::displaced_sphere(100_000);
    let bvh = displaced::mesh_bvh(displaced::triangle_mesh(&mesh));
    let camera = displaced::camera_rays(256);
    let rays = if bounce {
        displaced::bounce_rays(&bvh, &camera, camera.len())
    } else {
        camera
    };
    let (hits, sum) = trace_closest(&bvh, &rays);
    let any = trace_any(&bvh, &rays);
    let (records, record_sum) = trace_record(&bvh, &rays);
    println!(
        "mesh {}: {} rays, {hits} closest hits (sum {sum:.6}), {any} any hits, {records} \
         closest records (sum {record_sum:.6})",
        if bounce { "bounce" } else { "camera" },
        rays.len()
    );
}

/// The `spheres` workload: 20 000 small spheres scattered in the displaced sphere's place, so
/// that the BVH's leaves hold shapes (leaves with a record, unlike a mesh's), traced with the
/// `mesh-camera` rays for the closest and any hit.
fn spheres() {
    use sppm_lang::internals::shapes::primitive::AnyShape;
    use sppm_lang::internals::shapes::sphere::Sphere;
    let mut rnd = displaced::uniform_floats(0x9e3779b97f4a7c15);
    let shapes: Vec<(AnyShape, u32)> = (0..20_000)
        .map(|k| {
            let c = glam::Vec3A::new(rnd(), rnd(), rnd()) * 2.0 - 1.0;
            let sphere = Sphere::new(c, 0.01 + 0.03 * rnd()).expect("a positive radius");
            (AnyShape::Sphere(sphere), k)
        })
        .collect();
    let bvh = Bvh::new(shapes).expect("a BVH of bench size");
    let rays = displaced::camera_rays(256);
    let (hits, sum) = trace_closest(&bvh, &rays);
    let any = trace_any(&bvh, &rays);
    println!(
        "spheres camera: {} rays, {hits} closest hits (sum {sum:.6}), {any} any hits",
        rays.len()
    );
}

fn main() {
    // `cargo bench` passes `--bench`; ignore flags.
    let what: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let all = what.is_empty();
    if all || what.iter().any(|w| w == "rays") {
        rays();
    }
    // `photons` is the older name of `photon-pass`.
    if all || what.iter().any(|w| w == "photon-pass" || w == "photons") {
        photon_pass(None);
    }
    if all || what.iter().any(|w| w == "photon-pass-fixed") {
        photon_pass(Some(0.0111));
    }
    if all || what.iter().any(|w| w == "mesh-camera") {
        mesh_rays(false);
    }
    if all || what.iter().any(|w| w == "mesh-bounce") {
        mesh_rays(true);
    }
    if all || what.iter().any(|w| w == "spheres") {
        spheres();
    }
}
