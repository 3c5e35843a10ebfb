//! Embedding sppm-lang: a scene written in a string, with an include and an image texture
//! supplied from memory, rendered without reading the disk.
//!
//! `cargo run --example embed [out.png]`: writes the image when given a path (the only file
//! the program touches), else prints the mean colour of its pixels.

use std::path::Path;

use sppm_lang::SharedWorld;
use sppm_lang::{EvalOptions, MemoryWorld, RenderOptions};

const SCENE: &str = r#"
#include "lib/light.scn"
camera { location <0, 1.2, 3.5>  look_at <0, 0.4, 0>  fov 45 }
// The floor shows the image from memory; the sphere takes the included colour.
quad { <-2, 0, -2>, <4, 0, 0>, <0, 0, 4>
       material { diffuse texture { image "textures/checks.png" scale 0.25 } } }
sphere { <0, 0.5, 0>, 0.5  material { diffuse Tint } }
"#;

const INCLUDE: &str = r#"
#declare Tint = rgb <0.8, 0.3, 0.2>;
area_light { quad { <-1, 3, -1>, <2, 0, 0>, <0, 0, 2> }  radiance rgb <4, 4, 4> }
"#;

/// A 2x2 checkerboard of blue and white, as PNG bytes.
fn checks_png() -> Vec<u8> {
    let img = image::RgbImage::from_fn(2, 2, |x, y| {
        if (x + y) % 2 == 0 {
            image::Rgb([40, 60, 200])
        } else {
            image::Rgb([230, 230, 230])
        }
    });
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .expect("a PNG encodes in memory");
    bytes
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let world = MemoryWorld::new()
        .with("scene.scn", SCENE)
        .with("lib/light.scn", INCLUDE)
        .with("textures/checks.png", checks_png());
    let load_options = EvalOptions {
        world: SharedWorld::new(world),
        ..EvalOptions::default()
    };
    let document = sppm_lang::load(Path::new("scene.scn"), &load_options)?;
    for w in &document.warnings {
        eprintln!("warning: {}", w.message);
    }
    // The resolution, iterations and seed are the render's, not the scene's.
    let options = RenderOptions {
        resolution: Some((96, 72)),
        iterations: Some(4),
        photons: Some(20_000),
        seed: Some(7),
        ..RenderOptions::default()
    };
    let prepared = sppm_lang::prepare(&document, &options)?;
    let rendered = sppm_lang::render(&prepared)?;
    match std::env::args_os().nth(1) {
        Some(out) => rendered.image.write(Path::new(&out), 1.0)?,
        None => {
            let n = rendered.image.pixels.len() as f64;
            let mean = rendered
                .image
                .pixels
                .iter()
                .fold([0.0; 3], |m, p| [m[0] + p[0], m[1] + p[1], m[2] + p[2]])
                .map(|c| c / n);
            println!(
                "{}x{} pixels, {} iterations, mean colour {mean:.3?}",
                rendered.image.width, rendered.image.height, rendered.iterations
            );
        }
    }
    Ok(())
}
