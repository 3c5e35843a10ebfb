//! Draws the example image textures shipped in `examples/textures/`, procedurally, so that they
//! are the project's own work.
//!
//! ```text
//! cargo run --release --bin make-textures [OUTPUT_DIR]     # default: examples/textures
//! ```
//!
//! Writes `tiles.png` (256x256 glazed tiles with grout, for `uv` / `planar` mapping),
//! `world.png` (256x128 equirectangular map of an invented planet, seamless at `u = 0 = 1`, for
//! `spherical` mapping), `wood.png` (256x256 planks, for `cylindrical` / revolve `uv`), and
//! `sky.hdr` (128x64 equirectangular sky with a sun, linear radiance, for
//! `background { environment ... }`). Every picture is a pure function of the pixel position:
//! the same files come out every time.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use image::{Rgb, Rgb32FImage, RgbImage};
use sppm_lang::internals::textures::noise::{fbm, turbulence};

fn main() -> ExitCode {
    let dir = std::env::args_os()
        .nth(1)
        .map_or_else(|| PathBuf::from("examples/textures"), PathBuf::from);
    match write_all(&dir) {
        Ok(files) => {
            for f in files {
                println!("wrote {}", f.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("make-textures: {e}");
            ExitCode::FAILURE
        }
    }
}

fn write_all(dir: &Path) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create `{}`: {e}", dir.display()))?;
    let mut written = Vec::new();
    let mut save_png = |name: &str, img: RgbImage| -> Result<(), String> {
        let path = dir.join(name);
        img.save(&path)
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
        written.push(path);
        Ok(())
    };
    save_png("tiles.png", tiles())?;
    save_png("world.png", world())?;
    save_png("wood.png", wood())?;
    let path = dir.join("sky.hdr");
    sky()
        .save(&path)
        .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    written.push(path);
    Ok(written)
}

/// Linear [0, 1] to an 8-bit sRGB value.
fn srgb8(v: f64) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

fn pixel(c: [f64; 3]) -> Rgb<u8> {
    Rgb([srgb8(c[0]), srgb8(c[1]), srgb8(c[2])])
}

fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    let t = t.clamp(0.0, 1.0);
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// A small integer hash to pick per-tile variations.
fn hash(a: u32, b: u32) -> f64 {
    let mut h = a.wrapping_mul(0x9e37_79b1) ^ b.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    (h & 0xffff) as f64 / 65535.0
}

/// 4x4 glazed tiles, 64 px each, with 4 px grout; tiles repeat seamlessly.
pub fn tiles() -> RgbImage {
    const TILE: u32 = 64;
    const GROUT: u32 = 4;
    let glazes = [
        [0.05, 0.18, 0.45],
        [0.60, 0.62, 0.58],
        [0.08, 0.30, 0.30],
        [0.55, 0.20, 0.08],
    ];
    RgbImage::from_fn(256, 256, |x, y| {
        let (tx, ty) = (x / TILE, y / TILE);
        let (lx, ly) = (x % TILE, y % TILE);
        let inside = GROUT / 2..TILE - GROUT / 2;
        let grout = !inside.contains(&lx) || !inside.contains(&ly);
        let n = fbm(x as f64 / 9.0, y as f64 / 9.0, 0.5, 3);
        if grout {
            let g = 0.35 + 0.05 * n;
            return pixel([g, g * 0.97, g * 0.9]);
        }
        let pick = ((tx + ty) % 2 * 2 + (hash(tx, ty) > 0.5) as u32) as usize;
        let base = glazes[pick];
        // A soft sheen towards the tile's upper left, and glaze speckle.
        let (fx, fy) = (lx as f64 / TILE as f64, ly as f64 / TILE as f64);
        let sheen = 0.25 * (1.0 - (fx + fy)).max(0.0);
        let speckle = 0.08 * n;
        pixel(mix(base, [1.0, 1.0, 1.0], sheen + speckle))
    })
}

/// An invented planet: continents from noise sampled on the unit sphere (so the left and right
/// edges meet without a seam), shallow seas, mountains, polar ice.
pub fn world() -> RgbImage {
    let (w, h) = (256u32, 128u32);
    RgbImage::from_fn(w, h, |x, y| {
        let u = (x as f64 + 0.5) / w as f64;
        let theta = (y as f64 + 0.5) / h as f64 * std::f64::consts::PI;
        // The same convention as the spherical mapping: u = 0.5 faces -z.
        let phi = (u - 0.5) * 2.0 * std::f64::consts::PI;
        let p = [
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        ];
        let s = 1.7;
        let height = fbm(p[0] * s + 3.1, p[1] * s - 1.3, p[2] * s + 0.7, 6) - 0.04;
        let latitude = theta.cos().abs();
        let ice = latitude > 0.93 + 0.04 * fbm(p[0] * 6.0, p[1] * 6.0, p[2] * 6.0, 3);
        let c = if ice {
            [0.85, 0.88, 0.92]
        } else if height < 0.0 {
            mix(
                [0.10, 0.35, 0.55],
                [0.01, 0.05, 0.20],
                (-height * 5.0).min(1.0),
            )
        } else {
            let dry = 0.5 + 0.5 * fbm(p[0] * 4.0 + 9.0, p[1] * 4.0, p[2] * 4.0, 3);
            let lowland = mix(
                [0.10, 0.32, 0.08],
                [0.50, 0.42, 0.22],
                dry * (1.0 - latitude),
            );
            mix(lowland, [0.40, 0.36, 0.33], (height * 4.0 - 0.8).max(0.0))
        };
        pixel(c)
    })
}

/// Wood planks running vertically, 4 per image, each with its own ring pattern.
pub fn wood() -> RgbImage {
    RgbImage::from_fn(256, 256, |x, y| {
        let plank = x / 64;
        let (lx, ly) = (x as f64 % 64.0, y as f64);
        if lx < 1.5 {
            return pixel([0.05, 0.03, 0.02]);
        }
        // Rings of a log cut lengthwise: distance from a core off to one side, distorted.
        let core = 20.0 + 120.0 * hash(plank, 7);
        let d = ((lx - 32.0) * (lx - 32.0) * 4.0 + (ly - core) * (ly - core) * 0.02).sqrt();
        let t = turbulence(lx / 24.0, ly / 96.0, plank as f64 * 5.0, 4);
        let ring = (d / 6.0 + 3.0 * t).fract();
        let ring = (ring * 2.0 - 1.0).abs().powi(3);
        let light = [0.55, 0.33, 0.16];
        let dark = [0.28, 0.13, 0.05];
        let grain = 0.1 * fbm(lx / 3.0, ly / 40.0, plank as f64, 2);
        pixel(mix(light, dark, ring + grain + 0.15 * hash(plank, 1)))
    })
}

/// Equirectangular sky (same convention as the environment map: centre looks along +z, -x to its
/// right, row 0 straight up): blue zenith, pale horizon, a dim ground, and a sun 35 degrees up
/// towards +x (0.6 rad from +z), as linear radiance.
pub fn sky() -> Rgb32FImage {
    let (w, h) = (128u32, 64u32);
    let sun_phi: f64 = 0.6;
    let sun_elev: f64 = 35f64.to_radians();
    let sun = [
        sun_elev.cos() * sun_phi.sin(),
        sun_elev.sin(),
        sun_elev.cos() * sun_phi.cos(),
    ];
    Rgb32FImage::from_fn(w, h, |x, y| {
        let u = (x as f64 + 0.5) / w as f64;
        let theta = (y as f64 + 0.5) / h as f64 * std::f64::consts::PI;
        let phi = (0.5 - u) * 2.0 * std::f64::consts::PI;
        let d = [
            theta.sin() * phi.sin(),
            theta.cos(),
            theta.sin() * phi.cos(),
        ];
        let up = d[1];
        let mut c = if up >= 0.0 {
            mix([0.9, 1.0, 1.1], [0.25, 0.45, 0.95], up.powf(0.5))
        } else {
            mix([0.35, 0.32, 0.28], [0.12, 0.10, 0.08], (-up * 3.0).min(1.0))
        };
        let cos_sun = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
        // Glow around the sun and the sun itself (a few texels across at this resolution).
        let glow = (cos_sun.max(0.0)).powi(64) * 2.0;
        let disk = if cos_sun > (3.5f64).to_radians().cos() {
            400.0
        } else {
            0.0
        };
        let warm = [1.0, 0.92, 0.8];
        for (ch, k) in c.iter_mut().zip(warm) {
            *ch += (glow + disk) * k;
        }
        Rgb([c[0] as f32, c[1] as f32, c[2] as f32])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The committed files are exactly what the generator draws (regenerate them with the
    /// command in the module docs if a drawing changes).
    #[test]
    fn committed_textures_match_the_generator() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/textures");
        for (name, img) in [
            ("tiles.png", tiles()),
            ("world.png", world()),
            ("wood.png", wood()),
        ] {
            let file = image::open(dir.join(name)).expect(name).to_rgb8();
            assert!(file == img, "{name} differs from the generator");
        }
        let file = image::open(dir.join("sky.hdr")).unwrap().to_rgb32f();
        let drawn = sky();
        assert_eq!(file.dimensions(), drawn.dimensions());
        // Radiance HDR (RGBE) stores 8-bit mantissas under the exponent of the largest channel:
        // each channel is exact to one step of 2^e / 256 with 2^e <= 2 * max channel.
        for (a, b) in file.pixels().zip(drawn.pixels()) {
            let step = b.0.iter().fold(0.0f32, |m, &c| m.max(c)) / 128.0;
            for c in 0..3 {
                assert!((a.0[c] - b.0[c]).abs() <= step + 1e-6, "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn world_map_has_no_seam_and_has_land_and_sea() {
        let img = world();
        let (w, h) = img.dimensions();
        let mut diff = 0u32;
        for y in 0..h {
            let a = img.get_pixel(0, y).0;
            let b = img.get_pixel(w - 1, y).0;
            diff += (0..3).map(|c| a[c].abs_diff(b[c]) as u32).sum::<u32>();
        }
        let blue = img
            .pixels()
            .filter(|p| p.0[2] > p.0[1] && p.0[2] > p.0[0])
            .count();
        let frac = blue as f64 / (w * h) as f64;
        println!(
            "world: mean edge difference {} per row, sea fraction {frac:.2}",
            diff / h
        );
        // Neighbouring columns of a smooth map differ little; the wrap pair must too.
        assert!(diff / h < 40);
        assert!(frac > 0.2 && frac < 0.8);
    }
}
