//! Data loaded from files a scene names: images and OBJ meshes.
//!
//! Loading happens during evaluation, only for assets an object actually uses, so that a missing
//! file is reported at the span of its name and an unused one is never read.

use std::path::PathBuf;

use glam::{DVec2, DVec3};

use crate::world::{FileSystem, World};
use rayon::prelude::*;

/// Largest image side accepted (pixels).
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Largest image accepted: 2^25 pixels (8192x4096); decoded to linear RGB that is 400 MB.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 25;
/// Most pixels of all the images one scene loads together (2^27: 1.5 GiB decoded): each image
/// is checked against what is left before it is decoded, from its header.
pub const MAX_TOTAL_IMAGE_PIXELS: u64 = 1 << 27;
/// Most memory the image decoder may allocate for one file.
pub const MAX_IMAGE_DECODE_BYTES: u64 = 1 << 30;
/// Bytes of a decoded pixel ([`ImageData::pixels`]: f32 RGB); the render's memory estimate
/// counts each image at least this much.
pub const IMAGE_BYTES_PER_PIXEL: u64 = std::mem::size_of::<[f32; 3]>() as u64;

/// How many pixels an image may still have, and which limit says so (for the message).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageRoom {
    pub pixels: u64,
    /// `Some(bytes)`: the memory limit, not [`MAX_TOTAL_IMAGE_PIXELS`], is what is left of.
    pub memory_limit: Option<u64>,
    /// Bytes of that limit the load holds already (parsed text, strings, decoded images).
    pub held: u64,
}

impl ImageRoom {
    /// The room left after `loaded` pixels of images: [`MAX_TOTAL_IMAGE_PIXELS`], or less
    /// where what is left of `memory_limit` once the load's `held` bytes (those images
    /// included) are taken holds fewer pixels of [`IMAGE_BYTES_PER_PIXEL`].
    pub fn after(loaded: u64, held: u64, memory_limit: Option<u64>) -> Self {
        let by_count = MAX_TOTAL_IMAGE_PIXELS.saturating_sub(loaded);
        if let Some(limit) = memory_limit {
            let by_memory = limit.saturating_sub(held) / IMAGE_BYTES_PER_PIXEL;
            if by_memory < by_count {
                return Self {
                    pixels: by_memory,
                    memory_limit: Some(limit),
                    held,
                };
            }
        }
        Self {
            pixels: by_count,
            memory_limit: None,
            held,
        }
    }
}

/// How the stored values of an image are to be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColorSpace {
    /// 8-bit color images: decode the sRGB transfer curve.
    Srgb,
    /// Data images and float formats (EXR, HDR): use the values as they are.
    Linear,
}

/// A decoded image in linear RGB, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageData {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

/// The largest channel value of `image` (0 for an empty one; NaN pixels are skipped).
pub fn brightest_pixel(image: &ImageData) -> f64 {
    image.pixels.iter().flatten().fold(0.0f32, |m, &c| m.max(c)) as f64
}

/// A triangle mesh as read from an OBJ file (all groups merged).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshData {
    pub path: PathBuf,
    pub positions: Vec<DVec3>,
    /// Per-vertex normals, same length as `positions`, or empty.
    pub normals: Vec<DVec3>,
    /// Per-vertex texture coordinates, same length as `positions`, or empty.
    pub uvs: Vec<DVec2>,
    /// Three vertex indices per triangle.
    pub indices: Vec<[u32; 3]>,
}

/// Why an image or mesh file could not be loaded: a message fit for a diagnostic, and whether
/// the file itself was read (its content was refused) or not (missing, unreadable, special or
/// too large), which decides what the diagnostic suggests unless `help` says it.
#[derive(Debug, Clone, PartialEq)]
pub struct AssetError {
    pub message: String,
    pub read: bool,
    /// The fix, where the error knows it better than the caller (an image over a size limit).
    pub help: Option<String>,
}

impl AssetError {
    fn unread(message: String) -> Self {
        Self {
            message,
            read: false,
            help: None,
        }
    }

    fn content(message: String) -> Self {
        Self {
            message,
            read: true,
            help: None,
        }
    }

    fn too_large(message: String, help: &str) -> Self {
        Self {
            message,
            read: true,
            help: Some(help.to_string()),
        }
    }
}

impl From<AssetError> for String {
    fn from(e: AssetError) -> Self {
        e.message
    }
}

impl std::fmt::Display for AssetError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

/// Reads an image file from the disk into linear RGB. 8-bit and 16-bit images are decoded
/// with `space`; float formats (EXR, HDR) are always linear.
pub fn load_image(path: &std::path::Path, space: ColorSpace) -> Result<ImageData, AssetError> {
    load_image_within(&FileSystem, path, space, ImageRoom::after(0, 0, None))
}

/// [`load_image`] of an image of `world` that may have at most `room` pixels (what is left of
/// [`MAX_TOTAL_IMAGE_PIXELS`], or of a memory limit, after the images loaded before), refused
/// from its header before it is decoded.
pub fn load_image_within(
    world: &dyn World,
    path: &std::path::Path,
    space: ColorSpace,
    room: ImageRoom,
) -> Result<ImageData, AssetError> {
    let bytes = world
        .read(path, crate::files::MAX_ASSET_BYTES)
        .map_err(|e| match e {
            crate::files::FileError::Io(e) => {
                AssetError::unread(format!("cannot open image `{}`: {e}", path.display()))
            }
            refused => AssetError::unread(format!("cannot open image: {refused}")),
        })?;
    decode_image(&radiance_header(&bytes), path, space, room)
}

/// A Radiance HDR file's bytes with the magic line the decoder knows: files written with
/// `#?RGBE` (Mitsuba 3 and others write it) instead of `#?RADIANCE` are the same format.
fn radiance_header(bytes: &[u8]) -> std::borrow::Cow<'_, [u8]> {
    match bytes.strip_prefix(b"#?RGBE") {
        Some(rest) if rest.first() == Some(&b'\n') => {
            let mut fixed = b"#?RADIANCE".to_vec();
            fixed.extend_from_slice(rest);
            std::borrow::Cow::Owned(fixed)
        }
        _ => std::borrow::Cow::Borrowed(bytes),
    }
}

/// The image in a file's `bytes`.
fn decode_image(
    bytes: &[u8],
    path: &std::path::Path,
    space: ColorSpace,
    room: ImageRoom,
) -> Result<ImageData, AssetError> {
    let smaller = "use an image with fewer pixels (scale it down in an image editor)";
    let reader = || {
        let mut r = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("cannot read image `{}`: {e}", path.display()))?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_IMAGE_SIDE);
        limits.max_image_height = Some(MAX_IMAGE_SIDE);
        limits.max_alloc = Some(MAX_IMAGE_DECODE_BYTES);
        r.limits(limits);
        Ok::<_, String>(r)
    };
    // The header first: a few bytes of PNG can declare a picture of gigabytes.
    let (w, h) = reader()
        .map_err(AssetError::content)?
        .into_dimensions()
        .map_err(|e| {
            AssetError::content(format!("cannot decode image `{}`: {e}", path.display()))
        })?;
    if w as u64 * h as u64 > MAX_IMAGE_PIXELS {
        return Err(AssetError::too_large(
            format!(
                "image `{}` is {w}x{h} pixels, more than the limit of {MAX_IMAGE_PIXELS} pixels \
                 (for example 8192x4096)",
                path.display()
            ),
            smaller,
        ));
    }
    if w as u64 * h as u64 > room.pixels {
        let left = room.pixels;
        return Err(match room.memory_limit {
            None => AssetError::too_large(
                format!(
                    "image `{}` is {w}x{h} pixels, more than the {left} pixels left of the limit \
                 of {MAX_TOTAL_IMAGE_PIXELS} pixels for all the scene's images together",
                    path.display()
                ),
                "use smaller images, or fewer different ones (an image used by several textures \
                 is loaded once)",
            ),
            Some(limit) => AssetError::too_large(
                format!(
                    "image `{}` is {w}x{h} pixels; decoded ({IMAGE_BYTES_PER_PIXEL} bytes a \
                     pixel) it does not fit in the {left} pixels left of the memory limit of {}{}",
                    path.display(),
                    crate::diag::size_text(limit),
                    if room.held > 0 {
                        format!(
                            " (the load holds {} already: parsed text, strings and images)",
                            crate::diag::size_text(room.held)
                        )
                    } else {
                        String::new()
                    }
                ),
                "raise the limit with `--memory-limit` (e.g. `--memory-limit 4G`), or use a \
                 smaller image",
            ),
        });
    }
    decode_pixels(reader().map_err(AssetError::content)?, path, space).map_err(AssetError::content)
}

/// The pixels of an image whose header passed the size checks, in linear RGB.
fn decode_pixels(
    reader: image::ImageReader<std::io::Cursor<&[u8]>>,
    path: &std::path::Path,
    space: ColorSpace,
) -> Result<ImageData, String> {
    let decoded = reader
        .decode()
        .map_err(|e| format!("cannot decode image `{}`: {e}", path.display()))?;
    let is_float = matches!(
        decoded,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    );
    let rgb = decoded.to_rgb32f();
    let (width, height) = rgb.dimensions();
    if width == 0 || height == 0 {
        return Err(format!("image `{}` is empty", path.display()));
    }
    let decode = |v: f32| {
        if is_float || space == ColorSpace::Linear {
            v
        } else {
            srgb_to_linear(v)
        }
    };
    let pixels: Vec<[f32; 3]> = rgb
        .pixels()
        .map(|p| [decode(p.0[0]), decode(p.0[1]), decode(p.0[2])])
        .collect();
    // Float formats can hold NaN and infinity; such a texel would read as black (a texture) or
    // dark the whole sky (an environment) without a word.
    let bad = pixels
        .iter()
        .filter(|p| !p.iter().all(|c| c.is_finite()))
        .count();
    if bad > 0 {
        return Err(format!(
            "image `{}` has {bad} pixel{} that {} NaN or infinite",
            path.display(),
            if bad == 1 { "" } else { "s" },
            if bad == 1 { "is" } else { "are" },
        ));
    }
    Ok(ImageData {
        path: path.to_path_buf(),
        width,
        height,
        pixels,
    })
}

/// The sRGB transfer curve, decoded.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads a Wavefront OBJ file from the disk (all models merged, faces triangulated). Files of
/// the common form are read on every core (`obj::parse`); the others, and every file
/// with an error, by `tobj`.
pub fn load_obj(path: &std::path::Path) -> Result<MeshData, AssetError> {
    load_obj_in(&FileSystem, path)
}

/// [`load_obj`] of a file of `world`.
pub fn load_obj_in(world: &dyn World, path: &std::path::Path) -> Result<MeshData, AssetError> {
    let bytes = world
        .read(path, crate::files::MAX_ASSET_BYTES)
        .map_err(|e| match e {
            crate::files::FileError::Io(e) => {
                AssetError::unread(format!("cannot read OBJ mesh `{}`: {e}", path.display()))
            }
            refused => AssetError::unread(format!("cannot read OBJ mesh: {refused}")),
        })?;
    parse_obj(&bytes, path).map_err(AssetError::content)
}

/// The mesh in an OBJ file's `bytes`.
pub(super) fn parse_obj(bytes: &[u8], path: &std::path::Path) -> Result<MeshData, String> {
    // A UTF-8 byte order mark (Windows tools write one) would hide the first line.
    let body = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    let mesh = match super::obj::parse(body) {
        Some(mesh) => MeshData {
            path: path.to_path_buf(),
            ..mesh
        },
        None => read_with_tobj(body, path)?,
    };
    if mesh.indices.is_empty() {
        return Err(format!("OBJ mesh `{}` has no faces", path.display()));
    }
    if mesh.positions.par_iter().any(|p| !p.is_finite()) {
        let at = super::obj_errors::first_infinite_vertex(body)
            .map(|(n, line)| format!(", line {n} (`{line}`)"))
            .unwrap_or_default();
        return Err(format!(
            "OBJ mesh `{}`{at}: a vertex coordinate is not a finite number or is beyond \
             +-3.4e38 (meshes are stored in f32)",
            path.display()
        ));
    }
    Ok(mesh)
}

/// The mesh in an OBJ file's `bytes`, read by `tobj`.
pub(super) fn read_with_tobj(bytes: &[u8], path: &std::path::Path) -> Result<MeshData, String> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials (`mtllib`) are not used: the scene gives the material.
    let (models, _materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .map_err(|e| {
            let at = super::obj_errors::first_bad_line(bytes, &e)
                .map(|(n, line)| format!(" at line {n} (`{line}`)"))
                .unwrap_or_default();
            format!("cannot read OBJ mesh `{}`: {e}{at}", path.display())
        })?;
    let mut mesh = MeshData {
        path: path.to_path_buf(),
        ..MeshData::default()
    };
    let all_normals = models
        .iter()
        .all(|m| m.mesh.normals.len() == m.mesh.positions.len());
    let all_uvs = models
        .iter()
        .all(|m| m.mesh.texcoords.len() / 2 == m.mesh.positions.len() / 3);
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let count = (m.positions.len() / 3) as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)),
        );
        if all_normals {
            mesh.normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)),
            );
        }
        if all_uvs {
            mesh.uvs.extend(
                m.texcoords
                    .chunks_exact(2)
                    .map(|c| DVec2::new(c[0] as f64, c[1] as f64)),
            );
        }
        for tri in m.indices.chunks_exact(3) {
            if tri.iter().any(|&i| i >= count) {
                return Err(format!(
                    "OBJ mesh `{}` has a face with a vertex index out of range",
                    path.display()
                ));
            }
            mesh.indices
                .push([base + tri[0], base + tri[1], base + tri[2]]);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_triangulates_quads_and_keeps_uvs() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("quad.obj");
        std::fs::write(
            &path,
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n",
        )
        .unwrap();
        let mesh = load_obj(&path).unwrap();
        assert_eq!(mesh.indices.len(), 2);
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.uvs.len(), 4);
        assert!(mesh.normals.is_empty());
    }

    #[test]
    fn missing_files_are_errors_not_panics() {
        let missing = std::path::Path::new("/nonexistent/x.obj");
        assert!(
            load_obj(missing)
                .unwrap_err()
                .message
                .contains("cannot read OBJ")
        );
        let missing = std::path::Path::new("/nonexistent/x.png");
        assert!(load_image(missing, ColorSpace::Srgb).is_err());
    }

    #[test]
    fn png_is_decoded_from_srgb() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gray.png");
        image::RgbImage::from_pixel(2, 1, image::Rgb([188, 188, 188]))
            .save(&path)
            .unwrap();
        let img = load_image(&path, ColorSpace::Srgb).unwrap();
        assert_eq!((img.width, img.height), (2, 1));
        // sRGB 188/255 is about 0.5 linear.
        assert!((img.pixels[0][0] - 0.5029).abs() < 1e-3);
        let lin = load_image(&path, ColorSpace::Linear).unwrap();
        assert!((lin.pixels[0][0] - 188.0 / 255.0).abs() < 1e-6);
    }

    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in bytes {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }

    /// A PNG file of a few dozen bytes whose header declares `w` x `h` 1-bit pixels.
    fn png_header_only(w: u32, h: u32) -> Vec<u8> {
        let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
        let mut chunk = |kind: &[u8], data: &[u8]| {
            out.extend((data.len() as u32).to_be_bytes());
            let mut body = kind.to_vec();
            body.extend(data);
            out.extend(&body);
            out.extend(crc32(&body).to_be_bytes());
        };
        let mut ihdr = Vec::new();
        ihdr.extend(w.to_be_bytes());
        ihdr.extend(h.to_be_bytes());
        ihdr.extend([1, 0, 0, 0, 0]);
        chunk(b"IHDR", &ihdr);
        chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]);
        chunk(b"IEND", &[]);
        out
    }

    #[test]
    fn an_image_declaring_huge_dimensions_is_refused_before_decoding() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bomb.png");
        std::fs::write(&p, png_header_only(20_000, 20_000)).unwrap();
        let e = load_image(&p, ColorSpace::Srgb).unwrap_err().message;
        assert!(e.contains("20000") || e.contains("limit"), "{e}");
        // Within the side limit but too many pixels in all.
        std::fs::write(&p, png_header_only(16_000, 16_000)).unwrap();
        let e = load_image(&p, ColorSpace::Srgb).unwrap_err().message;
        assert!(e.contains("more than the limit"), "{e}");
    }

    #[test]
    fn an_exr_with_nan_or_infinite_pixels_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sky.exr");
        for (bad, count) in [(f32::NAN, 1), (f32::INFINITY, 1), (f32::NEG_INFINITY, 1)] {
            let mut img = image::Rgb32FImage::from_pixel(4, 2, image::Rgb([0.5, 1.0, 2.0]));
            img.put_pixel(3, 1, image::Rgb([0.5, bad, 2.0]));
            img.save(&p).unwrap();
            let e = load_image(&p, ColorSpace::Linear).unwrap_err().message;
            assert!(
                e.contains(&format!("{count} pixel that is NaN or infinite")),
                "{e}"
            );
        }
        let img = image::Rgb32FImage::from_pixel(4, 2, image::Rgb([0.5, 1e30, 2.0]));
        img.save(&p).unwrap();
        let ok = load_image(&p, ColorSpace::Linear).unwrap();
        assert_eq!(ok.pixels[7], [0.5, 1e30, 2.0]);
    }

    #[test]
    fn an_obj_with_a_byte_order_mark_and_crlf_reads_every_vertex() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bom.obj");
        std::fs::write(&p, "\u{feff}v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n").unwrap();
        let m = load_obj(&p).unwrap();
        assert_eq!(m.positions.len(), 3);
        assert_eq!(m.indices.len(), 1);
    }

    #[test]
    fn special_files_are_not_read_as_assets() {
        let dir = tempfile::tempdir().unwrap();
        let e = load_obj(dir.path()).unwrap_err();
        assert!(e.message.contains("directory") && !e.read, "{e}");
        #[cfg(unix)]
        {
            let e = load_obj(std::path::Path::new("/dev/zero")).unwrap_err();
            assert!(e.message.contains("device") && !e.read, "{e}");
            let e = load_image(std::path::Path::new("/dev/zero"), ColorSpace::Srgb).unwrap_err();
            assert!(e.message.contains("device") && !e.read, "{e}");
        }
    }

    /// A file that was read but whose content is refused says so (`read`), which the
    /// diagnostic's help follows; a missing file is not read.
    #[test]
    fn a_refused_content_is_told_from_an_unread_file() {
        let dir = tempfile::tempdir().unwrap();
        let obj = dir.path().join("bad.obj");
        std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
        assert!(load_obj(&obj).unwrap_err().read);
        let png = dir.path().join("text.png");
        std::fs::write(&png, "not an image").unwrap();
        assert!(load_image(&png, ColorSpace::Srgb).unwrap_err().read);
        assert!(!load_obj(&dir.path().join("missing.obj")).unwrap_err().read);
    }

    /// A Radiance file whose magic line is `#?RGBE` (as Mitsuba 3 writes them) reads as the
    /// same file with `#?RADIANCE`.
    #[test]
    fn an_rgbe_header_reads_as_radiance() {
        let dir = tempfile::tempdir().unwrap();
        let img = image::Rgb32FImage::from_fn(3, 2, |x, y| image::Rgb([x as f32, y as f32, 0.5]));
        let hdr = dir.path().join("a.hdr");
        img.save(&hdr).unwrap();
        let bytes = std::fs::read(&hdr).unwrap();
        let radiance = load_image(&hdr, ColorSpace::Linear).unwrap();
        let rest = bytes
            .strip_prefix(b"#?RADIANCE")
            .expect("the encoder's magic line");
        let rgbe = dir.path().join("b.hdr");
        std::fs::write(&rgbe, [&b"#?RGBE"[..], rest].concat()).unwrap();
        let read = load_image(&rgbe, ColorSpace::Linear).unwrap();
        assert_eq!(read.pixels, radiance.pixels);
        assert_eq!((read.width, read.height), (3, 2));
    }
}
