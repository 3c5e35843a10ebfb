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
//! `benches/photon_rate.sh` times the same pass on two builds.
//!
//! Without valgrind (`cargo bench --bench instructions`) both run once and print their result,
//! so the bench stays built and working. Fewer instructions is not the same as faster (cache
//! misses cost more than instructions in the photon lookup): this complements the timed
//! `render` bench, it does not replace it.

#[path = "../tests/common/mod.rs"]
mod common;

use std::sync::atomic::AtomicBool;

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

fn photons() {
    let scene = common::cornell_glass(256);
    let options = RenderOptions {
        iterations: Some(1),
        photons: Some(200_000),
        seed: Some(1),
        threads: Some(1),
        ..Default::default()
    };
    let cancel = AtomicBool::new(false);
    let out = render(&scene, &options, &cancel, &mut |_| {}).expect("render");
    println!(
        "photons: {} traced, {} deposits (one 256x256 iteration, 1 thread)",
        out.stats.photons, out.stats.deposits
    );
}

/// One SPPM iteration of 200 000 photons on 1 thread, `radius` the initial radius (`None`: the
/// default rule): the workload of `photon-pass` and `photon-pass-fixed`.
fn photon_pass(radius: Option<f64>) {
    let mut scene = common::cornell_glass(256);
    scene.settings.radius = radius;
    let options = RenderOptions {
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
    if all || what.iter().any(|w| w == "photons") {
        photons();
    }
    if all || what.iter().any(|w| w == "photon-pass") {
        photon_pass(None);
    }
    if all || what.iter().any(|w| w == "photon-pass-fixed") {
        photon_pass(Some(0.0111));
    }
}
