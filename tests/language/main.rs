//! The scene language: parsing, evaluation, diagnostics, budgets, hostile input, and the library API over them.
//!
//! One test binary for the group (each binary links the whole library): run one file's tests
//! with `cargo test --test language <file>::`.

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/measured.rs"]
mod measured;

mod bad_scenes;
mod eval_budgets;
mod examples_check;
mod fuzz;
mod good_csg;
mod good_povray_forms;
mod good_scenes;
mod hostile;
mod layering;
mod library_options;
mod load_memory;
mod parse_differential;
mod random_streams;
mod value_macros;
