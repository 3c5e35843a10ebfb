//! Image lookup: `(u, v)` to a linear RGB value, with nearest or bilinear filtering and
//! repeat / clamp / mirror wrapping.
//!
//! Conventions: `u` runs left to right, `v` bottom to top (as in POV-Ray), so `(0, 0)` is the
//! bottom-left corner of the image and `(1, 1)` the top-right; [`ImageData`] stores row 0 at the
//! top. Texel `(i, j)` covers `u ∈ [i/w, (i+1)/w)`; its centre is at `(i + 0.5)/w`.
//!
//! Wrapping is applied to integer texel indices, so bilinear filtering blends a texel with its
//! wrapped neighbour: with `Repeat`, the texel left of column 0 is column `w - 1`, which makes the
//! lookup continuous across the `u = 0 = 1` seam of spherical, cylindrical and revolve mappings.

use glam::Vec3A;

use crate::scene::{ImageData, Wrap};

/// Coordinates beyond this (in texels) are folded back first so that index arithmetic cannot
/// overflow; repetition makes the fold invisible except for `Clamp`, where it is beyond the edge
/// anyway.
const LIMIT: f64 = (1u64 << 40) as f64;

/// How an image is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lookup {
    pub wrap: Wrap,
    pub bilinear: bool,
    /// Rows do not blend across a tile's top or bottom edge (the poles of a spherical mapping
    /// are not a seam): the neighbour row is clamped into the tile the point lies in.
    pub clamp_rows_at_tile_edge: bool,
}

/// Index `i` wrapped into `0..n` (`n >= 1`).
#[inline]
pub fn wrap_index(i: i64, n: i64, wrap: Wrap) -> i64 {
    match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
    }
}

#[inline]
fn texel(image: &ImageData, col: i64, row: i64) -> Vec3A {
    let idx = row as usize * image.width as usize + col as usize;
    image
        .pixels
        .get(idx)
        .map(|&p| Vec3A::from(p))
        .unwrap_or(Vec3A::ZERO)
}

#[inline]
fn sanitize(x: f64) -> f64 {
    if x.is_finite() {
        x.clamp(-LIMIT, LIMIT)
    } else {
        0.0
    }
}

/// The value of `image` at `(u, v)`. An empty image reads as black; non-finite coordinates
/// read as `(0, 0)`.
pub fn lookup(image: &ImageData, u: f64, v: f64, how: Lookup) -> Vec3A {
    let (w, h) = (image.width as i64, image.height as i64);
    if w == 0 || h == 0 {
        return Vec3A::ZERO;
    }
    let x = sanitize(u) * w as f64;
    let y = sanitize(1.0 - sanitize(v)) * h as f64;
    if !how.bilinear {
        let col = wrap_index(x.floor() as i64, w, how.wrap);
        let row = wrap_index(y.floor() as i64, h, how.wrap);
        return texel(image, col, row);
    }
    // Texel centres sit at half-integers.
    let (xs, ys) = (x - 0.5, y - 0.5);
    let (x0, y0) = (xs.floor(), ys.floor());
    let (fx, fy) = ((xs - x0) as f32, (ys - y0) as f32);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (mut r0, mut r1) = (y0, y0 + 1);
    if how.clamp_rows_at_tile_edge {
        // The unit square is closed (v = 0 and v = 1 are its bottom and top rows, the two
        // poles); other tiles are half-open.
        let tile = if (0.0..=h as f64).contains(&y) {
            0
        } else {
            (y / h as f64).floor() as i64 * h
        };
        r0 = r0.clamp(tile, tile + h - 1);
        r1 = r1.clamp(tile, tile + h - 1);
    }
    let c0 = wrap_index(x0, w, how.wrap);
    let c1 = wrap_index(x0 + 1, w, how.wrap);
    let r0 = wrap_index(r0, h, how.wrap);
    let r1 = wrap_index(r1, h, how.wrap);
    let top = texel(image, c0, r0).lerp(texel(image, c1, r0), fx);
    let bottom = texel(image, c0, r1).lerp(texel(image, c1, r1), fx);
    top.lerp(bottom, fy)
}

#[cfg(test)]
pub(crate) mod tests {
    use std::path::PathBuf;

    use super::*;

    /// A `w` x `h` image whose texel (col, row) is `(col, row, 1)`.
    pub(crate) fn index_image(w: u32, h: u32) -> ImageData {
        let mut pixels = Vec::new();
        for row in 0..h {
            for col in 0..w {
                pixels.push([col as f32, row as f32, 1.0]);
            }
        }
        ImageData {
            path: PathBuf::from("index"),
            width: w,
            height: h,
            pixels,
        }
    }

    const NEAREST: Lookup = Lookup {
        wrap: Wrap::Repeat,
        bilinear: false,
        clamp_rows_at_tile_edge: false,
    };

    fn with(wrap: Wrap, bilinear: bool) -> Lookup {
        Lookup {
            wrap,
            bilinear,
            clamp_rows_at_tile_edge: false,
        }
    }

    #[test]
    fn nearest_picks_the_texel_under_the_point() {
        let img = index_image(4, 2);
        // Bottom-left corner is column 0 of the bottom row (row 1).
        assert_eq!(lookup(&img, 0.01, 0.01, NEAREST), Vec3A::new(0.0, 1.0, 1.0));
        assert_eq!(lookup(&img, 0.99, 0.99, NEAREST), Vec3A::new(3.0, 0.0, 1.0));
        assert_eq!(lookup(&img, 0.3, 0.7, NEAREST), Vec3A::new(1.0, 0.0, 1.0));
    }

    #[test]
    fn wrap_modes_outside_the_unit_square() {
        let img = index_image(4, 2);
        // u = 1.1 is column 0 again when repeating, the last column when clamped, and the
        // last column mirrored back when mirroring; u = -0.1 likewise on the other side.
        let col = |u: f64, wrap| lookup(&img, u, 0.75, with(wrap, false)).x;
        assert_eq!(col(1.1, Wrap::Repeat), 0.0);
        assert_eq!(col(1.1, Wrap::Clamp), 3.0);
        assert_eq!(col(1.1, Wrap::Mirror), 3.0);
        assert_eq!(col(1.3, Wrap::Mirror), 2.0);
        assert_eq!(col(-0.1, Wrap::Repeat), 3.0);
        assert_eq!(col(-0.1, Wrap::Clamp), 0.0);
        assert_eq!(col(-0.1, Wrap::Mirror), 0.0);
        assert_eq!(col(-5.9, Wrap::Clamp), 0.0);
        assert_eq!(col(2.1, Wrap::Mirror), 0.0);
        // Vertically too.
        let row = |v: f64, wrap| lookup(&img, 0.1, v, with(wrap, false)).y;
        assert_eq!(row(1.25, Wrap::Repeat), 1.0);
        assert_eq!(row(1.25, Wrap::Clamp), 0.0);
        assert_eq!(row(1.25, Wrap::Mirror), 0.0);
        assert_eq!(row(-0.25, Wrap::Clamp), 1.0);
    }

    #[test]
    fn bilinear_interpolates_between_texel_centres() {
        let img = index_image(4, 2);
        let b = with(Wrap::Clamp, true);
        // At a texel centre: exactly that texel.
        assert!((lookup(&img, 0.375, 0.75, b) - Vec3A::new(1.0, 0.0, 1.0)).length() < 1e-5);
        // Halfway between the centres of columns 1 and 2, rows 0 and 1.
        assert!((lookup(&img, 0.5, 0.5, b) - Vec3A::new(1.5, 0.5, 1.0)).length() < 1e-5);
        // Clamped at the left edge: the edge texel, no blending with the far side.
        assert!((lookup(&img, 0.0, 0.75, b).x - 0.0).abs() < 1e-6);
        assert!((lookup(&img, 1.0, 0.75, b).x - 3.0).abs() < 1e-6);
        // Mirror at the edge: the edge texel blends with itself.
        assert!((lookup(&img, 1.0, 0.75, with(Wrap::Mirror, true)).x - 3.0).abs() < 1e-6);
        // Repeat at the edge: halfway between the last and the first column.
        assert!((lookup(&img, 1.0, 0.75, with(Wrap::Repeat, true)).x - 1.5).abs() < 1e-6);
    }

    #[test]
    fn bilinear_repeat_is_continuous_across_the_seam() {
        // A smooth random-ish image: neighbouring lookups across u = 0 = 1 must agree.
        let mut img = index_image(16, 8);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            let t = i as f32;
            *p = [
                (t * 0.37).sin().abs(),
                (t * 0.91).cos().abs(),
                (t * 0.13).fract(),
            ];
        }
        let b = with(Wrap::Repeat, true);
        let mut worst = 0.0f32;
        for k in 0..50 {
            let v = 0.01 + 0.98 * k as f64 / 49.0;
            let left = lookup(&img, 1.0 - 1e-7, v, b);
            let right = lookup(&img, 1e-7, v, b);
            worst = worst.max((left - right).abs().max_element());
        }
        println!("largest jump across the seam: {worst:e}");
        assert!(worst < 1e-4, "seam jump {worst}");
        // Clamp, by contrast, has a jump there: the test above can fail.
        let c = with(Wrap::Clamp, true);
        let jump = (lookup(&img, 1.0 - 1e-7, 0.5, c) - lookup(&img, 1e-7, 0.5, c)).length();
        assert!(jump > 0.01);
    }

    #[test]
    fn pole_rows_do_not_blend_with_the_other_pole() {
        let img = index_image(4, 4);
        let pole = Lookup {
            wrap: Wrap::Repeat,
            bilinear: true,
            clamp_rows_at_tile_edge: true,
        };
        // At the very top (v = 1) the row is 0 only; without the clamp it would blend row 3.
        assert!(lookup(&img, 0.3, 1.0, pole).y.abs() < 1e-6);
        assert!((lookup(&img, 0.3, 0.0, pole).y - 3.0).abs() < 1e-6);
        assert!((lookup(&img, 0.3, 1.0, with(Wrap::Repeat, true)).y - 1.5).abs() < 1e-6);
        // Tiling still works one tile up.
        assert!(lookup(&img, 0.3, 2.0, pole).y.abs() < 1e-6);
    }

    #[test]
    fn garbage_does_not_panic() {
        let img = index_image(3, 3);
        for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
            for bilinear in [false, true] {
                for (u, v) in [
                    (f64::NAN, 0.5),
                    (f64::INFINITY, f64::NEG_INFINITY),
                    (1e300, -1e300),
                    (-1e20, 1e20),
                ] {
                    assert!(lookup(&img, u, v, with(wrap, bilinear)).is_finite());
                }
            }
        }
        let empty = ImageData {
            path: PathBuf::new(),
            width: 0,
            height: 0,
            pixels: Vec::new(),
        };
        assert_eq!(lookup(&empty, 0.5, 0.5, NEAREST), Vec3A::ZERO);
        // Fewer pixels than width * height: black, not a panic.
        let short = ImageData {
            pixels: vec![[1.0; 3]],
            ..index_image(2, 2)
        };
        assert_eq!(lookup(&short, 0.9, 0.1, NEAREST), Vec3A::ZERO);
    }
}
