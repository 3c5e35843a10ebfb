//! The numerical heart of Bezier surfaces, apart from the scene glue in `shapes`.
//!
//! - [`bernstein`]: polynomials in the Bernstein basis (de Casteljau, subdivision, products).
//! - [`roots`]: a root isolator on [0, 1] that cannot miss a root, with a bracketed polish;
//!   [`roots::bracket`] refines a sign change of a general function (the lathe's factors).
//! - [`lathe`]: ray intersection with a surface of revolution of a Bezier profile (f64).
//! - [`patch`]: ray intersection with a bicubic Bezier patch (f64).
//!
//! The slow reference intersectors that test the two above live in `tools/measure`
//! (`sppm_measure::reference`), outside the product library.
//!
//! See `docs/bezier.md` for the mathematics.

pub mod bernstein;
pub mod lathe;
pub mod patch;
pub mod roots;

/// Which method finds the ray's roots on a curved surface (lathe side or patch).
///
/// The scene's `IntersectMethod` says the same thing in the scene description; `shapes` maps it
/// to this type in one place (`bezier` may not import the scene).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Solver {
    /// Root isolation that cannot miss a root.
    Robust,
    /// Newton's method from about `starts` starting guesses (evenly spaced per lathe segment, a
    /// grid on a patch), at most `iterations` steps each. It can miss roots; kept for comparison.
    Newton { iterations: u32, starts: u32 },
}
