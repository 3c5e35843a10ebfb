//! The command line's words for animation: frame and clock ranges, and output names with a
//! frame number (`out_%04d.png`).

use std::path::{Path, PathBuf};

use sppm_lang::internals::scene::MAX_FRAME;

/// `A..B`: the first and last frames, both rendered.
pub fn parse_frames(text: &str) -> Result<(u32, u32), String> {
    let usage = || format!("`{text}` is not a frame range such as 0..99");
    let (a, b) = text.trim().split_once("..").ok_or_else(usage)?;
    let (a, b) = (parse_frame(a).map_err(|_| usage())?, parse_frame(b)?);
    if b < a {
        return Err(format!(
            "the frames run from {a} back to {b}: give the first frame, then the last"
        ));
    }
    Ok((a, b))
}

/// A frame number from 0 to [`MAX_FRAME`].
pub fn parse_frame(text: &str) -> Result<u32, String> {
    match text.trim().parse::<u32>() {
        Ok(n) if n <= MAX_FRAME => Ok(n),
        _ => Err(format!(
            "`{text}` is not a frame number (a whole number from 0 to {MAX_FRAME})"
        )),
    }
}

/// `A..B`: the clock at the first and the last frame (finite numbers).
pub fn parse_clock(text: &str) -> Result<(f64, f64), String> {
    let usage = || format!("`{text}` is not a clock range such as 0..1");
    let (a, b) = text.trim().split_once("..").ok_or_else(usage)?;
    let number = |s: &str| -> Result<f64, String> {
        match s.trim().parse::<f64>() {
            Ok(v) if v.abs() <= sppm_lang::internals::scene::animation::MAX_CLOCK => Ok(v),
            _ => Err(usage()),
        }
    };
    Ok((number(a)?, number(b)?))
}

/// An output name with a place for the frame number: `%d`, or `%0Nd` for at least N digits
/// (padded with zeros), once, in the file's name; `%%` is a `%`.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePattern {
    folder: Option<PathBuf>,
    before: String,
    width: usize,
    after: String,
}

impl FramePattern {
    /// The pattern in `path`'s file name: `Ok(None)` when it has no `%`, an error when its `%`s
    /// are not one placeholder (and `%%`s).
    pub fn parse(path: &Path) -> Result<Option<Self>, String> {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        let folder = path.parent().map(Path::to_path_buf);
        if folder
            .as_ref()
            .is_some_and(|f| f.to_string_lossy().contains('%'))
        {
            return Err(format!(
                "output `{}`: the frame number goes in the file's name, not in its folder",
                path.display()
            ));
        }
        let bad = || {
            format!(
                "output `{}`: a `%` starts the frame number, written `%d` or `%04d` (once); \
                 `%%` is a `%`",
                path.display()
            )
        };
        let (mut before, mut after) = (String::new(), String::new());
        let mut width = None;
        let mut chars = name.chars().peekable();
        while let Some(c) = chars.next() {
            let out = if width.is_some() {
                &mut after
            } else {
                &mut before
            };
            if c != '%' {
                out.push(c);
                continue;
            }
            if chars.peek() == Some(&'%') {
                chars.next();
                out.push('%');
                continue;
            }
            if width.is_some() {
                return Err(bad());
            }
            let mut digits = String::new();
            while let Some(d) = chars.peek().filter(|d| d.is_ascii_digit()) {
                digits.push(*d);
                chars.next();
            }
            if chars.next() != Some('d') || !digits.is_empty() && !digits.starts_with('0') {
                return Err(bad());
            }
            // `%4d` would pad with blanks: file names get zeros, as `%04d`.
            let w: usize = if digits.is_empty() {
                0
            } else {
                digits.parse().map_err(|_| bad())?
            };
            if w > 9 {
                return Err(bad());
            }
            width = Some(w);
        }
        Ok(width.map(|width| Self {
            folder: folder.filter(|f| !f.as_os_str().is_empty()),
            before,
            width,
            after,
        }))
    }

    /// The default for a scene's frames: `scene_0007.png` beside the scene.
    pub fn for_scene(scene: &Path) -> Option<Self> {
        let stem = scene.file_stem()?.to_str()?;
        if stem.is_empty() || stem == "." {
            return None;
        }
        Some(Self {
            folder: scene
                .parent()
                .map(Path::to_path_buf)
                .filter(|f| !f.as_os_str().is_empty()),
            before: format!("{stem}_"),
            width: 4,
            after: ".png".into(),
        })
    }

    /// The frame whose file name is `name` (the name [`FramePattern::path`] gives it), if any.
    pub fn frame_of(&self, name: &str) -> Option<u32> {
        let digits = name.strip_prefix(&self.before)?.strip_suffix(&self.after)?;
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let frame: u32 = digits.parse().ok()?;
        let own = format!("{frame:0width$}", width = self.width);
        (own == digits).then_some(frame)
    }

    /// The pattern written out again (`%` as `%%`, the number as `%0Nd`): what
    /// [`FramePattern::parse`] reads back as this pattern.
    pub fn path_text(&self) -> PathBuf {
        let number = if self.width == 0 {
            "%d".to_string()
        } else {
            format!("%0{}d", self.width)
        };
        let name = format!(
            "{}{number}{}",
            self.before.replace('%', "%%"),
            self.after.replace('%', "%%")
        );
        match &self.folder {
            Some(f) => f.join(name),
            None => PathBuf::from(name),
        }
    }

    /// The file of frame `frame`.
    pub fn path(&self, frame: u32) -> PathBuf {
        let name = format!(
            "{}{frame:0width$}{}",
            self.before,
            self.after,
            width = self.width
        );
        match &self.folder {
            Some(f) => f.join(name),
            None => PathBuf::from(name),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pattern(s: &str) -> Result<Option<FramePattern>, String> {
        FramePattern::parse(Path::new(s))
    }

    #[test]
    fn a_pattern_written_out_reads_back_as_itself() {
        for text in ["out/f_%04d.png", "a%%b_%d.exr", "%07d"] {
            let p = pattern(text).unwrap().unwrap();
            assert_eq!(p.path_text(), PathBuf::from(text));
            assert_eq!(pattern(p.path_text().to_str().unwrap()).unwrap(), Some(p));
        }
        let p = FramePattern::for_scene(Path::new("dir/scene.scn")).unwrap();
        assert_eq!(p.path_text(), PathBuf::from("dir/scene_%04d.png"));
    }

    #[test]
    fn placeholders_give_the_frame_number() {
        let p = pattern("out/f_%04d.png").unwrap().unwrap();
        assert_eq!(p.path(7), Path::new("out/f_0007.png"));
        assert_eq!(p.path(123456), Path::new("out/f_123456.png"));
        let p = pattern("f%d.exr").unwrap().unwrap();
        assert_eq!(p.path(12), Path::new("f12.exr"));
        let p = pattern("100%%_%03d.png").unwrap().unwrap();
        assert_eq!(p.path(5), Path::new("100%_005.png"));
        assert_eq!(pattern("plain.png").unwrap(), None);
        assert_eq!(pattern("100%%.png").unwrap(), None);
    }

    #[test]
    fn names_read_back_as_their_frames() {
        let p = pattern("out/f_%04d.png").unwrap().unwrap();
        for k in [0, 7, 9999, 12345, u32::MAX] {
            let path = p.path(k);
            let name = path.file_name().unwrap().to_str().unwrap();
            assert_eq!(p.frame_of(name), Some(k), "{name}");
        }
        // Not a name this pattern gives: other digits, padding, prefix or suffix.
        for name in [
            "f_007.png",
            "f_00007.png",
            "f_.png",
            "f_12a4.png",
            "g_0001.png",
            "f_0001.exr",
        ] {
            assert_eq!(p.frame_of(name), None, "{name}");
        }
        let plain = pattern("f%d.exr").unwrap().unwrap();
        assert_eq!(plain.frame_of("f12.exr"), Some(12));
        assert_eq!(plain.frame_of("f012.exr"), None);
    }

    #[test]
    fn bad_placeholders_are_refused() {
        for bad in [
            "f_%s.png",
            "f_%4d.png",
            "f_%d_%d.png",
            "f_%.png",
            "f%",
            "%04d/f.png",
            "f_%012d.png",
        ] {
            assert!(pattern(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn ranges_read_as_written() {
        assert_eq!(parse_frames("0..99"), Ok((0, 99)));
        assert_eq!(parse_frames("5..5"), Ok((5, 5)));
        assert!(parse_frames("9..2").is_err());
        assert!(parse_frames("-1..2").is_err());
        assert!(parse_frames("0-99").is_err());
        assert!(parse_frames(&format!("0..{}", MAX_FRAME + 1)).is_err());
        assert_eq!(parse_clock("0.5..-1.5"), Ok((0.5, -1.5)));
        assert!(parse_clock("0..inf").is_err());
        assert!(parse_clock("0..nan").is_err());
    }

    #[test]
    fn the_default_name_follows_the_scene() {
        let p = FramePattern::for_scene(Path::new("scenes/ball.scn")).unwrap();
        assert_eq!(p.path(3), Path::new("scenes/ball_0003.png"));
    }
}
