//! Rendering: every integrator, shapes and CSG, lights, environments, determinism, and the golden images.
//!
//! One test binary for the group (each binary links the whole library): run one file's tests
//! with `cargo test --test render <file>::`.

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/measured.rs"]
mod measured;

mod integrators;
mod determinism;
mod instancing;
mod csg_cost;
mod csg_glass;
mod csg_oracle;
mod csg_shapes;
mod bezier_cases;
mod environment;
mod backdrop_sky;
mod light_sampling;
mod final_gather;
mod golden;
mod scale_invariance;
