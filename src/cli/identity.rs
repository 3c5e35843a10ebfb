//! The identity of an evaluated scene: two loads that give the same picture to render have the
//! same [`SceneId`], so a save that changes nothing (the same text, a comment, a file rewritten
//! with the same bytes) does not restart a render.
//!
//! The identity is a 64-bit hash of everything the renderer reads: the scene's `Debug` text
//! (plain data, no hash maps: deterministic) with two exceptions. Spans are left out (they
//! only place diagnostics; a comment moves them), and the decoded pixels of images and the
//! arrays of meshes are hashed as raw numbers rather than formatted, which is far faster. The
//! scene holds every file it read by value (decoded images, parsed meshes), so their contents
//! are part of the identity. The hash is XXH3-64, whose definition is fixed and published: the
//! same scene gives the same identity in any build on any machine, so chains rendered on many
//! machines can be compared (`render --chain`, `merge`). The `Debug` text is that of this
//! version of the scene's types: a version that changes them changes the identity.

use std::fmt::Write as _;
use std::sync::Arc;

use sppm_lang::Span;
use sppm_lang::internals::scene::{
    Background, ImageData, LightDecl, MeshData, Object, Pattern, Scene, ShapeDecl,
};
use xxhash_rust::xxh3::Xxh3;

/// What a scene renders, as a hash (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SceneId(u64);

impl SceneId {
    pub fn of(scene: &Scene) -> SceneId {
        let mut h = Hashing::default();
        let stripped = stripped(scene, &mut h);
        // Writing into a hash cannot fail.
        let _ = write!(h, "{stripped:?}");
        h.flush();
        SceneId(h.hasher.digest())
    }

    /// The hash as a number (for a chain's header: the same scene gives the same on any machine).
    pub fn value(self) -> u64 {
        self.0
    }
}

/// A hash fed through a buffer: `Debug` writes many short pieces, each call of the hash costs.
#[derive(Default)]
struct Hashing {
    hasher: Xxh3,
    buffer: Vec<u8>,
}

impl Hashing {
    const BLOCK: usize = 1 << 16;

    fn bytes(&mut self, bytes: &[u8]) {
        self.buffer.extend_from_slice(bytes);
        if self.buffer.len() >= Self::BLOCK {
            self.flush();
        }
    }

    fn flush(&mut self) {
        self.hasher.update(&self.buffer);
        self.buffer.clear();
    }

    /// Numbers as their little-endian bytes, followed by their count (so that the arrays of
    /// one image or mesh cannot run into the next).
    fn numbers<const N: usize>(&mut self, values: impl Iterator<Item = [u8; N]>) {
        let mut count = 0u64;
        for v in values {
            self.bytes(&v);
            count += 1;
        }
        self.bytes(&count.to_le_bytes());
    }
}

impl std::fmt::Write for Hashing {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.bytes(s.as_bytes());
        Ok(())
    }
}

/// A copy of `scene` without spans, its images and meshes emptied after their numbers went into
/// `h` (in the order the scene holds them).
fn stripped(scene: &Scene, h: &mut Hashing) -> Scene {
    let mut s = scene.clone();
    s.settings.span = Span::detached();
    s.camera.span = Span::detached();
    for o in &mut s.objects {
        strip_object(o, h);
    }
    for light in &mut s.lights {
        match light {
            LightDecl::Point { span, .. } | LightDecl::Spot { span, .. } => {
                *span = Span::detached()
            }
        }
    }
    for t in &mut s.textures {
        t.span = Span::detached();
        if let Pattern::Image { image, .. } = &mut t.pattern {
            *image = strip_image(image, h);
        }
    }
    if let Background::Environment { image, .. } = &mut s.background {
        *image = strip_image(image, h);
    }
    s
}

fn strip_object(o: &mut Object, h: &mut Hashing) {
    o.span = Span::detached();
    match &mut o.shape {
        ShapeDecl::Mesh { mesh } => *mesh = strip_mesh(mesh, h),
        // Depth at most `MAX_CSG_DEPTH`, checked by the evaluator.
        ShapeDecl::Csg(csg) => {
            for child in &mut csg.children {
                strip_object(child, h);
            }
        }
        _ => {}
    }
}

fn strip_image(image: &ImageData, h: &mut Hashing) -> Arc<ImageData> {
    h.numbers(
        image
            .pixels
            .iter()
            .flatten()
            .map(|c| c.to_bits().to_le_bytes()),
    );
    Arc::new(ImageData {
        path: image.path.clone(),
        width: image.width,
        height: image.height,
        pixels: Vec::new(),
    })
}

fn strip_mesh(mesh: &MeshData, h: &mut Hashing) -> Arc<MeshData> {
    for vectors in [&mesh.positions, &mesh.normals] {
        h.numbers(
            vectors
                .iter()
                .flat_map(|v| v.to_array())
                .map(|x| x.to_bits().to_le_bytes()),
        );
    }
    h.numbers(
        mesh.uvs
            .iter()
            .flat_map(|v| v.to_array())
            .map(|x| x.to_bits().to_le_bytes()),
    );
    h.numbers(mesh.indices.iter().flatten().map(|i| i.to_le_bytes()));
    Arc::new(MeshData {
        path: mesh.path.clone(),
        ..MeshData::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DAffine3, DVec3};
    use sppm_lang::EvalOptions;
    use sppm_lang::internals::scene::MaterialId;

    const TEXT: &str = "settings { resolution <16, 16>  iterations 3 }\n\
                        camera { location <0, 0, -5>  look_at <0, 0, 0> }\n\
                        light { <0, 4, -4>  intensity rgb <1, 1, 1> }\n\
                        sphere { <0, 0, 0>, 1  material { diffuse rgb <0.8, 0.2, 0.2> } }\n";

    fn scene(text: &str) -> Scene {
        let loaded =
            sppm_lang::internals::eval::load_source("t.scn", text, &EvalOptions::default());
        assert!(!loaded.has_errors(), "{:?}", loaded.diagnostics);
        loaded.scene.expect("a scene")
    }

    /// The hash is XXH3-64 as published (its test vector for no input), fed the same bytes
    /// however they arrive: nothing in it depends on the build or the machine.
    #[test]
    fn the_hash_is_xxh3_whatever_the_pieces() {
        let mut h = Hashing::default();
        h.flush();
        assert_eq!(h.hasher.digest(), 0x2D06_8005_38D3_94C2);
        let text: Vec<u8> = (0..200_000u32).map(|i| (i * 7 % 251) as u8).collect();
        let mut h = Hashing::default();
        for piece in text.chunks(13) {
            h.bytes(piece);
        }
        h.flush();
        assert_eq!(h.hasher.digest(), xxhash_rust::xxh3::xxh3_64(&text));
    }

    #[test]
    fn the_same_text_loaded_twice_is_the_same_scene() {
        assert_eq!(SceneId::of(&scene(TEXT)), SceneId::of(&scene(TEXT)));
    }

    /// Comments and layout move every span; the picture is the same.
    #[test]
    fn comments_and_layout_do_not_change_the_identity() {
        let edited = format!("// a note\n\n{}", TEXT.replace("  ", "    "));
        let (a, b) = (scene(TEXT), scene(&edited));
        assert_ne!(a.objects[0].span, b.objects[0].span, "the spans did move");
        assert_eq!(SceneId::of(&a), SceneId::of(&b));
    }

    #[test]
    fn any_change_of_what_is_rendered_changes_the_identity() {
        let base = SceneId::of(&scene(TEXT));
        for (from, to) in [
            ("rgb <0.8, 0.2, 0.2>", "rgb <0.8, 0.2, 0.3>"),
            ("iterations 3", "iterations 4"),
            ("<0, 0, 0>, 1 ", "<0, 0, 0>, 1.0001 "),
            ("look_at <0, 0, 0>", "look_at <0, 0.001, 0>"),
        ] {
            assert!(TEXT.contains(from), "{from}");
            let changed = SceneId::of(&scene(&TEXT.replace(from, to)));
            assert_ne!(base, changed, "{from} -> {to}");
        }
    }

    fn with_environment(pixels: Vec<[f32; 3]>) -> Scene {
        let mut s = scene(TEXT);
        s.background = Background::Environment {
            image: Arc::new(ImageData {
                path: "sky.hdr".into(),
                width: pixels.len() as u32,
                height: 1,
                pixels,
            }),
            intensity: 1.0,
            transform: DAffine3::IDENTITY,
        };
        s
    }

    /// An image's content counts (not the path or the allocation): the same pixels are the same
    /// scene, one different pixel is another.
    #[test]
    fn image_pixels_are_part_of_the_identity() {
        let pixels: Vec<[f32; 3]> = (0..1000).map(|i| [i as f32, 0.5, 1.0]).collect();
        let a = SceneId::of(&with_environment(pixels.clone()));
        assert_eq!(a, SceneId::of(&with_environment(pixels.clone())));
        let mut other = pixels;
        other[999][2] = 0.999;
        assert_ne!(a, SceneId::of(&with_environment(other)));
    }

    fn with_mesh(indices: Vec<[u32; 3]>) -> Scene {
        let mut s = scene(TEXT);
        let mesh = MeshData {
            path: "m.obj".into(),
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            indices,
            ..MeshData::default()
        };
        s.objects.push(Object {
            shape: ShapeDecl::Mesh {
                mesh: Arc::new(mesh),
            },
            transform: DAffine3::IDENTITY,
            material: MaterialId(0),
            emission: None,
            span: Span::detached(),
        });
        s
    }

    #[test]
    fn mesh_contents_are_part_of_the_identity() {
        let a = SceneId::of(&with_mesh(vec![[0, 1, 2], [0, 2, 3]]));
        assert_eq!(a, SceneId::of(&with_mesh(vec![[0, 1, 2], [0, 2, 3]])));
        assert_ne!(a, SceneId::of(&with_mesh(vec![[0, 1, 2], [0, 3, 2]])));
        assert_ne!(a, SceneId::of(&with_mesh(vec![[0, 1, 2]])));
    }
}
