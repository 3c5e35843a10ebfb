//! The image: linear RGB in f64, and writing it to PNG (sRGB, exposure) or EXR (linear).
//! Files are written atomically: a temporary file in the target directory, then a rename.

use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

// The PNG encoder by name, not `write_to`: that builds every format's encoder for the
// writer's type (JPEG, GIF, HDR as well), code the library compiles and never runs.
use image::codecs::png::PngEncoder;
use image::{Rgb, RgbImage};

use crate::diag::Diagnostic;

/// A finished (or snapshot) image: linear RGB, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f64; 3]>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> [f64; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Mean over all pixels, per channel.
    pub fn mean(&self) -> [f64; 3] {
        let n = self.pixels.len().max(1) as f64;
        let s = self
            .pixels
            .iter()
            .fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
        [s[0] / n, s[1] / n, s[2] / n]
    }

    /// Writes the image; the format follows the extension (`.png`, `.exr`). `exposure`
    /// multiplies PNG values before the sRGB curve; EXR is written linear and unscaled.
    /// Fails with a diagnostic at no place (the file is the caller's, not the scene's).
    pub fn write(&self, path: &Path, exposure: f64) -> Result<(), Diagnostic> {
        crate::atomic_file::write_atomic(path, |_, file| self.encode_file(path, exposure, file))
            .map_err(Diagnostic::unplaced)
    }

    /// The image encoded into `file` in the format of `path`'s extension (see
    /// [`Image::write`]; `path` names the file in messages).
    pub fn encode(&self, path: &Path, exposure: f64, file: &mut File) -> Result<(), Diagnostic> {
        self.encode_file(path, exposure, file)
            .map_err(Diagnostic::unplaced)
    }

    /// [`Image::encode`] with the message alone, as [`crate::atomic_file`] takes it.
    fn encode_file(&self, path: &Path, exposure: f64, file: &mut File) -> Result<(), String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        // (The fields are public: an image built by hand may not hold what it says.)
        if self.width == 0 || self.height == 0 {
            return Err(format!(
                "cannot write `{}`: the image is {}x{} pixels (it needs at least one)",
                path.display(),
                self.width,
                self.height
            ));
        }
        if self.pixels.len() as u64 != self.width as u64 * self.height as u64 {
            return Err(format!(
                "cannot write `{}`: the image says {}x{} pixels but holds {}",
                path.display(),
                self.width,
                self.height,
                self.pixels.len()
            ));
        }
        let mut w = BufWriter::new(IoErrorKept {
            inner: file,
            error: None,
        });
        match ext.as_str() {
            "png" => {
                let img = RgbImage::from_fn(self.width, self.height, |x, y| {
                    let p = self.get(x, y);
                    Rgb(p.map(|v| encode_srgb(v * exposure)))
                });
                img.write_with_encoder(PngEncoder::new(&mut w))
                    .map_err(|e| e.to_string())
            }
            "exr" => self.write_exr(&mut w, &[]).map_err(|e| e.to_string()),
            _ => {
                return Err(format!(
                    "unknown image format `.{ext}` for `{}`: use .png or .exr",
                    path.display()
                ));
            }
        }
        .map_err(|e| {
            // The encoders wrap the file's own error (a full disk) in messages of their own:
            // the file's error is the one to show.
            match w.get_ref().error.as_ref() {
                Some(io) => format!("cannot write `{}`: {io}", path.display()),
                None => format!("cannot encode `{}`: {e}", path.display()),
            }
        })?;
        w.flush()
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))
    }
}

/// A file writer [`Image::write_exr`] takes: one type for every caller, so `exr`'s writer is
/// compiled once (it is generic over the writer and the pixel source).
pub(crate) trait WriteSeek: Write + Seek {}

impl<W: Write + Seek> WriteSeek for W {}

impl Image {
    /// The image as a linear f32 RGB EXR (`exr`'s default encoding), with `attributes` added
    /// to its header as text. Render images and chain files are both written here.
    pub(crate) fn write_exr(
        &self,
        w: &mut dyn WriteSeek,
        attributes: &[(&str, &str)],
    ) -> Result<(), exr::error::Error> {
        use exr::prelude::{AttributeValue, Image as ExrImage, SpecificChannels, Text, Vec2};
        let width = self.width as usize;
        let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
            let v = self.pixels[p.y() * width + p.x()];
            (v[0] as f32, v[1] as f32, v[2] as f32)
        });
        let mut exr = ExrImage::from_channels((width, self.height as usize), channels);
        for &(key, value) in attributes {
            exr.attributes
                .other
                .insert(Text::from(key), AttributeValue::Text(Text::from(value)));
        }
        exr::prelude::WritableImage::write(&exr).to_buffered(w)
    }
}

/// A writer that keeps the first error of the file it writes to.
struct IoErrorKept<'a> {
    inner: &'a mut File,
    error: Option<std::io::Error>,
}

impl Write for IoErrorKept<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.inner.write(buf).inspect_err(|e| self.keep(e))
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush().inspect_err(|e| self.keep(e))
    }
}

impl std::io::Seek for IoErrorKept<'_> {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(pos).inspect_err(|e| self.keep(e))
    }
}

impl IoErrorKept<'_> {
    fn keep(&mut self, e: &std::io::Error) {
        if self.error.is_none() {
            self.error = Some(std::io::Error::new(e.kind(), e.to_string()));
        }
    }
}

/// Linear value to an 8-bit sRGB code (NaN maps to 0).
pub fn encode_srgb(v: f64) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_png_and_exr_atomically() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = Image::new(3, 2);
        img.pixels[1] = [0.5, 1.0, 2.0];
        for name in ["a.png", "a.exr"] {
            let p = dir.path().join(name);
            img.write(&p, 1.0).unwrap();
            assert!(p.exists());
        }
        let back = image::open(dir.path().join("a.exr")).unwrap().to_rgb32f();
        assert_eq!(back.get_pixel(1, 0).0, [0.5, 1.0, 2.0]);
        assert!(img.write(&dir.path().join("a.bmp"), 1.0).is_err());
        // An image of no pixels, or holding fewer than it says, is refused in every format
        // (the EXR encoder wrote a file that does not load) and leaves no file.
        let mut short = Image::new(3, 2);
        short.pixels.pop();
        for bad in [Image::new(0, 5), Image::new(5, 0), short] {
            for name in ["b.png", "b.exr"] {
                let p = dir.path().join(name);
                let e = bad.write(&p, 1.0).unwrap_err();
                assert!(e.message.contains("cannot write"), "{e}");
                assert!(!p.exists());
            }
        }
        // Only the two outputs remain: no temporary left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
        assert_eq!(encode_srgb(1.0), 255);
        assert_eq!(encode_srgb(f64::NAN), 0);
    }
}
