//! A slow reference intersector for `superellipsoid`, sharing nothing with the product's: POV-Ray's
//! own function `F = (|x|^(2/e) + |y|^(2/e))^(e/n) + |z|^(2/n) - 1` (the first sum taken
//! relative to the larger of |x| and |y|, so that it does not underflow near the z axis; a
//! plain sum there makes a needle's tip look longer than it is) sampled at [`SAMPLES`] even steps along the
//! ray's chord through the cube, the first sign change bisected 200 times. A crossing pair
//! closer than a step can be missed by it: the stress test confirms such a case by the sign of
//! `F` on either side of the product's hit.

use glam::DVec3;

/// Samples along the chord.
pub const SAMPLES: usize = 4_000;

pub struct RefSuperellipsoid {
    e: f64,
    n: f64,
}

impl RefSuperellipsoid {
    pub fn new(e: f64, n: f64) -> Self {
        Self { e, n }
    }

    /// POV-Ray's function: negative inside.
    pub fn f(&self, p: DVec3) -> f64 {
        if p.abs().max_element() > 1.0 {
            return 1.0;
        }
        // |x|^(2/e) underflows near the z axis when 2/e is large: the sum is taken relative to
        // the larger of |x| and |y|, which is then raised to the power 2/n as a whole.
        let m = p.x.abs().max(p.y.abs());
        let xy = if m == 0.0 {
            0.0
        } else {
            let sum = (p.x.abs() / m).powf(2.0 / self.e) + (p.y.abs() / m).powf(2.0 / self.e);
            m.powf(2.0 / self.n) * sum.powf(self.e / self.n)
        };
        xy + p.z.abs().powf(2.0 / self.n) - 1.0
    }

    /// The chord of the ray through the cube, from `t_min` on.
    fn chord(&self, o: DVec3, d: DVec3, t_min: f64) -> Option<(f64, f64)> {
        let (mut a, mut b) = (t_min, f64::INFINITY);
        for k in 0..3 {
            if d[k] == 0.0 {
                if o[k].abs() > 1.0 {
                    return None;
                }
                continue;
            }
            let (t0, t1) = ((-1.0 - o[k]) / d[k], (1.0 - o[k]) / d[k]);
            a = a.max(t0.min(t1));
            b = b.min(t0.max(t1));
        }
        (a < b).then_some((a, b))
    }

    /// The first sign change of `F` along the ray after `t_min`.
    pub fn nearest(&self, o: DVec3, d: DVec3, t_min: f64) -> Option<f64> {
        let (a, b) = self.chord(o, d, t_min)?;
        let step = (b - a) / SAMPLES as f64;
        let f = |t: f64| self.f(o + t * d);
        let mut prev = f(a);
        for i in 1..=SAMPLES {
            let t = a + step * i as f64;
            let v = f(t);
            if (v < 0.0) != (prev < 0.0) {
                let (mut lo, mut hi) = (t - step, t);
                for _ in 0..200 {
                    let m = 0.5 * (lo + hi);
                    if m <= lo || m >= hi {
                        break;
                    }
                    if (f(m) < 0.0) == (prev < 0.0) {
                        lo = m;
                    } else {
                        hi = m;
                    }
                }
                return Some(0.5 * (lo + hi));
            }
            prev = v;
        }
        None
    }
}
