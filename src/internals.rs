//! Every module of the library, declared here rather than at the crate root so that the root
//! shows only the embedding API (`load`, `prepare`, `render` and the types their signatures
//! use). The crate reaches these modules as `crate::scene`, ... (the root imports them for the
//! crate alone); this repository's tests, benches, tools and command line reach them as
//! `sppm_lang::internals::...`. Nothing here is a stable interface: it changes with the code.
//!
//! The files stay where the modules' names put them (`src/scene/mod.rs`, `src/film.rs`): each
//! declaration names its file. The order is alphabetical; tests/language/layering.rs places
//! each module in the pipeline.

#[path = "accel/mod.rs"]
pub mod accel;
#[path = "api.rs"]
pub mod api;
#[path = "atomic_file.rs"]
pub mod atomic_file;
#[path = "bezier/mod.rs"]
pub mod bezier;
#[path = "camera.rs"]
pub mod camera;
#[path = "cancel.rs"]
pub mod cancel;
#[path = "chains.rs"]
pub mod chains;
#[cfg(feature = "chart")]
#[path = "chart/mod.rs"]
pub mod chart;
#[path = "compare/mod.rs"]
pub mod compare;
#[path = "diag/mod.rs"]
pub mod diag;
#[path = "eval/mod.rs"]
pub mod eval;
#[path = "farm.rs"]
pub mod farm;
#[path = "files.rs"]
pub mod files;
#[path = "film.rs"]
pub mod film;
#[path = "geometry/mod.rs"]
pub mod geometry;
#[path = "ide/mod.rs"]
pub mod ide;
#[path = "integrators/mod.rs"]
pub mod integrators;
#[path = "lights/mod.rs"]
pub mod lights;
#[path = "materials/mod.rs"]
pub mod materials;
#[path = "prepare/mod.rs"]
pub mod prepare;
#[path = "render/mod.rs"]
pub mod render;
#[path = "sampling/mod.rs"]
pub mod sampling;
#[path = "scene/mod.rs"]
pub mod scene;
#[path = "shapes/mod.rs"]
pub mod shapes;
#[path = "span.rs"]
pub mod span;
#[path = "syntax/mod.rs"]
pub mod syntax;
#[path = "textures/mod.rs"]
pub mod textures;
#[path = "world.rs"]
pub mod world;
