//! One evaluation of the watched scene, as the watch loop needs it.

use std::path::{Path, PathBuf};

use sppm_lang::FileError;
use sppm_lang::Span;
use sppm_lang::internals::eval::{Loaded, RangeOverride};
use sppm_lang::internals::scene::{Background, Scene};
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

/// Loads the scene at `path`: as a still, or frame K of its animation when `frame` is
/// `Some((over, K))`.
pub fn load(path: &Path, options: &EvalOptions, frame: Option<(&RangeOverride, u32)>) -> Load {
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
    let loaded =
        sppm_lang::internals::eval::load_file(path, options).and_then(|still| match frame {
            Some((over, k)) => load_frame(path, options, still, over, k),
            None => Ok(still),
        });
    match loaded {
        Ok(loaded) => {
            if !loaded.interrupted {
                print_diagnostics(&loaded.sources, &loaded.diagnostics);
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
                diagnostics: vec![Diagnostic::error(sppm_lang::Span::detached(), message)],
            }
        }
    }
}

/// Frame `k` of the animation `still` (the scene read as a still) declares, with `over`: the
/// still itself when it has errors, or a load whose error says why there is no such frame.
fn load_frame(
    path: &Path,
    options: &EvalOptions,
    mut still: Loaded,
    over: &RangeOverride,
    k: u32,
) -> Result<Loaded, FileError> {
    let Some(scene) = still.scene.as_ref().filter(|_| !still.has_errors()) else {
        return Ok(still);
    };
    let problem = match sppm_lang::internals::eval::frame_range(&scene.settings, over) {
        Ok(Some(range)) if range.frames().contains(&k) => {
            let mut loaded =
                sppm_lang::internals::eval::load_frame(path, options, &still, over, &range, k)?;
            for d in still.dependencies {
                if !loaded.dependencies.contains(&d) {
                    loaded.dependencies.push(d);
                }
            }
            return Ok(loaded);
        }
        Ok(Some(range)) => format!(
            "frame {k} is outside the animation's frames {}..{}",
            range.first, range.last
        ),
        Ok(None) => format!(
            "`--frame {k}` needs an animation, and the scene is a still: give its frames with \
             `--frames A..B` or `settings {{ frames A, B }}`"
        ),
        Err(e) => e,
    };
    still.scene = None;
    still
        .diagnostics
        .insert(0, Diagnostic::error(Span::detached(), problem));
    Ok(still)
}
