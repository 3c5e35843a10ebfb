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
use super::{EffectiveSettings, ObjectInfo};
use crate::bezier::lathe::Lathe;
use crate::diag::Diagnostic;
use crate::diag::size_text;
use crate::scene::{Background, DEFAULT_PHOTONS, Integrator, MeshData, Pattern, Scene, ShapeDecl};
use crate::shapes::patch::{BezierPatch, PIECES as PATCH_PIECES};
use crate::shapes::revolve::Revolve;

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

/// Primitives each scene shape becomes in the prepared scene (in a CSG: the surfaces of its
/// leaf).
pub(super) fn primitives(shape: &ShapeDecl) -> u64 {
    match shape {
        ShapeDecl::Mesh { mesh } => mesh.indices.len() as u64,
        ShapeDecl::Box { .. } => 6,
        // Body and two caps.
        ShapeDecl::Cylinder { .. } | ShapeDecl::Cone { .. } => 3,
        // Cut into pieces, each a primitive of its own.
        ShapeDecl::BezierPatch { .. } => u64::from(PATCH_PIECES * PATCH_PIECES),
        // One primitive per profile segment, and one for the caps of a partial sweep.
        ShapeDecl::Revolve { profile, sweep, .. } => {
            (profile.segments.len() as u64).max(1) + u64::from(sweep.is_some())
        }
        // Its shapes live in the one CSG primitive (an overestimate by one).
        ShapeDecl::Csg(csg) => csg
            .leaves()
            .iter()
            .map(|o| primitives(&o.shape))
            .fold(1u64, u64::saturating_add),
        _ => 1,
    }
}

/// Bytes a primitive of `shape` holds beyond its record: a patch piece's control net, a
/// revolve segment's share of its lathe (in their own allocations), and a heavy primitive's
/// own leaf ([`HEAVY_BVH`]).
fn held_bytes(shape: &ShapeDecl) -> u64 {
    let own = match shape {
        // The piece in its `Arc` and the boxed transform around it, each a heap allocation
        // (with its header and the `Arc`'s counts): measured 1.33 KB per piece in all against
        // 0.92 KB counted without them.
        ShapeDecl::BezierPatch { .. } => {
            (size_of::<BezierPatch>() + size_of::<crate::shapes::transformed::Transformed>()) as u64
                + WRAP_OVERHEAD
        }
        // A segment's part in its `Arc` and boxed transform, and its share of the lathe the
        // parts share (the segment, its tables and shells).
        ShapeDecl::Revolve { .. } => {
            (size_of::<Revolve>()
                + size_of::<crate::shapes::transformed::Transformed<Revolve>>()
                + Lathe::bytes_per_segment()) as u64
                + WRAP_OVERHEAD
        }
        // Its segments (with their boxes) in its own allocation, in an `Arc` and a boxed
        // transform.
        ShapeDecl::Prism(p) => {
            (size_of::<crate::shapes::prism::Prism>()
                + size_of::<crate::shapes::transformed::Transformed>()
                + p.segments.len() * 112) as u64
                + WRAP_OVERHEAD
        }
        // Its components and their hierarchy (about 200 bytes a component).
        ShapeDecl::Blob(b) => {
            (size_of::<crate::shapes::blob::Blob>()
                + size_of::<crate::shapes::transformed::Transformed>()
                + b.components.len() * 200) as u64
                + WRAP_OVERHEAD
        }
        // Its segments with their boxes, order and hierarchy (about 300 bytes a segment).
        ShapeDecl::SphereSweep(s) => {
            (size_of::<crate::shapes::sphere_sweep::SphereSweep>()
                + size_of::<crate::shapes::transformed::Transformed>()
                + s.centres.len() * 300) as u64
                + WRAP_OVERHEAD
        }
        // Its heights and their min/max hierarchy, in an `Arc` and a boxed transform.
        ShapeDecl::HeightField(h) => {
            (size_of::<crate::shapes::height_field::HeightField>()
                + size_of::<crate::shapes::transformed::Transformed>()) as u64
                + WRAP_OVERHEAD
                + h.grid.render_bytes()
        }
        _ => 0,
    };
    // Spheres, disks and cones under a transform the renderer cannot bake are heavy too, and
    // not counted here.
    let heavy = matches!(
        shape,
        ShapeDecl::Torus { .. }
            | ShapeDecl::Revolve { .. }
            | ShapeDecl::BezierPatch { .. }
            | ShapeDecl::Prism(_)
            | ShapeDecl::Superellipsoid { .. }
            | ShapeDecl::Blob(_)
            | ShapeDecl::Isosurface(_)
            | ShapeDecl::HeightField(_)
            | ShapeDecl::SphereSweep(_)
            | ShapeDecl::Csg(_)
    );
    own + if heavy { HEAVY_BVH } else { 0 }
}

/// Heap headers and reference counts of a shape held in an `Arc` inside a `Box`.
const WRAP_OVERHEAD: u64 = 64;

/// Bytes per primitive: the shape record, its share of the BVH (at most two nodes of 32 bytes
/// per primitive), the per-primitive object, light and material indices, and the build's
/// temporary centroid and bounds records.
const PER_PRIMITIVE: u64 = 64 + 3 * 4 + 64;

/// A heavy primitive's extra share of the BVH (a boxed shape: a torus, a revolve's segment, a
/// patch's piece, a mesh's placement; or a CSG tree): it gets a leaf of its own, so three to
/// four times the binary and wide nodes of a primitive sharing a leaf of up to four (100 000
/// tori: 10-20 MB more at the peak).
const HEAVY_BVH: u64 = 200;

/// Bytes per light beyond its shape: the light record, and its power and entries in the two
/// light distributions (f64 power, three f32 per distribution).
const PER_LIGHT: u64 = size_of::<crate::lights::Light>() as u64 + 8 + 2 * 12;

/// The BVH's bytes per triangle of a mesh kept in compact form: its share of the 8-wide nodes,
/// of the leaf records and of the triangle packets (160 bytes per four triangles), as the test
/// below measures it on sheets and scattered triangles of 128 to 500 000 triangles; the rest is
/// the margin for partly filled packets.
const BVH_PER_TRIANGLE: u64 = 100;
/// Bytes per compact mesh whatever its size: a tree's root, a leaf and a packet at least.
const PER_MESH: u64 = 1 << 10;

/// The bytes of a mesh in the BVH's compact form (see `shapes::mesh::TriangleMesh`): its
/// world-space buffers (f32 positions, and normals and texture coordinates where the file gives
/// them for every vertex; three u32 indices per triangle) and its share of the BVH. The
/// build's temporary records are freed before the render allocates its film and photons.
pub(super) fn compact_mesh_bytes(mesh: &MeshData) -> u64 {
    let vertices = mesh.positions.len() as u64;
    let per_vertex = size_of::<[f32; 3]>() as u64
        + if mesh.normals.len() == mesh.positions.len() {
            size_of::<[f32; 3]>() as u64
        } else {
            0
        }
        + if mesh.uvs.len() == mesh.positions.len() {
            size_of::<[f32; 2]>() as u64
        } else {
            0
        };
    let per_triangle = size_of::<[u32; 3]>() as u64 + BVH_PER_TRIANGLE;
    vertices
        .saturating_mul(per_vertex)
        .saturating_add((mesh.indices.len() as u64).saturating_mul(per_triangle))
        .saturating_add(PER_MESH)
}

/// Bytes a grid over `vcm`'s light vertices takes per vertex: its index, position, bucket
/// and about two table slots.
pub const VCM_GRID_BYTES: u64 = 32;

/// Bytes a stored light vertex of `vcm` takes: the vertex (what merges read: direction,
/// flux, length and weights' parts) in its path's chunk and again in the iteration's list, its
/// surface (position and compact BSDF) in the chunk, its position for the grids, its merge
/// grid entry, and the light-traced splat it may make (checked against the types' sizes by
/// the light path's tests).
pub const VCM_VERTEX_BYTES: u64 = 400;

/// Bytes a stored light vertex of `bpt` takes: the vertex and its surface in its path's chunk
/// alone (without merges there is no list and no grid) and its splat; checked as
/// `VCM_VERTEX_BYTES` is.
pub const BPT_VERTEX_BYTES: u64 = 272;

/// Bytes a vertex of a light path of `lt` takes: it stores no vertex, only the splat it may
/// make toward the lens.
pub const LT_VERTEX_BYTES: u64 = 32;

/// The estimate, largest item first.
pub fn estimate(scene: &Scene, settings: &EffectiveSettings) -> Vec<MemoryItem> {
    let pixels = settings.width() as u64 * settings.height() as u64;
    let shape_bytes = size_of::<crate::shapes::primitive::AnyShape>() as u64;
    let per_primitive = shape_bytes + PER_PRIMITIVE;
    // A placement of a shared mesh: its primitive and the boxed transform it carries.
    let per_placement =
        per_primitive + size_of::<crate::shapes::transformed::Transformed>() as u64 + HEAVY_BVH;
    let shared = shared_meshes(scene);
    let mut stored = HashSet::new();
    let shapes: u64 = scene
        .objects
        .iter()
        .map(|o| match (shared_key(o, &shared), &o.shape) {
            // A mesh placed several times: one primitive per placement, its triangles once.
            (Some(id), ShapeDecl::Mesh { mesh }) => {
                per_placement.saturating_add(if stored.insert(id) {
                    compact_mesh_bytes(mesh)
                } else {
                    0
                })
            }
            // A mesh that is not a light: one primitive, its triangles in compact form.
            (_, ShapeDecl::Mesh { mesh }) if o.emission.is_none() => {
                per_primitive.saturating_add(compact_mesh_bytes(mesh))
            }
            // An emissive object is built twice, as geometry and as lights (one per
            // primitive: a light record and its share of the power distributions).
            _ => {
                let held = held_bytes(&o.shape);
                let per = if o.emission.is_some() {
                    2 * (per_primitive + held) + PER_LIGHT
                } else {
                    per_primitive + held
                };
                primitives(&o.shape).saturating_mul(per)
            }
        })
        .fold(0u64, u64::saturating_add)
        .saturating_add(
            (scene.objects.len() as u64).saturating_mul(size_of::<ObjectInfo>() as u64),
        );
    let mut items = vec![MemoryItem {
        what: "primitives and their BVH",
        bytes: shapes,
    }];
    // Each image once, however many textures use it (they share its pixels).
    let mut seen = HashSet::new();
    let image_pixels: u64 = scene
        .textures
        .iter()
        .filter_map(|t| match &t.pattern {
            Pattern::Image { image, .. } if seen.insert(std::sync::Arc::as_ptr(image)) => {
                Some(image.width as u64 * image.height as u64)
            }
            _ => None,
        })
        .sum();
    // An environment map, per pixel at its peak while it is built: the scene's decoded image
    // (f32 RGB, 12 bytes), the map's own scaled copy (12), the filtered luminance (f64, 8) and
    // the sampling distribution (f32 value, cdf and pmf, 12).
    let environment_pixels = match &scene.background {
        Background::Environment { image, .. } => image.width as u64 * image.height as u64,
        // The baked image is the map's input, as a loaded one is.
        Background::Texture(_) => {
            crate::textures::sky::BAKE_WIDTH as u64 * crate::textures::sky::BAKE_HEIGHT as u64
        }
        Background::Color(_) => 0,
    };
    items.push(MemoryItem {
        what: "images",
        bytes: image_pixels
            .saturating_mul(crate::scene::IMAGE_BYTES_PER_PIXEL)
            .saturating_add(environment_pixels.saturating_mul(44)),
    });
    // Per pixel: the film's sums and the image snapshots (f32 RGB twice), plus the method's own
    // state (SPPM: the pixel record, its visible point and its grid entry; with final gathering
    // the gather estimate, its gather point and its grid entry too; `vcm`, `bpt` and `lt`:
    // the camera samples', delta parts' and non-delta parts' statistics, the connection
    // roulette's floor, the extra paths' count, the footprint ratio, the first radius, the
    // pass's values, the merges found and the radius scale, the light-path count's pilot sums,
    // and light tracing's film: 220 bytes).
    let per_pixel = match settings.method() {
        Integrator::Sppm if settings.final_gather => 640,
        Integrator::Sppm | Integrator::Ppm => 400,
        Integrator::Vcm | Integrator::Bpt | Integrator::Lt => 64 + 220,
        _ => 64,
    };
    items.push(MemoryItem {
        what: "film and per-pixel state",
        bytes: pixels.saturating_mul(per_pixel),
    });
    let photons = match settings.method() {
        // Rounds of at most 2^21 photon hits, 44 bytes while filed (the 40-byte record and its
        // bucket apart) and 40 again in the grid;
        // fewer where the photons of an iteration cannot store that many (at most `max_depth`
        // hits each; the automatic count is taken as the most).
        Integrator::Sppm | Integrator::Ppm => {
            let hits = settings.photons.map_or(1 << 21, |n| {
                n.saturating_mul(u64::from(settings.max_depth).max(1))
                    .min(1 << 21)
            });
            hits.saturating_mul(84)
        }
        // Three stored hits of 48 bytes per photon, in the list and in the kd-tree.
        Integrator::PhotonMap => settings
            .photons
            .unwrap_or(DEFAULT_PHOTONS)
            .saturating_mul(3 * 48 * 2),
        // One light path per pixel and iteration, its stored vertices at most `max_depth`
        // each, three on average; with final gathering `vcm` keeps a second grid.
        Integrator::Vcm if settings.final_gather => {
            pixels.saturating_mul(3 * (VCM_VERTEX_BYTES + VCM_GRID_BYTES))
        }
        Integrator::Vcm => pixels.saturating_mul(3 * VCM_VERTEX_BYTES),
        Integrator::Lt => pixels.saturating_mul(3 * LT_VERTEX_BYTES),
        Integrator::Bpt => pixels.saturating_mul(3 * BPT_VERTEX_BYTES),
        Integrator::Path | Integrator::Whitted => 0,
    };
    items.push(MemoryItem {
        what: PHOTONS,
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
    held: Option<MemoryItem>,
) -> Result<(), Diagnostic> {
    let mut items = estimate(scene, settings);
    items.extend(held);
    let total = items
        .iter()
        .map(|i| i.bytes)
        .fold(0u64, u64::saturating_add);
    if total <= limit {
        // Photons are stored as they are traced: a time limit may end the render long
        // before they fill what the estimate allows.
        let upfront = items
            .iter()
            .filter(|i| i.what != PHOTONS)
            .map(|i| i.bytes)
            .fold(0u64, u64::saturating_add);
        return allocatable(upfront);
    }
    let parts: Vec<String> = items
        .iter()
        .filter(|i| i.bytes > 0)
        .map(|i| format!("{} {}", i.what, size_text(i.bytes)))
        .collect();
    Err(Diagnostic::unplaced(format!(
        "this render needs about {} of memory, more than the limit of {} ({})",
        size_text(total),
        size_text(limit),
        parts.join(", ")
    ))
    .with_help(
        "lower the resolution, photons or object count, or raise the limit with --memory-limit",
    ))
}

/// What the estimate calls the photons one iteration stores.
const PHOTONS: &str = "photons of one iteration";

/// Whether the process can have `bytes` at all: reserved (address space only; nothing is
/// touched) and given back. A limit raised past what the machine or the process may have
/// (`--memory-limit 100G` on 16 GB, or under `ulimit -v`) lets an estimate pass that no
/// allocation can meet, and a failed allocation aborts the process mid-render.
fn allocatable(bytes: u64) -> Result<(), Diagnostic> {
    let reserved = usize::try_from(bytes)
        .map_err(|_| ())
        .and_then(|n| Vec::<u8>::new().try_reserve_exact(n).map_err(|_| ()));
    reserved.map_err(|()| {
        Diagnostic::unplaced(format!(
            "this render needs about {} of memory before its first photon, and this process \
             cannot allocate that much",
            size_text(bytes)
        ))
        .with_help(
            "lower the resolution, photons or object count: `--memory-limit` bounds the \
             estimate, it does not give the process more memory",
        )
    })
}

#[cfg(test)]
mod tests;
