//! Joins rendered frames into a looping GIF (each frame quantised to its own 256 colours).
//!
//! ```text
//! cargo run --release --features gif --bin frames-to-gif -- OUTPUT.gif DELAY_MS FRAME.png...
//! ```
//!
//! The frames are taken in the order given and must all have the size of the first.

use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [output, delay, frames @ ..] = args.as_slice() else {
        eprintln!("usage: frames-to-gif OUTPUT.gif DELAY_MS FRAME.png...");
        return ExitCode::from(2);
    };
    let Ok(delay) = delay.parse::<u32>() else {
        eprintln!("error: `{delay}` is not a delay in milliseconds");
        return ExitCode::from(2);
    };
    if frames.is_empty() {
        eprintln!("error: give at least one frame");
        return ExitCode::from(2);
    }
    match write(&PathBuf::from(output), delay, frames) {
        Ok(()) => {
            println!("wrote {output}: {} frames", frames.len());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

fn write(output: &Path, delay: u32, frames: &[String]) -> Result<(), String> {
    let mut images = Vec::with_capacity(frames.len());
    for f in frames {
        let image = image::open(f)
            .map_err(|e| format!("cannot read `{f}`: {e}"))?
            .to_rgba8();
        if let Some(first) = images.first().map(image::RgbaImage::dimensions)
            && first != image.dimensions()
        {
            return Err(format!("`{f}` is not the size of the first frame"));
        }
        images.push(image);
    }
    sppm_lang::internals::atomic_file::write_atomic(output, |_, file| {
        let mut encoder = GifEncoder::new_with_speed(BufWriter::new(file), 1);
        encoder
            .set_repeat(Repeat::Infinite)
            .and_then(|()| {
                encoder.encode_frames(
                    images
                        .into_iter()
                        .map(|i| Frame::from_parts(i, 0, 0, Delay::from_numer_denom_ms(delay, 1))),
                )
            })
            .map_err(|e| format!("cannot write `{}`: {e}", output.display()))
    })
}
