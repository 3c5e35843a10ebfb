//! Chains of one still and their merge. A chain is a whole render of the scene with its own
//! random streams ([`crate::sampling::chain_seed`]); it is written as a linear EXR whose header
//! says what merging needs ([`ChainInfo`]). [`merge`] checks that chains belong together and
//! combines them weighted by their iterations.
//!
//! Merging chains of I₁ … I_N iterations gives the variance of Σ Iₖ iterations of independent
//! samples, but not their bias: each chain shrinks its own progressive radii over its own Iₖ
//! iterations, so the radius bias of the merge stays that of a render of Iₖ iterations. The
//! render knows the chain (`RenderOptions::chain`): a chain of `vcm`, `bpt` or `lt` first runs
//! two warm-up passes it does not keep (docs/farm.md).

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::Path;

use exr::prelude::{AttributeValue, ReadChannels, ReadLayers, ReadSpecificChannel, Text, Vec2};

use crate::film::Image;

/// What a chain's file says about how it was made. Stored as EXR header attributes named
/// `sppm.*` (text values: the numbers may exceed the format's 32-bit integers).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChainInfo {
    /// Finished iterations: the chain's weight in a merge.
    pub iterations: u32,
    /// Photons per iteration (0 for methods without photons).
    pub photons: u64,
    /// The rendering method's name.
    pub method: String,
    /// The render seed the chain's streams are derived from (with `chain`).
    pub seed: u64,
    /// This chain's number, 1 ..= `chains`.
    pub chain: u32,
    pub chains: u32,
    /// The scene's identity hash (the same scene and build give the same hash).
    pub scene: u64,
}

/// A chain read back: its header and its pixels.
#[derive(Debug, Clone)]
pub struct Chain {
    pub info: ChainInfo,
    pub image: Image,
}

const KEYS: [&str; 7] = [
    "sppm.iterations",
    "sppm.photons",
    "sppm.method",
    "sppm.seed",
    "sppm.chain",
    "sppm.chains",
    "sppm.scene",
];

impl ChainInfo {
    fn values(&self) -> [String; 7] {
        [
            self.iterations.to_string(),
            self.photons.to_string(),
            self.method.clone(),
            self.seed.to_string(),
            self.chain.to_string(),
            self.chains.to_string(),
            format!("{:016x}", self.scene),
        ]
    }
}

/// Writes `image` with `info` in its header to `path` (linear f32 RGB EXR), atomically.
pub fn write_chain(path: &Path, image: &Image, info: &ChainInfo) -> Result<(), String> {
    if image.width == 0
        || image.height == 0
        || image.pixels.len() as u64 != image.width as u64 * image.height as u64
    {
        return Err(format!(
            "cannot write `{}`: the image says {}x{} pixels but holds {}",
            path.display(),
            image.width,
            image.height,
            image.pixels.len()
        ));
    }
    let values = info.values();
    // Keys and values are ASCII (numbers, hex, method names).
    let attributes: Vec<(&str, &str)> = KEYS
        .iter()
        .zip(&values)
        .map(|(key, value)| (*key, value.as_str()))
        .collect();
    crate::atomic_file::write_atomic(path, |_, file| {
        let mut w = BufWriter::new(file);
        image
            .write_exr(&mut w, &attributes)
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
        w.flush()
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))
    })
}

/// Reads a chain written by [`write_chain`]; a file without the chain header, or with a pixel
/// that is not a finite non-negative number, is refused with a message naming it.
pub fn read_chain(path: &Path) -> Result<Chain, String> {
    let name = path.display();
    let file = File::open(path).map_err(|e| format!("cannot read `{name}`: {e}"))?;
    type Pixels = (usize, Vec<[f64; 3]>);
    let exr = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required("R")
        .required("G")
        .required("B")
        .collect_pixels(
            |size: Vec2<usize>, _| -> Pixels { (size.width(), vec![[0.0; 3]; size.area()]) },
            |(w, px): &mut Pixels, p: Vec2<usize>, (r, g, b): (f32, f32, f32)| {
                px[p.y() * *w + p.x()] = [f64::from(r), f64::from(g), f64::from(b)];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(BufReader::new(file))
        .map_err(|e| format!("cannot read `{name}` as an RGB EXR: {e}"))?;
    let other = &exr.attributes.other;
    let layer_other = &exr.layer_data.attributes.other;
    let text = |key: &str| -> Result<String, String> {
        match other
            .get(&Text::from(key))
            .or_else(|| layer_other.get(&Text::from(key)))
        {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            _ => Err(format!(
                "`{name}` is not a chain: its header has no `{key}` (chains are written by \
                 `render --chain K/N`)"
            )),
        }
    };
    let number = |key: &str| -> Result<u64, String> {
        let t = text(key)?;
        let parsed = if key == "sppm.scene" {
            u64::from_str_radix(&t, 16).ok()
        } else {
            t.parse().ok()
        };
        parsed.ok_or_else(|| format!("`{name}`: header `{key}` is `{t}`, not a number"))
    };
    let small = |key: &str| -> Result<u32, String> {
        u32::try_from(number(key)?).map_err(|_| format!("`{name}`: header `{key}` is too large"))
    };
    let info = ChainInfo {
        iterations: small("sppm.iterations")?,
        photons: number("sppm.photons")?,
        method: text("sppm.method")?,
        seed: number("sppm.seed")?,
        chain: small("sppm.chain")?,
        chains: small("sppm.chains")?,
        scene: number("sppm.scene")?,
    };
    let size = exr.layer_data.size;
    let (_, pixels) = exr.layer_data.channel_data.pixels;
    let image = Image {
        width: u32::try_from(size.width()).map_err(|_| format!("`{name}` is too wide"))?,
        height: u32::try_from(size.height()).map_err(|_| format!("`{name}` is too tall"))?,
        pixels,
    };
    check_pixels(&name.to_string(), &image)?;
    Ok(Chain { info, image })
}

/// Refuses NaN, infinite and negative pixel values (a render writes none): they would spread
/// through the merge.
fn check_pixels(name: &str, image: &Image) -> Result<(), String> {
    let bad = image
        .pixels
        .iter()
        .position(|p| p.iter().any(|v| !v.is_finite() || *v < 0.0));
    match bad {
        Some(i) => {
            let w = image.width.max(1) as usize;
            Err(format!(
                "`{name}`: pixel ({}, {}) is {:?}, not a finite non-negative value",
                i % w,
                i / w,
                image.pixels[i]
            ))
        }
        None => Ok(()),
    }
}

/// Merges chains (each named for messages): they must be of one scene, method, photon count,
/// seed, chain count and size, with distinct chain numbers and at least one iteration in all.
/// The result is the mean of the chains weighted by their iterations, and the total
/// iterations.
pub fn merge(chains: &[(String, Chain)]) -> Result<(Image, u32), String> {
    let Some((first_name, first)) = chains.first() else {
        return Err("nothing to merge: give the chain files".into());
    };
    let mut seen: Vec<(u32, &str)> = Vec::new();
    let mut total: u64 = 0;
    for (name, c) in chains {
        check_pixels(name, &c.image)?;
        let (a, b) = (&first.info, &c.info);
        let differs = |what: &str, x: String, y: String| -> Result<(), String> {
            if x == y {
                Ok(())
            } else {
                Err(format!(
                    "`{name}` does not belong with `{first_name}`: its {what} is {y}, not {x}"
                ))
            }
        };
        differs(
            "scene hash",
            format!("{:016x}", a.scene),
            format!("{:016x}", b.scene),
        )?;
        differs("method", a.method.clone(), b.method.clone())?;
        differs(
            "size",
            format!("{}x{}", first.image.width, first.image.height),
            format!("{}x{}", c.image.width, c.image.height),
        )?;
        differs(
            "photons per iteration",
            a.photons.to_string(),
            b.photons.to_string(),
        )?;
        differs("seed", a.seed.to_string(), b.seed.to_string())?;
        differs("chain count", a.chains.to_string(), b.chains.to_string())?;
        if b.chain == 0 || b.chain > b.chains {
            return Err(format!(
                "`{name}`: chain {} of {} is not a chain number",
                b.chain, b.chains
            ));
        }
        if let Some((_, other)) = seen.iter().find(|(k, _)| *k == b.chain) {
            return Err(format!(
                "`{name}` and `{other}` are both chain {} of {}: a chain counts once",
                b.chain, b.chains
            ));
        }
        seen.push((b.chain, name));
        total += u64::from(b.iterations);
    }
    let total = u32::try_from(total).map_err(|_| "too many iterations in all".to_string())?;
    if total == 0 {
        return Err("the chains hold no finished iteration".into());
    }
    let mut out = Image::new(first.image.width, first.image.height);
    for (_, c) in chains {
        let w = f64::from(c.info.iterations) / f64::from(total);
        for (o, p) in out.pixels.iter_mut().zip(&c.image.pixels) {
            for ch in 0..3 {
                o[ch] += w * p[ch];
            }
        }
    }
    Ok((out, total))
}

/// Reads `inputs`, merges them ([`merge`]) and writes the merge to `output` (linear EXR, with
/// no chain header), atomically: on any error nothing is written. Returns the total iterations
/// and the chains' method.
pub fn merge_files(inputs: &[&Path], output: &Path) -> Result<(u32, String), String> {
    let chains = inputs
        .iter()
        .map(|p| Ok((p.display().to_string(), read_chain(p)?)))
        .collect::<Result<Vec<_>, String>>()?;
    let (image, total) = merge(&chains)?;
    image.write(output, 1.0).map_err(|d| d.message)?;
    // `merge` found at least one chain, all of one method.
    let method = chains
        .first()
        .map_or_else(String::new, |(_, c)| c.info.method.clone());
    Ok((total, method))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(chain: u32, iterations: u32) -> ChainInfo {
        ChainInfo {
            iterations,
            photons: 1000,
            method: "sppm".into(),
            seed: 7,
            chain,
            chains: 2,
            scene: 0xabc,
        }
    }

    fn flat(w: u32, h: u32, v: f64) -> Image {
        Image {
            width: w,
            height: h,
            pixels: vec![[v, v * 2.0, v * 3.0]; (w * h) as usize],
        }
    }

    fn chain(k: u32, iterations: u32, image: Image) -> (String, Chain) {
        (
            format!("c{k}.exr"),
            Chain {
                info: info(k, iterations),
                image,
            },
        )
    }

    #[test]
    fn merge_is_the_iteration_weighted_mean() {
        let mut a = flat(3, 2, 1.0);
        a.pixels[4] = [0.5, 0.0, 8.0];
        let b = flat(3, 2, 5.0);
        let (m, total) = merge(&[chain(1, 2, a.clone()), chain(2, 6, b.clone())]).unwrap();
        assert_eq!(total, 8);
        for (i, p) in m.pixels.iter().enumerate() {
            for ch in 0..3 {
                let want = (2.0 * a.pixels[i][ch] + 6.0 * b.pixels[i][ch]) / 8.0;
                assert!((p[ch] - want).abs() < 1e-12, "pixel {i}: {p:?}");
            }
        }
        // Not the plain mean: (1 + 5) / 2 = 3 at pixel 0's red.
        assert!((m.pixels[0][0] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn merge_refuses_mixed_scenes_duplicates_sizes_and_nan() {
        let a = chain(1, 2, flat(2, 2, 1.0));
        let mut other_scene = chain(2, 2, flat(2, 2, 1.0));
        other_scene.1.info.scene = 0xdef;
        let e = merge(&[a.clone(), other_scene]).unwrap_err();
        assert!(e.contains("scene hash") && e.contains("c2.exr"), "{e}");

        let e = merge(&[a.clone(), chain(1, 3, flat(2, 2, 1.0))]).unwrap_err();
        assert!(e.contains("both chain 1"), "{e}");

        let e = merge(&[a.clone(), chain(2, 2, flat(3, 2, 1.0))]).unwrap_err();
        assert!(e.contains("size is 3x2"), "{e}");

        let mut nan = chain(2, 2, flat(2, 2, 1.0));
        nan.1.image.pixels[3][1] = f64::NAN;
        let e = merge(&[a.clone(), nan]).unwrap_err();
        assert!(e.contains("c2.exr") && e.contains("pixel (1, 1)"), "{e}");

        let mut negative = chain(2, 2, flat(2, 2, 1.0));
        negative.1.image.pixels[0][0] = -1.0;
        assert!(merge(&[a.clone(), negative]).is_err());

        let mut method = chain(2, 2, flat(2, 2, 1.0));
        method.1.info.method = "path".into();
        assert!(merge(&[a, method]).unwrap_err().contains("method"));
    }

    #[test]
    fn chain_files_round_trip_and_a_failed_merge_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let (pa, pb, out) = (
            dir.path().join("a.exr"),
            dir.path().join("b.exr"),
            dir.path().join("m.exr"),
        );
        let a = flat(4, 3, 0.25);
        write_chain(&pa, &a, &info(1, 2)).unwrap();
        let back = read_chain(&pa).unwrap();
        assert_eq!(back.info, info(1, 2));
        assert_eq!(back.image, a);
        // A duplicate of chain 1 is refused and no output appears.
        write_chain(&pb, &flat(4, 3, 0.5), &info(1, 6)).unwrap();
        assert!(merge_files(&[&pa, &pb], &out).is_err());
        assert!(!out.exists());
        write_chain(&pb, &flat(4, 3, 0.5), &info(2, 6)).unwrap();
        assert_eq!(
            merge_files(&[&pa, &pb], &out).unwrap(),
            (8, "sppm".to_string())
        );
        let m = image::open(&out).unwrap().to_rgb32f();
        let want = (2.0 * 0.25 + 6.0 * 0.5) / 8.0;
        assert!((f64::from(m.get_pixel(0, 0)[0]) - want).abs() < 1e-6);
        // A plain EXR has no chain header.
        a.write(&out, 1.0).unwrap();
        assert!(read_chain(&out).unwrap_err().contains("not a chain"));
    }
}
