//! Hover: what the word under the cursor is. A declared name's value (as the last evaluation
//! left it, else as written) and where it is declared, a macro's signature, a kind of block's
//! or a property's or a directive's line with a link to the language reference.

use std::ops::Range;
use std::path::Path;

use super::docs;
use super::files::included;
use super::lex::{self, Kind};
use super::outline::{Decl, DeclKind, Outline};
use crate::world::World;

#[derive(Debug, Clone, PartialEq)]
pub struct Hover {
    /// Markdown.
    pub text: String,
    /// The word described.
    pub range: Range<usize>,
}

/// What the word at `offset` of `text` (the document at `path`) is.
pub fn hover(
    world: &dyn World,
    path: &Path,
    text: &str,
    outline: &Outline,
    offset: usize,
    globals: &[(String, String)],
) -> Option<Hover> {
    let i = lex::at(&outline.tokens, offset)?;
    let t = &outline.tokens[i];
    let range = t.range();
    let word = t.text(text);
    let found = |text: String| {
        Some(Hover {
            text,
            range: range.clone(),
        })
    };
    match t.kind {
        Kind::Directive => {
            let line = docs::directive(&word[1..])?;
            return found(format!("{line}\n\n{}", docs::link("directives")));
        }
        Kind::Word => {}
        _ => return None,
    }
    // A declared name: the document's own, then the included files'.
    if let Some(d) = outline.visible(word, offset).last() {
        return found(describe(d, text, None, globals));
    }
    for f in included(world, path, outline) {
        if let Some(d) = f
            .outline
            .decls
            .iter()
            .rev()
            .find(|d| d.name == word && d.scope.is_none())
        {
            return found(describe(d, &f.text, Some(&f.path), globals));
        }
    }
    // A property of the block around it.
    if let Some(b) = outline.blocks_at(text, t.start).last()
        && let Some(p) = crate::eval::block_properties(&b.kind)
            .and_then(|ps| ps.into_iter().find(|p| p.name == word))
    {
        let anchor = docs::block(&b.kind).map_or("objects", |(_, a)| a);
        let example = if p.example.is_empty() {
            String::new()
        } else {
            format!(", e.g. `{} {}`", p.name, p.example)
        };
        return found(format!(
            "`{}` in {}: takes {}{example}\n\n{}",
            p.name,
            b.kind,
            p.hint,
            docs::link(anchor)
        ));
    }
    if let Some((line, anchor)) = docs::block(word) {
        return found(format!("{line}\n\n{}", docs::link(anchor)));
    }
    if let Some(p) = crate::eval::top_level_properties()
        .into_iter()
        .find(|p| p.name == word)
    {
        return found(format!(
            "`{}`: takes {}, e.g. `{} {}`\n\n{}",
            p.name,
            p.hint,
            p.name,
            p.example,
            docs::link("background")
        ));
    }
    if crate::eval::FUNCTIONS.contains(&word) {
        return found(format!(
            "`{word}`: a built-in function\n\n{}",
            docs::link("functions")
        ));
    }
    if let Some((_, what)) = crate::scene::ANIMATION_NAMES
        .iter()
        .find(|(n, _)| *n == word)
    {
        return found(format!("`{word}`: {what}\n\n{}", docs::link("animation")));
    }
    None
}

fn describe(d: &Decl, text: &str, from: Option<&Path>, globals: &[(String, String)]) -> String {
    let at = |offset: usize| {
        let line = text[..offset].bytes().filter(|&b| b == b'\n').count() + 1;
        match from {
            Some(p) => format!("{}:{line}", p.display()),
            None => format!("line {line}"),
        }
    };
    match &d.kind {
        DeclKind::Macro { params } => format!(
            "```scn\n#macro {}({})\n```\ndeclared at {}",
            d.name,
            params.join(", "),
            at(d.range.start)
        ),
        DeclKind::Param => format!("`{}`: a parameter or loop variable", d.name),
        DeclKind::Value { local } => {
            let written = clip(&text[d.value.clone()], 400);
            let directive = if *local { "#local" } else { "#declare" };
            let mut out = format!("```scn\n{directive} {} = {written}\n```\n", d.name);
            if let Ok(k) = globals.binary_search_by(|(n, _)| n.as_str().cmp(&d.name)) {
                let value = &globals[k].1;
                if value.as_str() != written.trim() {
                    out.push_str(&format!("value: `{value}`"));
                    if let Some(hex) = swatch(value) {
                        out.push_str(&format!(" ({hex})"));
                    }
                    out.push('\n');
                }
            } else if let Some(hex) = swatch(&written) {
                out.push_str(&format!("{hex}\n"));
            }
            out.push_str(&format!("\ndeclared at {}", at(d.range.start)));
            out
        }
    }
}

fn clip(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((i, _)) => format!("{}…", &text[..i]),
        None => text.to_string(),
    }
}

/// A colour written `rgb <r, g, b>` (linear) as the sRGB hex code an editor's colour
/// picker shows, e.g. `#FF8000`.
fn swatch(value: &str) -> Option<String> {
    let inner = value
        .trim()
        .strip_prefix("rgb")?
        .trim()
        .strip_prefix('<')?
        .strip_suffix('>')?;
    let parts: Vec<f64> = inner
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()?;
    let [r, g, b] = parts[..] else {
        return None;
    };
    let encode = |c: f64| {
        let c = c.clamp(0.0, 1.0);
        let s = if c <= 0.003_130_8 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round() as u8
    };
    Some(format!(
        "sRGB #{:02X}{:02X}{:02X}",
        encode(r),
        encode(g),
        encode(b)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::MemoryWorld;

    fn hover_at(text: &str, marker: &str, globals: &[(String, String)]) -> Option<Hover> {
        let o = Outline::new(text);
        let at = text.find(marker).unwrap() + 1;
        hover(
            &MemoryWorld::new(),
            Path::new("s.scn"),
            text,
            &o,
            at,
            globals,
        )
    }

    #[test]
    fn a_declared_name_shows_its_value() {
        let text = "#declare Warm = rgb <1, 0.2159, 0>;\n#declare K = 2 * 3;\nsphere { <0,0,0>, K material { diffuse Warm } }";
        let h = hover_at(text, "Warm }", &[]).unwrap();
        assert!(
            h.text.contains("#declare Warm = rgb <1, 0.2159, 0>"),
            "{}",
            h.text
        );
        assert!(h.text.contains("sRGB #FF8000"), "{}", h.text);
        assert!(h.text.contains("line 1"));
        assert_eq!(&text[h.range], "Warm");
        let globals = [("K".to_string(), "6".to_string())];
        let h = hover_at(text, "K material", &globals).unwrap();
        assert!(h.text.contains("value: `6`"), "{}", h.text);
    }

    #[test]
    fn macros_keywords_properties_and_directives() {
        let text = "#macro Ball(R, M) sphere { <0,0,0>, R } #end\nBall(1, 2)\ncylinder { <0,0,0>, <0,1,0>, 1 open }";
        let h = hover_at(text, "Ball(1", &[]).unwrap();
        assert!(h.text.contains("#macro Ball(R, M)"), "{}", h.text);
        let h = hover_at(text, "cylinder", &[]).unwrap();
        assert!(h.text.contains("`cylinder {"), "{}", h.text);
        assert!(h.text.contains("docs/language.md#objects"));
        let h = hover_at(text, "open", &[]).unwrap();
        assert!(h.text.contains("`open` in cylinder"), "{}", h.text);
        let h = hover_at(text, "#macro", &[]).unwrap();
        assert!(h.text.contains("#directives"));
        assert!(hover_at(text, "<0,1", &[]).is_none());
    }
}
