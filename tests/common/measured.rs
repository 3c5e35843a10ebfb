//! The real binary run once under an address-space limit (`prlimit --as`), its wall and CPU
//! time and peak resident memory measured (`/usr/bin/time -v`), killed after a timeout.
//! (Included with `#[path]` by the tests that use it.)

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

pub struct Measured {
    /// Exit code; `None` when killed (by a signal or the timeout).
    pub code: Option<i32>,
    /// The program's stderr (without `time`'s report).
    pub stderr: String,
    /// Wall seconds.
    pub seconds: f64,
    /// User + system CPU seconds when `/usr/bin/time` could tell, else the wall seconds: the
    /// figure a bound on the program's own work compares, which the machine's other load
    /// stretches far less than the wall time.
    pub cpu_seconds: f64,
    /// Peak resident memory (bytes), when `/usr/bin/time` could tell.
    pub peak: Option<u64>,
}

/// Runs `sppm-lang args` under an address-space limit of `address_space` bytes.
pub fn run_measured(args: &[&str], address_space: u64, timeout: Duration) -> Measured {
    let bin = env!("CARGO_BIN_EXE_sppm-lang");
    let report = tempfile::NamedTempFile::new().unwrap();
    let timed = Path::new("/usr/bin/time").exists();
    let limited = Path::new("/usr/bin/prlimit").exists();
    let mut cmd = if timed {
        let mut c = Command::new("/usr/bin/time");
        c.arg("-v").arg("-o").arg(report.path());
        c
    } else {
        Command::new("env")
    };
    if limited {
        cmd.arg("/usr/bin/prlimit")
            .arg(format!("--as={address_space}"));
    }
    cmd.arg(bin).args(args);
    let stderr_file = tempfile::NamedTempFile::new().unwrap();
    let start = Instant::now();
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(stderr_file.reopen().unwrap())
        .spawn()
        .expect("spawn sppm-lang");
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
    let seconds = start.elapsed().as_secs_f64();
    let text = std::fs::read_to_string(report.path()).unwrap_or_default();
    let peak = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("Maximum resident set size (kbytes):"))
        .and_then(|v| v.trim().parse::<u64>().ok())
        .map(|kb| kb * 1024);
    let field = |name: &str| {
        text.lines()
            .find_map(|l| l.trim().strip_prefix(name))
            .and_then(|v| v.trim().parse::<f64>().ok())
    };
    let cpu_seconds = match (
        field("User time (seconds):"),
        field("System time (seconds):"),
    ) {
        (Some(u), Some(s)) => u + s,
        _ => seconds,
    };
    let bytes = std::fs::read(stderr_file.path()).unwrap_or_default();
    // `time` reports a child killed by a signal with a line of its own; the exit code it
    // passes on then is not the program's.
    let killed = text.contains("Command terminated by signal");
    Measured {
        code: if killed || timed_out {
            None
        } else {
            status.code()
        },
        stderr: String::from_utf8_lossy(&bytes).into_owned(),
        seconds,
        cpu_seconds,
        peak,
    }
}

/// The program's stderr as one line: words joined by single spaces, without the frame the
/// diagnostics wrap long lines in (`│`), so that a phrase matches wherever a line broke.
pub fn flat(stderr: &str) -> String {
    stderr
        .split_whitespace()
        .filter(|w| *w != "│")
        .collect::<Vec<_>>()
        .join(" ")
}

/// "1.23 GB" (decimal), or "?" when unknown.
pub fn peak_text(peak: Option<u64>) -> String {
    peak.map_or("?".into(), |b| format!("{:.3} GB", b as f64 / 1e9))
}
