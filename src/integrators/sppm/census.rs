//! Measurement (not a check): where an SPPM iteration's photons go and how many reach a visible
//! point, with the visible points' radii, on the Cornell box and on `smallppm_far`. Run:
//!
//!     cargo test --release --lib sppm::census -- --ignored --nocapture

use glam::Vec3A;

use super::grid::{Cells, HitChunk, PhotonGrid, PhotonHit};
use crate::camera::Camera;
use crate::integrators::common::camera_path::camera_path;
use crate::integrators::common::photons::trace_photon;
use crate::integrators::common::streams::Stream;
use crate::prepare::{EffectiveSettings, PreparedScene, RenderOptions, effective_settings};
use crate::scene::Scene;
use crate::{EvalOptions, load_file};

fn example(name: &str) -> (Scene, EffectiveSettings) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(format!("{name}.scn"));
    let scene = load_file(&path, &EvalOptions::default())
        .unwrap()
        .scene
        .unwrap();
    let settings = effective_settings(&scene, &RenderOptions::default()).unwrap();
    (scene, settings)
}

fn quantiles(mut v: Vec<f64>) -> String {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return "-".into();
    }
    let q = |f: f64| v[((v.len() - 1) as f64 * f) as usize];
    format!(
        "p5 {:.3e} p50 {:.3e} p95 {:.3e} mean {:.3e}",
        q(0.05),
        q(0.5),
        q(0.95),
        v.iter().sum::<f64>() / v.len() as f64
    )
}

/// One iteration's photons on an example at `1 / shrink` of its resolution (with `1 / shrink^2`
/// of its photons, so that the photons per pixel stay the same), every pixel's radius from
/// `radius(distance)` (the camera path's length to its visible point).
struct Census {
    pixels: u32,
    photons: u64,
    radii: Vec<f64>,
    distances: Vec<f64>,
    /// Photons within each visible point's radius.
    per_point: Vec<f64>,
    segments: u64,
    hits: u64,
    in_bounds: u64,
    /// Hits within at least one visible point's radius.
    useful: u64,
    hit_flux: f64,
}

fn census(
    name: &str,
    shrink: u32,
    radius: impl Fn(&EffectiveSettings, f64) -> Option<f64>,
) -> Census {
    let (mut scene, settings) = example(name);
    let (w, h) = (settings.width / shrink, settings.height / shrink);
    scene.settings.resolution = (w, h);
    let options = RenderOptions {
        photons: Some(settings.photons / u64::from(shrink * shrink)),
        ..Default::default()
    };
    let settings = effective_settings(&scene, &options).unwrap();
    let scene = PreparedScene::new(&scene).unwrap();
    let camera = Camera::new(&scene.scene.camera, w, h).unwrap();
    let (mut vps, mut radii, mut distances) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..w * h {
        let mut rng = Stream::Camera.rng(1, 0, u64::from(i));
        if let (_, Some(vp)) = camera_path(&scene, &camera, &settings, i % w, i / w, &mut rng)
            && let Some(r) = radius(&settings, f64::from(vp.distance))
        {
            radii.push(r);
            distances.push(f64::from(vp.distance));
            vps.push((vp, r as f32));
        }
    }
    let cells = Cells::new(vps.iter().map(|(vp, r)| (vp.p, *r))).unwrap();
    let mut chunk = HitChunk::default();
    chunk.reset(&cells);
    let (mut hits, mut in_bounds, mut segments, mut hit_flux) = (0u64, 0u64, 0u64, 0.0f64);
    for i in 0..settings.photons {
        let mut rng = Stream::Photon.rng(1, 0, i);
        trace_photon(
            &scene,
            settings.max_depth,
            &mut rng,
            |depth, sh, _, beta| {
                segments += 1;
                if depth == 0 {
                    return;
                }
                hits += 1;
                hit_flux += f64::from(beta.element_sum() / 3.0);
                in_bounds += u64::from(cells.contains(sh.hit.p));
                // The hit's index rides in `wi.x` (only counted here, never shaded).
                let wi = Vec3A::new(hits as f32, 0.0, 0.0);
                chunk.push(
                    &cells,
                    PhotonHit {
                        p: sh.hit.p,
                        wi,
                        beta,
                    },
                );
            },
        );
    }
    let mut grid = PhotonGrid::default();
    grid.build(cells, std::slice::from_ref(&chunk));
    let mut used = vec![false; hits as usize + 1];
    let mut per_point = Vec::with_capacity(vps.len());
    for (vp, r) in &vps {
        // Every photon within the radius (the BSDF keeps those on the point's side: on walls
        // nearly all).
        let mut found = 0u64;
        grid.for_each_within(vp.p, r * r, |tag, _| {
            found += 1;
            used[tag.x as usize] = true;
        });
        per_point.push(found as f64);
    }
    Census {
        pixels: w * h,
        photons: settings.photons,
        radii,
        distances,
        per_point,
        segments,
        hits,
        in_bounds,
        useful: used.iter().filter(|&&u| u).count() as u64,
        hit_flux,
    }
}

/// The default rule: one pixel footprint at each pixel's first visible point.
fn footprint(
    settings: &EffectiveSettings,
    distance: f64,
    camera: &crate::scene::Camera,
) -> Option<f64> {
    settings.initial_radius(camera).at(distance)
}

#[test]
#[ignore = "measurement; prints a table"]
fn photon_census() {
    for name in ["cornell", "smallppm_far"] {
        let camera = example(name).0.camera;
        let c = census(name, 1, |s, d| footprint(s, d, &camera));
        let n = c.photons as f64;
        let empty = c.per_point.iter().filter(|&&f| f == 0.0).count();
        let points = c.per_point.len();
        let deposits: f64 = c.per_point.iter().sum();
        println!("== {name}: {} pixels, {} photons", c.pixels, c.photons);
        println!(
            "  visible points {points}; distance {}",
            quantiles(c.distances)
        );
        println!("  initial radius {}", quantiles(c.radii));
        println!(
            "  per photon: ray casts {:.3}, stored hits (depth>0) {:.3}, within the points' \
             bounds {:.3}, within some point's radius {:.4}, deposits {:.4}",
            c.segments as f64 / n,
            c.hits as f64 / n,
            c.in_bounds as f64 / n,
            c.useful as f64 / n,
            deposits / n
        );
        println!(
            "  hits used {:.2} %; mean flux per stored hit {:.4}",
            100.0 * c.useful as f64 / c.hits as f64,
            c.hit_flux / c.hits as f64
        );
        println!(
            "  photons per visible point per iteration: {}; points with none {:.2} %",
            quantiles(c.per_point),
            100.0 * empty as f64 / points as f64
        );
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// With smallpt's camera (`smallppm_far`: look_at 100 units ahead, the objects about 235 away)
/// the visible points must gather at least as many photons per iteration as the Cornell box's
/// at the same photons per pixel (measured at full size: 6.7 against 3.6 on average), so that
/// its remaining noise comes from the scene (more indirect light, longer photon paths), not
/// from radii too small for the photons. The earlier rule, one footprint at the look-at
/// distance, starved it (a quarter of the area: the test checks it would fail).
#[test]
fn far_look_at_points_gather_as_many_photons_as_the_cornell_box() {
    let cornell_camera = example("cornell").0.camera;
    let far_camera = example("smallppm_far").0.camera;
    let cornell = mean(&census("cornell", 4, |s, d| footprint(s, d, &cornell_camera)).per_point);
    let far = mean(&census("smallppm_far", 4, |s, d| footprint(s, d, &far_camera)).per_point);
    let look_at = (far_camera.look_at - far_camera.location).length();
    let old = mean(
        &census("smallppm_far", 4, |s, _| {
            let pixel = 2.0 * (0.5 * far_camera.fov.to_radians()).tan() / f64::from(s.height);
            Some(pixel * look_at)
        })
        .per_point,
    );
    println!(
        "photons per point: cornell {cornell:.2}, smallppm_far {far:.2} (look-at rule {old:.2})"
    );
    assert!(far >= 1.2 * cornell, "{far} against {cornell}");
    assert!(
        old < 0.8 * cornell,
        "the look-at rule gave {old} against {cornell}"
    );
}

/// Seed-to-seed noise of two renders, split into the camera part (emitted + direct light) and
/// the photon part (`tau / (N_e pi r^2)`): mean over pixels and channels of
/// `(a - b)^2 / 2 / (m^2 + 0.01)`, `m` the two renders' mean (an estimate of one render's
/// relative MSE, as `src/compare` weighs it). Iterations as at about 100 us of CPU per pixel.
#[test]
#[ignore = "measurement; prints a table"]
fn noise_split() {
    for (name, iterations) in [("cornell", 64), ("smallppm_far", 22)] {
        let (mut scene, _) = example(name);
        scene.settings.iterations = iterations;
        let mut parts = Vec::new();
        for seed in [1, 2] {
            let options = RenderOptions {
                seed: Some(seed),
                ..Default::default()
            };
            let settings = effective_settings(&scene, &options).unwrap();
            let prepared = PreparedScene::new(&scene).unwrap();
            let (out, stats) = super::render_with_state(
                &prepared,
                &settings,
                &std::sync::atomic::AtomicBool::new(false),
                &mut |_| {},
            );
            let np = settings.photons as f64 * f64::from(out.iterations_done);
            let total: Vec<[f64; 3]> = out.image.pixels.iter().map(|p| p.map(f64::from)).collect();
            let indirect: Vec<[f64; 3]> = stats
                .iter()
                .map(|s| {
                    let area = std::f64::consts::PI * s.radius * s.radius;
                    s.tau
                        .map(|t| if area > 0.0 { t / (np * area) } else { 0.0 })
                })
                .collect();
            parts.push((total, indirect));
        }
        let ((ta, ia), (tb, ib)) = (&parts[0], &parts[1]);
        let (mut total, mut photon, mut camera, mut share) = (0.0, 0.0, 0.0, 0.0);
        let n = (ta.len() * 3) as f64;
        for i in 0..ta.len() {
            for c in 0..3 {
                let m = 0.5 * (ta[i][c] + tb[i][c]);
                let w = 0.5 / (m * m + 0.01);
                total += (ta[i][c] - tb[i][c]).powi(2) * w / n;
                photon += (ia[i][c] - ib[i][c]).powi(2) * w / n;
                let (da, db) = (ta[i][c] - ia[i][c], tb[i][c] - ib[i][c]);
                camera += (da - db).powi(2) * w / n;
                share += 0.5 * (ia[i][c] + ib[i][c]) / (m.max(1e-9) * n);
            }
        }
        println!(
            "{name}: {iterations} it: relative noise total {total:.5}, photon part {photon:.5}, \
             camera part {camera:.5}; photon part's mean share of a pixel {share:.3}"
        );
    }
}
