//! Random numbers and sample warps. Every stream is seeded from (seed, iteration, index), never
//! from a thread or from entropy, so renders are identical for any thread count.

mod distribution;
mod rng;
mod splitmix;
mod warp;

pub use distribution::{PiecewiseConstant1D, PiecewiseConstant2D};
pub use rng::{Rng, chain_seed, index_seed, iteration_seed, stream_seed};
pub use splitmix::{SplitMix64, mix64, splitmix64};
pub use warp::{
    concentric_disk, cosine_hemisphere, power_heuristic, uniform_cone, uniform_cone_pdf,
    uniform_sphere, uniform_triangle,
};
