//! The structure of a file as its tokens show it, also when it does not parse: declarations,
//! macros and their parameters, includes, blocks and the file names in strings. What
//! completion, hover, navigation and the document outline read.

use std::ops::Range;

use super::lex::{Kind, Token, tokens};

/// What a declaration declares.
#[derive(Debug, Clone, PartialEq)]
pub enum DeclKind {
    /// `#declare` (or `#local` when `local`).
    Value {
        local: bool,
    },
    Macro {
        params: Vec<String>,
    },
    /// A macro's parameter or a `#for` loop's variable: known inside `Decl::scope` only.
    Param,
}

#[derive(Debug, Clone)]
pub struct Decl {
    pub name: String,
    pub name_range: Range<usize>,
    pub kind: DeclKind,
    /// The whole declaration, from its directive to the end of its value (or the `#end` of a
    /// macro).
    pub range: Range<usize>,
    /// A value's text (`1.5`, `sphere { ... }`); empty for macros and parameters.
    pub value: Range<usize>,
    /// Where a parameter is known; `None`: everywhere after it.
    pub scope: Option<Range<usize>>,
}

/// `#include "path"`.
#[derive(Debug, Clone)]
pub struct Include {
    pub path: String,
    /// The string, quotes included.
    pub range: Range<usize>,
    /// The directive's start to the string's end.
    pub whole: Range<usize>,
}

/// A block: `kind { ... }`.
#[derive(Debug, Clone)]
pub struct Block {
    pub kind: String,
    pub kind_range: Range<usize>,
    /// From the kind to the closing brace (or the end of the text when it is never closed).
    pub range: Range<usize>,
    pub closed: bool,
    /// The innermost block around it.
    pub parent: Option<usize>,
}

#[derive(Debug, Clone, Default)]
pub struct Outline {
    pub tokens: Vec<Token>,
    pub decls: Vec<Decl>,
    pub includes: Vec<Include>,
    pub blocks: Vec<Block>,
}

/// What is open at a point of the scan.
enum Open {
    Brace(Option<usize>),
    /// `#if`, `#while`, ... up to `#end`; a macro's with its declaration and its parameters'.
    Directive(Option<(usize, Vec<usize>)>),
}

impl Outline {
    pub fn new(text: &str) -> Self {
        let all = tokens(text);
        // The tokens that mean something (comments left out), with their indices in `all`.
        let sig: Vec<&Token> = all.iter().filter(|t| t.kind != Kind::Comment).collect();
        let mut out = Outline::default();
        let mut open: Vec<Open> = Vec::new();
        let word = |j: usize| {
            sig.get(j)
                .filter(|t| t.kind == Kind::Word)
                .map(|t| (t.text(text).to_string(), t.range()))
        };
        let punct = |j: usize, c: char| sig.get(j).is_some_and(|t| t.is_punct(text, c));
        for (i, t) in sig.iter().enumerate() {
            match t.kind {
                Kind::Directive => {
                    let d = &text[t.start + 1..t.end];
                    match d {
                        "declare" | "local" => {
                            if let Some((name, name_range)) = word(i + 1) {
                                let value_start = if punct(i + 2, '=') { i + 3 } else { i + 2 };
                                let (value, end) = value_extent(text, &sig, value_start)
                                    .unwrap_or((name_range.end..name_range.end, name_range.end));
                                out.decls.push(Decl {
                                    name,
                                    name_range,
                                    kind: DeclKind::Value {
                                        local: d == "local",
                                    },
                                    range: t.start..end,
                                    value,
                                    scope: None,
                                });
                            }
                        }
                        "macro" => {
                            let mut params = Vec::new();
                            let mut names = Vec::new();
                            let mut body = t.end;
                            if let Some((name, name_range)) = word(i + 1) {
                                if punct(i + 2, '(') {
                                    let mut j = i + 3;
                                    while let Some(p) = sig.get(j) {
                                        if p.is_punct(text, ')') || p.kind == Kind::Directive {
                                            body = p.end;
                                            break;
                                        }
                                        if p.kind == Kind::Word {
                                            names.push(p.text(text).to_string());
                                            params.push(out.decls.len() + 1 + params.len());
                                        }
                                        body = p.end;
                                        j += 1;
                                    }
                                }
                                let m = out.decls.len();
                                out.decls.push(Decl {
                                    name,
                                    name_range,
                                    kind: DeclKind::Macro {
                                        params: names.clone(),
                                    },
                                    range: t.start..text.len(),
                                    value: body..body,
                                    scope: None,
                                });
                                let mut k = i + 3;
                                for n in &names {
                                    while let Some(p) = sig.get(k) {
                                        k += 1;
                                        if p.kind == Kind::Word && p.text(text) == n {
                                            out.decls.push(Decl {
                                                name: n.clone(),
                                                name_range: p.range(),
                                                kind: DeclKind::Param,
                                                range: p.range(),
                                                value: p.end..p.end,
                                                scope: Some(body..text.len()),
                                            });
                                            break;
                                        }
                                    }
                                }
                                open.push(Open::Directive(Some((m, params))));
                            } else {
                                open.push(Open::Directive(None));
                            }
                        }
                        "for" => {
                            let mut own = Vec::new();
                            if punct(i + 1, '(')
                                && let Some((name, name_range)) = word(i + 2)
                            {
                                own.push(out.decls.len());
                                out.decls.push(Decl {
                                    name,
                                    name_range: name_range.clone(),
                                    kind: DeclKind::Param,
                                    range: name_range.clone(),
                                    value: name_range.end..name_range.end,
                                    scope: Some(name_range.end..text.len()),
                                });
                            }
                            open.push(Open::Directive(Some((usize::MAX, own))));
                        }
                        "if" | "ifdef" | "ifndef" | "while" | "switch" => {
                            open.push(Open::Directive(None))
                        }
                        "end" => {
                            if let Some(k) =
                                open.iter().rposition(|o| matches!(o, Open::Directive(_)))
                            {
                                // Braces left open inside end with the directive's block.
                                for o in open.drain(k..).rev() {
                                    match o {
                                        Open::Brace(Some(b)) => out.blocks[b].range.end = t.start,
                                        Open::Directive(Some((m, params))) => {
                                            if let Some(d) = out.decls.get_mut(m) {
                                                d.range.end = t.end;
                                            }
                                            for p in params {
                                                if let Some(s) = &mut out.decls[p].scope {
                                                    s.end = t.start;
                                                }
                                            }
                                        }
                                        _ => {}
                                    }
                                }
                            }
                        }
                        "include" => {
                            if let Some(s) = sig.get(i + 1)
                                && matches!(s.kind, Kind::Str { .. })
                            {
                                out.includes.push(Include {
                                    path: s.inner(text).to_string(),
                                    range: s.range(),
                                    whole: t.start..s.end,
                                });
                            }
                        }
                        _ => {}
                    }
                }
                Kind::Punct if t.is_punct(text, '{') => {
                    let kind = i
                        .checked_sub(1)
                        .and_then(|j| sig.get(j))
                        .filter(|k| k.kind == Kind::Word);
                    let b = kind.map(|k| {
                        let parent = open.iter().rev().find_map(|o| match o {
                            Open::Brace(Some(b)) => Some(*b),
                            _ => None,
                        });
                        out.blocks.push(Block {
                            kind: k.text(text).to_string(),
                            kind_range: k.range(),
                            range: k.start..text.len(),
                            closed: false,
                            parent,
                        });
                        out.blocks.len() - 1
                    });
                    open.push(Open::Brace(b));
                }
                Kind::Punct if t.is_punct(text, '}') => {
                    if let Some(k) = open.iter().rposition(|o| matches!(o, Open::Brace(_))) {
                        for o in open.drain(k..) {
                            if let Open::Brace(Some(b)) = o {
                                out.blocks[b].range.end = t.end;
                                out.blocks[b].closed = true;
                            }
                        }
                    }
                }
                _ => {}
            }
        }
        out.tokens = all;
        out
    }

    /// The blocks open at `offset`, outermost first (the cursor is after the `{` and not after
    /// the `}`).
    pub fn blocks_at(&self, text: &str, offset: usize) -> Vec<&Block> {
        let mut inner = self
            .blocks
            .iter()
            .rposition(|b| b.range.start < offset && inside(text, b, offset));
        let mut chain = Vec::new();
        while let Some(i) = inner {
            chain.push(&self.blocks[i]);
            inner = self.blocks[i].parent;
        }
        chain.reverse();
        chain
    }

    /// The declarations whose name is `name` and that are known at `offset`.
    pub fn visible<'a>(&'a self, name: &'a str, offset: usize) -> impl Iterator<Item = &'a Decl> {
        self.decls
            .iter()
            .filter(move |d| d.name == name && d.scope.as_ref().is_none_or(|s| s.contains(&offset)))
    }
}

/// Whether `offset` is inside the braces of `b`.
fn inside(text: &str, b: &Block, offset: usize) -> bool {
    let brace = text[b.kind_range.end..]
        .find('{')
        .map(|k| b.kind_range.end + k);
    brace.is_some_and(|open| open < offset) && (!b.closed || offset < b.range.end)
}

/// Whether a value whose last token is `t` goes on after a line break.
fn continues(text: &str, t: &Token) -> bool {
    (t.kind == Kind::Punct
        && matches!(
            &text[t.start..t.end],
            "=" | "," | "+" | "-" | "*" | "/" | "<" | "?" | ":" | "&" | "|" | "!" | "."
        ))
        || (t.kind == Kind::Word && matches!(t.text(text), "rgb" | "rgbf" | "rgbt" | "rgbft"))
}

/// Whether a token at the start of a line goes on with the value before it.
fn goes_on(text: &str, t: &Token) -> bool {
    t.kind == Kind::Punct
        && matches!(
            &text[t.start..t.end],
            "{" | "+" | "*" | "/" | "?" | ":" | "&" | "|" | "." | ")" | "]" | ">"
        )
}

/// The value starting at `sig[start]`: its range and the end of the declaration (after a `;`).
/// It ends at a `;`, a directive or a line break that ends an item, outside brackets.
fn value_extent(text: &str, sig: &[&Token], start: usize) -> Option<(Range<usize>, usize)> {
    let first = sig.get(start)?;
    if first.kind == Kind::Directive {
        return None;
    }
    let mut depth = 0usize;
    let mut last: &Token = first;
    for (k, t) in sig[start..].iter().enumerate() {
        if depth == 0 && k > 0 {
            if t.is_punct(text, ';') {
                return Some((first.start..last.end, t.end));
            }
            let line_break = text[last.end..t.start].contains(['\n', '\r']);
            if t.kind == Kind::Directive
                || line_break && !continues(text, last) && !goes_on(text, t)
            {
                return Some((first.start..last.end, last.end));
            }
        }
        match t.kind {
            Kind::Punct if matches!(t.text(text), "{" | "(" | "[") => depth += 1,
            Kind::Punct if matches!(t.text(text), "}" | ")" | "]") => {
                if depth == 0 {
                    return Some((first.start..last.end, last.end));
                }
                depth -= 1;
            }
            _ => {}
        }
        last = *t;
    }
    Some((first.start..last.end, last.end))
}

/// What a symbol of the outline is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SymbolKind {
    Value,
    Macro,
    Object,
    Light,
    Camera,
    Settings,
    Material,
}

/// One entry of the document's outline, with the entries inside it.
#[derive(Debug, Clone)]
pub struct Symbol {
    pub name: String,
    pub detail: Option<String>,
    pub kind: SymbolKind,
    pub range: Range<usize>,
    /// The name (or the block's kind word).
    pub selection: Range<usize>,
    pub children: Vec<Symbol>,
}

/// The most symbols an outline lists (a generated file of a million spheres lists the first).
pub const MAX_SYMBOLS: usize = 5000;

fn block_symbol(kind: &str) -> Option<SymbolKind> {
    Some(match kind {
        "light" | "spotlight" | "area_light" => SymbolKind::Light,
        "camera" => SymbolKind::Camera,
        "settings" | "environment" => SymbolKind::Settings,
        "material" | "texture" => SymbolKind::Material,
        _ if crate::eval::block_names().any(|b| b == kind) => SymbolKind::Object,
        _ => return None,
    })
}

/// The document's outline: declarations, macros and blocks (objects, lights, the camera, ...)
/// nested as they stand in the text.
pub fn symbols(text: &str, outline: &Outline) -> Vec<Symbol> {
    let mut flat: Vec<Symbol> = Vec::new();
    for d in &outline.decls {
        let (kind, detail) = match &d.kind {
            DeclKind::Param => continue,
            DeclKind::Macro { params } => (SymbolKind::Macro, format!("({})", params.join(", "))),
            DeclKind::Value { .. } => (SymbolKind::Value, short(&text[d.value.clone()])),
        };
        flat.push(Symbol {
            name: d.name.clone(),
            detail: Some(detail),
            kind,
            range: d.range.clone(),
            selection: d.name_range.clone(),
            children: Vec::new(),
        });
    }
    for b in &outline.blocks {
        // Materials and textures inside objects are details, not entries.
        let Some(kind) = block_symbol(&b.kind) else {
            continue;
        };
        if kind == SymbolKind::Material && b.parent.is_some() {
            continue;
        }
        flat.push(Symbol {
            name: b.kind.clone(),
            detail: None,
            kind,
            range: b.range.clone(),
            selection: b.kind_range.clone(),
            children: Vec::new(),
        });
    }
    flat.truncate(MAX_SYMBOLS);
    // Outer first: by start, the longer range first at one start.
    flat.sort_by(|a, b| {
        a.range
            .start
            .cmp(&b.range.start)
            .then(b.range.end.cmp(&a.range.end))
    });
    nest(flat)
}

/// Nests each symbol in the last one before it whose range holds it.
fn nest(flat: Vec<Symbol>) -> Vec<Symbol> {
    let mut stack: Vec<Symbol> = Vec::new();
    let mut top = Vec::new();
    let close = |stack: &mut Vec<Symbol>, top: &mut Vec<Symbol>| {
        let s = stack.pop().expect("a symbol to close");
        match stack.last_mut() {
            Some(parent) => parent.children.push(s),
            None => top.push(s),
        }
    };
    for s in flat {
        while stack
            .last()
            .is_some_and(|p| !(p.range.start <= s.range.start && s.range.end <= p.range.end))
        {
            close(&mut stack, &mut top);
        }
        stack.push(s);
    }
    while !stack.is_empty() {
        close(&mut stack, &mut top);
    }
    top
}

/// A value's text on one line, at most 60 characters.
fn short(value: &str) -> String {
    let one: String = value.split_whitespace().collect::<Vec<_>>().join(" ");
    match one.char_indices().nth(60) {
        Some((i, _)) => format!("{}…", &one[..i]),
        None => one,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = "#include \"std/colors.scn\"\n\
        #declare R = 0.5;\n\
        #declare Ball = sphere { <0, 0, 0>, R\n  material { diffuse Red }\n}\n\
        #macro Row(N, Gap)\n  #for (I, 0, N)\n    object { Ball translate <I * Gap, 0, 0> }\n  #end\n#end\n\
        camera { location <0, 1, -5> look_at <0, 0, 0> }\n\
        light { <2, 4, -3>, rgb <1, 1, 1> }\n\
        union { Row(3, 1) sphere { <0,0,0>, 1 } }\n";

    #[test]
    fn declarations_macros_parameters_and_includes() {
        let o = Outline::new(SCENE);
        let names: Vec<&str> = o.decls.iter().map(|d| d.name.as_str()).collect();
        assert_eq!(names, ["R", "Ball", "Row", "N", "Gap", "I"]);
        assert_eq!(&SCENE[o.decls[0].value.clone()], "0.5");
        let ball = &SCENE[o.decls[1].value.clone()];
        assert!(
            ball.starts_with("sphere {") && ball.ends_with('}'),
            "{ball}"
        );
        assert_eq!(
            o.decls[2].kind,
            DeclKind::Macro {
                params: vec!["N".into(), "Gap".into()]
            }
        );
        // The parameters are known in the macro's body only.
        let body = SCENE.find("object { Ball").unwrap();
        assert_eq!(o.visible("Gap", body).count(), 1);
        assert_eq!(o.visible("Gap", SCENE.find("camera").unwrap()).count(), 0);
        assert_eq!(o.includes[0].path, "std/colors.scn");
    }

    #[test]
    fn blocks_at_a_point_and_when_left_open() {
        let text = "union {\n  sphere { <0,0,0>, 1 }\n  box { <0,0,0>, <1,1,1>\n    tra";
        let o = Outline::new(text);
        let at: Vec<&str> = o
            .blocks_at(text, text.len())
            .iter()
            .map(|b| b.kind.as_str())
            .collect();
        assert_eq!(at, ["union", "box"]);
        let in_sphere = text.find(", 1").unwrap();
        let at: Vec<&str> = o
            .blocks_at(text, in_sphere)
            .iter()
            .map(|b| b.kind.as_str())
            .collect();
        assert_eq!(at, ["union", "sphere"]);
        assert!(o.blocks_at(text, 3).is_empty());
    }

    #[test]
    fn the_outline_nests_and_names() {
        let o = Outline::new(SCENE);
        let s = symbols(SCENE, &o);
        let top: Vec<(&str, SymbolKind)> = s.iter().map(|s| (s.name.as_str(), s.kind)).collect();
        assert_eq!(
            top,
            [
                ("R", SymbolKind::Value),
                ("Ball", SymbolKind::Value),
                ("Row", SymbolKind::Macro),
                ("camera", SymbolKind::Camera),
                ("light", SymbolKind::Light),
                ("union", SymbolKind::Object)
            ]
        );
        assert_eq!(s[1].children[0].name, "sphere");
        assert_eq!(
            s[1].children[0].children.len(),
            0,
            "the material is a detail"
        );
        assert_eq!(s[2].detail.as_deref(), Some("(N, Gap)"));
        assert_eq!(s[5].children.len(), 1);
    }

    #[test]
    fn a_value_ends_at_a_line_that_starts_an_item() {
        let text = "#declare A = 1 +\n 2\nsphere { <0,0,0>, A }\n#declare B = <1,\n2, 3>\n";
        let o = Outline::new(text);
        assert_eq!(&text[o.decls[0].value.clone()], "1 +\n 2");
        assert_eq!(&text[o.decls[1].value.clone()], "<1,\n2, 3>");
    }
}
