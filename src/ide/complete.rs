//! Completion by context: what may be typed at a position of the text.
//!
//! - after `#`: the directives;
//! - in the string of an `#include`, a `mesh { }` or an image property: the files beside the
//!   document (scene files, OBJ meshes or images) and the standard files;
//! - inside a block: that block's properties (the evaluator's own tables), then the kinds of
//!   block, the names in scope and the built-in functions;
//! - at the top level: the kinds of block, the top level's properties and the same names.

use std::ops::Range;
use std::path::Path;

use super::docs;
use super::files::{Included, included};
use super::lex::{self, Kind};
use super::outline::{DeclKind, Outline};
use crate::world::World;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CompletionKind {
    Block,
    Property,
    Value,
    Macro,
    Function,
    Constant,
    Directive,
    File,
    Folder,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Completion {
    pub label: String,
    pub kind: CompletionKind,
    pub detail: Option<String>,
    /// Lower sorts first: what fits the place best.
    pub rank: u8,
}

/// The completions and the text they replace (the part of a word already typed).
#[derive(Debug, Clone, Default)]
pub struct Completions {
    pub items: Vec<Completion>,
    pub replace: Range<usize>,
}

/// The most names of a kind listed (a generated file may declare a million).
const MAX_ITEMS: usize = 2000;

/// What may be typed at `offset` of `text`, the document at `path` whose includes are read
/// from `world`. `globals` are the names the last evaluation left, with their values.
pub fn complete(
    world: &dyn World,
    path: &Path,
    text: &str,
    outline: &Outline,
    offset: usize,
    globals: &[(String, String)],
) -> Completions {
    let offset = floor_boundary(text, offset);
    let toks = &outline.tokens;
    let here = lex::at(toks, offset).filter(|&i| toks[i].start < offset);
    let mut out = Completions {
        items: Vec::new(),
        replace: offset..offset,
    };
    if let Some(i) = here {
        let t = &toks[i];
        match t.kind {
            // Inside a comment, or at the end of a line comment or an unclosed block comment.
            Kind::Comment
                if offset < t.end
                    || !t.text(text).starts_with("/*")
                    || !t.text(text).ends_with("*/") =>
            {
                return out;
            }
            Kind::Str { closed } if offset < t.end || !closed => {
                return files(path, text, outline, i, offset);
            }
            Kind::Directive => {
                out.replace = t.start + 1..offset;
                out.items = directives();
                return out;
            }
            Kind::Word => out.replace = t.start..offset,
            Kind::Number => return out,
            _ => {}
        }
    }
    // A lone `#` right before the cursor.
    if text[..offset].ends_with('#') {
        out.items = directives();
        return out;
    }
    // A new name is being written: nothing to offer.
    let before = toks[..here.unwrap_or_else(|| toks.partition_point(|t| t.end <= offset))]
        .iter()
        .rev()
        .find(|t| t.kind != Kind::Comment);
    if before.is_some_and(|b| {
        ["declare", "local", "macro", "undef"]
            .iter()
            .any(|d| b.is_directive(text, d))
    }) {
        return out;
    }
    let blocks = outline.blocks_at(text, offset);
    let inner = blocks.last().map(|b| b.kind.as_str());
    let mut items = Vec::new();
    match inner.map(|k| (k, crate::eval::block_properties(k))) {
        Some((kind, Some(props))) => {
            for p in props {
                items.push(Completion {
                    label: p.name.to_string(),
                    kind: CompletionKind::Property,
                    detail: Some(property_detail(kind, p.hint, p.example)),
                    rank: 0,
                });
            }
            block_items(&mut items, 2);
        }
        // A function's body or another block that takes no properties: values only.
        Some((_, None)) => {}
        None => {
            block_items(&mut items, 0);
            for p in crate::eval::top_level_properties() {
                items.push(Completion {
                    label: p.name.to_string(),
                    kind: CompletionKind::Property,
                    detail: Some(format!("{}, e.g. `{} {}`", p.hint, p.name, p.example)),
                    rank: 1,
                });
            }
        }
    }
    let includes = included(world, path, outline);
    name_items(&mut items, text, outline, &includes, offset, globals);
    builtin_items(&mut items);
    // One entry per label: the first (best ranked) wins.
    let mut seen = std::collections::HashSet::new();
    items.retain(|c| seen.insert(c.label.clone()));
    out.items = items;
    out
}

fn floor_boundary(text: &str, offset: usize) -> usize {
    let mut o = offset.min(text.len());
    while !text.is_char_boundary(o) {
        o -= 1;
    }
    o
}

fn property_detail(kind: &str, hint: &str, example: &str) -> String {
    if example.is_empty() {
        format!("{kind}: takes {hint}")
    } else {
        format!("{kind}: takes {hint}, e.g. `{example}`")
    }
}

fn directives() -> Vec<Completion> {
    docs::DIRECTIVES
        .iter()
        .map(|(d, line)| Completion {
            label: d.to_string(),
            kind: CompletionKind::Directive,
            detail: Some(line.to_string()),
            rank: 0,
        })
        .collect()
}

fn block_items(items: &mut Vec<Completion>, rank: u8) {
    for b in crate::eval::block_names() {
        items.push(Completion {
            label: b.to_string(),
            kind: CompletionKind::Block,
            detail: docs::block(b).map(|(line, _)| line.to_string()),
            rank,
        });
    }
}

/// The names declared in the document and the files it includes, known at `offset`.
fn name_items(
    items: &mut Vec<Completion>,
    text: &str,
    outline: &Outline,
    includes: &[Included],
    offset: usize,
    globals: &[(String, String)],
) {
    let value_of = |name: &str| {
        globals
            .binary_search_by(|(n, _)| n.as_str().cmp(name))
            .ok()
            .map(|i| globals[i].1.clone())
    };
    let own = outline
        .decls
        .iter()
        .filter(|d| d.scope.as_ref().is_none_or(|s| s.contains(&offset)))
        .map(|d| (d, text, None::<&Path>));
    let theirs = includes.iter().flat_map(|f| {
        f.outline
            .decls
            .iter()
            .filter(|d| d.scope.is_none())
            .map(move |d| (d, &*f.text, Some(f.path.as_path())))
    });
    for (n, (d, src, from)) in own.chain(theirs).enumerate() {
        if n >= MAX_ITEMS {
            break;
        }
        let (kind, mut detail) = match &d.kind {
            DeclKind::Macro { params } => (
                CompletionKind::Macro,
                format!("#macro {}({})", d.name, params.join(", ")),
            ),
            DeclKind::Param => (CompletionKind::Value, "parameter".to_string()),
            DeclKind::Value { .. } => (
                CompletionKind::Value,
                value_of(&d.name).unwrap_or_else(|| short(&src[d.value.clone()])),
            ),
        };
        if let Some(p) = from {
            detail = format!("{detail} ({})", p.display());
        }
        items.push(Completion {
            label: d.name.clone(),
            kind,
            detail: Some(detail),
            rank: 1,
        });
    }
}

fn builtin_items(items: &mut Vec<Completion>) {
    for f in crate::eval::FUNCTIONS {
        items.push(Completion {
            label: f.to_string(),
            kind: CompletionKind::Function,
            detail: Some("built-in function".into()),
            rank: 3,
        });
    }
    for c in crate::eval::CONSTANTS.iter().chain(&["true", "false"]) {
        items.push(Completion {
            label: c.to_string(),
            kind: CompletionKind::Constant,
            detail: Some("built-in constant".into()),
            rank: 3,
        });
    }
    for (n, what) in crate::scene::ANIMATION_NAMES {
        items.push(Completion {
            label: n.to_string(),
            kind: CompletionKind::Constant,
            detail: Some(what.to_string()),
            rank: 3,
        });
    }
    items.push(Completion {
        label: "rgb".into(),
        kind: CompletionKind::Function,
        detail: Some("a colour: `rgb <r, g, b>`".into()),
        rank: 3,
    });
    // The standard library's names, for a scene that has not included it yet.
    for (file, text) in crate::eval::STD_FILES {
        for d in Outline::new(text).decls {
            items.push(Completion {
                label: d.name,
                kind: CompletionKind::Value,
                detail: Some(format!("#include \"{file}\"")),
                rank: 4,
            });
        }
    }
}

fn short(value: &str) -> String {
    let one: String = value.split_whitespace().collect::<Vec<_>>().join(" ");
    match one.char_indices().nth(60) {
        Some((i, _)) => format!("{}…", &one[..i]),
        None => one,
    }
}

/// What a string names, by the word or block before it.
#[derive(Clone, Copy, PartialEq)]
enum FileKind {
    Scene,
    Mesh,
    Image,
}

impl FileKind {
    fn accepts(self, name: &str) -> bool {
        let ext = Path::new(name)
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let exts: &[&str] = match self {
            FileKind::Scene => &["scn", "inc"],
            FileKind::Mesh => &["obj"],
            FileKind::Image => &["png", "jpg", "jpeg", "hdr", "exr"],
        };
        ext.is_some_and(|e| exts.contains(&e.as_str()))
    }
}

/// The files a string at token `i` may name, relative to the document's folder.
fn files(path: &Path, text: &str, outline: &Outline, i: usize, offset: usize) -> Completions {
    let toks = &outline.tokens;
    let prev = toks[..i].iter().rev().find(|t| t.kind != Kind::Comment);
    let kind = match prev {
        Some(p) if p.is_directive(text, "include") => Some(FileKind::Scene),
        Some(p)
            if p.kind == Kind::Word
                && matches!(p.text(text), "image" | "png" | "jpeg" | "normal_map") =>
        {
            Some(FileKind::Image)
        }
        _ => match outline
            .blocks_at(text, offset)
            .last()
            .map(|b| b.kind.as_str())
        {
            Some("mesh") => Some(FileKind::Mesh),
            _ => None,
        },
    };
    let start = toks[i].start + 1;
    let typed = &text[start.min(offset)..offset];
    let (dir, name_start) = match typed.rfind('/') {
        Some(k) => (&typed[..=k], start + k + 1),
        None => ("", start),
    };
    let mut out = Completions {
        items: Vec::new(),
        replace: name_start..offset,
    };
    let Some(kind) = kind else {
        return out;
    };
    if kind == FileKind::Scene {
        for (std, _) in crate::eval::STD_FILES {
            if let Some(rest) = std.strip_prefix(dir)
                && rest.starts_with(&text[name_start..offset])
            {
                out.items.push(Completion {
                    label: rest.to_string(),
                    kind: CompletionKind::File,
                    detail: Some("standard library (built in)".into()),
                    rank: 1,
                });
            }
        }
        if dir.is_empty() && "std/".starts_with(&text[name_start..offset]) {
            out.items.push(Completion {
                label: "std/".into(),
                kind: CompletionKind::Folder,
                detail: Some("standard library (built in)".into()),
                rank: 1,
            });
        }
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let folder = if Path::new(dir).is_absolute() {
        Path::new(dir).to_path_buf()
    } else {
        base.join(dir)
    };
    let Ok(entries) = std::fs::read_dir(&folder) else {
        return out;
    };
    let typed_name = text[name_start..offset].to_lowercase();
    for e in entries.flatten().take(MAX_ITEMS) {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') || !name.to_lowercase().starts_with(&typed_name) {
            continue;
        }
        let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
        if is_dir {
            out.items.push(Completion {
                label: format!("{name}/"),
                kind: CompletionKind::Folder,
                detail: None,
                rank: 2,
            });
        } else if kind.accepts(&name) && folder.join(&name) != path {
            out.items.push(Completion {
                label: name,
                kind: CompletionKind::File,
                detail: None,
                rank: 0,
            });
        }
    }
    out.items
        .sort_by(|a, b| a.rank.cmp(&b.rank).then(a.label.cmp(&b.label)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::MemoryWorld;

    fn labels_at(text: &str, marker: &str) -> (Vec<String>, Completions) {
        let offset = text.find(marker).unwrap() + marker.len();
        let o = Outline::new(text);
        let c = complete(
            &MemoryWorld::new(),
            Path::new("s.scn"),
            text,
            &o,
            offset,
            &[],
        );
        (c.items.iter().map(|i| i.label.clone()).collect(), c)
    }

    #[test]
    fn inside_a_block_its_own_properties_come_first() {
        let text = "#declare R = 1;\ncylinder { <0,0,0>, <0,1,0>, R\n  op";
        let (labels, c) = labels_at(text, "  op");
        // The evaluator's table for cylinders: transforms, `open`, `inverse`.
        let props: Vec<&str> = crate::eval::block_properties("cylinder")
            .unwrap()
            .iter()
            .map(|p| p.name)
            .collect();
        assert!(props.contains(&"open"));
        assert_eq!(&labels[..props.len()], &props[..]);
        assert!(labels.contains(&"material".to_string()));
        assert!(labels.contains(&"R".to_string()));
        assert!(labels.contains(&"sin".to_string()));
        // A sphere's table has no `open`.
        assert!(!labels.contains(&"radiance".to_string()));
        assert_eq!(&text[c.replace.clone()], "op");
    }

    #[test]
    fn at_the_top_level_blocks_come_first() {
        let text = "#macro Ball(R) sphere { <0,0,0>, R } #end\ns";
        let (labels, c) = labels_at(text, "\ns");
        assert_eq!(labels[0], "sphere");
        assert!(labels.contains(&"camera".to_string()));
        assert!(labels.contains(&"background".to_string()));
        assert!(labels.contains(&"Ball".to_string()));
        // The parameter is known only in the macro's body.
        assert!(!labels.contains(&"R".to_string()));
        assert_eq!(
            c.items.iter().find(|i| i.label == "Ball").unwrap().kind,
            CompletionKind::Macro
        );
    }

    #[test]
    fn after_a_hash_the_directives() {
        let (labels, c) = labels_at("sphere { <0,0,0>, 1 }\n#dec", "#dec");
        assert!(labels.contains(&"declare".to_string()));
        assert_eq!(c.replace.len(), 3);
        let (labels, _) = labels_at("#", "#");
        assert_eq!(labels.len(), docs::DIRECTIVES.len());
    }

    #[test]
    fn nothing_in_comments_numbers_or_a_new_name() {
        assert!(labels_at("// sph", "sph").0.is_empty());
        assert!(labels_at("#declare Ne", "Ne").0.is_empty());
        assert!(labels_at("sphere { 1.5", "1.5").0.is_empty());
    }

    #[test]
    fn include_strings_offer_files_and_the_standard_library() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("parts")).unwrap();
        std::fs::write(dir.path().join("parts/walls.inc"), "").unwrap();
        std::fs::write(dir.path().join("parts/teapot.obj"), "").unwrap();
        let scene = dir.path().join("s.scn");
        let text = "#include \"parts/\nmesh { \"parts/";
        let o = Outline::new(text);
        let at = text.find("parts/").unwrap() + 6;
        let c = complete(&MemoryWorld::new(), &scene, text, &o, at, &[]);
        let labels: Vec<&str> = c.items.iter().map(|i| i.label.as_str()).collect();
        assert_eq!(labels, ["walls.inc"]);
        let c = complete(&MemoryWorld::new(), &scene, text, &o, text.len(), &[]);
        let labels: Vec<&str> = c.items.iter().map(|i| i.label.as_str()).collect();
        assert_eq!(labels, ["teapot.obj"]);
        let text = "#include \"";
        let c = complete(
            &MemoryWorld::new(),
            &scene,
            text,
            &Outline::new(text),
            text.len(),
            &[],
        );
        let labels: Vec<&str> = c.items.iter().map(|i| i.label.as_str()).collect();
        assert!(
            labels.contains(&"std/colors.scn") && labels.contains(&"parts/"),
            "{labels:?}"
        );
    }

    #[test]
    fn included_names_are_in_scope() {
        let world = MemoryWorld::new().with(
            "dir/lib.inc",
            "#declare Gold = 1;\n#macro Twice(A) A*2 #end\n",
        );
        let text = "#include \"lib.inc\"\n#include \"std/colors.scn\"\nsphere { <0,0,0>, ";
        let o = Outline::new(text);
        let c = complete(&world, Path::new("dir/s.scn"), text, &o, text.len(), &[]);
        let find = |n: &str| c.items.iter().find(|i| i.label == n).cloned();
        assert!(find("Gold").unwrap().detail.unwrap().contains("lib.inc"));
        assert_eq!(find("Twice").unwrap().kind, CompletionKind::Macro);
        // From the included standard file, ranked as the scene's own names.
        assert_eq!(find("Red").unwrap().rank, 1);
    }
}
