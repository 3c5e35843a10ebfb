//! sppm-lang: a POV-Ray-like scene language and a stochastic progressive photon mapping renderer.
//!
//! The pipeline, one module boundary per arrow:
//!
//! ```text
//! source text → syntax (pest parse, AST with spans) → eval (interpreter) → scene::Scene (plain data)
//!             → prepare (validated: BVH, lights, camera, budgets) → integrators → film → image files
//! ```
//!
//! The language side (`syntax`, `eval`, `diag`) never reaches into rendering internals; the
//! renderer knows nothing of source text except the [`span::Span`]s the scene carries.
//!
//! An embedding program needs three calls ([`api`]): [`load()`] a scene (its files come from a
//! [`World`]: the disk, or a [`MemoryWorld`]), [`prepare()`] it with [`RenderOptions`] that
//! override its settings, and [`render()`] it; each returns its warnings in its result and fails
//! with a [`Failure`] holding the diagnostics. `examples/embed.rs` renders a scene built in
//! memory; docs/library.md describes the API, the Cargo features and the build profiles.

pub mod accel;
pub mod api;
pub mod atomic_file;
pub mod bezier;
pub mod camera;
pub mod cancel;
pub mod chains;
#[cfg(feature = "chart")]
pub mod chart;
pub mod compare;
pub mod diag;
pub mod eval;
pub mod farm;
pub mod files;
pub mod film;
pub mod geometry;
pub mod ide;
pub mod integrators;
pub mod lights;
pub mod materials;
pub mod prepare;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shapes;
pub mod span;
pub mod syntax;
pub mod textures;
pub mod world;

pub use api::{Document, Failure, Prepared, Rendered, load, prepare, render};
pub use cancel::Cancel;
pub use diag::SourceMap;
pub use diag::{Diagnostic, Severity, SourceResult, render_plain, to_report};
pub use eval::{
    EvalOptions, Loaded, RangeOverride, frame_range, load_file, load_frame, load_source,
};
pub use prepare::RenderOptions;
pub use scene::{Frame, FrameRange};
pub use world::{FileSystem, MemoryWorld, World};
