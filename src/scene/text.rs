//! POV-Ray's `text`: a TrueType or OpenType font's glyphs as prisms, one per character, read
//! with `ttf-parser`. A glyph's outline (lines, quadratic and cubic curves) becomes the prism's
//! cubic Bezier profile in em units (the font's em is 1 unit), swept from z = 0 to the
//! thickness: the baseline runs along +x at y = 0, each character placed after the one before
//! it by its advance, the kerning of the pair (the font's `kern` table) and the offset.
//!
//! TrueType fills by the non-zero rule, the prism by even-odd: the two agree as long as a
//! glyph's contours do not overlap one another, which holds for the outlines of static fonts
//! (a variable font's overlapping contours would show their overlap as a hole).

use glam::{DAffine3, DVec2, DVec3};

use super::Prism;

/// Most curve segments of all the glyphs of one `text` (a glyph has a few dozen): about 64 MB
/// of profiles in the scene.
pub const MAX_TEXT_SEGMENTS: usize = 1_000_000;

/// One character's glyph: its prism (profile in em units, swept along y from 0 to the
/// thickness) and the transform that stands it up at its place along the baseline.
#[derive(Debug, Clone)]
pub struct PlacedGlyph {
    pub prism: Prism,
    pub transform: DAffine3,
}

/// What the text came to, and what it could not draw.
#[derive(Debug, Clone, Default)]
pub struct TextGlyphs {
    pub glyphs: Vec<PlacedGlyph>,
    /// Characters the font has no glyph for (drawn as its missing-glyph shape, glyph 0).
    pub missing: Vec<char>,
}

/// Why a text cannot be made.
#[derive(Debug, Clone, PartialEq)]
pub enum TextError {
    /// The bytes are not a font `ttf-parser` reads.
    NotAFont(String),
    /// The glyphs' profiles pass [`MAX_TEXT_SEGMENTS`].
    TooLarge { segments: usize },
}

/// Collects a glyph's outline as cubic Bezier segments, in font units.
struct Outline {
    segments: Vec<[DVec2; 4]>,
    start: DVec2,
    at: DVec2,
}

impl Outline {
    fn push(&mut self, c: [DVec2; 4]) {
        if c.iter().any(|p| *p != c[0]) {
            self.segments.push(c);
        }
        self.at = c[3];
    }
}

impl ttf_parser::OutlineBuilder for Outline {
    fn move_to(&mut self, x: f32, y: f32) {
        self.close();
        self.start = DVec2::new(f64::from(x), f64::from(y));
        self.at = self.start;
    }
    fn line_to(&mut self, x: f32, y: f32) {
        let (a, b) = (self.at, DVec2::new(f64::from(x), f64::from(y)));
        self.push([a, a + (b - a) / 3.0, a + (b - a) * (2.0 / 3.0), b]);
    }
    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        let (a, c, b) = (
            self.at,
            DVec2::new(f64::from(x1), f64::from(y1)),
            DVec2::new(f64::from(x), f64::from(y)),
        );
        // The quadratic raised to a cubic (the same curve).
        self.push([a, a + (c - a) * (2.0 / 3.0), b + (c - b) * (2.0 / 3.0), b]);
    }
    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        let p = |x: f32, y: f32| DVec2::new(f64::from(x), f64::from(y));
        self.push([self.at, p(x1, y1), p(x2, y2), p(x, y)]);
    }
    fn close(&mut self) {
        if self.at != self.start {
            self.line_to(self.start.x as f32, self.start.y as f32);
            self.at = self.start;
        }
    }
}

/// The glyphs of `text` in the font `font` (a TrueType or OpenType file's bytes), `thickness`
/// deep, each character moved by `offset` from where the one before it left off.
pub fn text_glyphs(
    font: &[u8],
    text: &str,
    thickness: f64,
    offset: DVec3,
) -> Result<TextGlyphs, TextError> {
    let face = ttf_parser::Face::parse(font, 0).map_err(|e| TextError::NotAFont(e.to_string()))?;
    let em = f64::from(face.units_per_em());
    let kern: Vec<_> = face
        .tables()
        .kern
        .map(|k| {
            k.subtables
                .into_iter()
                .filter(|s| s.horizontal && !s.variable && !s.has_cross_stream)
                .collect()
        })
        .unwrap_or_default();
    // Stands a prism (profile in x and z, swept along y) up: its y becomes z and its z the
    // glyph's y (the profile is stored with z = -y, so the turn is a rotation, not a mirror).
    let stand = DAffine3::from_rotation_x(std::f64::consts::FRAC_PI_2);
    let mut out = TextGlyphs::default();
    let mut pen = DVec3::ZERO;
    let mut previous: Option<ttf_parser::GlyphId> = None;
    let mut total = 0usize;
    for ch in text.chars() {
        let id = face.glyph_index(ch).unwrap_or_else(|| {
            if !out.missing.contains(&ch) {
                out.missing.push(ch);
            }
            ttf_parser::GlyphId(0)
        });
        if let Some(left) = previous {
            let k = kern
                .iter()
                .find_map(|s| s.glyphs_kerning(left, id))
                .unwrap_or(0);
            pen.x += f64::from(k) / em;
        }
        let mut outline = Outline {
            segments: Vec::new(),
            start: DVec2::ZERO,
            at: DVec2::ZERO,
        };
        face.outline_glyph(id, &mut outline);
        ttf_parser::OutlineBuilder::close(&mut outline);
        if !outline.segments.is_empty() {
            total += outline.segments.len();
            if total > MAX_TEXT_SEGMENTS {
                return Err(TextError::TooLarge { segments: total });
            }
            let segments = outline
                .segments
                .iter()
                .map(|c| c.map(|p| DVec2::new(p.x / em, -p.y / em)))
                .collect();
            out.glyphs.push(PlacedGlyph {
                prism: Prism {
                    segments,
                    heights: (0.0, thickness),
                    conic: false,
                    open: false,
                },
                transform: DAffine3::from_translation(pen) * stand,
            });
        }
        pen.x += f64::from(face.glyph_hor_advance(id).unwrap_or(0)) / em;
        pen += offset;
        previous = Some(id);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEJAVU: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

    #[test]
    fn glyphs_stand_on_the_baseline_one_em_high() {
        let Ok(font) = std::fs::read(DEJAVU) else {
            panic!("{DEJAVU} is missing: install fonts-dejavu-core (.ci/run does)");
        };
        let t = text_glyphs(&font, "Hi", 0.5, DVec3::ZERO).unwrap();
        assert_eq!(t.glyphs.len(), 2);
        assert!(t.missing.is_empty());
        // The H's profile, stood up: from the baseline to the cap height (0.73 em in DejaVu).
        let g = &t.glyphs[0];
        let ys: Vec<f64> = g
            .prism
            .segments
            .iter()
            .flatten()
            .map(|p| g.transform.transform_point3(DVec3::new(p.x, 0.0, p.y)).y)
            .collect();
        let (lo, hi) = ys
            .iter()
            .fold((f64::MAX, f64::MIN), |m, &y| (m.0.min(y), m.1.max(y)));
        assert!(lo.abs() < 1e-9 && (hi - 0.729).abs() < 0.01, "{lo} {hi}");
        // The i starts after the H's advance.
        assert!(t.glyphs[1].transform.translation.x > 0.7);
        // The sweep runs along +z.
        let z = g.transform.transform_point3(DVec3::new(0.0, 0.5, 0.0)).z;
        assert!((z - 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_file_that_is_not_a_font_is_refused() {
        assert!(matches!(
            text_glyphs(b"not a font at all", "a", 1.0, DVec3::ZERO),
            Err(TextError::NotAFont(_))
        ));
    }
}
