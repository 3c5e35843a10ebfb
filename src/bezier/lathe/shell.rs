//! Per-segment culling: each profile segment is cut into [`PIECES`] parameter pieces, each
//! bounded by an annular shell (radii `rmin..rmax`, heights `hmin..hmax` from the piece's
//! control polygon, so the shell contains the swept piece). A ray can meet the piece's surface
//! only at a `t` where it is inside the shell; [`RayFrame::shell_entry`] decides that in closed
//! form (the ray's squared distance from the axis is a quadratic in `t`) and gives the ray's
//! entry into the shell's height slab, a lower bound on the `t` of any hit in the piece.

use super::frame::RayFrame;
use crate::bezier::bernstein::Bernstein;

/// Pieces per segment (uniform in the segment's parameter).
pub const PIECES: usize = 8;

/// The annular shell of one piece of a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shell {
    pub rmin: f64,
    pub rmax: f64,
    pub hmin: f64,
    pub hmax: f64,
}

impl Shell {
    /// The shells of the [`PIECES`] pieces of the segment `(r, h)`.
    pub fn of_segment(r: &Bernstein, h: &Bernstein) -> [Shell; PIECES] {
        std::array::from_fn(|k| {
            let (a, b) = (k as f64 / PIECES as f64, (k + 1) as f64 / PIECES as f64);
            let (rp, hp) = (r.restrict(a, b), h.restrict(a, b));
            let range = |p: &Bernstein| {
                p.coeffs()
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &c| {
                        (lo.min(c), hi.max(c))
                    })
            };
            let ((rmin, rmax), (hmin, hmax)) = (range(&rp), range(&hp));
            Shell {
                rmin: rmin.max(0.0),
                rmax,
                hmin,
                hmax,
            }
        })
    }
}

/// Padding of the shells, relative to the surface size: far above the rounding of the
/// quantities compared (f64, values of the size of the scene), far below any visible margin.
pub const SHELL_PAD: f64 = 1e-7;

impl RayFrame {
    /// Where the ray (unit direction) enters the padded shell within `(tmin, tmax)`: `None` when
    /// it is not inside the shell anywhere on that interval, else a lower bound on the `t` of
    /// every point of the interval inside it.
    pub fn shell_entry(&self, s: &Shell, tmin: f64, tmax: f64, size: f64) -> Option<f64> {
        let (o, dn) = (self.o, self.dn);
        let pad = SHELL_PAD * size;
        let (h0, h1) = (s.hmin - pad, s.hmax + pad);
        let (mut ta, mut tb) = (tmin - pad, tmax + pad);
        if dn.y != 0.0 {
            let (u, v) = if self.inv_dy.is_finite() {
                // A product with the reciprocal (no division per shell), its rounding (a few
                // ulps of the quotient) allowed for on the safe side.
                let (u, v) = ((h0 - o.y) * self.inv_dy, (h1 - o.y) * self.inv_dy);
                let (lo, hi) = (u.min(v), u.max(v));
                (
                    lo - 4.0 * f64::EPSILON * lo.abs(),
                    hi + 4.0 * f64::EPSILON * hi.abs(),
                )
            } else {
                ((h0 - o.y) / dn.y, (h1 - o.y) / dn.y)
            };
            ta = ta.max(u.min(v));
            tb = tb.min(u.max(v));
        } else if !(o.y >= h0 && o.y <= h1) {
            return None;
        }
        if ta.is_nan() || tb.is_nan() || ta > tb {
            return None;
        }
        // Squared distance from the axis along the ray: line_rho2 + dh2 (t - tc)^2.
        let q = |t: f64| {
            let dt = t - self.tc;
            self.line_rho2 + self.dh2 * dt * dt
        };
        let (qmin, qmax) = if self.dh2 > 0.0 {
            (q(self.tc.clamp(ta, tb)), q(ta).max(q(tb)))
        } else {
            (self.line_rho2, self.line_rho2)
        };
        let (r0, r1) = ((s.rmin - pad).max(0.0), s.rmax + pad);
        // Rounding of q: relative to q itself and to the size (terms of the size cancel in it).
        let slack = 1e-12 * size * size;
        (qmin * (1.0 - 1e-12) <= r1 * r1 + slack && qmax * (1.0 + 1e-12) + slack >= r0 * r0)
            .then_some(ta)
    }
}
