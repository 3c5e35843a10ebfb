//! `sppm-lang watch` driven by real file operations on a temporary folder.
//!
//! Each step changes files the way an editor does and waits (with a timeout) for the watcher's
//! plain status lines on stderr, then checks the image on disk: its colour must be the one the
//! last valid scene asked for (the scenes differ only in their background colour), an erroneous
//! edit must leave the previous image byte-for-byte, and no temporary file may be left behind.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::running;
use running::Running;

const STEP_TIMEOUT: Duration = Duration::from_secs(60);

/// A scene whose background is `bg` as sRGB bytes; use only 0 and 255, which are linear 0 and 1
/// and come back exactly.
fn scene_text(bg: [u8; 3]) -> String {
    let [r, g, b] = bg.map(|c| f32::from(c) / 255.0);
    scene_with(&format!("background rgb <{r}, {g}, {b}>"))
}

/// A tiny scene that sees only its background (the light keeps the renderer's light sampler
/// non-empty; nothing is in view).
fn scene_with(background_line: &str) -> String {
    format!(
        "settings {{ resolution <16, 16>  iterations 3  photons 500  seed 1 }}\n\
         camera {{ location <0, 0, -5>  look_at <0, 0, 0>  fov 30 }}\n\
         light {{ <0, 0, -20>  intensity rgb <1, 1, 1> }}\n\
         {background_line}\n"
    )
}

/// `sppm-lang watch`, running.
struct Watch(Running);

impl Watch {
    fn start(dir: &Path, scene: &str, out: &str) -> Watch {
        Watch::start_with(dir, &[scene, "-o", out, "--no-preview"])
    }

    /// `watch` with `args`, writing every snapshot.
    fn start_with(dir: &Path, args: &[&str]) -> Watch {
        let mut command = Command::new(env!("CARGO_BIN_EXE_sppm-lang"));
        command
            .current_dir(dir)
            .arg("watch")
            .args(args)
            .args(["--snapshot-every", "0"]);
        Watch(Running::spawn(command))
    }

    /// Waits for a status line containing `needle`; returns it.
    fn expect(&mut self, needle: &str) -> String {
        self.0.expect(needle, STEP_TIMEOUT)
    }

    /// Collects lines until `quiet` passes without one.
    fn drain(&mut self, quiet: Duration) -> Vec<String> {
        self.0.drain(quiet)
    }

    fn interrupt(mut self) -> (std::process::ExitStatus, Vec<String>) {
        let pid = self.0.child.id().to_string();
        let ok = Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill -INT failed");
        let deadline = Instant::now() + STEP_TIMEOUT;
        let status = loop {
            if let Some(s) = self.0.child.try_wait().unwrap() {
                break s;
            }
            assert!(Instant::now() < deadline, "watch did not exit after Ctrl-C");
            std::thread::sleep(Duration::from_millis(20));
        };
        let rest = self.drain(Duration::from_millis(200));
        (status, rest)
    }
}

/// The colour of the output image's centre pixel (sRGB bytes).
fn centre(path: &Path) -> [u8; 3] {
    let img = image::open(path).expect("output image readable").to_rgb8();
    img.get_pixel(img.width() / 2, img.height() / 2).0
}

fn no_temporaries(dir: &Path) {
    let names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let left: Vec<&String> = names.iter().filter(|n| n.starts_with(".sppm-")).collect();
    assert!(left.is_empty(), "temporary files left behind: {left:?}");
}

fn rename_over(path: &Path, text: &str) {
    let tmp = path.with_extension("scn.tmp~");
    fs::write(&tmp, text).unwrap();
    fs::rename(&tmp, path).unwrap();
}

fn latency_of(line: &str) -> Option<f64> {
    let i = line.find(" s after the change")?;
    line[..i].rsplit(", ").next()?.parse().ok()
}

#[test]
fn watch_follows_editor_saves_and_keeps_the_last_good_image() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.scn");
    let out = dir.path().join("out.png");
    fs::write(&scene, scene_text([255, 0, 0])).unwrap();
    let mut w = Watch::start(dir.path(), "scene.scn", "out.png");
    let mut latencies = Vec::new();

    w.expect("render #1 started");
    w.expect("render #1 full finished");
    assert_eq!(centre(&out), [255, 0, 0]);

    // 1. In-place write.
    let saved = Instant::now();
    fs::write(&scene, scene_text([0, 255, 0])).unwrap();
    w.expect("render #2 started");
    let line = w.expect("render #2 full iteration 1/");
    latencies.push((saved.elapsed().as_secs_f64(), latency_of(&line)));
    w.expect("render #2 full finished");
    assert_eq!(centre(&out), [0, 255, 0]);

    // 2. Rename over the file (vim, many IDEs).
    let saved = Instant::now();
    rename_over(&scene, &scene_text([0, 0, 255]));
    w.expect("render #3 started");
    let line = w.expect("render #3 full iteration 1/");
    latencies.push((saved.elapsed().as_secs_f64(), latency_of(&line)));
    w.expect("render #3 full finished");
    assert_eq!(centre(&out), [0, 0, 255]);

    // 3. Delete and recreate.
    fs::remove_file(&scene).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    fs::write(&scene, scene_text([255, 255, 0])).unwrap();
    w.expect("render #4 started");
    w.expect("render #4 full finished");
    assert_eq!(centre(&out), [255, 255, 0]);

    // 4. An edit with a syntax error: diagnostics, the image stays byte-for-byte.
    let before = fs::read(&out).unwrap();
    fs::write(&scene, "background rgb <1, 0, \n").unwrap();
    w.expect("the scene has errors; the last image is kept");
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(
        fs::read(&out).unwrap(),
        before,
        "the last good image changed"
    );

    // 5. The fix.
    fs::write(&scene, scene_text([0, 255, 255])).unwrap();
    w.expect("render #5 started");
    w.expect("render #5 full finished");
    assert_eq!(centre(&out), [0, 255, 255]);

    // 6. A burst of 50 saves in about a second: far fewer renders, the last content wins.
    // Cycle through the primaries, finish with white, which no earlier save used.
    let primaries = [[255, 0, 0], [0, 255, 0], [0, 0, 255]];
    for i in 0..50usize {
        let bg = if i == 49 {
            [255, 255, 255]
        } else {
            primaries[i % 3]
        };
        fs::write(&scene, scene_text(bg)).unwrap();
        std::thread::sleep(Duration::from_millis(20));
    }
    let last = [255, 255, 255];
    let mut started = 0;
    let mut finished_last = false;
    let deadline = Instant::now() + STEP_TIMEOUT;
    while Instant::now() < deadline {
        let lines = w.drain(Duration::from_millis(1500));
        started += lines.iter().filter(|l| l.contains(" started")).count();
        if lines.is_empty() && fs::read(&out).is_ok() && centre(&out) == last {
            finished_last = true;
            break;
        }
    }
    println!("50 saves in ~1 s started {started} renders");
    assert!(
        finished_last,
        "the image never showed the last save; output:\n{}",
        w.0.log.join("\n")
    );
    assert!(
        (1..=8).contains(&started),
        "50 saves started {started} renders"
    );
    no_temporaries(dir.path());

    // Seen by the test (save → status line read) and reported by the watcher (first event →
    // snapshot written); the first includes the 100 ms batching quiet time.
    println!(
        "save-to-first-snapshot latency (s), test-measured vs watcher-reported: {latencies:?}"
    );
    for (seen, reported) in &latencies {
        let reported = reported.expect("the watcher reports its latency");
        // The watcher prints milliseconds, rounded: allow that half millisecond.
        assert!(
            reported <= *seen + 0.0005,
            "reported {reported} s > seen {seen} s"
        );
    }

    // 7. Ctrl-C: exit 0.
    let (status, _) = w.interrupt();
    assert!(
        status.success(),
        "watch exited with {status:?} after Ctrl-C"
    );
    no_temporaries(dir.path());
}

#[test]
fn watch_follows_included_files() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("main.scn");
    let inc = dir.path().join("colors.scn");
    let out = dir.path().join("main.png");
    fs::write(&inc, "#declare Bg = rgb <255, 0, 0>;\n").unwrap();
    fs::write(&scene, scene_with("#include \"colors.scn\"\nbackground Bg")).unwrap();
    let mut w = Watch::start(dir.path(), "main.scn", "main.png");
    w.expect("render #1 full finished");
    assert_eq!(centre(&out), [255, 0, 0]);
    fs::write(&inc, "#declare Bg = rgb <0, 0, 255>;\n").unwrap();
    w.expect("render #2 full finished");
    assert_eq!(centre(&out), [0, 0, 255]);
    // A typo'd include that does not exist yet is polled: creating it re-renders.
    fs::write(
        &scene,
        scene_with("#include \"later/extra.scn\"\nbackground Bg"),
    )
    .unwrap();
    w.expect("the scene has errors; the last image is kept");
    fs::create_dir(dir.path().join("later")).unwrap();
    fs::write(
        dir.path().join("later/extra.scn"),
        "#declare Bg = rgb <0, 255, 0>;\n",
    )
    .unwrap();
    w.expect("render #3 full finished");
    assert_eq!(centre(&out), [0, 255, 0]);
    no_temporaries(dir.path());
}

#[test]
fn watch_rerenders_when_a_texture_image_is_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("tex.scn");
    let tex = dir.path().join("tex.png");
    let out = dir.path().join("tex-out.png");
    image::RgbImage::from_pixel(4, 4, image::Rgb([255, 0, 0]))
        .save(&tex)
        .unwrap();
    // A textured quad filling the view, lit from the camera.
    fs::write(
        &scene,
        "settings { resolution <16, 16>  iterations 3  photons 2000  seed 1 }\n\
         camera { location <0, 0, -5>  look_at <0, 0, 0>  fov 30 }\n\
         light { <0, 0, -5>  intensity rgb <30, 30, 30> }\n\
         quad { <-5, -5, 0>, <0, 10, 0>, <10, 0, 0>\n\
           material { diffuse texture { image \"tex.png\" } } }\n",
    )
    .unwrap();
    let mut w = Watch::start(dir.path(), "tex.scn", "tex-out.png");
    w.expect("render #1 full finished");
    let [r, g, b] = centre(&out);
    assert!(
        r > 50 && g < 10 && b < 10,
        "red texture gave {:?}",
        [r, g, b]
    );
    let tmp = dir.path().join("tex.tmp.png");
    image::RgbImage::from_pixel(4, 4, image::Rgb([0, 0, 255]))
        .save(&tmp)
        .unwrap();
    fs::rename(&tmp, &tex).unwrap();
    w.expect("render #2 full finished");
    let [r, g, b] = centre(&out);
    assert!(
        b > 50 && r < 10 && g < 10,
        "blue texture gave {:?}",
        [r, g, b]
    );
}

#[test]
fn watch_without_a_scene_file_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let missing: PathBuf = dir.path().join("nope.scn");
    // A missing scene, and a folder (it exists, but is no scene), named as such.
    for (scene, why) in [
        (&missing, "does not exist"),
        (&dir.path().to_path_buf(), "is a directory"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_sppm-lang"))
            .args(["watch", scene.to_str().unwrap(), "-o"])
            .arg(dir.path().join("x.png"))
            .stdin(Stdio::null())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(why), "{err}");
    }
    let _ = std::io::stdout().flush();
}

/// `watch STEM.scn -o STEM.png` in a new folder on a red scene, after its first render: the
/// folder, the scene, the image and the running watch.
fn watching_a_red_scene(stem: &str) -> (tempfile::TempDir, PathBuf, PathBuf, Watch) {
    let dir = tempfile::tempdir().unwrap();
    let (scene_name, out_name) = (format!("{stem}.scn"), format!("{stem}.png"));
    let scene = dir.path().join(&scene_name);
    let out = dir.path().join(&out_name);
    fs::write(&scene, scene_text([255, 0, 0])).unwrap();
    let mut w = Watch::start(dir.path(), &scene_name, &out_name);
    w.expect("render #1 full finished");
    (dir, scene, out, w)
}

/// An edit that makes the scene read its own output image (as a texture) is refused for that
/// round: writing the image would destroy the texture, and each write would start the next
/// round, forever. The image stays as it was until a save that no longer reads it.
#[test]
fn a_scene_that_reads_its_own_output_is_not_rendered_over_it() {
    let (dir, scene, out, mut w) = watching_a_red_scene("own");
    let before = fs::read(&out).unwrap();
    fs::write(
        &scene,
        scene_with(
            "background rgb <0, 0, 1>
             sphere { <0, 0, 0>, 1 material { diffuse texture { image \"own.png\" } } }",
        ),
    )
    .unwrap();
    w.expect("which this command reads");
    w.expect("the output cannot be written; the last image is kept");
    w.expect("waiting for changes");
    let later = w.drain(Duration::from_millis(800));
    assert!(
        !later.iter().any(|l| l.contains("started")),
        "rendered over its own texture: {later:?}"
    );
    assert_eq!(fs::read(&out).unwrap(), before, "the image changed");
    fs::write(&scene, scene_text([0, 255, 0])).unwrap();
    w.expect("render #2 full finished");
    assert_eq!(centre(&out), [0, 255, 0]);
    no_temporaries(dir.path());
}

#[test]
fn ctrl_c_during_a_render_writes_the_finished_iterations_and_exits_0() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("long.scn");
    let out = dir.path().join("long.png");
    // Far more iterations than the test waits for.
    fs::write(
        &scene,
        scene_text([255, 0, 0]).replace("iterations 3", "iterations 1000000"),
    )
    .unwrap();
    let mut w = Watch::start(dir.path(), "long.scn", "long.png");
    w.expect("render #1 full iteration 1/");
    fs::remove_file(&out).unwrap();
    let (status, rest) = w.interrupt();
    assert!(status.success(), "exit {status:?}");
    assert!(
        rest.iter()
            .any(|l| l.contains("stopped after") && l.contains("written to")),
        "{rest:?}"
    );
    assert_eq!(
        centre(&out),
        [255, 0, 0],
        "the interrupted render's image is on disk"
    );
    no_temporaries(dir.path());
}

#[test]
fn an_empty_save_keeps_the_last_image_and_the_next_save_renders() {
    // Editors truncate a file before writing it; the empty scene (or one of comments alone) is
    // not rendered over the image.
    let (dir, scene, out, mut w) = watching_a_red_scene("scene");
    let before = fs::read(&out).unwrap();
    fs::write(&scene, "").unwrap();
    w.expect("is empty; the last image is kept");
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(fs::read(&out).unwrap(), before, "the image changed");
    // Only a comment and blanks: nothing declared, nothing rendered over the image either.
    fs::write(&scene, "// saving...\n\n").unwrap();
    w.expect("declares no object, no light and no background; the last image is kept");
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(fs::read(&out).unwrap(), before, "the image changed");
    fs::write(&scene, scene_text([0, 0, 255])).unwrap();
    w.expect("render #2 full finished");
    assert_eq!(centre(&out), [0, 0, 255]);
    no_temporaries(dir.path());
}

/// The preview is written at the full size (a viewer never sees the size change), `--scale`
/// sets that size, and "waiting for changes" is said only once nothing renders.
#[test]
fn the_preview_is_written_at_full_size_and_status_lines_are_true() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("wide.scn");
    let out = dir.path().join("wide.png");
    let text = scene_text([255, 0, 0])
        .replace("resolution <16, 16>", "resolution <256, 128>")
        .replace("iterations 3", "iterations 6");
    fs::write(&scene, &text).unwrap();
    let mut w = Watch::start_with(
        dir.path(),
        &["wide.scn", "-o", "wide.png", "--scale", "0.5"],
    );
    w.expect("render #1 started");
    let mut sizes = Vec::new();
    loop {
        let line = w.expect("render #1");
        assert!(
            !w.0.log.iter().any(|l| l.contains("waiting for changes")),
            "`waiting for changes` while rendering: {:?}",
            w.0.log
        );
        if line.contains("written to") {
            let img = image::open(&out).unwrap();
            sizes.push((line.contains("preview"), img.width(), img.height()));
        }
        if line.contains("full finished") {
            break;
        }
    }
    w.expect("waiting for changes");
    assert!(
        sizes.iter().any(|s| s.0),
        "no preview was written: {sizes:?}"
    );
    assert!(
        sizes.iter().all(|&(_, w, h)| (w, h) == (128, 64)),
        "every image is the full size of the scaled scene: {sizes:?}"
    );
    // A scene with errors: nothing renders, so the watcher waits.
    fs::write(&scene, "sphere {").unwrap();
    w.expect("the scene has errors");
    w.expect("waiting for changes");
}

#[test]
fn serve_on_a_port_in_use_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.scn");
    fs::write(&scene, scene_text([255, 0, 0])).unwrap();
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port().to_string();
    let out = Command::new(env!("CARGO_BIN_EXE_sppm-lang"))
        .args(["watch", scene.to_str().unwrap(), "--serve", "--port", &port])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("the port is in use"), "{err}");
    assert!(err.contains("--port"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
