//! `sppm-lang watch` never loses a save and keeps the best image: a save during a long first
//! evaluation is rendered, a save that leaves the scene as it was does not restart the render,
//! and a render never replaces a more converged image of the same scene.
//!
//! Each test drives the real binary on a temporary folder and reads its plain `[watch]` status
//! lines; the scenes differ in their background colour, which the image's centre shows.

use std::fs;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

use crate::running;
use running::Running;

const STEP_TIMEOUT: Duration = Duration::from_secs(60);

/// A tiny scene that sees only its background `bg` (sRGB bytes 0 or 255, which come back
/// exactly), rendered for `iterations`, with `extra` lines.
fn scene(bg: [u8; 3], iterations: u32, extra: &str) -> String {
    let [r, g, b] = bg.map(|c| f32::from(c) / 255.0);
    format!(
        "settings {{ resolution <16, 16>  iterations {iterations}  photons 500  seed 1 }}\n\
         camera {{ location <0, 0, -5>  look_at <0, 0, 0>  fov 30 }}\n\
         light {{ <0, 0, -20>  intensity rgb <1, 1, 1> }}\n\
         background rgb <{r}, {g}, {b}>\n\
         {extra}\n"
    )
}

const RED: [u8; 3] = [255, 0, 0];
const GREEN: [u8; 3] = [0, 255, 0];

/// `watch` in `dir` with `args`, writing every snapshot.
fn watch(dir: &Path, args: &[&str]) -> Running {
    let mut command = Command::new(env!("CARGO_BIN_EXE_sppm-lang"));
    command
        .current_dir(dir)
        .arg("watch")
        .args(args)
        .args(["--no-clear", "--snapshot-every", "0"]);
    Running::spawn(command)
}

/// The colour of the image's centre pixel (sRGB bytes).
fn centre(path: &Path) -> [u8; 3] {
    let img = image::open(path).expect("output image readable").to_rgb8();
    img.get_pixel(img.width() / 2, img.height() / 2).0
}

/// The iteration of a `render #N STAGE iteration I/M written` line.
fn iteration_of(line: &str) -> u32 {
    let after = line.split(" iteration ").nth(1).expect("an iteration line");
    after.split('/').next().unwrap().parse().expect("a number")
}

/// The first evaluation takes seconds (a long `#while` loop); a save made meanwhile must be
/// rendered once that evaluation ends, even though its files were not known yet.
#[test]
fn a_save_during_the_first_evaluation_is_rendered() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("slow.scn");
    let out = dir.path().join("slow.png");
    // About 8 steps per turn: 20 million turns (4 loops of 5 million: a loop stops at 10
    // million) are seconds of evaluation even on a fast idle machine (3 million took 0.3 s on
    // one, 2026-11-30), far more than the 0.2 s the test waits before its save.
    let slow = "#declare J = 0;\n\
                #while (J < 4)\n  #declare I = 0;\n\
                #while (I < 5000000)\n  #declare I = I + 1;\n#end\n\
                #declare J = J + 1;\n#end\n\
                #debug \"the slow scene was evaluated\"";
    fs::write(&path, scene(RED, 3, slow)).unwrap();
    let mut w = watch(
        dir.path(),
        &[
            "slow.scn",
            "-o",
            "slow.png",
            "--no-preview",
            "--max-iterations",
            "10000000",
            "--max-steps",
            "500000000",
        ],
    );
    std::thread::sleep(Duration::from_millis(200));
    let early = w.drain(Duration::from_millis(1));
    assert!(
        early.is_empty(),
        "the first evaluation ended within 0.2 s (the test needs it to be running): {early:?}"
    );
    fs::write(
        &path,
        scene(GREEN, 3, "#debug \"the quick scene was evaluated\""),
    )
    .unwrap();
    // The slow scene is what the first load read; the save comes after it.
    w.expect("the slow scene was evaluated", STEP_TIMEOUT);
    w.expect("render #1 started", STEP_TIMEOUT);
    w.expect("changed: ", STEP_TIMEOUT);
    w.expect("the quick scene was evaluated", STEP_TIMEOUT);
    w.expect("render #2 full finished", STEP_TIMEOUT);
    assert_eq!(centre(&out), GREEN, "the image is the saved scene's");
}

/// The same text saved again, then an edit that only adds a comment and spaces: neither
/// restarts a finished render nor touches its image; a save of the same text during a render
/// lets it go on.
#[test]
fn a_save_that_leaves_the_scene_as_it_was_does_not_restart_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("same.scn");
    let out = dir.path().join("same.png");
    let text = scene(RED, 3, "");
    fs::write(&path, &text).unwrap();
    let mut w = watch(dir.path(), &["same.scn", "-o", "same.png"]);
    w.expect("render #1 full finished", STEP_TIMEOUT);
    let converged = fs::read(&out).unwrap();
    let commented = format!(
        "// the same scene, commented\n\n{}",
        text.replace("  ", "    ")
    );
    for (what, edit) in [("the same text", &text), ("a comment", &commented)] {
        fs::write(&path, edit).unwrap();
        w.expect("changed: ", STEP_TIMEOUT);
        let line = w.expect("unchanged", STEP_TIMEOUT);
        assert!(line.contains("render #1 stays"), "{what}: {line}");
        let later = w.drain(Duration::from_millis(800));
        assert!(
            !later.iter().any(|l| l.contains("started")),
            "{what} restarted the render: {later:?}"
        );
        assert_eq!(
            fs::read(&out).unwrap(),
            converged,
            "{what} changed the image"
        );
    }

    // During a render (far more iterations than the test waits for): it goes on.
    let long = scene(GREEN, 1_000_000, "");
    fs::write(&path, &long).unwrap();
    w.expect("render #2 full iteration 1/", STEP_TIMEOUT);
    fs::write(&path, &long).unwrap();
    w.expect("changed: ", STEP_TIMEOUT);
    let line = w.expect("unchanged", STEP_TIMEOUT);
    assert!(line.contains("render #2 goes on"), "{line}");
    let mut after = 0;
    while after < 3 {
        let line = w.expect("render #", STEP_TIMEOUT);
        assert!(
            !line.contains("cancelled") && !line.contains("render #3"),
            "the save restarted the render: {line}"
        );
        if line.contains("render #2 full iteration") {
            after += 1;
        }
    }
}

/// The testers' sequence: a finished render, a save that changes nothing, then a save with an
/// error. The image on disk stays the finished one, byte for byte.
#[test]
fn a_broken_save_after_a_no_op_save_keeps_the_finished_image() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("keep.scn");
    let out = dir.path().join("keep.png");
    let text = scene(RED, 8, "");
    fs::write(&path, &text).unwrap();
    // With the preview: a restarted render would write a 1-iteration preview first.
    let mut w = watch(dir.path(), &["keep.scn", "-o", "keep.png"]);
    w.expect("render #1 full finished: 8 iterations", STEP_TIMEOUT);
    let converged = fs::read(&out).unwrap();
    fs::write(&path, &text).unwrap();
    w.expect("unchanged", STEP_TIMEOUT);
    fs::write(&path, "background rgb <0, 1, \n").unwrap();
    w.expect("the scene has errors; the last image is kept", STEP_TIMEOUT);
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(
        fs::read(&out).unwrap(),
        converged,
        "the finished image was replaced"
    );
    // Back to the scene as it was: its finished image is still the one on disk.
    fs::write(&path, &text).unwrap();
    let line = w.expect("unchanged", STEP_TIMEOUT);
    assert!(line.contains("render #1 stays"), "{line}");
    assert_eq!(fs::read(&out).unwrap(), converged);
    // The image deleted by hand: the same save renders it again.
    fs::remove_file(&out).unwrap();
    fs::write(&path, &text).unwrap();
    w.expect("render #2 full finished", STEP_TIMEOUT);
    assert_eq!(fs::read(&out).unwrap(), converged, "the same render, again");
}

/// A texture rewritten with the same pixels (a new file renamed over it, as an image editor
/// saves) leaves the scene as it was; one different pixel does not.
#[test]
fn a_texture_saved_with_the_same_pixels_does_not_restart_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tex.scn");
    let tex = dir.path().join("tex.png");
    let out = dir.path().join("tex-out.png");
    let save_texture = |corner: image::Rgb<u8>| {
        let mut img = image::RgbImage::from_pixel(4, 4, image::Rgb([255, 0, 0]));
        img.put_pixel(0, 0, corner);
        let tmp = dir.path().join("tex.tmp.png");
        img.save(&tmp).unwrap();
        fs::rename(&tmp, &tex).unwrap();
    };
    save_texture(image::Rgb([255, 0, 0]));
    fs::write(
        &path,
        scene(
            RED,
            3,
            "quad { <-5, -5, 0>, <0, 10, 0>, <10, 0, 0>\n\
               material { diffuse texture { image \"tex.png\" } } }",
        ),
    )
    .unwrap();
    let mut w = watch(
        dir.path(),
        &["tex.scn", "-o", "tex-out.png", "--no-preview"],
    );
    w.expect("render #1 full finished", STEP_TIMEOUT);
    let image = fs::read(&out).unwrap();
    save_texture(image::Rgb([255, 0, 0]));
    w.expect("changed: ", STEP_TIMEOUT);
    let line = w.expect("unchanged", STEP_TIMEOUT);
    assert!(line.contains("render #1 stays"), "{line}");
    assert_eq!(fs::read(&out).unwrap(), image);
    save_texture(image::Rgb([0, 0, 255]));
    w.expect("render #2 started", STEP_TIMEOUT);
}

/// A render cancelled by a broken save, then the same scene saved again: the new render of it
/// writes nothing (neither its preview nor its first iterations) until it has as many
/// iterations as the image on disk.
#[test]
fn a_restarted_render_of_the_same_scene_writes_only_once_it_caught_up() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("again.scn");
    let out = dir.path().join("again.png");
    let text = scene(RED, 1_000_000, "");
    fs::write(&path, &text).unwrap();
    let mut w = watch(dir.path(), &["again.scn", "-o", "again.png"]);
    // About a millisecond an iteration: render #2 takes about a second to catch up, far longer
    // than the test needs to look at the image once render #2 has said it keeps it.
    w.expect("render #1 full iteration 1000/", STEP_TIMEOUT);
    fs::write(&path, "sphere {").unwrap();
    w.expect("render #1 cancelled", STEP_TIMEOUT);
    w.expect("the scene has errors; the last image is kept", STEP_TIMEOUT);
    let on_disk = w
        .log
        .iter()
        .filter(|l| l.contains("render #1 full iteration") && l.contains("written to"))
        .map(|l| iteration_of(l))
        .max()
        .expect("render #1 wrote full iterations");
    let image = fs::read(&out).unwrap();

    fs::write(&path, &text).unwrap();
    w.expect("render #2 started", STEP_TIMEOUT);
    w.expect(
        "render #2: the image on disk is a more converged render",
        STEP_TIMEOUT,
    );
    assert_eq!(
        fs::read(&out).unwrap(),
        image,
        "the image of {on_disk} iterations was replaced before render #2 caught up"
    );
    w.expect("render #2 full iteration", STEP_TIMEOUT);
    // Every image render #2 wrote (each says so), up to its first one.
    let writes: Vec<&String> = w
        .log
        .iter()
        .filter(|l| l.contains("render #2") && l.contains("written to"))
        .collect();
    assert!(
        writes
            .iter()
            .all(|l| l.contains("full iteration") && iteration_of(l) >= on_disk),
        "render #2 wrote before it had {on_disk} iterations: {writes:?}"
    );
}
