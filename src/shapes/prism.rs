//! POV-Ray's `prism` in its own space: a closed profile of cubic Bezier segments in the (x, z)
//! plane (built by [`crate::scene::prism_segments`]) swept along y between two heights,
//! straight or toward the origin (conic), with flat caps; holes by the even-odd rule.
//!
//! The side is exact: a straight sweep's side is met where the ray's projection on the (x, z)
//! plane crosses a segment, `(X(s) - o_x) d_z - (Z(s) - o_z) d_x = 0`; a conic sweep's side is
//! made of lines through the origin along `(X(s), 1, Z(s))`, and the ray meets one where that
//! direction lies in the plane through the origin and the ray, `(o × d) · (X(s), 1, Z(s)) = 0`.
//! Both are cubics in `s` whose Bernstein coefficients are the same affine function of the
//! segment's control points, so their roots are isolated by the Bezier root finder
//! ([`crate::bezier::roots`]), which cannot miss a simple root. A double root (the ray's
//! projection tangent to the profile) touches the surface without entering it and is no hit.
//! The caps are planes whose hits are kept inside the profile (a crossing count along a
//! half-line in a direction no profile written by hand lines up with).
//!
//! Normals point out of the solid: which side of a segment is inside is found once, when the
//! prism is built, from points just beside its middle; so sub-shapes may nest (holes) but
//! their curves should not cross one another.

use glam::{DVec2, DVec3, Vec2, Vec3A};

use super::{AreaSample, Shape};
use crate::bezier::bernstein::Bernstein;
use crate::bezier::roots::{Root, RootKind, find_roots_with_noise};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene;

/// The direction of the half-line the even-odd count follows (about 35° from +x): not along an
/// axis or a diagonal, where profiles written by hand put their corners.
const COUNT_DIR: DVec2 = DVec2::new(0.819_152_044_288_991_8, 0.573_576_436_351_046);

#[derive(Debug, Clone)]
struct Segment {
    c: [DVec2; 4],
    min: DVec2,
    max: DVec2,
    /// +1 when `(-Z'(s), X'(s))` points out of the profile beside this segment, else -1.
    out: f64,
}

/// Where a hit lies on the prism.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PrismPart {
    /// On the side of segment `seg`, at curve parameter `s`.
    Side { seg: u32, s: f64 },
    /// On the cap at the lower (`false`) or upper (`true`) height.
    Cap { top: bool },
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrismHit {
    /// Along the ray, in units of its direction.
    pub t: f64,
    pub part: PrismPart,
}

#[derive(Debug, Clone)]
pub struct Prism {
    segs: Vec<Segment>,
    lo: f64,
    hi: f64,
    conic: bool,
    open: bool,
    /// The profile's bounding rectangle (the caps' uv).
    pmin: DVec2,
    pmax: DVec2,
    bounds: Aabb,
}

fn eval(c: &[DVec2; 4], s: f64) -> DVec2 {
    let u = 1.0 - s;
    c[0] * (u * u * u) + c[1] * (3.0 * u * u * s) + c[2] * (3.0 * u * s * s) + c[3] * (s * s * s)
}

fn tangent(c: &[DVec2; 4], s: f64) -> DVec2 {
    let u = 1.0 - s;
    let t = (c[1] - c[0]) * (3.0 * u * u)
        + (c[2] - c[1]) * (6.0 * u * s)
        + (c[3] - c[2]) * (3.0 * s * s);
    if t.length_squared() > 0.0 {
        return t;
    }
    // A cusp where control points coincide: the chord of a small step shows the way.
    let (a, b) = ((s - 1e-6).max(0.0), (s + 1e-6).min(1.0));
    eval(c, b) - eval(c, a)
}

/// The extremes of one coordinate of a cubic Bezier segment on [0, 1]: its ends and the zeros
/// of its derivative.
fn extent(p: [f64; 4]) -> (f64, f64) {
    let a = -p[0] + 3.0 * p[1] - 3.0 * p[2] + p[3];
    let b = 2.0 * (p[0] - 2.0 * p[1] + p[2]);
    let c = p[1] - p[0];
    // x'(s) / 3 = a s^2 + b s + c.
    let mut ts = vec![];
    if a.abs() > 1e-14 * (b.abs() + c.abs()) {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            ts.push(q / a);
            if q != 0.0 {
                ts.push(c / q);
            }
        }
    } else if b != 0.0 {
        ts.push(-c / b);
    }
    let at = |s: f64| {
        let u = 1.0 - s;
        u * u * u * p[0] + 3.0 * u * u * s * p[1] + 3.0 * u * s * s * p[2] + s * s * s * p[3]
    };
    let (mut lo, mut hi) = (p[0].min(p[3]), p[0].max(p[3]));
    for s in ts.into_iter().filter(|s| *s > 0.0 && *s < 1.0) {
        let v = at(s);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    (lo, hi)
}

/// The roots in [0, 1] of the cubic whose Bernstein coefficients are `f`, values within `noise`
/// counting as zero.
fn roots(f: [f64; 4], noise: f64, out: &mut Vec<Root>) {
    out.clear();
    // A segment whose line runs along the ray (every coefficient zero) is met edge-on.
    if f.iter().all(|v| v.abs() <= noise) {
        return;
    }
    if let Some(p) = Bernstein::new(&f) {
        find_roots_with_noise(&p, noise, out);
    }
}

impl Prism {
    pub fn new(p: &scene::Prism) -> Result<Self, String> {
        let (lo, hi) = (p.heights.0.min(p.heights.1), p.heights.0.max(p.heights.1));
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(format!(
                "a prism needs two different finite heights, got {} and {}",
                p.heights.0, p.heights.1
            ));
        }
        if p.segments.is_empty() || p.segments.iter().flatten().any(|q| !q.is_finite()) {
            return Err("a prism needs a profile of finite points".into());
        }
        let mut segs: Vec<Segment> = p
            .segments
            .iter()
            .map(|c| {
                let (x0, x1) = extent(c.map(|q| q.x));
                let (z0, z1) = extent(c.map(|q| q.y));
                Segment {
                    c: *c,
                    min: DVec2::new(x0, z0),
                    max: DVec2::new(x1, z1),
                    out: 1.0,
                }
            })
            .collect();
        let pmin = segs.iter().fold(DVec2::INFINITY, |m, s| m.min(s.min));
        let pmax = segs.iter().fold(DVec2::NEG_INFINITY, |m, s| m.max(s.max));
        let mut prism = Self {
            segs: Vec::new(),
            lo,
            hi,
            conic: p.conic,
            open: p.open,
            pmin,
            pmax,
            bounds: Aabb::new(Vec3A::ZERO, Vec3A::ZERO),
        };
        // Which side of each segment is inside: the even-odd count just beside three of its
        // points, by majority (a point may fall on another curve by chance).
        let size = (pmax - pmin).max_element();
        let step = 1e-7 * size;
        let outs: Vec<f64> = {
            prism.segs = segs.clone();
            segs.iter()
                .map(|seg| {
                    let votes: i32 = [0.31, 0.5, 0.73]
                        .iter()
                        .map(|&s| {
                            let t = tangent(&seg.c, s);
                            let m = DVec2::new(-t.y, t.x).normalize_or_zero();
                            let q = eval(&seg.c, s);
                            let ahead = prism.inside_profile(q + m * step);
                            let behind = prism.inside_profile(q - m * step);
                            match (ahead, behind) {
                                (false, true) => 1,
                                (true, false) => -1,
                                _ => 0,
                            }
                        })
                        .sum();
                    if votes >= 0 { 1.0 } else { -1.0 }
                })
                .collect()
        };
        for (seg, out) in segs.iter_mut().zip(outs) {
            seg.out = out;
        }
        prism.segs = segs;
        let (xs, zs) = if p.conic {
            let hull = |a: f64, b: f64| {
                let v = [a * lo, a * hi, b * lo, b * hi];
                (
                    v.iter().copied().fold(f64::INFINITY, f64::min),
                    v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                )
            };
            (hull(pmin.x, pmax.x), hull(pmin.y, pmax.y))
        } else {
            ((pmin.x, pmax.x), (pmin.y, pmax.y))
        };
        let b = Aabb::new(
            DVec3::new(xs.0, lo, zs.0).as_vec3a(),
            DVec3::new(xs.1, hi, zs.1).as_vec3a(),
        );
        // Rounded to f32 outward by a relative step.
        let pad = 1e-6 * b.diagonal().max_element().max(b.min.abs().max_element());
        prism.bounds = b.padded(pad);
        Ok(prism)
    }

    /// Crossings of the half-line from `q` along `dir` with the profile.
    fn crossings(&self, q: DVec2, dir: DVec2, buf: &mut Vec<Root>) -> u32 {
        let mut n = 0;
        for seg in &self.segs {
            // The half-line misses a box whose corners all lie on one side of its line, or
            // behind its start.
            let side = |p: DVec2| (p - q).perp_dot(dir);
            let corners = [
                seg.min,
                seg.max,
                DVec2::new(seg.min.x, seg.max.y),
                DVec2::new(seg.max.x, seg.min.y),
            ];
            if corners.iter().all(|&c| side(c) > 0.0) || corners.iter().all(|&c| side(c) < 0.0) {
                continue;
            }
            if corners.iter().all(|&c| (c - q).dot(dir) < 0.0) {
                continue;
            }
            let f = seg.c.map(side);
            let noise = 8.0
                * f64::EPSILON
                * seg
                    .c
                    .iter()
                    .map(|c| {
                        (c.x.abs() + q.x.abs()) * dir.y.abs()
                            + (c.y.abs() + q.y.abs()) * dir.x.abs()
                    })
                    .fold(0.0, f64::max);
            roots(f, noise, buf);
            for r in buf.iter() {
                // Half-open in s, so a curve passing through a joint counts once there.
                if r.kind == RootKind::Simple && r.t < 1.0 && (eval(&seg.c, r.t) - q).dot(dir) > 0.0
                {
                    n += 1;
                }
            }
        }
        n
    }

    /// Whether the profile point `q` is inside (even-odd rule).
    pub fn inside_profile(&self, q: DVec2) -> bool {
        let mut buf = Vec::new();
        self.crossings(q, COUNT_DIR, &mut buf) % 2 == 1
    }

    /// Whether `p` lies inside the solid (never, for an open prism).
    pub fn inside(&self, p: DVec3) -> bool {
        if self.open || !(p.y >= self.lo && p.y <= self.hi) {
            return false;
        }
        if self.conic {
            if p.y == 0.0 {
                return false;
            }
            self.inside_profile(DVec2::new(p.x / p.y, p.z / p.y))
        } else {
            self.inside_profile(DVec2::new(p.x, p.z))
        }
    }

    /// Every hit with `t_min < t < t_max`, in no particular order, handed to `f` until it returns
    /// `false`.
    pub fn hits(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        mut f: impl FnMut(PrismHit) -> bool,
    ) {
        if !(o.is_finite() && d.is_finite()) || d == DVec3::ZERO {
            return;
        }
        let mut buf = Vec::new();
        let in_range = |t: f64, h: f64| t > t_min && t < t_max && h >= self.lo && h <= self.hi;
        // The ray's cubic for a segment, and the rounding noise of its coefficients.
        let nv = o.cross(d);
        let scale = o.length() * d.length();
        if self.conic || d.x != 0.0 || d.z != 0.0 {
            for (k, seg) in self.segs.iter().enumerate() {
                let value = |p: DVec2| {
                    if self.conic {
                        nv.x * p.x + nv.y + nv.z * p.y
                    } else {
                        (p.x - o.x) * d.z - (p.y - o.z) * d.x
                    }
                };
                let corners = [
                    seg.min,
                    seg.max,
                    DVec2::new(seg.min.x, seg.max.y),
                    DVec2::new(seg.max.x, seg.min.y),
                ];
                let noise_of = |p: DVec2| {
                    8.0 * f64::EPSILON
                        * if self.conic {
                            scale * (p.x.abs() + 1.0 + p.y.abs())
                        } else {
                            (p.x.abs() + o.x.abs()) * d.z.abs()
                                + (p.y.abs() + o.z.abs()) * d.x.abs()
                        }
                };
                let noise = seg.c.iter().map(|&p| noise_of(p)).fold(0.0, f64::max);
                let cv = corners.map(value);
                if cv.iter().all(|&v| v > noise) || cv.iter().all(|&v| v < -noise) {
                    continue;
                }
                roots(seg.c.map(value), noise, &mut buf);
                for r in &buf {
                    if r.kind != RootKind::Simple {
                        continue;
                    }
                    let q = eval(&seg.c, r.t);
                    let (t, h) = if self.conic {
                        let (ex, ez) = (d.x - d.y * q.x, d.z - d.y * q.y);
                        let t = if ex.abs() >= ez.abs() {
                            -(o.x - o.y * q.x) / ex
                        } else {
                            -(o.z - o.y * q.y) / ez
                        };
                        (t, o.y + t * d.y)
                    } else {
                        let t = if d.x.abs() >= d.z.abs() {
                            (q.x - o.x) / d.x
                        } else {
                            (q.y - o.z) / d.z
                        };
                        (t, o.y + t * d.y)
                    };
                    if t.is_finite()
                        && in_range(t, h)
                        && !f(PrismHit {
                            t,
                            part: PrismPart::Side {
                                seg: k as u32,
                                s: r.t,
                            },
                        })
                    {
                        return;
                    }
                }
            }
        }
        if self.open || d.y == 0.0 {
            return;
        }
        for (h, top) in [(self.lo, false), (self.hi, true)] {
            if self.conic && h == 0.0 {
                continue;
            }
            let t = (h - o.y) / d.y;
            if !(t > t_min && t < t_max) {
                continue;
            }
            let p = o + t * d;
            let q = if self.conic {
                DVec2::new(p.x / h, p.z / h)
            } else {
                DVec2::new(p.x, p.z)
            };
            if q.cmplt(self.pmin).any() || q.cmpgt(self.pmax).any() {
                continue;
            }
            if self.crossings(q, COUNT_DIR, &mut buf) % 2 == 1
                && !f(PrismHit {
                    t,
                    part: PrismPart::Cap { top },
                })
            {
                return;
            }
        }
    }

    /// The nearest hit with `t_min < t < t_max`.
    pub fn nearest(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<PrismHit> {
        let mut best: Option<PrismHit> = None;
        self.hits(o, d, t_min, t_max, |h| {
            if best.is_none_or(|b| h.t < b.t) {
                best = Some(h);
            }
            true
        });
        best
    }

    /// The point, outward unit normal, uv and `dp/du` of a hit of the ray `o + t d`.
    pub fn surface(&self, o: DVec3, d: DVec3, hit: PrismHit) -> (DVec3, DVec3, DVec2, DVec3) {
        let p = o + hit.t * d;
        match hit.part {
            PrismPart::Side { seg, s } => {
                let segment = &self.segs[seg as usize];
                let (q, tq) = (eval(&segment.c, s), tangent(&segment.c, s));
                let h = p.y.clamp(self.lo, self.hi);
                let u = (f64::from(seg) + s) / self.segs.len() as f64;
                let v = (h - self.lo) / (self.hi - self.lo);
                let k = self.segs.len() as f64;
                let (point, n, dpdu) = if self.conic {
                    let g = DVec3::new(q.x, 1.0, q.y);
                    let n = DVec3::new(-tq.y, tq.y * q.x - tq.x * q.y, tq.x)
                        * (segment.out * h.signum());
                    (g * h, n, DVec3::new(tq.x, 0.0, tq.y) * (h * k))
                } else {
                    let n = DVec3::new(-tq.y, 0.0, tq.x) * segment.out;
                    (DVec3::new(q.x, h, q.y), n, DVec3::new(tq.x, 0.0, tq.y) * k)
                };
                (point, n.normalize_or(DVec3::Y), DVec2::new(u, v), dpdu)
            }
            PrismPart::Cap { top } => {
                let h = if top { self.hi } else { self.lo };
                let w = if self.conic { h } else { 1.0 };
                let q = DVec2::new(p.x, p.z) / w;
                let span = (self.pmax - self.pmin).max(DVec2::splat(1e-300));
                let uv = (q - self.pmin) / span;
                let n = if top { DVec3::Y } else { DVec3::NEG_Y };
                (
                    DVec3::new(p.x, h, p.z),
                    n,
                    uv,
                    DVec3::X * (span.x * w.abs()),
                )
            }
        }
    }
}

impl Shape for Prism {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        let (lo, hi) = super::f64_range(t_min, t_max);
        let hit = self.nearest(o, d, lo, hi)?;
        let t = hit.t as f32;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let (p, n, uv, dpdu) = self.surface(o, d, hit);
        let n = n.as_vec3a();
        Some(Hit {
            t,
            p: p.as_vec3a(),
            n,
            ns: n,
            uv: uv.as_vec2(),
            dpdu: dpdu.as_vec3a(),
        })
    }

    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        let mut any = false;
        let (lo, hi) = super::f64_range(t_min, t_max);
        self.hits(o, d, lo, hi, |h| {
            let t = h.t as f32;
            any = t > t_min && t < t_max;
            !any
        });
        any
    }

    /// A prism is not a light's shape: it is never sampled.
    fn area(&self) -> f32 {
        0.0
    }

    fn sample(&self, _u: Vec2) -> Option<AreaSample> {
        None
    }
}
