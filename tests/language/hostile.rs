//! Hostile input through the real binary: every scene in `tests/hostile/` (one hazard each, its
//! expected exit codes in a `// expect: check=<1|2|ok> render=<1|2|ok>` header) plus a few
//! generated ones (an empty file, binary garbage, a 70 KB line, 300 000 nested `<`, 100 000
//! errors and 100 000 warnings, an area light of 3 million triangles, a PNG that declares
//! 20000x20000 pixels), and hazardous command-line flags. Each child runs under a 2 GB
//! address-space limit (`prlimit`) and is killed after 60 s. A case passes when the process did
//! not panic or die of a signal, exited as expected, located its error (file:line:column) when
//! it exited 1 and suggested a fix (`help:`, unless the text is the scene's own `#error`), printed
//! no control character from the scene raw (a terminal would obey it),
//! left no `.sppm-*` temporary file and, for `ok`, wrote a PNG. All failures are
//! reported together, one line per case.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

const MEMORY_LIMIT: &str = "2147483648";
const TIMEOUT: Duration = Duration::from_secs(60);
const PARALLEL: usize = 2;

/// What one child did.
struct Outcome {
    /// Exit code, or `None` when killed by a signal.
    code: Option<i32>,
    signal: Option<i32>,
    timed_out: bool,
    stderr: String,
}

impl Outcome {
    fn describe(&self) -> String {
        let first = self
            .stderr
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty())
            .unwrap_or("")
            .chars()
            .take(140)
            .collect::<String>();
        let how = if self.timed_out {
            "timeout".to_string()
        } else if let Some(s) = self.signal {
            format!("signal {s}")
        } else {
            format!("exit {}", self.code.unwrap_or(-1))
        };
        format!("{how}: {first}")
    }
    fn panicked(&self) -> bool {
        self.code == Some(101) || self.stderr.contains("panicked")
    }
}

/// Runs the binary with `args` under the memory limit, killing it after `timeout`.
fn run(args: &[&str], timeout: Duration) -> Outcome {
    let bin = env!("CARGO_BIN_EXE_sppm-lang");
    let mut cmd = if Path::new("/usr/bin/prlimit").exists() {
        let mut c = Command::new("/usr/bin/prlimit");
        c.arg(format!("--as={MEMORY_LIMIT}")).arg(bin);
        c
    } else {
        Command::new(bin)
    };
    let stderr_file = tempfile::NamedTempFile::new().unwrap();
    let mut child = cmd
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(stderr_file.reopen().unwrap())
        .spawn()
        .expect("spawn sppm-lang");
    let start = Instant::now();
    let (status, timed_out) = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break (s, false);
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            break (child.wait().unwrap(), true);
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    use std::os::unix::process::ExitStatusExt;
    let bytes = std::fs::read(stderr_file.path()).unwrap_or_default();
    Outcome {
        code: status.code(),
        signal: status.signal(),
        timed_out,
        stderr: String::from_utf8_lossy(&bytes).into_owned(),
    }
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Expect {
    Ok,
    Exit(i32),
}

fn parse_expect(s: &str) -> Expect {
    match s {
        "ok" => Expect::Ok,
        n => Expect::Exit(n.parse().expect("expect: 1, 2 or ok")),
    }
}

/// One corpus case: the scene, and the expected result of `check` and `render`.
struct Case {
    path: PathBuf,
    check: Expect,
    render: Expect,
}

fn read_header(path: &Path) -> Option<(Expect, Expect)> {
    let bytes = std::fs::read(path).ok()?;
    let text = String::from_utf8_lossy(&bytes);
    let first = text.lines().next()?.trim_start_matches('\u{feff}');
    let line = first.strip_prefix("// expect:")?.trim();
    let mut check = None;
    let mut render = None;
    for part in line.split_whitespace() {
        if let Some(v) = part.strip_prefix("check=") {
            check = Some(parse_expect(v));
        } else if let Some(v) = part.strip_prefix("render=") {
            render = Some(parse_expect(v));
        }
    }
    Some((check?, render?))
}

/// Writes a PNG that declares `w` x `h` pixels but holds almost no data.
fn huge_png(path: &Path, w: u32, h: u32) {
    fn crc32(data: &[u8]) -> u32 {
        let mut crc = 0xffff_ffffu32;
        for &b in data {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xedb8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
    fn chunk(out: &mut Vec<u8>, kind: &[u8], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    }
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]); // 8-bit RGBA
    chunk(&mut png, b"IHDR", &ihdr);
    // A zlib stream of one empty stored block: far too little data for the image.
    chunk(
        &mut png,
        b"IDAT",
        &[0x78, 0x01, 0x01, 0x00, 0x00, 0xff, 0xff, 0, 0, 0, 1],
    );
    chunk(&mut png, b"IEND", &[]);
    std::fs::write(path, png).unwrap();
}

/// The cases too big, or too binary, to commit: written into `dir`.
fn generated_cases(dir: &Path) -> Vec<Case> {
    let header = "settings { resolution <16, 16> }\ncamera { location <0, 0, -5> look_at <0, 0, 0> }\nlight { <0, 5, -5> intensity rgb 10 }\n";
    let mut cases = Vec::new();
    let mut add = |name: &str, bytes: Vec<u8>, check, render| {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        cases.push(Case {
            path,
            check,
            render,
        });
    };
    // 0 bytes: legal, renders the default scene.
    add("empty_scene.scn", Vec::new(), Expect::Ok, Expect::Ok);
    // Deterministic garbage, NULs and high bytes included.
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let garbage = (0..4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect();
    add(
        "binary_garbage.scn",
        garbage,
        // Not text: refused as an unreadable input file (usage error), with the byte offset.
        Expect::Exit(2),
        Expect::Exit(2),
    );
    // One line over 70 KB, its error at the very end.
    let mut line = String::from(header).replace('\n', " ");
    while line.len() < 72 * 1024 {
        line.push_str("sphere { <0, 0, 0>, 0.5 } ");
    }
    line.push_str("sphere { <0, 0, 0>, -1 }");
    add(
        "long_line_error_at_end.scn",
        line.into_bytes(),
        Expect::Exit(1),
        Expect::Exit(1),
    );
    // 300 000 nested `<`.
    let mut nested = format!("{header}sphere {{ ");
    nested.push_str(&"<".repeat(300_000));
    add(
        "nested_lt_300000.scn",
        nested.into_bytes(),
        Expect::Exit(1),
        Expect::Exit(1),
    );
    // 100 000 errors, one per line: each diagnostic once showed a copy of the whole file,
    // which miette then scanned from its start (quadratic: 8 000 of them took 7 s, these an
    // hour).
    add(
        "errors_100000.scn",
        "sphere { <0, 0, 0>, -1 }\n".repeat(100_000).into_bytes(),
        Expect::Exit(1),
        Expect::Exit(1),
    );
    // A macro with 100 000 parameters, the last named like the sixth: the check for a name
    // given twice goes by name (comparing every pair would take minutes).
    let params: Vec<String> = (0..100_000).map(|i| format!("a{i}")).collect();
    add(
        "macro_params_100000_twice.scn",
        format!("{header}#macro M({}, a5)\n  1\n#end\n", params.join(", ")).into_bytes(),
        Expect::Exit(1),
        Expect::Exit(1),
    );
    // 100 000 unused declarations: as many warnings, on a scene that renders.
    let mut unused = String::from(header);
    for i in 0..100_000 {
        unused.push_str(&format!("#declare Unused{i} = {i};\n"));
    }
    add(
        "warnings_100000.scn",
        unused.into_bytes(),
        Expect::Ok,
        Expect::Ok,
    );
    // An area light made of a mesh of 3 million triangles: one light each. The memory estimate
    // once left the light records out (2.4 GB in all), and preparing aborted on a failed
    // allocation under the 2 GB limit instead of refusing the render.
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    obj.push_str(&"f 1 2 3\n".repeat(3_000_000));
    std::fs::write(dir.join("light_3m.obj"), obj).unwrap();
    add(
        "area_light_mesh_3m_triangles.scn",
        format!("{header}area_light {{ mesh {{ \"light_3m.obj\" }} radiance rgb 1 }}\n")
            .into_bytes(),
        Expect::Exit(1),
        Expect::Exit(1),
    );
    // A texture that declares 20000x20000 pixels (1.6 GB as RGBA8, more as floats).
    huge_png(&dir.join("huge_20000.png"), 20_000, 20_000);
    add(
        "image_png_20000x20000.scn",
        format!(
            "{header}sphere {{ <0, 0, 0>, 1 material {{ diffuse texture {{ image \"huge_20000.png\" }} }} }}\n"
        )
        .into_bytes(),
        Expect::Exit(1),
        Expect::Exit(1),
    );
    cases
}

fn corpus_cases() -> Vec<Case> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir("tests/hostile")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "scn"))
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|path| {
            let (check, render) = read_header(&path)
                .unwrap_or_else(|| panic!("{}: no `// expect:` header", path.display()));
            Case {
                path,
                check,
                render,
            }
        })
        .collect()
}

fn leftover_temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(".sppm-"))
                .collect()
        })
        .unwrap_or_default()
}

/// Judges one command on one case; `None` when it behaved.
fn judge(
    name: &str,
    command: &str,
    expect: Expect,
    outcome: &Outcome,
    out_dir: &Path,
    png: &Path,
) -> Option<String> {
    let want = match expect {
        Expect::Ok => "ok".to_string(),
        Expect::Exit(n) => format!("exit {n}"),
    };
    let fail = |why: &str| {
        Some(format!(
            "{name} [{command}] expected {want}, got {} ({why})",
            outcome.describe()
        ))
    };
    if outcome.timed_out {
        return fail("no answer within 60 s");
    }
    if outcome.signal.is_some() {
        return fail("killed by a signal");
    }
    if outcome.panicked() {
        return fail("panicked");
    }
    if outcome.stderr.contains("memory allocation of") {
        return fail("allocation failure");
    }
    // A control character from the scene would reach the terminal (escape injection).
    if let Some(c) = outcome
        .stderr
        .chars()
        .find(|c| c.is_control() && !matches!(c, '\n' | '\t'))
    {
        return fail(&format!("a raw control character {c:?} in the diagnostics"));
    }
    let leftovers = leftover_temporaries(out_dir);
    if !leftovers.is_empty() {
        return fail(&format!("left temporary files {leftovers:?}"));
    }
    match expect {
        Expect::Ok => {
            if outcome.code != Some(0) {
                return fail("wrong exit code");
            }
            if command == "render" && !png.is_file() {
                return fail("no PNG written");
            }
        }
        Expect::Exit(n) => {
            if outcome.code != Some(n) {
                return fail("wrong exit code");
            }
            if n == 1 && !has_span(&outcome.stderr, name) {
                return fail("no file:line:column in the message");
            }
            // Every error suggests a fix, except the scene's own `#error` text.
            if n == 1 && !outcome.stderr.contains("help:") && !name.contains("error_message") {
                return fail("no suggested fix (`help:`) in the message");
            }
        }
    }
    None
}

/// Whether `stderr` names `file` followed by `:line:column` (or, for a line too long to show,
/// `file (line N cut around column C)`).
fn has_span(stderr: &str, file: &str) -> bool {
    stderr.match_indices(file).any(|(i, _)| {
        let rest = &stderr[i + file.len()..];
        if rest.starts_with(" (line ") && rest.contains(" cut around column ") {
            return true;
        }
        let mut parts = rest.splitn(3, ':');
        parts.next() == Some("")
            && parts.next().is_some_and(|l| l.parse::<u32>().is_ok())
            && parts
                .next()
                .is_some_and(|c| c.chars().next().is_some_and(|ch| ch.is_ascii_digit()))
    })
}

fn run_case(case: &Case, work: &Path) -> Vec<String> {
    let name = case
        .path
        .file_name()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let scene = case.path.to_str().unwrap();
    let mut failures = Vec::new();
    let out_dir = work.join(name.replace('.', "_"));
    std::fs::create_dir_all(&out_dir).unwrap();
    let png = out_dir.join("out.png");
    let check = run(&["check", scene], TIMEOUT);
    failures.extend(judge(&name, "check", case.check, &check, &out_dir, &png));
    // Render when the scene is legal, or when rendering is itself the hazard.
    if case.check == Expect::Ok || case.render != case.check {
        let render = run(
            &[
                "render",
                scene,
                "--iterations",
                "1",
                "--photons",
                "1000",
                "-o",
                png.to_str().unwrap(),
            ],
            TIMEOUT,
        );
        failures.extend(judge(&name, "render", case.render, &render, &out_dir, &png));
    }
    failures
}

#[test]
fn hostile_scenes_are_rejected_or_rendered_without_crashing() {
    let work = tempfile::tempdir().unwrap();
    let generated = work.path().join("generated");
    std::fs::create_dir(&generated).unwrap();
    let mut cases = corpus_cases();
    assert!(cases.len() >= 70, "only {} corpus files", cases.len());
    cases.extend(generated_cases(&generated));
    let total = cases.len();
    let queue = Mutex::new(cases.into_iter());
    let failures = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..PARALLEL {
            s.spawn(|| {
                loop {
                    let Some(case) = queue.lock().unwrap().next() else {
                        break;
                    };
                    let f = run_case(&case, work.path());
                    failures.lock().unwrap().extend(f);
                }
            });
        }
    });
    let mut failures = failures.into_inner().unwrap();
    failures.sort();
    assert!(
        failures.is_empty(),
        "{} of {total} hostile cases misbehaved:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// A small legal scene for the flag hazards.
fn small_scene(dir: &Path) -> PathBuf {
    let path = dir.join("small.scn");
    std::fs::write(
        &path,
        "settings { resolution <16, 16> iterations 1 photons 1000 }\nsphere { <0, 0, 0>, 1 }\nlight { <0, 5, -5> intensity rgb 10 }\n",
    )
    .unwrap();
    path
}

#[test]
fn hostile_flags_are_refused_or_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let scene = small_scene(dir.path());
    let scene = scene.to_str().unwrap();
    let png = dir.path().join("flags.png");
    let png_s = png.to_str().unwrap();
    let mut failures = Vec::new();
    // (label, arguments, accepted exit codes)
    let cases: Vec<(&str, Vec<&str>, &[i32])> = vec![
        (
            "--photons 1e12 --time-limit 1",
            vec![
                "render",
                scene,
                "-o",
                png_s,
                "--photons",
                "1000000000000",
                "--time-limit",
                "1",
            ],
            &[0, 1, 2],
        ),
        (
            "--threads 100000",
            vec!["render", scene, "-o", png_s, "--threads", "100000"],
            &[0, 1, 2],
        ),
        (
            "--iterations 0",
            vec!["render", scene, "-o", png_s, "--iterations", "0"],
            &[2],
        ),
        (
            "--photons 0",
            vec!["render", scene, "-o", png_s, "--photons", "0"],
            &[2],
        ),
        (
            "--time-limit 0",
            vec!["render", scene, "-o", png_s, "--time-limit", "0"],
            &[0, 2],
        ),
        (
            "--time-limit -1",
            vec!["render", scene, "-o", png_s, "--time-limit=-1"],
            &[2],
        ),
        (
            "--time-limit NaN",
            vec!["render", scene, "-o", png_s, "--time-limit", "NaN"],
            &[2],
        ),
        (
            "--time-limit 1e300",
            vec!["render", scene, "-o", png_s, "--time-limit", "1e300"],
            // Longer than a year is refused as a usage error.
            &[2],
        ),
        (
            "scene is a directory",
            vec!["check", dir.path().to_str().unwrap()],
            &[2],
        ),
        ("scene is /dev/zero", vec!["check", "/dev/zero"], &[1, 2]),
        (
            // A limit raised past what the process can have (its 2 GB address space here): the
            // estimate (about 32 GB) passes, the allocation cannot be made.
            "--memory-limit 100G --resolution 11585x11585",
            vec![
                "render",
                scene,
                "-o",
                png_s,
                "--memory-limit",
                "100G",
                "--resolution",
                "11585x11585",
                "--time-limit",
                "1",
            ],
            &[1],
        ),
        (
            "check --memory-limit 100G --resolution 11585x11585",
            vec![
                "check",
                scene,
                "--memory-limit",
                "100G",
                "--resolution",
                "11585x11585",
            ],
            &[1],
        ),
    ];
    for (label, args, accepted) in &cases {
        let o = run(args, TIMEOUT);
        let bad = o.timed_out
            || o.signal.is_some()
            || o.panicked()
            || !o.code.is_some_and(|c| accepted.contains(&c));
        if bad {
            failures.push(format!(
                "{label}: expected exit {accepted:?}, got {}",
                o.describe()
            ));
        }
        let leftovers = leftover_temporaries(dir.path());
        if !leftovers.is_empty() {
            failures.push(format!("{label}: left temporary files {leftovers:?}"));
        }
    }

    // `watch` never ends by itself: it must just not panic within 5 s.
    if cfg!(feature = "watch") {
        let o = run(
            &["watch", scene, "-o", png_s, "--snapshot-every", "1e300"],
            Duration::from_secs(5),
        );
        if o.panicked() || (!o.timed_out && o.code != Some(2)) {
            failures.push(format!(
                "watch --snapshot-every 1e300: expected to run or exit 2, got {}",
                o.describe()
            ));
        }
    }

    // An output that is a symbolic link must be refused, and its target left alone.
    let target = dir.path().join("precious.txt");
    std::fs::write(&target, "precious").unwrap();
    let link = dir.path().join("link.png");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let o = run(&["render", scene, "-o", link.to_str().unwrap()], TIMEOUT);
    let link_kept = std::fs::symlink_metadata(&link).is_ok_and(|m| m.file_type().is_symlink());
    if o.panicked() || !matches!(o.code, Some(1 | 2)) || !link_kept {
        failures.push(format!(
            "-o symlink to a file: expected refusal (exit 1 or 2, link kept), got {} (link kept: {link_kept})",
            o.describe()
        ));
    }
    if std::fs::read_to_string(&target).ok().as_deref() != Some("precious") {
        failures.push("-o symlink to a file: the link target was changed".to_string());
    }
    let null_link = dir.path().join("null.png");
    std::os::unix::fs::symlink("/dev/null", &null_link).unwrap();
    let o = run(
        &["render", scene, "-o", null_link.to_str().unwrap()],
        TIMEOUT,
    );
    let link_kept = std::fs::symlink_metadata(&null_link).is_ok_and(|m| m.file_type().is_symlink());
    if o.panicked() || !matches!(o.code, Some(1 | 2)) || !link_kept {
        failures.push(format!(
            "-o symlink to /dev/null: expected refusal (exit 1 or 2, link kept), got {} (link kept: {link_kept})",
            o.describe()
        ));
    }
    use std::os::unix::fs::FileTypeExt;
    if !std::fs::metadata("/dev/null").is_ok_and(|m| m.file_type().is_char_device()) {
        failures.push("-o symlink to /dev/null: /dev/null is no longer a device".to_string());
    }
    assert!(
        failures.is_empty(),
        "{} flag hazards misbehaved:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
