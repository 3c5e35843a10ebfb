//! Measurements the project makes of itself, behind `sppm-lang bench`.
//!
//! - [`bezier`]: speed against accuracy of the Bezier intersectors (robust, Newton) and of
//!   tessellated meshes of the same surfaces.

pub mod bezier;
