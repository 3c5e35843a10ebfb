//! The scene language: parsing, evaluation, diagnostics, budgets, hostile input, and the library API over them.
//!
//! One test binary for the group (each binary links the whole library): run one file's tests
//! with `cargo test --test language <file>::`.

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/measured.rs"]
mod measured;

mod bad_scenes;
mod good_scenes;
mod good_csg;
mod good_povray_forms;
mod value_macros;
mod eval_budgets;
mod parse_differential;
mod fuzz;
mod hostile;
mod random_streams;
mod load_memory;
mod layering;
mod examples_check;
mod library_options;
