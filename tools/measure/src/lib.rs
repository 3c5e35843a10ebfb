//! Measurements sppm-lang makes of itself, outside the product library (`sppm-lang` does not
//! depend on this crate; `cargo run --release -p sppm-measure -- bezier` runs the study).
//!
//! - [`bezier`]: speed against accuracy of the Bezier intersectors (robust, Newton) and of
//!   tessellated meshes of the same surfaces.
//! - [`blob_reference`]: slow reference intersectors of `blob` and `isosurface` (dense
//!   sampling and bisection), the oracles of their stress tests.
//! - [`cost`]: cost per ray of the Bezier surfaces as a ratio to a quad's.
//! - [`layered`]: directional albedos of the rough coat against a random walk through the
//!   layer, and of the rough metal lobe in a white furnace (`sppm-measure coat`, `furnace`).
//! - [`lights`]: direct-light noise of area lights sampled by area and by solid angle, at
//!   equal time (`cargo run --release -p sppm-measure -- lights`).
//! - [`prism_reference`]: a slow reference intersector of `prism`, the oracle of its stress
//!   test.
//! - [`reference`](mod@reference): slow, obviously right intersectors of the Bezier surfaces, the oracles of
//!   the study and of the stress tests.
//! - [`sweep_reference`]: a slow reference intersector of the curved `sphere_sweep` (dense
//!   sampling along the curve and golden-section refinement), the oracle of its stress test.
//! - [`superellipsoid_reference`]: a slow reference intersector of `superellipsoid`, the
//!   oracle of its stress test.
//! - [`setup`]: the set-up of a large mesh (OBJ read, triangles, BVH) step by step, on 1
//!   and more threads.
//! - [`tessellate`]: triangle meshes of the Bezier surfaces, the study's meshes.
//! - [`twin`]: a scene's twin with its revolves replaced by meshes at a given accuracy.

pub mod bezier;
pub mod blob_reference;
pub mod cost;
pub mod height_field_reference;
pub mod layered;
pub mod lights;
pub mod prism_reference;
pub mod reference;
pub mod setup;
pub mod superellipsoid_reference;
pub mod sweep_reference;
pub mod tessellate;
pub mod twin;
