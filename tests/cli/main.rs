//! The command line as a user runs it: exit codes, charts, watch, saves, interrupts, the live view
//! and the language server.
//!
//! One test binary for the group (each binary links the whole library): run one file's tests
//! with `cargo test --test cli <file>::`.

#[path = "../common/running.rs"]
mod running;
#[path = "../common/slurm.rs"]
mod slurm;

// The commands behind a Cargo feature (all on by default) are tested when it is on.
#[cfg(feature = "chart")]
mod chart_cli;
mod cli_exit;
mod editor_grammar;
mod interrupt;
#[cfg(feature = "watch")]
mod live_browser;
#[cfg(feature = "watch")]
mod live_security;
#[cfg(feature = "lsp")]
mod lsp;
#[cfg(feature = "watch")]
mod watch_cli;
#[cfg(feature = "watch")]
mod watch_saves;
