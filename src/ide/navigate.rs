//! Go to definition and find references: for declared names and macros (in the document and
//! the files it includes) and for the files that `#include`, `mesh` and image strings name.

use std::path::{Path, PathBuf};

use super::files::{included, resolve};
use super::lex::{self, Kind, Token};
use super::outline::{DeclKind, Outline};
use super::text::{LineIndex, Position};
use crate::world::World;

/// A range of a file, in editor positions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    pub path: PathBuf,
    pub start: Position,
    pub end: Position,
}

fn location(path: &Path, text: &str, index: &LineIndex, range: std::ops::Range<usize>) -> Location {
    Location {
        path: path.to_path_buf(),
        start: index.position(text, range.start),
        end: index.position(text, range.end),
    }
}

/// Where the name or file at `offset` is declared: the declarations of the name known there
/// (the document's own first, else the included files'), or the start of the file a string
/// names.
pub fn definition(
    world: &dyn World,
    path: &Path,
    text: &str,
    outline: &Outline,
    offset: usize,
) -> Vec<Location> {
    let Some(i) = lex::at(&outline.tokens, offset) else {
        return Vec::new();
    };
    let t = &outline.tokens[i];
    if matches!(t.kind, Kind::Str { .. }) {
        let (p, builtin) = resolve(path, t.inner(text));
        if builtin || world.size(&p).is_none() {
            return Vec::new();
        }
        return vec![Location {
            path: p,
            start: Position::default(),
            end: Position::default(),
        }];
    }
    if t.kind != Kind::Word {
        return Vec::new();
    }
    let name = t.text(text);
    let index = LineIndex::new(text);
    // A parameter hides the global names of its name.
    let visible: Vec<_> = outline.visible(name, offset).collect();
    let param = visible.iter().any(|d| d.kind == DeclKind::Param);
    let own: Vec<Location> = visible
        .iter()
        .filter(|d| !param || d.kind == DeclKind::Param)
        .map(|d| location(path, text, &index, d.name_range.clone()))
        .collect();
    if !own.is_empty() {
        return own;
    }
    let mut out = Vec::new();
    for f in included(world, path, outline) {
        if f.builtin {
            continue;
        }
        let ix = LineIndex::new(&f.text);
        for d in f
            .outline
            .decls
            .iter()
            .filter(|d| d.name == name && d.scope.is_none())
        {
            out.push(location(&f.path, &f.text, &ix, d.name_range.clone()));
        }
    }
    out
}

/// Every use of the name at `offset` in the document and the files it includes (a parameter's
/// in its macro only), declarations included when `declarations`.
pub fn references(
    world: &dyn World,
    path: &Path,
    text: &str,
    outline: &Outline,
    offset: usize,
    declarations: bool,
) -> Vec<Location> {
    let Some(i) = lex::at(&outline.tokens, offset) else {
        return Vec::new();
    };
    let t = &outline.tokens[i];
    if matches!(t.kind, Kind::Str { .. }) {
        return file_references(world, path, text, outline, t.inner(text));
    }
    if t.kind != Kind::Word {
        return Vec::new();
    }
    let name = t.text(text);
    // A parameter is its own name inside its scope only.
    let param = outline
        .visible(name, offset)
        .find(|d| d.kind == DeclKind::Param)
        .and_then(|d| d.scope.clone().map(|s| d.name_range.start..s.end));
    let is_decl = |o: &Outline, t: &Token| o.decls.iter().any(|d| d.name_range == t.range());
    let mut out = Vec::new();
    let index = LineIndex::new(text);
    for u in uses(text, outline, name) {
        if param.as_ref().is_some_and(|s| !s.contains(&u.start))
            || param.is_none() && in_param_scope(outline, name, u.start)
        {
            continue;
        }
        if declarations || !is_decl(outline, u) {
            out.push(location(path, text, &index, u.range()));
        }
    }
    if param.is_some() {
        return out;
    }
    for f in included(world, path, outline) {
        if f.builtin {
            continue;
        }
        let ix = LineIndex::new(&f.text);
        for u in uses(&f.text, &f.outline, name) {
            if in_param_scope(&f.outline, name, u.start) {
                continue;
            }
            if declarations || !is_decl(&f.outline, u) {
                out.push(location(&f.path, &f.text, &ix, u.range()));
            }
        }
    }
    out
}

/// The `#include`s of the document and its included files that name the file `name` (as
/// resolved from the document) names.
fn file_references(
    world: &dyn World,
    path: &Path,
    text: &str,
    outline: &Outline,
    name: &str,
) -> Vec<Location> {
    let (target, _) = resolve(path, name);
    let mut out = Vec::new();
    let index = LineIndex::new(text);
    for i in &outline.includes {
        if resolve(path, &i.path).0 == target {
            out.push(location(path, text, &index, i.range.clone()));
        }
    }
    for f in included(world, path, outline) {
        if f.builtin {
            continue;
        }
        let ix = LineIndex::new(&f.text);
        for i in &f.outline.includes {
            if resolve(&f.path, &i.path).0 == target {
                out.push(location(&f.path, &f.text, &ix, i.range.clone()));
            }
        }
    }
    out
}

fn uses<'a>(text: &'a str, outline: &'a Outline, name: &'a str) -> impl Iterator<Item = &'a Token> {
    outline
        .tokens
        .iter()
        .filter(move |t| t.kind == Kind::Word && t.text(text) == name)
}

/// Whether a parameter or loop variable named `name` hides the global name at `offset`.
fn in_param_scope(outline: &Outline, name: &str, offset: usize) -> bool {
    outline.decls.iter().any(|d| {
        d.kind == DeclKind::Param
            && d.name == name
            && (d.name_range.start == offset
                || d.scope.as_ref().is_some_and(|s| s.contains(&offset)))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::MemoryWorld;

    const LIB: &str = "#declare Gold = rgb <1, 0.8, 0.3>;\n";
    const SCENE: &str = "#include \"lib.inc\"\n#declare R = 1;\n#macro Ball(R) sphere { <0,0,0>, R material { diffuse Gold } } #end\nBall(R)\nBall(2 * R)\n";

    fn world() -> MemoryWorld {
        MemoryWorld::new()
            .with("d/lib.inc", LIB)
            .with("d/s.scn", SCENE)
    }

    fn at(marker: &str, skip: usize) -> usize {
        SCENE.find(marker).unwrap() + skip
    }

    #[test]
    fn definitions_of_names_macros_and_files() {
        let (w, p, o) = (world(), Path::new("d/s.scn"), Outline::new(SCENE));
        let d = definition(&w, p, SCENE, &o, at("Ball(R)\n", 1));
        assert_eq!(d.len(), 1);
        assert_eq!(
            d[0].start,
            Position {
                line: 2,
                character: 7
            }
        );
        // The global `R`, not the parameter, outside the macro.
        let d = definition(&w, p, SCENE, &o, at("Ball(2 * R", 9));
        assert_eq!(d[0].start.line, 1);
        // The parameter inside it.
        let d = definition(&w, p, SCENE, &o, at(", R material", 2));
        assert_eq!(
            d[0].start,
            Position {
                line: 2,
                character: 12
            }
        );
        let d = definition(&w, p, SCENE, &o, at("Gold }", 1));
        assert_eq!(d[0].path, Path::new("d/lib.inc"));
        assert_eq!(
            d[0].start,
            Position {
                line: 0,
                character: 9
            }
        );
        let d = definition(&w, p, SCENE, &o, at("lib.inc", 1));
        assert_eq!(d[0].path, Path::new("d/lib.inc"));
    }

    #[test]
    fn references_respect_parameters() {
        let (w, p, o) = (world(), Path::new("d/s.scn"), Outline::new(SCENE));
        let global = references(&w, p, SCENE, &o, at("#declare R", 9), true);
        let lines: Vec<u32> = global.iter().map(|l| l.start.line).collect();
        assert_eq!(lines, [1, 3, 4]);
        let param = references(&w, p, SCENE, &o, at(", R material", 2), true);
        assert_eq!(param.len(), 2);
        assert!(param.iter().all(|l| l.start.line == 2));
        let gold = references(&w, p, SCENE, &o, at("Gold }", 1), false);
        assert_eq!(
            gold.len(),
            1,
            "the declaration in lib.inc is left out: {gold:?}"
        );
        assert_eq!(references(&w, p, SCENE, &o, at("Gold }", 1), true).len(), 2);
    }

    #[test]
    fn references_of_an_included_file_are_its_includes() {
        let w = MemoryWorld::new()
            .with("d/lib.inc", LIB)
            .with("d/sub/part.inc", "#include \"../lib.inc\"\n");
        let text = "#include \"lib.inc\"\n#include \"sub/part.inc\"\n";
        let o = Outline::new(text);
        let r = references(&w, Path::new("d/s.scn"), text, &o, 11, true);
        let found: Vec<(&Path, u32)> = r.iter().map(|l| (l.path.as_path(), l.start.line)).collect();
        assert_eq!(
            found,
            [(Path::new("d/s.scn"), 0), (Path::new("d/sub/part.inc"), 0)]
        );
    }
}
