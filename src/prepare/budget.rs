//! The memory a render will need, estimated from the scene and the settings before anything
//! large is allocated, and refused with a message when it passes the limit.
//!
//! The estimate adds up what grows with the input: the film and per-pixel state, the
//! primitives and their BVH, the decoded images, and what the chosen method stores per
//! iteration (SPPM and PPM: photon hits in rounds of bounded size; photon mapping: every stored
//! photon and its kd-tree, taken as three stored hits per emitted photon). Fixed costs (code,
//! thread stacks, small tables) are left out. The figure is meant to be within a factor of about
//! two of the peak, which is what a limit needs to stop a 30 GB allocation before it starts.

use std::collections::HashSet;
use std::mem::size_of;

use super::instances::{shared_key, shared_meshes};
use super::{EffectiveSettings, RenderError};
use crate::scene::{Background, DEFAULT_PHOTONS, Integrator, Pattern, Scene, Shape};

/// The default limit: 2 GiB, or half the machine's memory when that is less.
pub fn default_memory_limit() -> u64 {
    let two_gib = 2u64 << 30;
    physical_memory().map_or(two_gib, |m| two_gib.min(m / 2))
}

/// Total physical memory in bytes, where the system tells (Linux: `/proc/meminfo`).
fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// One part of the estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryItem {
    pub what: &'static str,
    pub bytes: u64,
}

/// Primitives each scene shape becomes in the prepared scene.
fn primitives(shape: &Shape) -> u64 {
    match shape {
        Shape::Mesh { mesh } => mesh.indices.len() as u64,
        Shape::Box { .. } => 6,
        // Body and two caps.
        Shape::Cylinder { .. } => 3,
        // Its shapes live in the one CSG primitive (an overestimate by one).
        Shape::Csg(csg) => csg
            .leaves()
            .iter()
            .map(|o| primitives(&o.shape))
            .fold(1u64, u64::saturating_add),
        _ => 1,
    }
}

/// Bytes per primitive: the shape record, its share of the BVH (at most two nodes of 32 bytes
/// per primitive), the per-primitive object, light and material indices, and the build's
/// temporary centroid and bounds records.
const PER_PRIMITIVE: u64 = 64 + 3 * 4 + 64;

/// The estimate, largest item first.
pub fn estimate(scene: &Scene, settings: &EffectiveSettings) -> Vec<MemoryItem> {
    let pixels = settings.width as u64 * settings.height as u64;
    let shape_bytes = size_of::<crate::shapes::primitive::AnyShape>() as u64;
    let shared = shared_meshes(scene);
    let mut stored = HashSet::new();
    let prims: u64 = scene
        .objects
        .iter()
        .map(|o| match shared_key(o, &shared) {
            // A mesh placed several times: one primitive per placement, its triangles once.
            Some(id) => {
                1 + if stored.insert(id) {
                    primitives(&o.shape)
                } else {
                    0
                }
            }
            // An emissive object is built twice: as geometry and as a light.
            None => {
                let copies = if o.emission.is_some() { 2 } else { 1 };
                primitives(&o.shape).saturating_mul(copies)
            }
        })
        .fold(0u64, u64::saturating_add);
    let mut items = vec![MemoryItem {
        what: "primitives and their BVH",
        bytes: prims.saturating_mul(shape_bytes + PER_PRIMITIVE),
    }];
    let mut image_pixels: u64 = scene
        .textures
        .iter()
        .filter_map(|t| match &t.pattern {
            Pattern::Image { image, .. } => Some(image.width as u64 * image.height as u64),
            _ => None,
        })
        .sum();
    if let Background::Environment { image, .. } = &scene.background {
        // The map and its sampling distribution.
        image_pixels += 2 * image.width as u64 * image.height as u64;
    }
    items.push(MemoryItem {
        what: "images",
        bytes: image_pixels.saturating_mul(12),
    });
    // Per pixel: the film's sums and the image snapshots (f32 RGB twice), plus the method's own
    // state (SPPM: the pixel record, its visible point and its grid entry).
    let per_pixel = match settings.integrator {
        Integrator::Sppm | Integrator::Ppm => 400,
        _ => 64,
    };
    items.push(MemoryItem {
        what: "film and per-pixel state",
        bytes: pixels.saturating_mul(per_pixel),
    });
    let photons = match settings.integrator {
        // Rounds of at most 2^21 photon hits (32 bytes), filed twice while the grid is built.
        Integrator::Sppm | Integrator::Ppm => 64u64 << 21,
        // Three stored hits of 48 bytes per photon, in the list and in the kd-tree.
        Integrator::PhotonMap => settings
            .photons
            .unwrap_or(DEFAULT_PHOTONS)
            .saturating_mul(3 * 48 * 2),
        Integrator::Path | Integrator::Whitted => 0,
    };
    items.push(MemoryItem {
        what: "photons of one iteration",
        bytes: photons,
    });
    items.sort_by_key(|i| std::cmp::Reverse(i.bytes));
    items
}

/// Refuses a render whose estimate passes `limit` bytes, naming what takes the memory.
pub fn check_memory(
    scene: &Scene,
    settings: &EffectiveSettings,
    limit: u64,
) -> Result<(), RenderError> {
    let items = estimate(scene, settings);
    let total = items
        .iter()
        .map(|i| i.bytes)
        .fold(0u64, u64::saturating_add);
    if total <= limit {
        return Ok(());
    }
    let parts: Vec<String> = items
        .iter()
        .filter(|i| i.bytes > 0)
        .map(|i| format!("{} {}", i.what, mib(i.bytes)))
        .collect();
    Err(RenderError::new(format!(
        "this render needs about {} of memory, more than the limit of {} ({}); lower the \
         resolution, photons or object count, or raise the limit with --memory-limit",
        mib(total),
        mib(limit),
        parts.join(", ")
    )))
}

fn mib(bytes: u64) -> String {
    if bytes >= 10 << 30 {
        format!("{} GiB", bytes >> 30)
    } else {
        format!("{} MiB", bytes.div_ceil(1 << 20))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prepare::{RenderOptions, effective_settings};

    fn settings_of(scene: &Scene) -> EffectiveSettings {
        effective_settings(scene, &RenderOptions::default()).unwrap()
    }

    fn scene(text: &str) -> Scene {
        let l = crate::eval::load_source("budget.scn", text, &Default::default());
        l.scene.expect("a valid scene")
    }

    #[test]
    fn a_huge_film_is_refused_and_a_small_one_is_not() {
        let mut scene = scene("sphere { <0,0,0> 1 }");
        scene.settings.resolution = (16384, 8192);
        let e = check_memory(&scene, &settings_of(&scene), 2 << 30).unwrap_err();
        assert!(
            e.message.contains("film and per-pixel state"),
            "{}",
            e.message
        );
        assert!(e.message.contains("--memory-limit"), "{}", e.message);
        scene.settings.resolution = (512, 512);
        check_memory(&scene, &settings_of(&scene), 2 << 30).unwrap();
    }

    #[test]
    fn photon_mapping_counts_its_photons_and_sppm_does_not() {
        let mut scene = scene("sphere { <0,0,0> 1 }");
        scene.settings.resolution = (64, 64);
        scene.settings.photons = Some(10_000_000_000);
        scene.settings.integrator = Integrator::Sppm;
        check_memory(&scene, &settings_of(&scene), 2 << 30).unwrap();
        scene.settings.integrator = Integrator::PhotonMap;
        let e = check_memory(&scene, &settings_of(&scene), 2 << 30).unwrap_err();
        assert!(
            e.message.contains("photons of one iteration"),
            "{}",
            e.message
        );
    }

    #[test]
    fn the_default_limit_is_at_most_two_gib() {
        let l = default_memory_limit();
        assert!(l > 0 && l <= 2 << 30, "{l}");
    }
}
