//! A slow reference intersector for `prism`, sharing no root finder with the product.
//!
//! Each segment's coordinates are taken to the power basis; the ray's cubic `f(s)` (the same
//! condition as the product's: the ray's projection crosses the curve, or for a conic sweep the
//! line through the origin along `(X, 1, Z)` lies in the plane of the origin and the ray) is
//! cut at the zeros of `f'` (the quadratic formula) into monotone pieces, and each piece with a
//! sign change gives its one root by 200 bisections. A piece whose extreme value comes within
//! [`AMBIGUOUS`] (relative) of zero is a near-tangency the reference does not decide: the ray
//! is flagged ambiguous. The caps keep a hit inside the profile by the even-odd count along
//! +x, with the same monotone-piece bisection on `Z(s) - q_z`; a crossing too close to its end
//! or to `q` to decide makes the ray ambiguous too.

use glam::{DVec2, DVec3};

/// Relative size below which a value counts as undecidable.
pub const AMBIGUOUS: f64 = 1e-10;

/// The reference's answer for one ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefPrismHit {
    pub t: Option<f64>,
    pub ambiguous: bool,
}

pub struct RefPrism {
    /// Power coefficients `[a, b, c, d]` (`a s^3 + b s^2 + c s + d`) of x and z per segment.
    segs: Vec<[DVec2; 4]>,
    lo: f64,
    hi: f64,
    conic: bool,
    open: bool,
    size: f64,
}

fn cubic(c: &[f64; 4], s: f64) -> f64 {
    ((c[0] * s + c[1]) * s + c[2]) * s + c[3]
}

/// Zeros of `3a s^2 + 2b s + c` inside (0, 1), ascending.
fn critical(c: &[f64; 4]) -> Vec<f64> {
    let (a, b, cc) = (3.0 * c[0], 2.0 * c[1], c[2]);
    let mut r = vec![];
    if a != 0.0 {
        let disc = b * b - 4.0 * a * cc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            r.push((-b - sq) / (2.0 * a));
            r.push((-b + sq) / (2.0 * a));
        }
    } else if b != 0.0 {
        r.push(-cc / b);
    }
    r.retain(|s| *s > 0.0 && *s < 1.0);
    r.sort_by(f64::total_cmp);
    r
}

/// Roots of the cubic `c` on [0, 1] by monotone pieces and bisection; `Err` when a piece's end
/// comes within `tol` of zero without a clear sign change (undecidable).
fn roots(c: &[f64; 4], tol: f64) -> Result<Vec<f64>, ()> {
    let mut cuts = vec![0.0];
    cuts.extend(critical(c));
    cuts.push(1.0);
    let mut out = vec![];
    for w in cuts.windows(2) {
        let (mut a, mut b) = (w[0], w[1]);
        let (fa, fb) = (cubic(c, a), cubic(c, b));
        if fa.abs() <= tol || fb.abs() <= tol {
            // A touch, or a root at a joint: too close to call.
            return Err(());
        }
        if (fa < 0.0) == (fb < 0.0) {
            continue;
        }
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            if (cubic(c, m) < 0.0) == (fa < 0.0) {
                a = m;
            } else {
                b = m;
            }
        }
        out.push(0.5 * (a + b));
    }
    Ok(out)
}

impl RefPrism {
    /// From the product's scene description (its Bezier segments).
    pub fn new(p: &sppm_lang::internals::scene::Prism) -> Self {
        let segs = p
            .segments
            .iter()
            .map(|c| {
                let a = -c[0] + 3.0 * c[1] - 3.0 * c[2] + c[3];
                let b = 3.0 * c[0] - 6.0 * c[1] + 3.0 * c[2];
                let cc = 3.0 * (c[1] - c[0]);
                [a, b, cc, c[0]]
            })
            .collect::<Vec<_>>();
        let size = p
            .segments
            .iter()
            .flatten()
            .fold(0.0f64, |m, q| m.max(q.abs().max_element()))
            .max(p.heights.0.abs())
            .max(p.heights.1.abs());
        Self {
            segs,
            lo: p.heights.0.min(p.heights.1),
            hi: p.heights.0.max(p.heights.1),
            conic: p.conic,
            open: p.open,
            size,
        }
    }

    fn xz(&self, k: usize) -> ([f64; 4], [f64; 4]) {
        let s = &self.segs[k];
        (s.map(|v| v.x), s.map(|v| v.y))
    }

    /// Whether the profile point `q` is inside by the even-odd count along +x; `None` when a
    /// crossing is too close to call.
    pub fn inside_profile(&self, q: DVec2) -> Option<bool> {
        let mut n = 0;
        let tol = AMBIGUOUS * self.size;
        for k in 0..self.segs.len() {
            let (x, mut z) = self.xz(k);
            z[3] -= q.y;
            let rs = roots(&z, tol).ok()?;
            for s in rs {
                let dx = cubic(&x, s) - q.x;
                if dx.abs() <= tol {
                    return None;
                }
                if dx > 0.0 {
                    n += 1;
                }
            }
        }
        Some(n % 2 == 1)
    }

    /// Whether `p` is inside the solid; `None` when too close to the surface to call.
    pub fn inside(&self, p: DVec3) -> Option<bool> {
        if self.open {
            return Some(false);
        }
        let tol = AMBIGUOUS * self.size;
        if (p.y - self.lo).abs() <= tol || (p.y - self.hi).abs() <= tol {
            return None;
        }
        if p.y < self.lo || p.y > self.hi {
            return Some(false);
        }
        if self.conic {
            self.inside_profile(DVec2::new(p.x / p.y, p.z / p.y))
        } else {
            self.inside_profile(DVec2::new(p.x, p.z))
        }
    }

    /// The nearest hit with `t > t_min` (in units of `d`).
    pub fn nearest(&self, o: DVec3, d: DVec3, t_min: f64) -> RefPrismHit {
        let mut best: Option<f64> = None;
        let mut ambiguous = false;
        let mut keep = |t: f64| {
            if t > t_min && best.is_none_or(|b| t < b) {
                best = Some(t);
            }
        };
        let nv = o.cross(d);
        let tol = AMBIGUOUS * self.size * d.length() * (1.0 + o.length());
        if self.conic || d.x != 0.0 || d.z != 0.0 {
            for k in 0..self.segs.len() {
                let (x, z) = self.xz(k);
                let f: [f64; 4] = if self.conic {
                    std::array::from_fn(|i| {
                        nv.x * x[i] + nv.z * z[i] + if i == 3 { nv.y } else { 0.0 }
                    })
                } else {
                    std::array::from_fn(|i| {
                        let (xo, zo) = if i == 3 { (o.x, o.z) } else { (0.0, 0.0) };
                        (x[i] - xo) * d.z - (z[i] - zo) * d.x
                    })
                };
                let Ok(rs) = roots(&f, tol) else {
                    ambiguous = true;
                    continue;
                };
                for s in rs {
                    let q = DVec2::new(cubic(&x, s), cubic(&z, s));
                    let t = if self.conic {
                        let (ex, ez) = (d.x - d.y * q.x, d.z - d.y * q.y);
                        if ex.abs() >= ez.abs() {
                            -(o.x - o.y * q.x) / ex
                        } else {
                            -(o.z - o.y * q.y) / ez
                        }
                    } else if d.x.abs() >= d.z.abs() {
                        (q.x - o.x) / d.x
                    } else {
                        (q.y - o.z) / d.z
                    };
                    let h = o.y + t * d.y;
                    let htol = AMBIGUOUS * self.size * 100.0;
                    if (h - self.lo).abs() <= htol || (h - self.hi).abs() <= htol {
                        ambiguous = true;
                    } else if h > self.lo && h < self.hi {
                        keep(t);
                    }
                }
            }
        }
        if !self.open && d.y != 0.0 {
            for h in [self.lo, self.hi] {
                let t = (h - o.y) / d.y;
                let p = o + t * d;
                let q = if self.conic {
                    DVec2::new(p.x / h, p.z / h)
                } else {
                    DVec2::new(p.x, p.z)
                };
                match self.inside_profile(q) {
                    Some(true) => keep(t),
                    Some(false) => {}
                    None => ambiguous = true,
                }
            }
        }
        RefPrismHit { t: best, ambiguous }
    }
}
