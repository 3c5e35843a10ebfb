//! The library's render options are range-checked by the render itself, not only by the command
//! line: a caller passing absurd overrides gets an error, never a panic, a hang or a huge
//! allocation.

mod common;

use std::sync::atomic::AtomicBool;

use common::furnace_emitting;
use sppm_lang::render::{RenderOptions, render};

#[test]
fn absurd_overrides_are_errors() {
    let scene = furnace_emitting(4);
    let cases = [
        (
            "iterations",
            RenderOptions {
                iterations: Some(0),
                ..Default::default()
            },
        ),
        (
            "iterations",
            RenderOptions {
                iterations: Some(u32::MAX),
                ..Default::default()
            },
        ),
        (
            "photons",
            RenderOptions {
                photons: Some(u64::MAX),
                ..Default::default()
            },
        ),
        (
            "threads",
            RenderOptions {
                threads: Some(0),
                ..Default::default()
            },
        ),
        (
            "threads",
            RenderOptions {
                threads: Some(usize::MAX),
                ..Default::default()
            },
        ),
        (
            "time limit",
            RenderOptions {
                time_limit: Some(f64::NAN),
                ..Default::default()
            },
        ),
        (
            "time limit",
            RenderOptions {
                time_limit: Some(-1.0),
                ..Default::default()
            },
        ),
    ];
    for (what, opts) in cases {
        let err = render(&scene, &opts, &AtomicBool::new(false), &mut |_| {})
            .err()
            .unwrap_or_else(|| panic!("{opts:?} was accepted"));
        assert!(err.to_string().contains(what), "{opts:?}: {err}");
    }
    // In range, the same overrides render.
    let ok = RenderOptions {
        iterations: Some(1),
        photons: Some(1000),
        threads: Some(1),
        ..Default::default()
    };
    let out = render(&scene, &ok, &AtomicBool::new(false), &mut |_| {}).unwrap();
    assert_eq!(out.iterations_done, 1);
}
