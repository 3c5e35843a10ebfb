//! Writing to stdout and stderr without panicking when the reader has gone away.
//!
//! `print!` panics with "failed printing to stdout: Broken pipe" when the output is piped into a
//! program that exits early (`sppm-lang check big.scn | head -1`). A command-line tool should
//! then stop writing quietly, as `cat` does; the exit status still reports the command's result.

use std::io::Write;

/// Writes `text` to stdout; a closed pipe or any other write error is ignored.
pub fn out(text: &str) {
    let mut s = std::io::stdout().lock();
    let _ = s.write_all(text.as_bytes()).and_then(|()| s.flush());
}

/// Writes `text` to stderr; a closed pipe or any other write error is ignored.
pub fn err(text: &str) {
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}
