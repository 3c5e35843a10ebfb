//! Accuracy against independent references: closed forms, SmallPPM, Mitsuba 3 images and the shared reference.
//!
//! One test binary for the group (each binary links the whole library): run one file's tests
//! with `cargo test --test accuracy <file>::`.

#[path = "../common/mod.rs"]
mod common;

mod caustic_reference;
mod glossy_reference;
mod reference_image;
mod render_accuracy;
mod smallppm_reference;
mod sppm_theory;
