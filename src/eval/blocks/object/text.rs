//! `text { ttf "font.ttf" "string" thickness, offset }` as POV-Ray writes it: the font found
//! (beside the scene file first, then in the system's font folders) and read through the load's
//! world, each character's glyph a prism part of the object.

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::ObjectBuilder;
use crate::diag::{At, Diagnostic, Error, SourceResult, short_number};
use crate::eval::Evaluator;
use crate::eval::value::{Part, ShapeDef, Value};
use crate::scene::ShapeDecl;
use crate::scene::text::{MAX_TEXT_SEGMENTS, TextError, text_glyphs};

const EXAMPLE: &str = "text { ttf \"DejaVuSans.ttf\" \"Hello\" 0.2, 0 }";

/// Where a font named by a bare relative path is looked for when it is not beside the scene
/// file: the usual folders of Debian's and other systems' TrueType fonts.
const FONT_DIRS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu",
    "/usr/share/fonts/truetype",
    "/usr/share/fonts/TTF",
    "/usr/share/fonts",
    "/Library/Fonts",
    "C:/Windows/Fonts",
];

impl ObjectBuilder {
    pub(super) fn text(&self, ev: &mut Evaluator) -> SourceResult<Vec<Part>> {
        let Some((path, written, fspan)) = self.ttf.clone() else {
            return Err(vec![
                Error::new("a text needs a font: `ttf \"file.ttf\"`")
                    .label("no font")
                    .help(format!("e.g. `{EXAMPLE}`"))
                    .at(self.span),
            ]);
        };
        let (string, sspan) = match self.values.first() {
            Some((Value::Str(s), span)) => (s.to_string(), *span),
            _ => {
                return Err(vec![
                    Error::new("a text takes its string, a thickness and an offset")
                        .label("no string first")
                        .help(format!("e.g. `{EXAMPLE}`"))
                        .at(self.values.first().map_or(self.span, |v| v.1)),
                ]);
            }
        };
        let [_, (t, tspan), (o, ospan)] = self.values.as_slice() else {
            return Err(vec![
                Error::new(format!(
                    "a text takes three values (the string, the thickness and the offset), \
                     found {}",
                    self.values.len()
                ))
                .label("here")
                .help(format!("e.g. `{EXAMPLE}` (as in POV-Ray)"))
                .at(self.span),
            ]);
        };
        let thickness = t
            .num()
            .map_err(|e| e.help("the thickness is a number, e.g. `0.2`"))
            .at(*tspan)?;
        if !(thickness.is_finite() && thickness > 0.0) {
            return Err(vec![
                Error::new(format!(
                    "the text's thickness is {}: the letters would have no depth",
                    short_number(thickness)
                ))
                .label("not a positive number")
                .help("give the depth of the letters, e.g. `0.2` (the letters are 1 unit high)")
                .at(*tspan),
            ]);
        }
        // POV-Ray promotes a number to a vector of three equal components.
        let offset = match o {
            Value::Num(n) => DVec3::splat(*n),
            v => v
                .vec3()
                .map_err(|e| e.help("the offset is a vector (or a number): `<0.1, 0, 0>`"))
                .at(*ospan)?,
        };
        if !offset.is_finite() {
            return Err(vec![
                Error::new("the text's offset is not finite")
                    .label("here")
                    .help("e.g. `0` or `<0.05, 0, 0>`")
                    .at(*ospan),
            ]);
        }
        let found = find_font(ev, &path, &written);
        ev.dependencies.push(found.clone());
        let bytes = ev
            .options
            .world
            .read(&found, crate::files::MAX_ASSET_BYTES)
            .map_err(|e| {
                vec![
                    Error::new(format!("cannot open font `{}`: {e}", path.display()))
                        .label("cannot load this font")
                        .help(format!(
                            "{}; a bare file name is also looked for in {}",
                            ev.path_help(fspan),
                            FONT_DIRS.join(", ")
                        ))
                        .at(fspan),
                ]
            })?;
        let glyphs = text_glyphs(&bytes, &string, thickness, offset).map_err(|e| match e {
            TextError::NotAFont(why) => vec![
                Error::new(format!("`{}` is not a font: {why}", found.display()))
                    .label("not a TrueType or OpenType font")
                    .help("give a .ttf or .otf file")
                    .at(fspan),
            ],
            TextError::TooLarge { segments } => vec![
                Error::new(format!(
                    "this text's glyphs make more than {MAX_TEXT_SEGMENTS} curve segments \
                     ({segments} by the character where it stopped)"
                ))
                .label("too much text")
                .help("a text object is for a title or a label: split a long text into lines")
                .at(sspan),
            ],
        })?;
        if string.is_empty() {
            ev.warn(
                Diagnostic::warning(sspan, "this text is empty: it draws nothing")
                    .with_label("empty string")
                    .with_help("give the characters to draw"),
            );
        }
        if !glyphs.missing.is_empty() {
            let list: String = glyphs.missing.iter().take(10).collect();
            ev.warn(
                Diagnostic::warning(
                    sspan,
                    format!(
                        "the font has no glyph for {} character{} (`{list}`): drawn as its \
                         missing-glyph shape",
                        glyphs.missing.len(),
                        if glyphs.missing.len() == 1 { "" } else { "s" }
                    ),
                )
                .with_label("not in the font")
                .with_help("use a font that has these characters"),
            );
        }
        ev.count_parts(0, glyphs.glyphs.len(), sspan)?;
        Ok(glyphs
            .glyphs
            .into_iter()
            .map(|g| Part {
                shape: ShapeDef::Ready(ShapeDecl::Prism(g.prism)),
                transform: g.transform,
                material: None,
                emission: None,
                span: self.span,
            })
            .collect())
    }
}

/// The font's path: beside the scene file when it is there (or the name is not a bare
/// relative name), else the first of [`FONT_DIRS`] that holds a file of that name.
fn find_font(ev: &Evaluator, resolved: &Path, written: &str) -> PathBuf {
    let world = &ev.options.world;
    if world.size(resolved).is_some() || Path::new(written).is_absolute() {
        return resolved.to_path_buf();
    }
    FONT_DIRS
        .iter()
        .map(|d| Path::new(d).join(written))
        .find(|p| world.size(p).is_some())
        .unwrap_or_else(|| resolved.to_path_buf())
}
