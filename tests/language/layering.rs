//! The pipeline's direction, enforced: every module of `src/` may import (`crate::...`) only
//! the modules written beside it below. Data flows one way,
//!
//! ```text
//! source text → syntax → eval → scene (plain data) → prepare → integrators → film → files
//! ```
//!
//! with `span` and `diag` as the leaf every stage may use, and the renderer's building blocks
//! (geometry, sampling, shapes, ...) below `prepare`. Nothing imports from a stage above it and
//! the renderer knows nothing of the language. A module missing from the table fails the test,
//! so a new module has to be placed in the order on purpose.
//!
//! Test code (from a file's `#[cfg(test)]` on, and files named `tests.rs`) is not part of the
//! product's dependency graph and is not checked: a unit test may load a scene from text.
//!
//! The library is the package `sppm-lang`, whose manifest (`lib/Cargo.toml`) takes its sources
//! from this repository's `src/`; the first test checks that, so the files read here are the
//! ones the library compiles.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Each top-level module of the library and the modules it may import. Written once, here.
const ALLOWED: &[(&str, &[&str])] = &[
    // The leaf: spans, source map, diagnostics. Imports nothing of the language or renderer.
    ("span", &[]),
    ("diag", &["span"]),
    ("atomic_file", &[]),
    ("files", &["diag"]),
    // Where a load's files come from (the disk, or memory).
    ("world", &["files"]),
    // The caller's cancel handle, read by every stage that can take long.
    ("cancel", &[]),
    // Leaves of the renderer's building blocks, placed before the language because they know
    // nothing of it: the language's random streams (`seed`, `rand`) are `sampling`'s splitmix64.
    ("geometry", &[]),
    ("sampling", &["geometry"]),
    // The language.
    ("syntax", &["span", "diag"]),
    ("scene", &["span", "diag", "files", "world", "sampling"]),
    (
        "eval",
        &[
            "span", "diag", "files", "world", "cancel", "syntax", "scene", "sampling",
        ],
    ),
    // The renderer's building blocks.
    ("bezier", &["geometry", "sampling"]),
    ("shapes", &["geometry", "sampling", "bezier", "scene"]),
    ("accel", &["geometry", "sampling", "shapes"]),
    ("textures", &["span", "geometry", "sampling", "scene"]),
    (
        "materials",
        &["geometry", "sampling", "shapes", "textures", "scene"],
    ),
    ("lights", &["geometry", "sampling", "shapes", "textures"]),
    ("camera", &["diag", "geometry", "sampling", "scene"]),
    ("film", &["diag", "atomic_file"]),
    // The stages.
    (
        "prepare",
        &[
            "span",
            "diag",
            "cancel",
            "scene",
            "geometry",
            "sampling",
            "bezier",
            "shapes",
            "accel",
            "textures",
            "materials",
            "lights",
            "camera",
        ],
    ),
    (
        "integrators",
        &[
            "span",
            "scene",
            "geometry",
            "sampling",
            "shapes",
            "accel",
            "textures",
            "materials",
            "lights",
            "camera",
            "film",
            "prepare",
        ],
    ),
    (
        "render",
        &[
            "span",
            "diag",
            "cancel",
            "scene",
            "film",
            "prepare",
            "integrators",
        ],
    ),
    // Tools over finished images and renders.
    ("compare", &["film", "atomic_file"]),
    ("chart", &["atomic_file", "compare"]),
    ("chains", &["film", "atomic_file"]),
    ("farm", &["chains"]),
    // The library's three calls (load, prepare, render) over the stages.
    (
        "api",
        &[
            "span", "diag", "cancel", "eval", "scene", "film", "prepare", "render",
        ],
    ),
    // Editor support (diagnostics, completion, navigation) over the language and the stages.
    (
        "ide",
        &[
            "span", "diag", "world", "cancel", "eval", "scene", "prepare", "render",
        ],
    ),
];

fn allowed() -> BTreeMap<&'static str, &'static [&'static str]> {
    ALLOWED.iter().copied().collect()
}

/// The first path segments after `crate::` in `code` (a `use crate::{a, b::c}` group gives
/// `a` and `b`). The modules are declared in `internals`, so `crate::internals::a` is `a`.
fn crate_imports(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        let before = rest[..i].chars().last();
        rest = &rest[i + "crate::".len()..];
        // `$crate::` in macros and identifiers ending in `crate` are not paths of this crate.
        if matches!(before, Some(c) if c == '$' || c.is_alphanumeric() || c == '_') {
            continue;
        }
        rest = rest.strip_prefix("internals::").unwrap_or(rest);
        if let Some(group) = rest.strip_prefix('{') {
            let end = matching_brace(group);
            for item in split_top_level(&group[..end]) {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
    }
    out
}

fn matching_brace(s: &str) -> usize {
    let mut depth = 0usize;
    for (i, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => return i,
            '}' => depth -= 1,
            _ => {}
        }
    }
    s.len()
}

fn split_top_level(s: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0usize, 0);
    for (i, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth = depth.saturating_sub(1),
            ',' if depth == 0 => {
                parts.push(&s[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&s[start..]);
    parts
}

/// The product code of a source file: comments dropped, and nothing from `#[cfg(test)]` on.
fn product_code(text: &str) -> String {
    let mut code = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        let line = match line.find("//") {
            Some(i) if !line[..i].contains('"') => &line[..i],
            _ => line,
        };
        code.push_str(line);
        code.push('\n');
    }
    code
}

/// Every backward import in the module `module` whose file is `file` with text `text`.
fn violations(module: &str, file: &str, text: &str) -> Vec<String> {
    let table = allowed();
    let Some(ok) = table.get(module) else {
        return vec![format!(
            "{file}: module `{module}` is not placed in tests/language/layering.rs's ALLOWED table"
        )];
    };
    let mut found = Vec::new();
    for target in crate_imports(&product_code(text)) {
        if target == module || ok.contains(&target.as_str()) {
            continue;
        }
        if table.contains_key(target.as_str()) {
            found.push(format!(
                "{file}: `{module}` imports `crate::{target}`, which is not below it \
                 (allowed: {ok:?})"
            ));
        } else {
            found.push(format!(
                "{file}: `{module}` imports `crate::{target}`, which is not a module in the \
                 ALLOWED table (the crate root's re-exports are for users, not for modules)"
            ));
        }
    }
    found
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The library's modules: `src/` minus the crate root and the file that declares the modules
/// (`internals.rs`), the binaries and the command line. Those (`main.rs`, `cli/`, `bin/`) are
/// the root package's, another crate: the compiler already holds them to the library's public
/// items, and `crate::` in them is not the library.
fn library_files() -> Vec<(String, PathBuf)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut out = Vec::new();
    for f in files {
        let rel = f.strip_prefix(&src).expect("under src");
        let first = rel.components().next().expect("a path").as_os_str();
        let first = first.to_string_lossy();
        if matches!(
            first.as_ref(),
            "lib.rs" | "internals.rs" | "main.rs" | "cli" | "bin"
        ) {
            continue;
        }
        if f.file_name().is_some_and(|n| n == "tests.rs") {
            continue;
        }
        let module = first.trim_end_matches(".rs").to_string();
        out.push((module, f));
    }
    out
}

#[test]
fn no_module_imports_from_a_stage_above_it() {
    // The files below are the library's only while its manifest's crate root is `src/lib.rs`.
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("lib/Cargo.toml");
    let manifest = std::fs::read_to_string(&manifest).expect("lib/Cargo.toml");
    assert!(
        manifest.contains("path = \"../src/lib.rs\""),
        "lib/Cargo.toml no longer builds the library from src/lib.rs"
    );
    let mut all = Vec::new();
    let files = library_files();
    assert!(files.len() > 50, "found only {} library files", files.len());
    for (module, file) in &files {
        let text = std::fs::read_to_string(file).expect("readable source");
        all.extend(violations(module, &file.display().to_string(), &text));
    }
    assert!(all.is_empty(), "backward imports:\n{}", all.join("\n"));
}

/// The modules `src/internals.rs` declares (every module of the library is declared there).
fn declared_modules(internals: &str) -> Vec<&str> {
    internals
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod "))
        .map(|name| name.trim_end_matches(';'))
        .collect()
}

#[test]
fn every_declared_module_is_placed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let internals = std::fs::read_to_string(root.join("internals.rs")).expect("src/internals.rs");
    let declared = declared_modules(&internals);
    // The library's top-level files and folders, each a module that must be declared there.
    assert!(declared.len() > 20, "found only {declared:?}");
    let table = allowed();
    for name in &declared {
        assert!(
            table.contains_key(name),
            "src/internals.rs declares `{name}`, which tests/language/layering.rs does not place"
        );
    }
    // The root declares no module of its own beside `internals` (a module declared there
    // would escape this table and be public).
    let lib = std::fs::read_to_string(root.join("lib.rs")).expect("src/lib.rs");
    let own: Vec<&str> = lib
        .lines()
        .map(str::trim)
        .filter(|l| l.contains("mod ") && !l.starts_with("//"))
        .collect();
    assert_eq!(own, ["pub mod internals;"], "src/lib.rs declares {own:?}");
    // ... and a module missing from the table is found.
    let planted = "#[path = \"newcomer.rs\"]\npub mod newcomer;\n";
    assert!(
        declared_modules(planted)
            .iter()
            .any(|m| !table.contains_key(m))
    );
}

#[test]
fn the_table_itself_points_downwards_only() {
    // Each module's allowed imports come before it in ALLOWED, so the table has no cycle.
    let mut seen: Vec<&str> = Vec::new();
    for (module, deps) in ALLOWED {
        for d in *deps {
            assert!(
                seen.contains(d),
                "`{module}` may import `{d}`, which is not placed before it"
            );
        }
        seen.push(module);
    }
}

#[test]
fn a_planted_backward_import_is_found() {
    // The check itself must be able to fail: each of these is a backward import.
    let planted = [
        ("prepare", "use crate::integrators::Progress;\n"),
        ("syntax", "use crate::{span::Span, eval::Value};\n"),
        ("diag", "fn f() -> crate::syntax::SourceMap { todo!() }\n"),
        ("shapes", "pub use crate::eval::load_file;\n"),
        ("geometry", "use crate::{\n    sampling::Rng,\n};\n"),
        ("integrators", "use crate::render::render;\n"),
        ("newcomer", "use crate::span::Span;\n"),
        // Through the modules' declaring module, or the root's re-exports.
        ("prepare", "use crate::internals::render::render;\n"),
        ("span", "use crate::Diagnostic;\n"),
    ];
    for (module, code) in planted {
        assert!(
            !violations(module, "planted.rs", code).is_empty(),
            "a backward import in `{module}` was not found: {code}"
        );
    }
    // ... and these are fine: own module, allowed imports, comments, test code, `$crate`.
    let fine = [
        (
            "prepare",
            "use crate::prepare::settings::X;\nuse crate::shapes::Shape;\n",
        ),
        (
            "integrators",
            "use crate::{prepare::PreparedScene, film::Image};\n",
        ),
        (
            "geometry",
            "// see crate::render::render\n/// [`crate::eval`]\n",
        ),
        (
            "shapes",
            "#[cfg(test)]\nmod tests { use crate::eval::load_source; }\n",
        ),
        (
            "sampling",
            "macro_rules! m { () => { $crate::sampling::Rng } }\n",
        ),
        ("eval", "pub(in crate::internals::eval) fn f() {}\n"),
    ];
    for (module, code) in fine {
        let v = violations(module, "fine.rs", code);
        assert!(v.is_empty(), "false alarm in `{module}`: {v:?}");
    }
}
