//! A lathe's hit: where it is ([`NearestHit`], what the search finds) and its surface data
//! ([`LatheHit`], computed once, for the hit kept).

use std::f64::consts::TAU;

use glam::{DVec2, DVec3};

use super::{Lathe, Part};

/// A hit in the lathe's own space, `t` in units of the ray direction given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatheHit {
    pub t: f64,
    pub p: DVec3,
    /// Unit outward geometric normal (outward is to the right of the profile's direction).
    pub n: DVec3,
    /// NaN where it was not asked for ([`Lathe::complete`]).
    pub uv: DVec2,
    pub dpdu: DVec3,
    pub part: Part,
    /// Profile parameter within the segment (0 on caps).
    pub s: f64,
}

/// Where the nearest hit of a ray is ([`Lathe::nearest`]): enough to compute its surface data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NearestHit {
    /// In units of the ray direction given.
    pub t: f64,
    /// Along the unit direction (the search's parameter).
    pub t_unit: f64,
    pub part: Part,
    /// Profile parameter within the segment (0 on caps).
    pub s: f64,
}

impl Lathe {
    /// The surface data of `h`, found by [`Lathe::nearest`] for the ray `o + t d`; the same as
    /// [`Lathe::intersect_parts`] gives, except that `uv: false` leaves `uv` NaN.
    pub fn complete(&self, o: DVec3, d: DVec3, h: &NearestHit, uv: bool) -> LatheHit {
        // The point as the search's frame computes it (`d / |d|` is its direction).
        let dn = d / d.length();
        self.hit_record(o + h.t_unit * dn, h.t, h.part, h.s, uv)
    }

    /// The surface data at `p` (the hit's point), `t` along the ray as given; `uv: false`
    /// leaves `uv` NaN (the arc length and the angle are not computed).
    pub fn hit_record(&self, p: DVec3, t: f64, part: Part, s: f64, uv: bool) -> LatheHit {
        let (a0, span) = self.sweep.unwrap_or((0.0, TAU));
        match part {
            Part::Side(i) => {
                let seg = &self.segs[i];
                let rxz = (p.x * p.x + p.z * p.z).sqrt();
                let phi = || p.z.atan2(p.x);
                let (c, sn) = if rxz > 0.0 {
                    (p.x / rxz, p.z / rxz)
                } else {
                    (phi().cos(), phi().sin())
                };
                let tan = seg.tangent(s, self.size);
                let n = DVec3::new(tan.y * c, -tan.x, tan.y * sn).normalize();
                let dpdu = DVec3::new(tan.x * c, tan.y, tan.x * sn) * self.total_len.max(1e-300);
                let uv = if uv {
                    let u = (self.len_before[i] + seg.arc(s)) / self.total_len.max(1e-300);
                    let v = (phi() - a0).rem_euclid(TAU) / span;
                    DVec2::new(u.clamp(0.0, 1.0), v.clamp(0.0, 1.0))
                } else {
                    DVec2::NAN
                };
                LatheHit {
                    t,
                    p,
                    n,
                    uv,
                    dpdu,
                    part,
                    s,
                }
            }
            Part::StartCap | Part::EndCap => {
                let angle = if part == Part::StartCap {
                    a0
                } else {
                    a0 + span
                };
                let e = DVec3::new(angle.cos(), 0.0, angle.sin());
                let m = DVec3::new(-angle.sin(), 0.0, angle.cos());
                let n = if part == Part::StartCap { -m } else { m };
                let h = (self.hmax - self.hmin).max(1e-300);
                LatheHit {
                    t,
                    p,
                    n,
                    uv: DVec2::new(
                        (p.dot(e) / self.rmax.max(1e-300)).clamp(0.0, 1.0),
                        ((p.y - self.hmin) / h).clamp(0.0, 1.0),
                    ),
                    dpdu: e * self.rmax,
                    part,
                    s: 0.0,
                }
            }
        }
    }
}
