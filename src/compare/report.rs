//! A failure report for image comparisons: expected, actual and difference images side by side
//! in an HTML page, so a person can see what changed.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::{ErrorStats, ImageView};

/// The files a report consists of.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportFiles {
    pub html: PathBuf,
    pub expected: PathBuf,
    pub actual: PathBuf,
    pub difference: PathBuf,
}

/// Writes `<name>.expected.png`, `<name>.actual.png`, `<name>.diff.png` and `<name>.html` into
/// `dir`. The images are tone-mapped for eyes (clamp, sRGB); the difference image shows
/// `|actual - expected|` scaled so that the largest difference is white.
pub fn write_report(
    dir: &Path,
    name: &str,
    expected: ImageView<'_>,
    actual: ImageView<'_>,
    stats: Option<&ErrorStats>,
    notes: &str,
) -> Result<ReportFiles, String> {
    if (expected.width, expected.height) != (actual.width, actual.height) {
        return Err(format!(
            "cannot compare a {}x{} image with a {}x{} one",
            actual.width, actual.height, expected.width, expected.height
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create `{}`: {e}", dir.display()))?;
    let files = ReportFiles {
        html: dir.join(format!("{name}.html")),
        expected: dir.join(format!("{name}.expected.png")),
        actual: dir.join(format!("{name}.actual.png")),
        difference: dir.join(format!("{name}.diff.png")),
    };
    save_png(&files.expected, expected)?;
    save_png(&files.actual, actual)?;
    let diff: Vec<[f32; 3]> = expected
        .pixels
        .iter()
        .zip(actual.pixels)
        .map(|(e, a)| {
            let d = (0..3).map(|c| (a[c] - e[c]).abs()).sum::<f32>() / 3.0;
            let d = if d.is_finite() { d } else { f32::MAX };
            [d; 3]
        })
        .collect();
    let max = diff.iter().map(|p| p[0]).fold(0.0f32, f32::max);
    let scaled: Vec<[f32; 3]> = diff
        .iter()
        .map(|p| {
            let v = if max > 0.0 { p[0] / max } else { 0.0 };
            // Black = same; shades of red to white = larger differences.
            [v.sqrt(), v, v]
        })
        .collect();
    save_png(
        &files.difference,
        ImageView {
            width: expected.width,
            height: expected.height,
            pixels: &scaled,
        },
    )?;
    let file_name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let mut html = String::new();
    let _ = write!(
        html,
        "<!doctype html><meta charset=utf-8><title>{name}: image comparison</title>\
         <style>body{{font-family:sans-serif}} img{{width:384px;image-rendering:pixelated}} \
         td{{padding:4px;text-align:center}}</style>\
         <h1>{name}</h1><p>{}</p>",
        escape(notes)
    );
    if let Some(s) = stats {
        let _ = write!(
            html,
            "<p>RMSE {:.6}, relative MSE {:.6}, mean absolute error {:.6}, mean bias {:+.6}, \
             {} pixels compared, {} non-finite.</p>",
            s.rmse, s.rel_mse, s.mae, s.mean_bias, s.pixels, s.non_finite
        );
    }
    let _ = write!(
        html,
        "<table><tr><td><img src=\"{}\"><br>expected</td><td><img src=\"{}\"><br>actual</td>\
         <td><img src=\"{}\"><br>|actual - expected| (white = {max:.4})</td></tr></table>",
        file_name(&files.expected),
        file_name(&files.actual),
        file_name(&files.difference)
    );
    std::fs::write(&files.html, html)
        .map_err(|e| format!("cannot write `{}`: {e}", files.html.display()))?;
    Ok(files)
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// sRGB-encodes a linear value clamped to [0, 1] into a byte.
fn srgb8(v: f32) -> u8 {
    let v = if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

fn save_png(path: &Path, img: ImageView<'_>) -> Result<(), String> {
    let bytes: Vec<u8> = img.pixels.iter().flat_map(|p| p.map(srgb8)).collect();
    image::RgbImage::from_raw(img.width, img.height, bytes)
        .ok_or_else(|| "image size does not match its pixels".to_string())?
        .save(path)
        .map_err(|e| format!("cannot write `{}`: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_shows_where_images_differ() {
        let dir = tempfile::tempdir().unwrap();
        let expected = vec![[0.5f32; 3]; 16];
        let mut actual = expected.clone();
        actual[5] = [1.0, 0.5, 0.5];
        let (e, a) = (
            ImageView::new(4, 4, &expected).unwrap(),
            ImageView::new(4, 4, &actual).unwrap(),
        );
        let stats = super::super::error(a, e, None).unwrap();
        let files = write_report(dir.path(), "case", e, a, Some(&stats), "a <test>").unwrap();
        let html = std::fs::read_to_string(&files.html).unwrap();
        assert!(html.contains("case.diff.png") && html.contains("a &lt;test&gt;"));
        let diff = image::open(&files.difference).unwrap().to_rgb8();
        assert_eq!(
            diff.get_pixel(1, 1).0,
            [255, 255, 255],
            "the changed pixel is white"
        );
        assert_eq!(
            diff.get_pixel(0, 0).0,
            [0, 0, 0],
            "unchanged pixels are black"
        );
        let exp = image::open(&files.expected).unwrap().to_rgb8();
        assert_eq!(
            exp.get_pixel(0, 0).0,
            [188, 188, 188],
            "0.5 linear is sRGB 188"
        );
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let a = vec![[0.0f32; 3]; 4];
        let b = vec![[0.0f32; 3]; 1];
        let r = write_report(
            dir.path(),
            "x",
            ImageView::new(2, 2, &a).unwrap(),
            ImageView::new(1, 1, &b).unwrap(),
            None,
            "",
        );
        assert!(r.is_err());
    }
}
