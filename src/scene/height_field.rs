//! POV-Ray's `height_field`: a grid of heights over the unit square of the (x, z) plane, read
//! from an image (grey level, or red and green as the high and low byte of a colour image) or
//! sampled from a function, as the renderer takes it.
//!
//! Sample `(i, j)` lies at `x = i / (nx - 1)`, `z = j / (nz - 1)`, its height in `[0, 1]`; an
//! image's top row is at `z = 1` (POV-Ray's orientation: the image seen from above, +z up).

use std::sync::Arc;

/// Most samples along either side of a height field (an image's own limit).
pub const MAX_HEIGHT_FIELD_SIDE: u32 = super::assets::MAX_IMAGE_SIDE;

/// Bytes a height field holds per sample while it renders: its height (f32, 4 bytes) and its
/// share of the min/max hierarchy (two f32 per block of 2x2 cells and a third more for the
/// coarser levels: 2.7 bytes), rounded up.
pub const HEIGHT_FIELD_BYTES_PER_SAMPLE: u64 = 7;

/// The heights of a grid, row by row along x (`heights[j * nx + i]`).
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGrid {
    pub nx: u32,
    pub nz: u32,
    pub heights: Vec<f32>,
}

impl HeightGrid {
    /// The height of sample `(i, j)`.
    #[inline]
    pub fn at(&self, i: u32, j: u32) -> f32 {
        self.heights[j as usize * self.nx as usize + i as usize]
    }

    /// The bytes the renderer holds for this grid ([`HEIGHT_FIELD_BYTES_PER_SAMPLE`] a sample).
    pub fn render_bytes(&self) -> u64 {
        (self.nx as u64 * self.nz as u64).saturating_mul(HEIGHT_FIELD_BYTES_PER_SAMPLE)
    }
}

/// A height field: the solid between the water level and the surface over the unit square.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightField {
    pub grid: Arc<HeightGrid>,
    /// POV-Ray's `water_level`: the solid's bottom; the terrain below it is cut away.
    pub water: f64,
    /// Normals interpolated from the samples' (POV-Ray's `smooth`).
    pub smooth: bool,
}

use super::assets::AssetError;

/// How a pixel becomes a height, as POV-Ray reads it (values in `[0, 1]` as stored, no
/// transfer curve).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reading {
    /// A grey image: the grey level.
    Grey,
    /// An 8-bit colour image: red and green as the high and low byte of a 16-bit number.
    RedGreen,
    /// A colour image of more bits (16-bit PNG, EXR): the grey level of its colour.
    Luminance,
}

fn height_of(reading: Reading, [r, g, b]: [f32; 3]) -> f32 {
    match reading {
        Reading::Grey => r,
        Reading::RedGreen => ((r * 255.0).round() * 256.0 + (g * 255.0).round()) / 65535.0,
        // POV-Ray's GREY_SCALE3.
        Reading::Luminance => 0.297 * r + 0.589 * g + 0.114 * b,
    }
    .clamp(0.0, 1.0)
}

/// Bytes decoding an image of `w x h` pixels may hold at its peak besides the heights: the
/// decoded pixels at their widest (four f32 channels).
pub fn decode_bytes(w: u32, h: u32) -> u64 {
    (w as u64 * h as u64).saturating_mul(16)
}

/// The heights of the image in `bytes` (named `path` in messages), refused from its header
/// when a side passes [`MAX_HEIGHT_FIELD_SIDE`] or decoding it and keeping its heights would
/// take more than `room` bytes.
pub fn height_grid_from_image(
    bytes: &[u8],
    path: &std::path::Path,
    room: u64,
) -> Result<HeightGrid, AssetError> {
    let content = |message: String| AssetError {
        message,
        read: true,
        help: None,
    };
    let reader = || {
        let mut r = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| content(format!("cannot read image `{}`: {e}", path.display())))?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_HEIGHT_FIELD_SIDE);
        limits.max_image_height = Some(MAX_HEIGHT_FIELD_SIDE);
        limits.max_alloc = Some(room);
        r.limits(limits);
        Ok::<_, AssetError>(r)
    };
    let (w, h) = reader()?
        .into_dimensions()
        .map_err(|e| content(format!("cannot decode image `{}`: {e}", path.display())))?;
    if w > MAX_HEIGHT_FIELD_SIDE || h > MAX_HEIGHT_FIELD_SIDE {
        return Err(AssetError {
            message: format!(
                "image `{}` is {w}x{h} pixels: a height field has at most \
                 {MAX_HEIGHT_FIELD_SIDE} samples a side",
                path.display()
            ),
            read: true,
            help: Some("scale the image down in an image editor".into()),
        });
    }
    let need = decode_bytes(w, h).saturating_add(grid_bytes(w, h));
    if need > room {
        return Err(AssetError {
            message: format!(
                "image `{}` is {w}x{h} pixels; decoded and kept as heights it needs {}, more \
                 than the {} left of the load's memory limit",
                path.display(),
                crate::diag::size_text(need),
                crate::diag::size_text(room)
            ),
            read: true,
            help: Some(
                "raise the limit with `--memory-limit` (e.g. `--memory-limit 8G`), or use a \
                 smaller image"
                    .into(),
            ),
        });
    }
    if w < 2 || h < 2 {
        return Err(content(format!(
            "image `{}` is {w}x{h} pixels: a height field needs at least 2x2",
            path.display()
        )));
    }
    let decoded = reader()?
        .decode()
        .map_err(|e| content(format!("cannot decode image `{}`: {e}", path.display())))?;
    use image::DynamicImage as D;
    let reading = match &decoded {
        D::ImageLuma8(_) | D::ImageLumaA8(_) | D::ImageLuma16(_) | D::ImageLumaA16(_) => {
            Reading::Grey
        }
        D::ImageRgb8(_) | D::ImageRgba8(_) => Reading::RedGreen,
        _ => Reading::Luminance,
    };
    let rgb = decoded.into_rgb32f();
    let mut heights = vec![0.0f32; w as usize * h as usize];
    // The image's top row lies at z = 1.
    for (row, pixels) in rgb.rows().enumerate() {
        let j = h as usize - 1 - row;
        for (i, p) in pixels.enumerate() {
            let v = height_of(reading, p.0);
            if !v.is_finite() {
                return Err(content(format!(
                    "image `{}` has a pixel that is NaN or infinite (column {i}, row {row})",
                    path.display()
                )));
            }
            heights[j * w as usize + i] = v;
        }
    }
    Ok(HeightGrid {
        nx: w,
        nz: h,
        heights,
    })
}

/// Bytes a grid of `w x h` samples holds while it is evaluated (its f32 heights).
pub fn grid_bytes(w: u32, h: u32) -> u64 {
    (w as u64 * h as u64).saturating_mul(4)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_pixels_read_as_povray_reads_them() {
        // 8-bit colour: red the high byte, green the low one.
        let v = height_of(Reading::RedGreen, [1.0 / 255.0, 2.0 / 255.0, 0.7]);
        assert_eq!(v, (256.0 + 2.0) / 65535.0);
        assert_eq!(height_of(Reading::Grey, [0.25, 0.0, 0.0]), 0.25);
        assert!((height_of(Reading::Luminance, [1.0, 1.0, 1.0]) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn an_image_is_read_top_row_at_the_far_side() {
        let mut img = image::GrayImage::new(2, 3);
        img.put_pixel(0, 0, image::Luma([255]));
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .unwrap();
        let g = height_grid_from_image(&bytes, std::path::Path::new("t.png"), 1 << 20).unwrap();
        assert_eq!((g.nx, g.nz), (2, 3));
        assert_eq!(g.at(0, 2), 1.0);
        assert_eq!(g.at(0, 0), 0.0);
    }
}
