//! The memory one load holds, through the real binary under an address-space limit: the text
//! it parses (every include), the strings it joins and the images it decodes count in one
//! running total against `--memory-limit`, and the include or string that passes it is
//! refused at its span with a help naming the flag. Each case prints its peak memory.

use crate::measured;

use measured::{flat, peak_text, run_measured};
use std::time::Duration;

use sppm_lang::EvalOptions;
use sppm_lang::internals::syntax::{PARSE_BYTES_PER_LEXEME, parse_memory};

const MIB: u64 = 1 << 20;

/// A chain of ten files, each including the next before its own 1.6 MB array literal (inside
/// `#if (0)`: parsed, never evaluated), each just under a memory limit of 512 MiB to parse
/// (90 % of it). Each alone passed the check on its own, and their syntax trees were alive
/// together (a chain just under the default 2 GiB peaked at 6.5 GB). Now the second file is
/// refused at the first file's `#include`, with the total named, and the peak stays under the
/// limit.
#[test]
fn a_chain_of_includes_each_under_the_limit_is_refused_by_their_total() {
    let limit = 512 * MIB;
    let dir = tempfile::tempdir().unwrap();
    let elements = (limit * 9 / 10 / PARSE_BYTES_PER_LEXEME / 2) as usize;
    let filler = format!(
        "#if (0)\n#declare A = [{}1];\n#end\n",
        "1,".repeat(elements)
    );
    for k in 0..10 {
        let text = format!("#include \"chain{}.scn\"\n{filler}", k + 1);
        let need = parse_memory(&text);
        assert!(need < limit && need > limit * 8 / 10, "{need}");
        std::fs::write(dir.path().join(format!("chain{k}.scn")), text).unwrap();
    }
    std::fs::write(dir.path().join("chain10.scn"), "sphere { <0, 0, 0>, 1 }\n").unwrap();
    let main = dir.path().join("chain0.scn").display().to_string();
    let m = run_measured(
        &["check", &main, "--memory-limit", "512M"],
        4 << 30,
        Duration::from_secs(300),
    );
    println!(
        "ten includes of {:.1} MB each, limit 512 MiB: exit {:?} in {:.2} s ({:.2} CPU-s), peak {}",
        filler.len() as f64 / 1e6,
        m.code,
        m.seconds,
        m.cpu_seconds,
        peak_text(m.peak)
    );
    assert_eq!(m.code, Some(1), "{}", m.stderr);
    let stderr = flat(&m.stderr);
    assert!(
        stderr.contains("too large to parse within the memory limit")
            && stderr.contains("the load holds")
            && stderr.contains("parsed text")
            && stderr.contains("chain0.scn:1:10")
            && stderr.contains("--memory-limit"),
        "{stderr}"
    );
    if let Some(peak) = m.peak {
        assert!(peak < limit, "peak {peak} bytes, past the limit of {limit}");
    }
}

/// 40 strings of 16 MiB (copies of one string built by doubling), under a memory limit of
/// 512 MiB: refused at the join that passes it, at its span, before it is made. The strings
/// alive then (480 MiB) stay under the limit; with the program's own memory (code, stacks,
/// about 25 MB, not counted) the peak was 528 MB, and must stay under the limit and 64 MiB.
/// Under the default limit of 2 GiB, 40 such strings and four 8192x4096 images once reached
/// 2.8 GB.
#[test]
fn forty_strings_of_16_mib_are_refused_by_the_total() {
    let dir = tempfile::tempdir().unwrap();
    let mut text =
        String::from("#declare S = \"x\";\n#for (I, 1, 24)\n  #declare S = S + S;\n#end\n");
    for k in 0..40 {
        text.push_str(&format!("#declare C{k} = S + \"\";\n"));
    }
    text.push_str("sphere { <0, 0, 0>, 1 }\n");
    let path = dir.path().join("strings.scn");
    std::fs::write(&path, &text).unwrap();
    let path = path.display().to_string();
    let m = run_measured(
        &["check", &path, "--memory-limit", "512M"],
        4 << 30,
        Duration::from_secs(300),
    );
    println!(
        "40 strings of 16 MiB, limit 512 MiB: exit {:?} in {:.2} s ({:.2} CPU-s), peak {}",
        m.code,
        m.seconds,
        m.cpu_seconds,
        peak_text(m.peak)
    );
    assert_eq!(m.code, Some(1), "{}", m.stderr);
    let stderr = flat(&m.stderr);
    // 32 MiB to build the first (doubling), then one string per line: the 30th copy (line
    // 34) takes the total past 512 MiB.
    assert!(
        stderr.contains("this string of 16.0 MiB would take the load past its memory limit")
            && stderr.contains("strings.scn:34:")
            && stderr.contains("--memory-limit"),
        "{stderr}"
    );
    if let Some(peak) = m.peak {
        assert!(peak < 576 * MIB, "peak {peak} bytes");
    }
}

/// Strings and images share the one total: with room for the strings alone, or for the image
/// alone, a load holding 48 MiB of strings (16 MiB built by doubling, and a copy) is refused
/// its 12 MiB image (at the image's name, the total in the message), and loads with room for
/// both.
#[test]
fn strings_and_images_count_in_one_total() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::from_pixel(1024, 1024, image::Rgb([200, 100, 50]))
        .save(dir.path().join("a.png"))
        .unwrap();
    let text = "#declare S = \"x\";\n#for (I, 1, 24)\n  #declare S = S + S;\n#end\n\
                #declare T = S + \"\";\n\
                quad { <0, 0, 0>, <1, 0, 0>, <0, 1, 0> material { diffuse texture { image \"a.png\" } } }\n";
    let scene = dir.path().join("s.scn");
    std::fs::write(&scene, text).unwrap();
    let load = |limit: u64| {
        let options = EvalOptions {
            memory_limit: Some(limit),
            ..EvalOptions::default()
        };
        sppm_lang::internals::eval::load_file(&scene, &options).unwrap()
    };
    let errors = |l: &sppm_lang::internals::eval::Loaded| -> Vec<String> {
        l.diagnostics
            .iter()
            .filter(|d| d.is_error())
            .map(|d| d.message.clone())
            .collect()
    };
    // Strings: 1 + 2 + ... + 16 MiB built by doubling, and the 16 MiB copy: 48 MiB.
    let l = load(50 * MIB);
    let e = errors(&l);
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].contains("1024x1024") && e[0].contains("the load holds 48.0 MiB already"),
        "{e:?}"
    );
    let d = l.diagnostics.iter().find(|d| d.is_error()).unwrap();
    assert!(
        text[..d.span.start as usize].ends_with("image "),
        "{:?}",
        d.span
    );
    assert!(d.help.as_deref().unwrap().contains("--memory-limit"));
    assert!(errors(&load(61 * MIB)).is_empty());
}

/// A height field's heights count against the load's limit before they are allocated: a
/// function grid of 16 384 x 16 384 samples (1 GiB of heights) is refused at its grid under a
/// limit of 512 MiB, and a 16 384 x 16 384 PNG (a few hundred KB of zeros on disk, 4 GiB to
/// decode) from its header, each with a help naming the flag; a 64 x 64 grid loads.
#[test]
fn a_height_field_past_the_memory_limit_is_refused_before_it_is_allocated() {
    let dir = tempfile::tempdir().unwrap();
    let big = image::GrayImage::new(16_384, 16_384);
    big.save(dir.path().join("big.png")).unwrap();
    drop(big);
    let options = EvalOptions {
        memory_limit: Some(512 * MIB),
        ..EvalOptions::default()
    };
    for (name, text, want) in [
        (
            "grid.scn",
            "height_field { function 16384, 16384 { x * y } }\n",
            "a grid of 16384 x 16384 heights needs 1.00 GiB",
        ),
        (
            "image.scn",
            "height_field { png \"big.png\" }\n",
            "16384x16384 pixels; decoded and kept as heights it needs 5.00 GiB",
        ),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let l = sppm_lang::internals::eval::load_file(&path, &options).unwrap();
        let d = l.diagnostics.iter().find(|d| d.is_error()).expect(name);
        assert!(d.message.contains(want), "{name}: {}", d.message);
        assert!(
            d.help.as_deref().unwrap().contains("--memory-limit"),
            "{name}"
        );
        let at = &text[d.span.start as usize..d.span.end as usize];
        assert!(at == "16384, 16384" || at == "\"big.png\"", "{name}: {at}");
    }
    let l = sppm_lang::internals::eval::load_source(
        "small.scn",
        "height_field { function 64, 64 { x * y } }",
        &options,
    );
    assert!(!l.has_errors(), "{:?}", l.diagnostics);
}
