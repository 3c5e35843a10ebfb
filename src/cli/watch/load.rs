//! One evaluation of the watched scene, as the watch loop needs it.

use std::path::{Path, PathBuf};

use sppm_lang::scene::{Background, Scene};
use sppm_lang::{Diagnostic, EvalOptions, SourceMap};

use super::super::check::print_diagnostics;
use super::status;

/// What one load gives the watch loop.
pub struct Load {
    /// The file was empty or declared nothing: no object, no light, no background (already
    /// reported).
    pub empty: bool,
    pub scene: Option<Scene>,
    pub dependencies: Vec<PathBuf>,
    pub sources: SourceMap,
    pub diagnostics: Vec<Diagnostic>,
}

pub fn load(path: &Path, options: &EvalOptions) -> Load {
    // Editors truncate a file before writing it: an empty scene is a save in progress (or a
    // mistake), never a scene to render over the last image.
    if std::fs::metadata(path).is_ok_and(|m| m.is_file() && m.len() == 0) {
        status(&format!(
            "`{}` is empty; the last image is kept (waiting for the next save)",
            path.display()
        ));
        return Load {
            empty: true,
            scene: None,
            dependencies: vec![path.to_path_buf()],
            sources: SourceMap::default(),
            diagnostics: Vec::new(),
        };
    }
    match sppm_lang::load_file(path, options) {
        Ok(loaded) => {
            if !loaded.interrupted {
                print_diagnostics(&loaded);
            }
            let scene = if loaded.has_errors() {
                None
            } else {
                loaded.scene
            };
            // Only blanks and comments (a save caught half-written, or a file cleared to start
            // again): nothing to render over the last image either. (A background alone, such
            // as an environment map to look at, is something.)
            let bare = scene.as_ref().is_some_and(|s| {
                s.objects.is_empty()
                    && s.lights.is_empty()
                    && matches!(s.background, Background::Color(c) if c == glam::DVec3::ZERO)
                    && s.backdrop.is_none()
            });
            if bare {
                status(&format!(
                    "`{}` declares no object, no light and no background; the last image is \
                     kept (waiting for the next save)",
                    path.display()
                ));
            }
            Load {
                empty: bare,
                scene: scene.filter(|_| !bare),
                dependencies: loaded.dependencies,
                sources: loaded.sources,
                diagnostics: loaded.diagnostics,
            }
        }
        Err(e) => {
            // Deleted between saves (delete-and-recreate): keep watching the path.
            let message = e.with_path(path);
            status(&message);
            Load {
                empty: false,
                scene: None,
                dependencies: vec![path.to_path_buf()],
                sources: SourceMap::default(),
                diagnostics: vec![Diagnostic::error(
                    sppm_lang::span::Span::detached(),
                    message,
                )],
            }
        }
    }
}
