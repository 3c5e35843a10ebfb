//! Image comparison: error metrics of a rendered image against a reference, in linear RGB.
//!
//! Used by the speed-versus-accuracy chart and by the golden-image tests. All metrics average
//! over pixels and the three channels. The relative MSE is the one pbrt and Mitsuba report
//! (`(x - ref)^2 / (ref^2 + eps)`, eps = 0.01), so that dark regions count as much as bright ones
//! without dividing by zero.

use std::fmt;

mod report;

pub use report::{ReportFiles, write_report};

/// A borrowed linear RGB image, row 0 at the top.
#[derive(Debug, Clone, Copy)]
pub struct ImageView<'a> {
    pub width: u32,
    pub height: u32,
    pub pixels: &'a [[f32; 3]],
}

impl<'a> ImageView<'a> {
    pub fn new(width: u32, height: u32, pixels: &'a [[f32; 3]]) -> Result<Self, String> {
        if pixels.len() != width as usize * height as usize {
            return Err(format!(
                "image of {width}x{height} needs {} pixels, has {}",
                width as usize * height as usize,
                pixels.len()
            ));
        }
        Ok(Self {
            width,
            height,
            pixels,
        })
    }
}

/// A rectangle of pixels: columns `x0..x1`, rows `y0..y1` (half-open, 0-based, row 0 at the top).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Window {
    /// Parses `x0,y0,x1,y1` (columns then rows, half-open).
    pub fn parse(text: &str) -> Result<Self, String> {
        let parts: Vec<u32> = text
            .split(',')
            .map(|s| s.trim().parse::<u32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("window `{text}`: expected four whole numbers x0,y0,x1,y1"))?;
        match parts[..] {
            [x0, y0, x1, y1] if x0 < x1 && y0 < y1 => Ok(Self { x0, y0, x1, y1 }),
            [_, _, _, _] => Err(format!(
                "window `{text}` is empty: need x0 < x1 and y0 < y1"
            )),
            _ => Err(format!(
                "window `{text}`: expected four numbers x0,y0,x1,y1"
            )),
        }
    }

    fn whole(width: u32, height: u32) -> Self {
        Self {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }
}

impl fmt::Display for Window {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "columns {}..{}, rows {}..{}",
            self.x0, self.x1, self.y0, self.y1
        )
    }
}

/// Error of an image against a reference over a window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorStats {
    /// Root mean squared error.
    pub rmse: f64,
    /// Mean of `(x - ref)^2 / (ref^2 + 0.01)`.
    pub rel_mse: f64,
    /// Mean absolute error.
    pub mae: f64,
    /// Mean of the image minus mean of the reference (the bias of the average).
    pub mean_bias: f64,
    /// Pixels compared.
    pub pixels: usize,
    /// Non-finite values found in the image (they are counted as errors, not compared).
    pub non_finite: usize,
}

/// Compares `image` with `reference` over `window` (the whole image when `None`).
pub fn error(
    image: ImageView<'_>,
    reference: ImageView<'_>,
    window: Option<Window>,
) -> Result<ErrorStats, String> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(format!(
            "image is {}x{} but the reference is {}x{}",
            image.width, image.height, reference.width, reference.height
        ));
    }
    let w = window.unwrap_or(Window::whole(image.width, image.height));
    if w.x1 > image.width || w.y1 > image.height || w.x0 >= w.x1 || w.y0 >= w.y1 {
        return Err(format!(
            "window {w} does not fit in a {}x{} image",
            image.width, image.height
        ));
    }
    let (mut se, mut rel, mut ae, mut sum_i, mut sum_r) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
    let (mut count, mut non_finite) = (0usize, 0usize);
    for y in w.y0..w.y1 {
        for x in w.x0..w.x1 {
            let i = (y * image.width + x) as usize;
            let (p, r) = (image.pixels[i], reference.pixels[i]);
            if p.iter().any(|v| !v.is_finite()) {
                non_finite += 1;
                continue;
            }
            for c in 0..3 {
                let (v, rv) = (p[c] as f64, r[c] as f64);
                let d = v - rv;
                se += d * d;
                rel += d * d / (rv * rv + 0.01);
                ae += d.abs();
                sum_i += v;
                sum_r += rv;
            }
            count += 1;
        }
    }
    let n = (count * 3).max(1) as f64;
    Ok(ErrorStats {
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
        mae: ae / n,
        mean_bias: (sum_i - sum_r) / n,
        pixels: count,
        non_finite,
    })
}

/// Per-pixel relative difference `|x - ref| / (|ref| + eps)` averaged over channels, for
/// thresholded "share of bad pixels" tests.
pub fn pixel_relative_differences(
    image: ImageView<'_>,
    reference: ImageView<'_>,
    eps: f32,
) -> Result<Vec<f32>, String> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(format!(
            "image is {}x{} but the reference is {}x{}",
            image.width, image.height, reference.width, reference.height
        ));
    }
    Ok(image
        .pixels
        .iter()
        .zip(reference.pixels)
        .map(|(p, r)| {
            (0..3)
                .map(|c| {
                    // Equal values differ by nothing, whatever `eps` (0 / 0 would be NaN).
                    if p[c] == r[c] {
                        return 0.0;
                    }
                    let d = (p[c] - r[c]).abs() / (r[c].abs() + eps);
                    if d.is_finite() { d } else { f32::INFINITY }
                })
                .sum::<f32>()
                / 3.0
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view(w: u32, h: u32, px: &[[f32; 3]]) -> ImageView<'_> {
        ImageView::new(w, h, px).unwrap()
    }

    #[test]
    fn identical_images_have_zero_error() {
        let px = vec![[0.5, 0.25, 1.0]; 16];
        let e = error(view(4, 4, &px), view(4, 4, &px), None).unwrap();
        assert_eq!(e.rmse, 0.0);
        assert_eq!(e.rel_mse, 0.0);
        assert_eq!(e.pixels, 16);
    }

    /// Equal pixels differ by 0, black ones with `eps` 0 too (0 / 0 was counted as infinite).
    #[test]
    fn equal_pixels_have_no_relative_difference() {
        let px = vec![[0.0, 0.25, 1.0]; 4];
        for eps in [0.0, 1e-3] {
            let d = pixel_relative_differences(view(2, 2, &px), view(2, 2, &px), eps).unwrap();
            assert_eq!(d, vec![0.0; 4], "eps {eps}");
        }
        let other = vec![[1.0, 0.25, 1.0]; 4];
        let d = pixel_relative_differences(view(2, 2, &other), view(2, 2, &px), 0.0).unwrap();
        assert!(d.iter().all(|v| v.is_infinite()), "{d:?}");
    }

    #[test]
    fn constant_offset_gives_known_rmse_and_bias() {
        let reference = vec![[1.0, 1.0, 1.0]; 4];
        let image = vec![[1.1, 1.1, 1.1]; 4];
        let e = error(view(2, 2, &image), view(2, 2, &reference), None).unwrap();
        assert!((e.rmse - 0.1).abs() < 1e-6);
        assert!((e.mean_bias - 0.1).abs() < 1e-6);
        assert!((e.rel_mse - 0.01 / 1.01).abs() < 1e-6);
    }

    #[test]
    fn window_restricts_the_comparison() {
        // Only pixel (1, 0) differs; a window excluding it sees no error.
        let reference = vec![[0.0; 3]; 4];
        let mut image = reference.clone();
        image[1] = [1.0; 3];
        let left = Window::parse("0,0,1,2").unwrap();
        let e = error(view(2, 2, &image), view(2, 2, &reference), Some(left)).unwrap();
        assert_eq!((e.rmse, e.pixels), (0.0, 2));
        let right = Window::parse("1,0,2,1").unwrap();
        let e = error(view(2, 2, &image), view(2, 2, &reference), Some(right)).unwrap();
        assert_eq!((e.rmse, e.pixels), (1.0, 1));
    }

    #[test]
    fn non_finite_pixels_are_counted_not_averaged() {
        let reference = vec![[0.5; 3]; 2];
        let image = vec![[f32::NAN, 0.5, 0.5], [0.5; 3]];
        let e = error(view(2, 1, &image), view(2, 1, &reference), None).unwrap();
        assert_eq!((e.non_finite, e.pixels), (1, 1));
        assert!(e.rmse.is_finite());
    }

    #[test]
    fn bad_windows_and_sizes_are_errors() {
        assert!(Window::parse("1,2,3").is_err());
        assert!(Window::parse("3,0,1,4").is_err());
        assert!(Window::parse("a,b,c,d").is_err());
        let px = vec![[0.0; 3]; 4];
        let far = Window::parse("0,0,5,5").unwrap();
        assert!(error(view(2, 2, &px), view(2, 2, &px), Some(far)).is_err());
        let small = vec![[0.0; 3]; 1];
        assert!(error(view(2, 2, &px), view(1, 1, &small), None).is_err());
        assert!(ImageView::new(3, 3, &px).is_err());
    }
}
