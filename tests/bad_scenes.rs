//! Every scene in `tests/bad/` yields spanned diagnostics; the rendered text is snapshotted.
//! Files named `warn_*` must evaluate (warnings only); all others must fail with errors.

use std::path::Path;

use sppm_lang::{EvalOptions, load_file, render_plain};

#[test]
fn bad_scenes_give_spanned_diagnostics() {
    let mut paths: Vec<_> = std::fs::read_dir("tests/bad")
        .expect("tests/bad")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "scn"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 40, "only {} bad scenes", paths.len());
    let options = EvalOptions {
        max_iterations: 1000,
        max_depth: 64,
        ..EvalOptions::default()
    };
    for path in &paths {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let rel = Path::new("tests/bad").join(path.file_name().unwrap());
        let loaded = load_file(&rel, &options).expect("readable");
        assert!(!loaded.diagnostics.is_empty(), "{name}: no diagnostic");
        for d in &loaded.diagnostics {
            assert!(
                loaded.sources.get(d.span.file).is_some(),
                "{name}: diagnostic without a source span: {}",
                d.message
            );
        }
        if name.starts_with("warn_") {
            assert!(!loaded.has_errors(), "{name}: expected warnings only");
            assert!(loaded.scene.is_some());
        } else {
            assert!(loaded.has_errors(), "{name}: expected an error");
            assert!(loaded.scene.is_none());
        }
        let text = render_plain(&loaded.sources, &loaded.diagnostics, 100);
        insta::assert_snapshot!(name, text);
    }
}
