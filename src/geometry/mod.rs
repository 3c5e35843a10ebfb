//! Core geometric types of the renderer (f32, `Vec3A` in the hot path).

mod bounds;
mod frame;
mod ray;

pub use bounds::Aabb;
pub use frame::Frame;
pub use ray::{Hit, Ray};
