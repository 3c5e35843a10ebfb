//! Every scene the project shows people evaluates cleanly: each `examples/*.scn` and the scene
//! in README.md (no errors, no warnings).

use std::path::Path;

use sppm_lang::internals::eval::{load_file, load_source};
use sppm_lang::{EvalOptions, render_plain};

#[test]
fn every_example_evaluates_without_diagnostics() {
    let mut checked = Vec::new();
    for entry in std::fs::read_dir("examples").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("scn") {
            continue;
        }
        let loaded = load_file(&path, &EvalOptions::default()).unwrap();
        assert!(
            loaded.diagnostics.is_empty(),
            "{}:\n{}",
            path.display(),
            render_plain(&loaded.sources, &loaded.diagnostics, 100)
        );
        let scene = loaded.scene.expect("a scene without errors");
        assert!(
            !scene.objects.is_empty(),
            "{} has no objects",
            path.display()
        );
        checked.push(path);
    }
    println!("checked {} example scenes", checked.len());
    assert!(checked.len() >= 4, "examples/ lost its scenes: {checked:?}");
}

#[test]
fn the_readme_scene_evaluates_and_its_light_faces_the_floor() {
    let readme = std::fs::read_to_string(Path::new("README.md")).unwrap();
    let start = readme
        .find("A scene, in short")
        .expect("README shows a scene");
    let block = &readme[start..];
    let open = block.find("```\n").unwrap() + 4;
    let close = open + block[open..].find("```").unwrap();
    let text = &block[open..close];
    let loaded = load_source("README.md", text, &EvalOptions::default());
    assert!(
        loaded.diagnostics.is_empty(),
        "{}",
        render_plain(&loaded.sources, &loaded.diagnostics, 100)
    );
    let scene = loaded.scene.unwrap();
    let light = scene
        .objects
        .iter()
        .find(|o| o.emission.is_some())
        .expect("the README scene has an area light");
    match &light.shape {
        sppm_lang::internals::scene::ShapeDecl::Quad { edge_u, edge_v, .. } => {
            assert!(edge_u.cross(*edge_v).y < 0.0, "the light must shine down");
        }
        other => panic!("expected a quad light, found {}", other.kind()),
    }
}
