//! The command line as a user runs it: exit codes, charts, watch, saves, interrupts, the live view
//! and the language server.
//!
//! One test binary for the group (each binary links the whole library): run one file's tests
//! with `cargo test --test cli <file>::`.

#[path = "../common/running.rs"]
mod running;
#[path = "../common/slurm.rs"]
mod slurm;

mod chart_cli;
mod cli_exit;
mod editor_grammar;
mod interrupt;
mod live_browser;
mod live_security;
mod lsp;
mod watch_cli;
mod watch_saves;
