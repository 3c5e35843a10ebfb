//! Same seed, 1 thread vs 2 threads: bit-identical image and EXR bytes.

use crate::common;

use std::sync::atomic::AtomicBool;

use sppm_lang::internals::render::{RenderOptions, render};

#[test]
fn one_and_two_threads_give_identical_exr() {
    let scene = common::cornell_glass(24);
    let dir = tempfile::tempdir().unwrap();
    let mut images = Vec::new();
    let mut bytes = Vec::new();
    for threads in [1, 2] {
        let opts = RenderOptions {
            iterations: Some(3),
            photons: Some(30_000),
            seed: Some(42),
            threads: Some(threads),
            ..Default::default()
        };
        let out = render(&scene, &opts, &AtomicBool::new(false), &mut |_| {}).unwrap();
        let path = dir.path().join(format!("t{threads}.exr"));
        out.image.write(&path, 1.0).unwrap();
        bytes.push(std::fs::read(&path).unwrap());
        println!(
            "threads {threads}: mean {:?}, {} deposits",
            out.image.mean(),
            out.stats.deposits
        );
        images.push(out.image);
    }
    let same = images[0]
        .pixels
        .iter()
        .zip(&images[1].pixels)
        .all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits));
    assert!(same, "pixels differ between 1 and 2 threads");
    assert_eq!(bytes[0], bytes[1]);
    // A different seed does change the image (the test could fail).
    let opts = RenderOptions {
        iterations: Some(3),
        photons: Some(30_000),
        seed: Some(43),
        threads: Some(2),
        ..Default::default()
    };
    let other = render(&scene, &opts, &AtomicBool::new(false), &mut |_| {}).unwrap();
    assert_ne!(other.image, images[0]);
}

#[test]
fn cancel_stops_and_progress_reports_each_iteration() {
    let scene = common::cornell_glass(16);
    let cancel = AtomicBool::new(false);
    let mut seen = Vec::new();
    let opts = RenderOptions {
        iterations: Some(10),
        photons: Some(2_000),
        ..Default::default()
    };
    let out = render(&scene, &opts, &cancel, &mut |p| {
        seen.push(p.iteration);
        assert_eq!(p.image().pixels.len(), 256);
        if p.iteration == 3 {
            cancel.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    })
    .unwrap();
    println!("cancelled after {} iterations", out.iterations_done);
    assert!(out.cancelled);
    assert_eq!(out.iterations_done, 3);
    assert_eq!(seen, vec![1, 2, 3]);
}

/// Every integrator, not only SPPM (SPPM and VCM also with final gathering): 1, 2 and 3
/// threads give bit-identical pixels.
#[test]
fn every_integrator_is_independent_of_the_thread_count() {
    let methods = sppm_lang::Integrator::ALL.map(|i| (i, false));
    let gathering = [
        (sppm_lang::Integrator::Sppm, true),
        (sppm_lang::Integrator::Vcm, true),
    ];
    for (integrator, final_gather) in methods.into_iter().chain(gathering) {
        let mut scene = common::cornell_glass(16);
        scene.settings.integrator = Some(integrator);
        scene.settings.final_gather = final_gather;
        let images: Vec<_> = [1, 2, 3]
            .into_iter()
            .map(|threads| {
                let opts = RenderOptions {
                    iterations: Some(2),
                    photons: Some(10_000),
                    seed: Some(9),
                    threads: Some(threads),
                    ..Default::default()
                };
                render(&scene, &opts, &AtomicBool::new(false), &mut |_| {})
                    .unwrap()
                    .image
            })
            .collect();
        let bits = |i: usize| -> Vec<[u64; 3]> {
            images[i]
                .pixels
                .iter()
                .map(|p| p.map(f64::to_bits))
                .collect()
        };
        println!("{}: mean {:?}", integrator.name(), images[0].mean());
        assert!(images[0].mean().iter().all(|m| *m > 0.0));
        assert_eq!(
            bits(0),
            bits(1),
            "{} differs with 2 threads",
            integrator.name()
        );
        assert_eq!(
            bits(0),
            bits(2),
            "{} differs with 3 threads",
            integrator.name()
        );
    }
}

/// SPPM's automatic photon count (no `photons` anywhere, chosen from the pixels and the
/// photons' counted segments): the count of every iteration and the image are the same on 1,
/// 2 and 3 threads.
#[test]
fn the_automatic_photon_count_is_independent_of_the_thread_count() {
    let scene = common::cornell_glass(48);
    assert_eq!(scene.settings.photons, None);
    let runs = counts_and_pixels_on_1_2_3_threads(&scene, 8, 5);
    println!("photons per iteration: {:?}", runs[0].0);
    // 2 x 3 rays per pixel, 2 segments per photon assumed at first: 6912, in chunks of 4096.
    assert_eq!(runs[0].0[0], 8192);
    assert_eq!(runs[0].0.len(), 8);
    for (threads, run) in [(2, &runs[1]), (3, &runs[2])] {
        assert_eq!(
            run.0, runs[0].0,
            "photon counts differ with {threads} threads"
        );
        assert!(run.1 == runs[0].1, "pixels differ with {threads} threads");
    }
}

/// Where the camera part's noise dominates (textures.scn: an environment map's sun), SPPM
/// moves ray casts from the photon pass to the camera pass once both parts' noise is known
/// (`sppm/balance.rs`): fewer photons per iteration than at first. The split, the counts and
/// the image are the same on 1, 2 and 3 threads.
#[test]
fn the_camera_photon_split_is_independent_of_the_thread_count() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/textures.scn");
    let mut scene =
        sppm_lang::internals::eval::load_file(&path, &sppm_lang::EvalOptions::default())
            .unwrap()
            .scene
            .expect("textures.scn loads");
    // Large enough for the photon count to span several chunks of 4096.
    scene.settings.resolution = (128, 96);
    scene.settings.photons = None;
    let runs = counts_and_pixels_on_1_2_3_threads(&scene, 6, 3);
    let counts = &runs[0].0;
    println!("photons per iteration: {counts:?}");
    assert!(
        counts[3..].iter().all(|&n| n < counts[1]),
        "the camera pass took no casts from the photons: {counts:?}"
    );
    for (threads, run) in [(2, &runs[1]), (3, &runs[2])] {
        assert_eq!(
            &run.0, counts,
            "photon counts differ with {threads} threads"
        );
        assert!(run.1 == runs[0].1, "pixels differ with {threads} threads");
    }
}

/// Renders `scene` on 1, 2 and 3 threads: each run's photons per iteration and its pixels'
/// bits.
fn counts_and_pixels_on_1_2_3_threads(
    scene: &sppm_lang::internals::scene::Scene,
    iterations: u32,
    seed: u64,
) -> Vec<(Vec<u64>, Vec<[u64; 3]>)> {
    [1, 2, 3]
        .into_iter()
        .map(|threads| {
            let opts = RenderOptions {
                iterations: Some(iterations),
                seed: Some(seed),
                threads: Some(threads),
                ..Default::default()
            };
            let mut totals = Vec::new();
            let out = render(scene, &opts, &AtomicBool::new(false), &mut |p| {
                totals.push(p.stats.photons)
            })
            .unwrap();
            let per_iteration = totals
                .iter()
                .scan(0, |before, &t| {
                    let n = t - *before;
                    *before = t;
                    Some(n)
                })
                .collect();
            let bits = out.image.pixels.iter().map(|p| p.map(f64::to_bits));
            (per_iteration, bits.collect())
        })
        .collect()
}

/// VCM, BPT and light tracing with several chunks of light paths (48x48 pixels: three chunks
/// of 1024 light paths) and their splats, over three iterations (the third has the extra camera
/// paths that the first two's samples allocate): 1 and 2 threads give bit-identical pixels.
/// VCM runs 14 iterations, past the 12 that choose its count of light paths from the pixels.
#[test]
fn vcm_splats_are_independent_of_the_thread_count() {
    use sppm_lang::Integrator;
    for integrator in [Integrator::Vcm, Integrator::Bpt, Integrator::Lt] {
        let mut scene = common::cornell_glass(48);
        scene.settings.integrator = Some(integrator);
        let iterations = if integrator == Integrator::Vcm { 14 } else { 3 };
        let images: Vec<_> = [1, 2]
            .into_iter()
            .map(|threads| {
                let opts = RenderOptions {
                    iterations: Some(iterations),
                    seed: Some(5),
                    threads: Some(threads),
                    ..Default::default()
                };
                render(&scene, &opts, &AtomicBool::new(false), &mut |_| {})
                    .unwrap()
                    .image
            })
            .collect();
        assert!(images[0].mean().iter().all(|m| *m > 0.0));
        let same = images[0]
            .pixels
            .iter()
            .zip(&images[1].pixels)
            .all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits));
        assert!(same, "{} differs with 2 threads", integrator.name());
    }
}
