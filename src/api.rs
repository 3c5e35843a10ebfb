//! The library in three calls: [`load`] a scene, [`prepare`] it, [`render`] it.
//!
//! ```text
//! load(path, &EvalOptions)          -> Document  (the scene, its warnings and sources)
//! prepare(&document, &RenderOptions) -> Prepared  (BVH, lights, camera, checked budgets)
//! render(&prepared)                 -> Rendered  (the image, its statistics)
//! ```
//!
//! Each returns its warnings in its result and fails with a [`Failure`]: the diagnostics and
//! the sources they point into. The files come from [`EvalOptions::world`] (the disk unless
//! set; a [`crate::MemoryWorld`] supplies them from memory). [`RenderOptions`] overrides
//! the scene's settings (integrator, resolution, seed, threads, iterations, time, budgets)
//! without editing the scene, and its `cancel` handle both stops every stage and tells the
//! render's progress ([`crate::Cancel::progress`]).

use std::path::{Path, PathBuf};

use crate::cancel::Cancel;
use crate::diag::{Diagnostic, SourceMap, render_plain};
use crate::eval::EvalOptions;
use crate::film::Image;
use crate::prepare::{EffectiveSettings, PreparedScene, RenderOptions};
use crate::render::RenderStats;
use crate::scene::{Scene, Settings};

/// Why a call failed: its diagnostics (the errors, and the warnings found before them), with
/// the sources they point into. `Display` renders them as plain text.
#[derive(Debug, Clone, Default)]
pub struct Failure {
    pub diagnostics: Vec<Diagnostic>,
    pub sources: SourceMap,
    /// The caller cancelled the work: not the scene's fault.
    pub interrupted: bool,
}

impl Failure {
    fn render(e: Diagnostic, sources: &SourceMap) -> Self {
        Self {
            interrupted: e.interrupted,
            diagnostics: vec![e],
            sources: sources.clone(),
        }
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&render_plain(&self.sources, &self.diagnostics, 100))
    }
}

impl std::error::Error for Failure {}

/// A scene loaded without errors.
#[derive(Debug, Clone)]
pub struct Document {
    /// The scene model is the crate's own (it changes with the language); a caller reads the
    /// settings ([`Document::settings`]).
    pub(crate) scene: Scene,
    /// Warnings and the notes the scene asked for (`#debug`).
    pub warnings: Vec<Diagnostic>,
    pub sources: SourceMap,
    /// Every file the load read (the scene, includes, images, meshes).
    pub dependencies: Vec<PathBuf>,
}

impl Document {
    /// The scene's `settings` as written (resolution, exposure, ...), before the render's
    /// options apply ([`Prepared::settings`] has them applied).
    pub fn settings(&self) -> &Settings {
        &self.scene.settings
    }
}

/// Reads the scene file `path` from `options.world`, parses and evaluates it.
pub fn load(path: &Path, options: &EvalOptions) -> Result<Document, Failure> {
    let loaded = crate::eval::load_file(path, options).map_err(|e| Failure {
        diagnostics: vec![e.to_diagnostic(path)],
        ..Failure::default()
    })?;
    let failed = loaded.has_errors();
    match loaded.scene {
        Some(scene) if !failed => Ok(Document {
            scene,
            warnings: loaded.diagnostics,
            sources: loaded.sources,
            dependencies: loaded.dependencies,
        }),
        _ => Err(Failure {
            diagnostics: loaded.diagnostics,
            sources: loaded.sources,
            interrupted: loaded.interrupted,
        }),
    }
}

/// A scene ready to render, borrowing its document.
pub struct Prepared<'a> {
    scene: PreparedScene<'a>,
    settings: EffectiveSettings,
    options: RenderOptions,
    sources: &'a SourceMap,
    /// What is legal but probably not meant (a scene without light, a light facing away).
    pub warnings: Vec<Diagnostic>,
}

impl Prepared<'_> {
    /// The settings the render will use: the scene's with the options applied.
    pub fn settings(&self) -> &EffectiveSettings {
        &self.settings
    }
}

/// Builds what the render needs (BVH, lights, camera) with the scene's settings overridden by
/// `options`, after checking them and the memory the render would take.
pub fn prepare<'a>(
    document: &'a Document,
    options: &RenderOptions,
) -> Result<Prepared<'a>, Failure> {
    let (settings, scene) = crate::render::prepare(&document.scene, options)
        .map_err(|e| Failure::render(e, &document.sources))?;
    let warnings = scene.warnings();
    Ok(Prepared {
        scene,
        settings,
        options: options.clone(),
        sources: &document.sources,
        warnings,
    })
}

/// A finished render.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// Linear RGB (write it with [`Image::write`], or read its pixels).
    pub image: Image,
    pub iterations: u32,
    /// Stopped by the options' cancel handle (the image holds the finished iterations).
    pub cancelled: bool,
    pub stats: RenderStats,
    /// What went wrong in the render without stopping it (rays that gave up on an
    /// isosurface: [`PreparedScene::render_warnings`]).
    pub warnings: Vec<Diagnostic>,
}

/// Renders `prepared`. Its options' `cancel` handle stops the render at its next check and
/// tells its progress meanwhile.
pub fn render(prepared: &Prepared) -> Result<Rendered, Failure> {
    let cancel: &Cancel = &prepared.options.cancel;
    let out = crate::render::render_prepared(
        &prepared.scene,
        &prepared.settings,
        &prepared.options,
        cancel.flag(),
        &mut |_| {},
    )
    .map_err(|e| Failure::render(e, prepared.sources))?;
    Ok(Rendered {
        image: out.image,
        iterations: out.iterations_done,
        cancelled: out.cancelled,
        stats: out.stats,
        warnings: prepared.scene.render_warnings(),
    })
}
