//! `sppm-lang check`: parse and evaluate a scene, print diagnostics or a summary.

use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

use sppm_lang::internals::diag::short_number;
use sppm_lang::internals::render::{
    EffectiveSettings, InitialRadius, PreparedScene, RADIUS_FOOTPRINTS, RenderOptions,
};
use sppm_lang::internals::scene::{
    Background, ColorParam, Integrator, LightDecl, Scene, ShapeDecl,
};
use sppm_lang::{Diagnostic, EvalOptions, Severity, SourceMap};

use super::output::{err, out};
use super::{EXIT_SCENE_ERROR, EXIT_USAGE, SizeArgs};

/// Prints diagnostics to stderr: the one place the command line renders them. Those at a place
/// in the sources show it (miette's fancy output on a terminal, plain text otherwise); those
/// about no place (a default the file never wrote, an option, the machine) read
/// `error: <scene file>: message` and their help.
pub fn print_diagnostics(sources: &SourceMap, diagnostics: &[Diagnostic]) {
    let (placed, unplaced): (Vec<&Diagnostic>, Vec<&Diagnostic>) = diagnostics
        .iter()
        .partition(|d| d.is_placed() && sources.get(d.span.file).is_some());
    if !placed.is_empty() {
        let placed: Vec<Diagnostic> = placed.into_iter().cloned().collect();
        if std::io::stderr().is_terminal() {
            let report = sppm_lang::to_report(sources, &placed);
            err(&format!("{report:?}\n"));
        } else {
            err(&sppm_lang::render_plain(sources, &placed, 100));
        }
    }
    for d in unplaced {
        print_unplaced(sources, d);
    }
}

/// A message about the whole scene: `kind: file: message`, then its help.
fn print_unplaced(sources: &SourceMap, d: &Diagnostic) {
    let kind = match d.severity {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Note => "note",
    };
    match sources.files().first() {
        Some(f) => err(&format!("{kind}: {}: {}\n", f.name, d.message)),
        None => err(&format!("{kind}: {}\n", d.message)),
    }
    if let Some(h) = &d.help {
        err(&format!("  help: {h}\n"));
    }
}

/// A scene loaded without errors, the text of its files and every file the load read.
pub struct LoadedScene {
    pub scene: Scene,
    pub sources: SourceMap,
    pub dependencies: Vec<std::path::PathBuf>,
}

/// Loads a scene named on the command line and prints its diagnostics: the scene (free of
/// errors) and its sources, or the exit status (usage error: the file cannot be read; scene
/// error: it has errors).
pub fn load_scene(path: &Path, options: &EvalOptions) -> Result<LoadedScene, ExitCode> {
    let loaded = sppm_lang::internals::eval::load_file(path, options).map_err(|e| {
        print_diagnostics(&SourceMap::new(), &[e.to_diagnostic(path)]);
        ExitCode::from(EXIT_USAGE)
    })?;
    if loaded.interrupted {
        return Err(interrupted());
    }
    print_diagnostics(&loaded.sources, &loaded.diagnostics);
    let has_errors = loaded.has_errors();
    match loaded.scene {
        Some(scene) if !has_errors => Ok(LoadedScene {
            scene,
            sources: loaded.sources,
            dependencies: loaded.dependencies,
        }),
        _ => Err(ExitCode::from(failure_code(&loaded))),
    }
}

/// Ctrl-C (or SIGTERM) stopped the load or the prepare stage: said in one word, without the
/// diagnostics of a scene that was not read to its end, with the exit status of a command that
/// has no result.
fn interrupted() -> ExitCode {
    err("interrupted\n");
    ExitCode::from(EXIT_SCENE_ERROR)
}

/// What the prepare stage decided: the method and why, mesh sizes, the focus distance, the
/// initial radius.
fn render_summary(prepared: &PreparedScene, settings: &EffectiveSettings) -> String {
    let mut out = String::new();
    // The method and why: the option, the scene's setting or the default rule.
    let method = settings.method_choice();
    out.push_str(&format!(
        "integrator: {method}{}\n",
        if settings.final_gather && matches!(method.integrator, Integrator::Sppm | Integrator::Vcm)
        {
            ", with final gathering"
        } else {
            ""
        }
    ));
    let meshes: Vec<String> = prepared
        .scene
        .objects
        .iter()
        .filter_map(|o| match &o.shape {
            ShapeDecl::Mesh { mesh } => Some(format!(
                "{} ({} triangle{})",
                mesh.path.display(),
                mesh.indices.len(),
                if mesh.indices.len() == 1 { "" } else { "s" }
            )),
            _ => None,
        })
        .collect();
    if !meshes.is_empty() {
        out.push_str(&format!("meshes: {}\n", meshes.join(", ")));
    }
    out.push_str(&format!(
        "focus distance: {}{}\n",
        short_number(prepared.camera.focus_distance()),
        if prepared.scene.camera.aperture > 0.0 {
            ""
        } else {
            " (pinhole camera: everything is sharp)"
        }
    ));
    match settings.method() {
        // `vcm` merges within each camera path's radius, which starts by SPPM's rule.
        Integrator::Sppm | Integrator::Ppm | Integrator::Vcm => {
            let text = match settings.initial_radius(&prepared.scene.camera) {
                InitialRadius::Fixed(r) => format!("{} (from settings)", short_number(r)),
                InitialRadius::Orthographic(r) => format!(
                    "{} (default: {RADIUS_FOOTPRINTS} pixel footprints of the orthographic view)",
                    short_number(r)
                ),
                InitialRadius::Footprint { per_distance } => format!(
                    "{} x the distance to each pixel's first visible point (default: \
                     {RADIUS_FOOTPRINTS} pixel footprints there)",
                    short_number(per_distance)
                ),
            };
            out.push_str(&format!("initial radius: {text}\n"));
        }
        other => out.push_str(&format!("initial radius: not used by {}\n", other.name())),
    }
    out
}

pub fn run(
    scene: &Path,
    options: &EvalOptions,
    render_options: &RenderOptions,
    size: &SizeArgs,
) -> ExitCode {
    // First: Ctrl-C stops the load and the prepare stage at their next check.
    let cancel = super::cancel_on_ctrl_c();
    let options = &EvalOptions {
        cancel: cancel.clone(),
        ..options.clone()
    };
    let render_options = &RenderOptions {
        cancel,
        ..render_options.clone()
    };
    let mut loaded = match sppm_lang::internals::eval::load_file(scene, options) {
        Ok(l) => l,
        Err(e) => {
            print_diagnostics(&SourceMap::new(), &[e.to_diagnostic(scene)]);
            return ExitCode::from(EXIT_USAGE);
        }
    };
    if loaded.interrupted {
        return interrupted();
    }
    print_diagnostics(&loaded.sources, &loaded.diagnostics);
    let has_errors = loaded.has_errors();
    // Taken, not copied: a large scene's objects are tens of megabytes.
    match loaded.scene.take() {
        Some(mut s) if !has_errors => {
            if let Err(e) = size.apply_to(&mut s) {
                err(&format!("error: {e}\n"));
                return ExitCode::from(EXIT_USAGE);
            }
            // The prepare stage a render runs: `check` accepts exactly what `render` accepts.
            let (settings, prepared) =
                match sppm_lang::internals::render::prepare(&s, render_options) {
                    Ok(p) => p,
                    Err(e) if e.interrupted => return interrupted(),
                    Err(e) => {
                        print_diagnostics(&loaded.sources, &[e]);
                        return ExitCode::from(EXIT_SCENE_ERROR);
                    }
                };
            print_diagnostics(&loaded.sources, &prepared.warnings());
            let mut text = summary(&s, loaded.dependencies.len());
            text.push_str(&render_summary(&prepared, &settings));
            out(&text);
            ExitCode::SUCCESS
        }
        _ => ExitCode::from(failure_code(&loaded)),
    }
}

/// The exit code of a load that failed: a usage error when the evaluation could not start in
/// this environment (as for a scene file that cannot be read), else a scene error.
pub fn failure_code(loaded: &sppm_lang::internals::eval::Loaded) -> u8 {
    if loaded.environment {
        EXIT_USAGE
    } else {
        EXIT_SCENE_ERROR
    }
}

/// A one-screen description of an evaluated scene that read `files_read` files.
pub fn summary(s: &Scene, files_read: usize) -> String {
    let mut out = String::new();
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    let mut emitters = 0;
    for o in &s.objects {
        *kinds.entry(o.shape.kind()).or_default() += 1;
        emitters += usize::from(o.emission.is_some());
    }
    out.push_str(&format!("objects: {}", s.objects.len()));
    if !kinds.is_empty() {
        let list: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
        out.push_str(&format!(" ({})", list.join(", ")));
    }
    out.push('\n');
    let points = s
        .lights
        .iter()
        .filter(|l| matches!(l, LightDecl::Point { .. }))
        .count();
    let spots = s.lights.len() - points;
    out.push_str(&format!(
        "lights: {emitters} area, {points} point, {spots} spot\n"
    ));
    out.push_str(&format!(
        "materials: {}, textures: {}\n",
        s.materials.len(),
        s.textures.len()
    ));
    let c = &s.camera;
    out.push_str(&format!(
        "camera: location <{}, {}, {}> look_at <{}, {}, {}> {}{}{}\n",
        c.location.x,
        c.location.y,
        c.location.z,
        c.look_at.x,
        c.look_at.y,
        c.look_at.z,
        if c.orthographic {
            let (w, h) = c.view_size(s.settings.resolution.0, s.settings.resolution.1);
            format!(
                "orthographic, view {} x {}",
                short_number(w),
                short_number(h)
            )
        } else {
            format!("fov {}", c.fov)
        },
        if c.aperture > 0.0 {
            format!(" aperture {}", c.aperture)
        } else {
            String::new()
        },
        if c.mirrored(s.settings.handedness) {
            ", left-handed (+x on the right)"
        } else {
            ""
        }
    ));
    let st = &s.settings;
    out.push_str(&format!(
        "settings: {}x{}, {} iterations, {} photons/iteration, radius {}, alpha {}, max_depth {}, seed {}{}\n",
        st.resolution.0,
        st.resolution.1,
        st.iterations,
        st.photons.map_or("auto".to_string(), |n| n.to_string()),
        st.radius.map_or("auto".to_string(), short_number),
        short_number(st.alpha),
        st.max_depth,
        st.seed,
        if st.final_gather {
            ", final_gather on"
        } else {
            ""
        }
    ));
    match &s.background {
        Background::Color(c) => {
            out.push_str(&format!("background: rgb <{}, {}, {}>\n", c.x, c.y, c.z))
        }
        Background::Environment {
            image, intensity, ..
        } => out.push_str(&format!(
            "background: environment {} x{intensity}\n",
            image.path.display()
        )),
        Background::Texture(id) => out.push_str(&format!("background: texture {}\n", id.0)),
    }
    match &s.backdrop {
        Some(ColorParam::Const(c)) => {
            out.push_str(&format!("backdrop: rgb <{}, {}, {}>\n", c.x, c.y, c.z))
        }
        Some(ColorParam::Texture(id)) => out.push_str(&format!("backdrop: texture {}\n", id.0)),
        None => {}
    }
    out.push_str(&format!("files read: {files_read}\n"));
    out
}
