//! Golden-image tests: every example scene rendered small, with a fixed seed and iteration count,
//! compared in linear space with a reference stored in `tests/golden/`.
//!
//! Run: `cargo test --test render golden::`. Re-bless after an intended change:
//! `SPPM_BLESS=1 cargo test --test render golden::` (writes `tests/golden/<scene>.exr`, a `.png` for eyes,
//! and `<scene>.noise`, the measured seed-to-seed noise and the tolerances derived from it).
//! Without `SPPM_BLESS` a missing reference is a failure, never a silent bless.
//!
//! **Settings**: [`WIDTH`] pixels wide (height from the scene's aspect), [`ITERATIONS`]
//! iterations of [`PHOTONS`] photons, seed [`SEED`]; everything else as the scene says.
//!
//! **Metrics** (linear RGB, `sppm_lang::compare`):
//! - `rel_mse`: mean of `(x - ref)^2 / (ref^2 + 0.01)` over channels and over the best 99% of
//!   pixels (single fireflies made the plain mean vary 60-fold between seeds in `caustics`);
//! - `bad_share`: share of pixels whose channel-averaged relative difference
//!   `|x - ref| / (ref + 0.05)` exceeds [`BAD_PIXEL`] (catches a local change, e.g. one object);
//! - `mean_rel`: largest relative difference of the image mean over the three channels
//!   (catches a global change, e.g. a light 10% brighter, that per-pixel noise would hide).
//!
//! **Tolerances from measured noise**: when blessing, the scene is rendered with seed [`SEED`]
//! (the reference) and with [`NOISE_SEEDS`] other seeds; each metric is measured between every
//! other-seed render and the reference. The tolerance is the largest measured value times
//! [`FACTOR_PIXELS`] (`rel_mse`, `bad_share`: averages over thousands of pixels, their spread
//! between seeds is small) or [`FACTOR_MEAN`] (`mean_rel`: a single number per channel, more
//! spread), with small floors. So a change that only consumes random numbers differently passes,
//! and a change of a material or a light by more than the noise fails. The numbers are stored in
//! `tests/golden/<scene>.noise` and printed by every run.
//!
//! Measured at bless time (2026-11-25 04:40, all scenes re-blessed; seeds 2..=6 against seed
//! 1, the largest of the five; tolerance = 1.5x / 1.5x / 3x these, see each `.noise` file for
//! the single seeds):
//!
//! | scene | rel_mse | bad_share | mean_rel |
//! |---|---|---|---|
//! | caustics | 3.0e-3 | 0.23% | 0.40% |
//! | cornell | 2.7e-3 | 0.22% | 1.4% |
//! | crystal_tree | 3.7e-3 | 0.66% | 0.71% |
//! | furnace | 5.0e-3 | 0% | 0.32% |
//! | room | 3.7e-3 | 0.20% | 0.85% |
//! | smallppm | 3.1e-3 | 0.07% | 0.42% |
//! | smallppm_far | 4.7e-3 | 0.29% | 0.39% |
//! | textures (HDR sky: sun shadows are noisy at 16 iterations) | 3.3e-2 | 1.5% | 0.96% |
//! | vase | 3.0e-3 | 0.36% | 0.38% |
//! | teapot | 3.9e-3 | 0.20% | 0.22% |
//! | csg (a dim fill light: noisy at 64 px) | 4.7e-2 | 6.6% | 2.9% |
//! | goblet | 2.4e-3 | 0.24% | 1.0% |
//! | materials (re-blessed 2026-11-29, coated model; rough metals and plastics are grainy at 64 px) | 6.2e-2 | 5.7% | 1.3% |
//! | shapes (blessed 2026-11-29 08:25, new) | 8.5e-3 | 0.52% | 0.77% |
//!
//! The 2026-11-29 re-bless of `materials` only: `coated` now dims a coloured base at every
//! bounce between base and coat (`1 - c Ri`) and lets through the coat's transmission albedo,
//! chosen against a random walk through the layer (docs/measurements.md, "Coated against a
//! random walk"); the plastic and glaze rows are darker and more saturated. Seed-to-seed noise
//! after: rel_mse 6.2e-2, bad_share 5.7 %, mean_rel 1.3 %.
//!
//! The 2026-11-26 12:10 re-bless of `textures` only: the `planar` mapping showed its image
//! mirrored seen from -z (`u` grew toward +x); the back wall's wood runs the other way now. The
//! old reference passed within the scene's loose tolerance. Seed-to-seed noise after: rel_mse
//! 3.3e-2, bad_share 1.5 %, mean_rel 0.96 % (7.5e-2, 5.6 %, 0.98 % at the last bless).
//!
//! The 2026-11-25 09:30 re-bless of `vase` and `textures` only: the `cylindrical` and
//! `spherical` image mappings, a sphere's own `uv` and the environment map showed their images
//! mirrored (u ran the wrong way round for a right-handed camera; the sphere's `uv` was also
//! upside down; `tools/reference/conformance.py` against Mitsuba 3 found it). The vase's tiles
//! and the globe and uv-mapped ball of `textures` changed relative to the old references;
//! `sky.hdr` was regenerated so that its sun lights from the same direction. The old `vase`
//! reference failed (rel_mse 5.0e-3 > 4.6e-3, bad_share 1.1 % > 0.54 %); `textures` passed
//! within its loose tolerance. Seed-to-seed noise after: vase rel_mse 3.1e-3, bad_share 0.36 %,
//! mean_rel 0.49 %; textures 7.5e-2, 5.6 %, 0.98 %.
//!
//! Why the 04:40 re-bless: the default initial radius grew from 1 to 1.5 pixel footprints
//! (`RADIUS_FOOTPRINTS`, chosen on every example at equal CPU time, docs/integrators.md). The
//! seed-to-seed rel_mse fell on every scene: furnace 1.0e-2 -> 5.0e-3, smallppm 6.0e-3 ->
//! 3.1e-3, smallppm_far 8.9e-3 -> 4.7e-3, cornell 4.4e-3 -> 2.7e-3, caustics 4.8e-3 ->
//! 3.0e-3, crystal_tree 5.9e-3 -> 3.7e-3, goblet 3.7e-3 -> 2.4e-3, vase 4.4e-3 -> 3.0e-3,
//! room 4.8e-3 -> 3.7e-3, teapot 4.8e-3 -> 3.9e-3, textures 8.2e-2 -> 7.6e-2, csg 4.8e-2 ->
//! 4.7e-2. Every old reference still passed with the new radius, but with tolerances up to
//! 3x the new noise. (The examples that no longer set `photons` do not change these renders:
//! the test sets [`PHOTONS`].)
//!
//! The 2026-11-24 23:15 re-bless: two defaults changed the noise. Each pixel's initial radius
//! became one footprint at its own first visible point (it was one footprint at the look-at
//! distance), and SPPM began to trace extra camera samples for the emitted and direct light where
//! they vary most. The seed-to-seed noise fell on every scene but the furnace (which has no
//! direct light to resample and sets its own radius): rel_mse smallppm 2.4e-2 -> 6.0e-3,
//! room 1.3e-2 -> 4.8e-3, teapot 1.2e-2 -> 4.8e-3, crystal_tree 1.1e-2 -> 5.9e-3, textures
//! 1.5e-1 -> 8.2e-2, cornell 6.1e-3 -> 4.4e-3, caustics 7.9e-3 -> 4.8e-3. The old tolerances
//! were 1.4-4x the new noise: a regression of that size would have passed. (Before the
//! re-bless every old reference still passed.)
//!
//! The earlier re-bless (2026-11-24, morning): the first references (2026-11-22, 08:28) were
//! measured before the default initial radius became one pixel footprint at the look-at
//! distance (09:43). Where that shrank the radius at 64 px (furnace: 0.035 -> 0.018) the noise
//! grew (furnace 3.1e-3 -> 1.0e-2), where it grew it the noise fell (cornell 8.2e-3 ->
//! 6.1e-3), and scenes with their own radius did not move. The furnace still passed only
//! because the test renders with its reference's seed, so their noise was mostly shared: a
//! change that used the random numbers differently, with the same accuracy (checked against
//! the exact answer at 8 seeds), failed it. Tolerances are only right for the settings they
//! were measured with: re-bless after a change of the defaults.
//!
//! Deliberate changes fail, and [`deliberate_material_and_light_changes_fail_with_a_report`]
//! checks it on every run: the Cornell box's red wall made blue gives rel_mse 5.0e-2 (tol
//! 4.0e-3), bad_share 8.2% (tol 0.33%), mean_rel 20% (tol 4.1%); its light 15% dimmer gives
//! rel_mse 8.0e-3 (tol 4.0e-3), mean_rel 15.0% (tol 4.1%); (measured once by hand, before the re-bless) the caustics light
//! 17% dimmer gave rel_mse 1.8e-2 (tolerance now 1.2e-2), mean_rel 16.6% (now 5.4%).
//!
//! Because the renderer is deterministic per seed, an unchanged renderer reproduces the
//! reference exactly (all metrics 0); a renderer change that stays within the noise passes
//! without a re-bless, but a change of the defaults (radius, photons) changes the noise itself
//! and needs one (see above). [`checksum_is_unchanged`] additionally pins one small
//! render bit for bit, to catch *any* unintended change.
//!
//! On failure the test writes expected / actual / difference PNGs and an HTML report into
//! `target/golden-report/` and prints the path.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use sppm_lang::EvalOptions;
use sppm_lang::Image;
use sppm_lang::internals::compare::{self, ImageView};
use sppm_lang::internals::eval::load_file;
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::scene::{ColorParam, ColorSpace, Material, Scene, load_image};

/// Image width of every golden render; the height follows the scene's aspect ratio.
const WIDTH: u32 = 64;
const ITERATIONS: u32 = 16;
const PHOTONS: u64 = 40_000;
/// Seed of the reference renders.
const SEED: u64 = 1;
/// Seeds rendered at bless time to measure seed-to-seed noise.
const NOISE_SEEDS: [u64; 5] = [2, 3, 4, 5, 6];
/// Tolerance = FACTOR x largest measured seed-to-seed value.
const FACTOR_PIXELS: f64 = 1.5;
const FACTOR_MEAN: f64 = 3.0;
/// A pixel is "bad" when its relative difference exceeds this.
const BAD_PIXEL: f32 = 0.5;
const BAD_EPS: f32 = 0.05;
/// Share of pixels (the best ones) the relative MSE averages over.
const TRIM_KEEP: f64 = 0.99;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn golden_dir() -> PathBuf {
    root().join("tests/golden")
}

fn report_dir() -> PathBuf {
    root().join("target/golden-report")
}

fn blessing() -> bool {
    std::env::var_os("SPPM_BLESS").is_some_and(|v| !v.is_empty() && v != "0")
}

/// Loads `examples/<name>.scn` and shrinks it to the golden resolution. `None`: the file is
/// missing (the scene is skipped with a message).
fn load_example(name: &str) -> Option<Scene> {
    let path = root().join("examples").join(format!("{name}.scn"));
    if !path.exists() {
        return None;
    }
    let loaded = load_file(&path, &EvalOptions::default())
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let errors: Vec<String> = loaded
        .diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| format!("{d:?}"))
        .collect();
    let mut scene = loaded
        .scene
        .unwrap_or_else(|| panic!("{} has errors: {errors:#?}", path.display()));
    let (w, h) = scene.settings.resolution;
    let height = ((WIDTH as f64 * h as f64 / w as f64).round() as u32).max(1);
    scene.settings.resolution = (WIDTH, height);
    scene.settings.time_limit = None;
    Some(scene)
}

fn render_with(scene: &Scene, seed: u64, iterations: u32, photons: u64) -> Image {
    let opts = RenderOptions {
        iterations: Some(iterations),
        photons: Some(photons),
        seed: Some(seed),
        ..Default::default()
    };
    render(scene, &opts, &AtomicBool::new(false), &mut |_| {})
        .unwrap_or_else(|e| panic!("render failed: {e}"))
        .image
}

fn to_f32(img: &Image) -> Vec<[f32; 3]> {
    img.pixels.iter().map(|p| p.map(|v| v as f32)).collect()
}

#[derive(Debug, Clone, Copy, Default)]
struct Metrics {
    rel_mse: f64,
    bad_share: f64,
    mean_rel: f64,
}

fn metrics(image: ImageView<'_>, reference: ImageView<'_>) -> Metrics {
    let e = compare::error(image, reference, None).expect("same size");
    let diffs = compare::pixel_relative_differences(image, reference, BAD_EPS).expect("same size");
    let bad = diffs
        .iter()
        .filter(|d| d.is_nan() || **d > BAD_PIXEL)
        .count();
    let mean = |v: ImageView<'_>| {
        let n = v.pixels.len().max(1) as f64;
        let mut m = [0.0f64; 3];
        for p in v.pixels {
            for c in 0..3 {
                m[c] += p[c] as f64 / n;
            }
        }
        m
    };
    let (mi, mr) = (mean(image), mean(reference));
    let mean_rel = (0..3)
        .map(|c| (mi[c] - mr[c]).abs() / (mr[c].abs() + 1e-3))
        .fold(0.0, f64::max);
    // Relative MSE over the best 99% of pixels: single fireflies (caustic paths found by a
    // few photons) make the plain mean heavy-tailed from seed to seed; outliers are what
    // `bad_share` counts.
    let mut per_pixel: Vec<f64> = image
        .pixels
        .iter()
        .zip(reference.pixels)
        .map(|(p, r)| {
            (0..3)
                .map(|c| {
                    let (v, rv) = (p[c] as f64, r[c] as f64);
                    let d = v - rv;
                    let q = d * d / (rv * rv + 0.01);
                    if q.is_finite() { q } else { f64::INFINITY }
                })
                .sum::<f64>()
                / 3.0
        })
        .collect();
    per_pixel.sort_by(f64::total_cmp);
    let keep = (per_pixel.len() as f64 * TRIM_KEEP).ceil() as usize;
    let kept = &per_pixel[..keep.min(per_pixel.len())];
    let rel_mse = kept.iter().sum::<f64>() / kept.len().max(1) as f64;
    Metrics {
        rel_mse: rel_mse + e.non_finite as f64,
        bad_share: bad as f64 / diffs.len().max(1) as f64,
        mean_rel,
    }
}

/// The `<scene>.noise` file: measured noise and tolerances, `key = value` lines.
fn write_noise(path: &Path, measured: &[Metrics], tol: &Metrics) {
    let max = |f: fn(&Metrics) -> f64| measured.iter().map(f).fold(0.0, f64::max);
    let mut text = format!(
        "# Seed-to-seed noise measured by `SPPM_BLESS=1 cargo test --test render golden::`:\n\
         # seeds {NOISE_SEEDS:?} against seed {SEED}, {WIDTH} px wide, {ITERATIONS} iterations, \
         {PHOTONS} photons.\n"
    );
    for (s, m) in NOISE_SEEDS.iter().zip(measured) {
        text += &format!(
            "# seed {s}: rel_mse {:.3e}, bad_share {:.4}, mean_rel {:.3e}\n",
            m.rel_mse, m.bad_share, m.mean_rel
        );
    }
    text += &format!(
        "noise_rel_mse = {:e}\nnoise_bad_share = {:e}\nnoise_mean_rel = {:e}\n",
        max(|m| m.rel_mse),
        max(|m| m.bad_share),
        max(|m| m.mean_rel)
    );
    text += &format!(
        "tol_rel_mse = {:e}\ntol_bad_share = {:e}\ntol_mean_rel = {:e}\n",
        tol.rel_mse, tol.bad_share, tol.mean_rel
    );
    std::fs::write(path, text).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
}

fn read_noise(path: &Path) -> Result<BTreeMap<String, f64>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut map = BTreeMap::new();
    for line in text.lines() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (k, v) = line
            .split_once('=')
            .ok_or_else(|| format!("{}: bad line `{line}`", path.display()))?;
        let v: f64 = v
            .trim()
            .parse()
            .map_err(|_| format!("{}: bad number in `{line}`", path.display()))?;
        map.insert(k.trim().to_string(), v);
    }
    Ok(map)
}

fn missing_reference(what: &Path) -> ! {
    panic!(
        "golden reference {} is missing.\n\
         If this scene is new or its change is intended, write the references with\n\
         \n    SPPM_BLESS=1 cargo test --test render golden::\n\n\
         then look at tests/golden/*.png and commit them.",
        what.display()
    )
}

fn bless(name: &str, scene: &Scene, image: &Image) {
    let dir = golden_dir();
    std::fs::create_dir_all(&dir).unwrap();
    image.write(&dir.join(format!("{name}.exr")), 1.0).unwrap();
    image
        .write(&dir.join(format!("{name}.png")), scene.settings.exposure)
        .unwrap();
    let reference = to_f32(image);
    let (w, h) = (image.width, image.height);
    let rv = ImageView::new(w, h, &reference).unwrap();
    let measured: Vec<Metrics> = NOISE_SEEDS
        .iter()
        .map(|&s| {
            let other = to_f32(&render_with(scene, s, ITERATIONS, PHOTONS));
            metrics(ImageView::new(w, h, &other).unwrap(), rv)
        })
        .collect();
    let max = |f: fn(&Metrics) -> f64| measured.iter().map(f).fold(0.0, f64::max);
    let tol = Metrics {
        rel_mse: (FACTOR_PIXELS * max(|m| m.rel_mse)).max(1e-6),
        bad_share: (FACTOR_PIXELS * max(|m| m.bad_share)).max(1.0 / (w * h) as f64),
        mean_rel: (FACTOR_MEAN * max(|m| m.mean_rel)).max(1e-4),
    };
    write_noise(&dir.join(format!("{name}.noise")), &measured, &tol);
    println!("{name}: blessed; seed-to-seed noise {measured:?}; tolerances {tol:?}");
}

/// Renders one example and compares it with its reference (or writes it when blessing).
fn check(name: &str) {
    let Some(scene) = load_example(name) else {
        println!("SKIPPED golden `{name}`: examples/{name}.scn does not exist");
        return;
    };
    let start = std::time::Instant::now();
    let image = render_with(&scene, SEED, ITERATIONS, PHOTONS);
    println!(
        "{name}: {}x{} rendered in {:.2} s",
        image.width,
        image.height,
        start.elapsed().as_secs_f64()
    );
    if blessing() {
        bless(name, &scene, &image);
        return;
    }
    if let Err(e) = verdict(name, &image) {
        panic!("{e}");
    }
}

/// Compares a render of example `name` with its stored reference; on failure writes the report
/// and returns what failed and where the report is.
fn verdict(name: &str, image: &Image) -> Result<(), String> {
    let exr = golden_dir().join(format!("{name}.exr"));
    let noise = golden_dir().join(format!("{name}.noise"));
    if !exr.exists() {
        missing_reference(&exr);
    }
    if !noise.exists() {
        missing_reference(&noise);
    }
    let reference = load_image(&exr, ColorSpace::Linear)
        .unwrap_or_else(|e| panic!("cannot load {}: {e}", exr.display()));
    let tol = read_noise(&noise).unwrap_or_else(|e| panic!("{e}"));
    let get = |k: &str| {
        *tol.get(k)
            .unwrap_or_else(|| panic!("{} lacks `{k}`: re-bless", noise.display()))
    };
    let tol = Metrics {
        rel_mse: get("tol_rel_mse"),
        bad_share: get("tol_bad_share"),
        mean_rel: get("tol_mean_rel"),
    };
    let actual = to_f32(image);
    let av = ImageView::new(image.width, image.height, &actual).unwrap();
    let rv = match ImageView::new(reference.width, reference.height, &reference.pixels) {
        Ok(v) if (v.width, v.height) == (av.width, av.height) => v,
        _ => panic!(
            "{name}: reference is {}x{}, render is {}x{}: re-bless (SPPM_BLESS=1 cargo test --test render golden::)",
            reference.width, reference.height, image.width, image.height
        ),
    };
    let m = metrics(av, rv);
    println!("{name}: {m:?}\n{name}: tolerance {tol:?}");
    let fails: Vec<String> = [
        ("rel_mse", m.rel_mse, tol.rel_mse),
        ("bad_share", m.bad_share, tol.bad_share),
        ("mean_rel", m.mean_rel, tol.mean_rel),
    ]
    .iter()
    .filter(|(_, v, t)| v.is_nan() || v > t)
    .map(|(k, v, t)| format!("{k} {v:.4e} > tolerance {t:.4e}"))
    .collect();
    if fails.is_empty() {
        return Ok(());
    }
    let stats = compare::error(av, rv, None).ok();
    let notes = format!(
        "golden scene `{name}`: {}. Measured seed-to-seed noise and tolerances: {}. \
         If the change is intended: SPPM_BLESS=1 cargo test --test render golden::",
        fails.join("; "),
        noise.display()
    );
    let report = compare::write_report(&report_dir(), name, rv, av, stats.as_ref(), &notes);
    let where_ = match report {
        Ok(files) => format!("report: {}", files.html.display()),
        Err(e) => format!("(could not write the report: {e})"),
    };
    Err(format!(
        "golden `{name}` differs from its reference: {}\n{where_}",
        fails.join("; ")
    ))
}

/// The golden comparison catches deliberate changes of a material and of a light in the
/// Cornell box (and writes its report), while the unchanged scene passes.
#[test]
fn deliberate_material_and_light_changes_fail_with_a_report() {
    if blessing() {
        return;
    }
    let scene = load_example("cornell").expect("examples/cornell.scn");
    assert!(verdict("cornell", &render_with(&scene, SEED, ITERATIONS, PHOTONS)).is_ok());
    let red = scene
        .materials
        .iter()
        .position(|m| {
            matches!(m, Material::Diffuse { albedo: ColorParam::Const(c) } if c.x > 0.5 && c.y < 0.1)
        })
        .expect("the red wall's material");
    let mut blue_wall = scene.clone();
    blue_wall.materials[red] = Material::Diffuse {
        albedo: ColorParam::Const(glam::DVec3::new(0.05, 0.065, 0.63)),
    };
    let mut dimmer = scene.clone();
    let mut dimmed = 0;
    for o in dimmer.objects.iter_mut() {
        if let Some(e) = o.emission.as_mut() {
            e.radiance *= 0.85;
            dimmed += 1;
        }
    }
    assert_eq!(dimmed, 1, "the Cornell box has one area light");
    for (what, changed) in [
        ("red wall made blue", blue_wall),
        ("light 15% dimmer", dimmer),
    ] {
        let err =
            verdict("cornell", &render_with(&changed, SEED, ITERATIONS, PHOTONS)).expect_err(what);
        println!("{what}: {err}");
        assert!(err.contains("report: "), "{err}");
        let html = err.rsplit("report: ").next().unwrap().trim();
        assert!(Path::new(html).exists(), "{html}");
    }
}

/// One test per example; adding a scene (e.g. `vase`) is one more name in this list.
macro_rules! golden {
    ($($name:ident),* $(,)?) => {
        $(
            #[test]
            fn $name() {
                check(stringify!($name));
            }
        )*
    };
}

golden!(
    caustics,
    cornell,
    crystal_tree,
    furnace,
    room,
    smallppm,
    smallppm_far,
    textures,
    vase,
    teapot,
    csg,
    goblet,
    materials,
    bumps,
    shapes,
);

/// FNV-1a over the bits of every pixel.
fn image_hash(img: &Image) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |b: u8| {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    };
    for b in img
        .width
        .to_le_bytes()
        .into_iter()
        .chain(img.height.to_le_bytes())
    {
        eat(b);
    }
    for p in &img.pixels {
        for v in p {
            for b in v.to_bits().to_le_bytes() {
                eat(b);
            }
        }
    }
    h
}

/// Bit-exact hash of a small Cornell render (32 px, 2 iterations, 5000 photons, seed 1): any
/// change of the renderer's output at all (even one that stays inside the noise) changes it.
/// Re-bless with `SPPM_BLESS=1 cargo test --test render golden::` when the change is intended.
#[test]
fn checksum_is_unchanged() {
    let path = root().join("examples/cornell.scn");
    let mut scene = load_file(&path, &EvalOptions::default())
        .unwrap()
        .scene
        .expect("cornell.scn loads");
    scene.settings.resolution = (32, 32);
    let image = render_with(&scene, SEED, 2, 5_000);
    let hash = format!("{:016x}", image_hash(&image));
    let file = golden_dir().join("checksum.txt");
    if blessing() {
        std::fs::create_dir_all(golden_dir()).unwrap();
        std::fs::write(&file, format!("{hash}\n")).unwrap();
        println!("checksum blessed: {hash}");
        return;
    }
    if !file.exists() {
        missing_reference(&file);
    }
    let want = std::fs::read_to_string(&file).unwrap();
    println!("checksum {hash}, stored {}", want.trim());
    assert_eq!(
        hash,
        want.trim(),
        "the 32x32 Cornell render changed bit for bit; if intended, re-bless with \
         SPPM_BLESS=1 cargo test --test render golden::"
    );
}
