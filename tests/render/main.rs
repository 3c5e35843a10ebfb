//! Rendering: every integrator, shapes and CSG, lights, environments, determinism, and the golden images.
//!
//! One test binary for the group (each binary links the whole library): run one file's tests
//! with `cargo test --test render <file>::`.

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/measured.rs"]
mod measured;

mod backdrop_sky;
mod bezier_cases;
mod chains;
mod csg_cost;
mod csg_glass;
mod csg_oracle;
mod csg_shapes;
mod determinism;
mod environment;
mod final_gather;
mod golden;
mod instancing;
mod integrators;
mod light_sampling;
mod scale_invariance;
