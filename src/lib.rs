//! sppm-lang: a POV-Ray-like scene language and a stochastic progressive photon mapping renderer.
//!
//! An embedding program needs three calls: [`load()`] a scene (its files come from a
//! [`World`]: the disk, or a [`MemoryWorld`]), [`prepare()`] it with [`RenderOptions`] that
//! override its settings, and [`render()`] it to an [`Image`]. Each returns its warnings in its
//! result and fails with a [`Failure`] holding the [`Diagnostic`]s; a [`Cancel`] handle stops
//! any of them and tells the render's progress. Everything else this crate declares (the
//! parser, the interpreter, the renderer's parts) is private to it: the crate root holds the
//! whole supported interface. `examples/embed.rs` renders a scene built in memory;
//! docs/library.md describes the API, the Cargo features and the build profiles.
//!
//! The pipeline behind the three calls, one module boundary per arrow:
//!
//! ```text
//! source text → syntax (pest parse, AST with spans) → eval (interpreter) → scene (plain data)
//!             → prepare (validated: BVH, lights, camera, budgets) → integrators → film → image files
//! ```
//!
//! The language side (`syntax`, `eval`, `diag`) never reaches into rendering internals; the
//! renderer knows nothing of source text except the [`Span`]s the scene carries.

#[doc(hidden)]
pub mod internals;

// Inside the crate every module keeps its short path (`crate::scene::Scene`).
pub(crate) use internals::*;

/// The repository's root, for unit tests that read its examples and docs: the library's
/// manifest, and so `CARGO_MANIFEST_DIR`, is `lib/`, one folder below it.
#[cfg(test)]
pub(crate) fn repo_root() -> &'static std::path::Path {
    std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

pub use internals::api::{Document, Failure, Prepared, Rendered, load, prepare, render};
pub use internals::cancel::Cancel;
pub use internals::diag::{
    Diagnostic, Location, Severity, SourceFile, SourceMap, render_plain, to_report,
};
pub use internals::eval::EvalOptions;
pub use internals::files::FileError;
pub use internals::film::Image;
pub use internals::prepare::{
    EffectiveSettings, MemoryItem, MethodChoice, MethodSource, RenderOptions,
};
pub use internals::render::RenderStats;
pub use internals::scene::{Antialias, Frame, FrameRange, Handedness, Integrator, Settings};
pub use internals::span::{FileId, Span};
pub use internals::world::{FileSystem, MemoryWorld, SharedWorld, World};
