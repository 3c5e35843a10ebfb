//! Slow reference intersectors for `blob` and `isosurface`, sharing nothing with the product's:
//! the field (or function) sampled at even steps along the ray's chord through a box, the first
//! sign change bisected 200 times. The blob's field is POV-Ray's, written from its definition
//! (the distance to a capsule's segment by the clamped projection, no regions). A crossing pair
//! closer than a step can be missed by the sampling: the stress tests confirm such a case by
//! the sign of the field on either side of the product's hit.

use glam::{DAffine3, DVec3};

/// A component: segment `a`–`b` (a sphere when equal), radius, strength, and the map from the
/// blob's space to the component's own.
#[derive(Clone, Copy)]
pub struct RefComponent {
    pub a: DVec3,
    pub b: DVec3,
    pub r: f64,
    pub s: f64,
    pub to_local: DAffine3,
}

pub struct RefBlob {
    pub threshold: f64,
    pub comps: Vec<RefComponent>,
}

impl RefBlob {
    /// The field minus the threshold: positive inside.
    pub fn f(&self, p: DVec3) -> f64 {
        let mut sum = 0.0;
        for c in &self.comps {
            let l = c.to_local.transform_point3(p);
            let ab = c.b - c.a;
            let len2 = ab.length_squared();
            let u = if len2 > 0.0 {
                ((l - c.a).dot(ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d2 = (l - (c.a + u * ab)).length_squared();
            if d2 < c.r * c.r {
                let w = 1.0 - d2 / (c.r * c.r);
                sum += c.s * w * w;
            }
        }
        sum - self.threshold
    }
}

/// The first `t > t_min` where `g` changes sign along `o + t d` within the box `lo..hi`,
/// from `samples` even steps over the chord and bisection.
pub fn first_sign_change(
    g: impl Fn(DVec3) -> f64,
    lo: DVec3,
    hi: DVec3,
    o: DVec3,
    d: DVec3,
    t_min: f64,
    samples: usize,
) -> Option<f64> {
    let (mut a, mut b) = (t_min, f64::INFINITY);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (t0, t1) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        a = a.max(t0.min(t1));
        b = b.min(t0.max(t1));
    }
    if a.is_nan() || b.is_nan() || a >= b {
        return None;
    }
    let side = |t: f64| g(o + t * d) > 0.0;
    let mut t0 = a;
    let mut s0 = side(a);
    for i in 1..=samples {
        let t1 = a + (b - a) * i as f64 / samples as f64;
        let s1 = side(t1);
        if s1 != s0 {
            let (mut l, mut h) = (t0, t1);
            for _ in 0..200 {
                let m = 0.5 * (l + h);
                if side(m) == s0 {
                    l = m;
                } else {
                    h = m;
                }
            }
            return Some(0.5 * (l + h));
        }
        t0 = t1;
        s0 = s1;
    }
    None
}
