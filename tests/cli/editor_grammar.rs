//! The editor highlighting (`editors/vscode/syntaxes/scn.tmLanguage.json`) against the parser.
//!
//! The grammar's word lists must be the parser's reserved words and the evaluator's built-in
//! names (checked here, without node), and the grammar must tokenize every scene of the
//! repository as the parser reads it: `editors/vscode/test/tokenize.js`, run with node and the
//! npm packages `vscode-textmate` and `vscode-oniguruma` (`npm ci` in editors/vscode, as
//! `.ci/run` does), gets the parser's verdict on each file from this test. Without node or
//! `editors/vscode/node_modules` that part fails when `CI=true` and is skipped otherwise.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use sppm_lang::FileId;
use sppm_lang::internals::syntax::parse;

const GRAMMAR: &str = "editors/vscode/syntaxes/scn.tmLanguage.json";

/// The words of the grammar's rule in `repository.words` whose scope is `scope`, read from its
/// `\b(?:a|b|...)\b` pattern.
fn grammar_words(scope: &str) -> BTreeSet<String> {
    let grammar: Value = serde_json::from_str(&std::fs::read_to_string(GRAMMAR).unwrap()).unwrap();
    let rules = grammar["repository"]["words"]["patterns"]
        .as_array()
        .unwrap();
    let rule = rules
        .iter()
        .find(|r| r["name"] == scope)
        .unwrap_or_else(|| panic!("no rule scoped {scope} in {GRAMMAR}"));
    let pattern = rule["match"].as_str().unwrap();
    let inner = pattern
        .strip_prefix("\\b(?:")
        .and_then(|p| p.split_once(")\\b"))
        .unwrap_or_else(|| panic!("{scope}: `{pattern}` is not a word list"))
        .0;
    inner.split('|').map(str::to_string).collect()
}

/// Whether the parser takes `word` as a name (`#declare word = 1` parses).
fn is_name(word: &str) -> bool {
    parse(FileId(0), &format!("#declare {word} = 1")).is_ok()
}

#[test]
fn the_grammars_keywords_are_the_parsers_reserved_words() {
    let keywords = grammar_words("keyword.other.property.scn");
    let rgb = grammar_words("storage.type.colour.scn");
    assert!(keywords.len() > 50, "too few keywords: {keywords:?}");
    // Every listed word is reserved, and the list is not made of half-words: a word one letter
    // longer is a name again.
    for word in keywords.iter().chain(&rgb) {
        assert!(
            !is_name(word),
            "`{word}` is highlighted as a keyword, but the parser takes it as a name"
        );
        assert!(is_name(&format!("{word}q")), "`{word}q` should be a name");
    }
    // Completeness: every word that the sources spell as a string and the parser reserves is
    // listed (a keyword the evaluator reads appears in its sources as a string).
    let mut candidates = BTreeSet::new();
    let mut stack = vec![PathBuf::from("src"), PathBuf::from("docs")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs" || e == "md") {
                let text = std::fs::read_to_string(&path).unwrap();
                for word in text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
                    if word.starts_with(|c: char| c.is_ascii_lowercase()) {
                        candidates.insert(word.to_string());
                    }
                }
            }
        }
    }
    let reserved: Vec<&String> = candidates.iter().filter(|w| !is_name(w)).collect();
    let missing: Vec<&&String> = reserved
        .iter()
        .filter(|w| {
            !keywords.contains(**w)
                && !rgb.contains(**w)
                && !["true", "false"].contains(&w.as_str())
        })
        .collect();
    assert!(
        missing.is_empty(),
        "reserved words missing from {GRAMMAR}: {missing:?} (run `npm run generate` in editors/vscode)"
    );
    assert!(
        reserved.len() >= keywords.len(),
        "the sources and docs should spell every keyword"
    );
}

#[test]
fn the_grammar_knows_the_built_in_names() {
    let functions = grammar_words("support.function.builtin.scn");
    let constants = grammar_words("support.constant.builtin.scn");
    for f in sppm_lang::internals::eval::FUNCTIONS {
        assert!(
            functions.contains(*f),
            "built-in function `{f}` is not highlighted"
        );
    }
    for c in sppm_lang::internals::eval::CONSTANTS.iter().chain(
        sppm_lang::internals::scene::ANIMATION_NAMES
            .iter()
            .map(|(n, _)| n),
    ) {
        assert!(
            constants.contains(*c),
            "built-in constant `{c}` is not highlighted"
        );
    }
}

fn node() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("node"))
        .find(|p| p.is_file())
}

fn scenes(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            scenes(&path, out);
        } else if path.extension().is_some_and(|e| e == "scn") {
            out.push(path);
        }
    }
}

#[test]
fn the_textmate_grammar_tokenizes_every_scene_as_the_parser_reads_it() {
    let modules = Path::new("editors/vscode/node_modules");
    let (Some(node), true) = (node(), modules.is_dir()) else {
        let on_ci = std::env::var("CI").is_ok_and(|v| v == "true");
        assert!(
            !on_ci,
            "node or editors/vscode/node_modules is missing (CI=true): the grammar test cannot \
             run; install nodejs and npm and run `npm ci` in editors/vscode, as .ci/run does"
        );
        eprintln!("skipped: no node on PATH or no editors/vscode/node_modules (`npm ci` there)");
        return;
    };
    // The parser's verdict on each file: the grammar may leave a region open, or mark a token
    // invalid, only where the parser reports an error.
    let mut files = Vec::new();
    for dir in ["examples", "tests/good", "tests/bad"] {
        scenes(Path::new(dir), &mut files);
    }
    let mut rejected = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        if parse(FileId(0), &text).is_err() {
            rejected.push(file.to_str().unwrap().replace('\\', "/"));
        }
    }
    assert!(
        files.len() > 200 && !rejected.is_empty(),
        "{} files, {} rejected",
        files.len(),
        rejected.len()
    );
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("editor-grammar");
    std::fs::create_dir_all(&dir).unwrap();
    let verdicts = dir.join("rejected.json");
    std::fs::write(&verdicts, serde_json::to_string(&rejected).unwrap()).unwrap();

    let out = Command::new(node)
        .arg("editors/vscode/test/tokenize.js")
        .arg("--verdicts")
        .arg(&verdicts)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprintln!("{stdout}{stderr}");
    assert!(
        out.status.success(),
        "the grammar test failed:\n{stdout}{stderr}"
    );
    assert!(
        stdout.contains(&format!("tokenized {} files", files.len())),
        "tokenize.js saw other files than the {} scenes here:\n{stdout}",
        files.len()
    );
}
