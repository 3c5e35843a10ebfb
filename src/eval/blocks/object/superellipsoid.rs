//! `superellipsoid { <e, n> }` as POV-Ray writes it: the two exponents, checked here against
//! the range the shape accepts.

use super::ObjectBuilder;
use crate::diag::{At, Error, SourceResult, short_number};
use crate::scene::{SUPERELLIPSOID_EXPONENTS, ShapeDecl};

impl ObjectBuilder {
    pub(super) fn superellipsoid(&self) -> SourceResult<ShapeDecl> {
        let (lo, hi) = SUPERELLIPSOID_EXPONENTS;
        let [(v, span)] = self.values.as_slice() else {
            return Err(vec![
                Error::new(format!(
                    "a superellipsoid takes one value, its exponents `<e, n>`, found {}",
                    self.values.len()
                ))
                .label("here")
                .help("e.g. `superellipsoid { <0.25, 0.5> }` (as in POV-Ray)")
                .at(self.span),
            ]);
        };
        let en = v
            .vec2()
            .map_err(|e| e.help("the exponents are a 2-D vector `<e, n>`"))
            .at(*span)?;
        for (x, what) in [
            (en.x, "east-west exponent e"),
            (en.y, "north-south exponent n"),
        ] {
            if !(x >= lo && x <= hi) {
                return Err(vec![
                    Error::new(format!(
                        "the superellipsoid's {what} is {}, outside [{}, {}]",
                        short_number(x),
                        short_number(lo),
                        short_number(hi)
                    ))
                    .label("out of range")
                    .help(
                        "near 0 the shape is a box with rounded edges (below 0.001 use a `box`), \
                         1 a sphere, 2 an octahedron, beyond 2 a pinched star (beyond 10 only \
                         needles along the axes are left)",
                    )
                    .at(*span),
                ]);
            }
        }
        Ok(ShapeDecl::Superellipsoid { e: en.x, n: en.y })
    }
}
