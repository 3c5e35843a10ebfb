//! A slow reference intersector for the curved `sphere_sweep`, sharing nothing with the
//! product's: the spline evaluated from POV-Ray's basis matrices in power form (the product
//! uses the Bernstein form), its spheres sampled at even steps of `s` on every segment, the best
//! sample refined by golden-section search over its two neighbouring steps. A feature narrower
//! than a step can be missed by the sampling; the stress tests judge such a ray by
//! [`RefSweep::reach`], refined the same way.

use glam::DVec3;

/// POV-Ray's Catmull-Rom matrix (rows: powers of `s`, columns: the four points).
const CATMULL_ROM: [[f64; 4]; 4] = [
    [0.0, 1.0, 0.0, 0.0],
    [-0.5, 0.0, 0.5, 0.0],
    [1.0, -2.5, 2.0, -0.5],
    [-0.5, 1.5, -1.5, 0.5],
];
/// POV-Ray's uniform cubic B-spline matrix.
const B_SPLINE: [[f64; 4]; 4] = [
    [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0, 0.0],
    [-0.5, 0.0, 0.5, 0.0],
    [0.5, -1.0, 0.5, 0.0],
    [-1.0 / 6.0, 0.5, -0.5, 1.0 / 6.0],
];

pub struct RefSweep {
    pub b_spline: bool,
    pub centres: Vec<DVec3>,
    pub radii: Vec<f64>,
}

/// Along a ray: the least near root and the greatest far root over the spheres that meet it.
#[derive(Debug, Clone, Copy)]
pub struct RefSpan {
    pub entry: f64,
    pub exit: f64,
}

impl RefSweep {
    pub fn segments(&self) -> usize {
        self.centres.len().saturating_sub(3)
    }

    /// Centre and radius of segment `i` at `s` in [0, 1].
    pub fn at(&self, i: usize, s: f64) -> (DVec3, f64) {
        let m = if self.b_spline {
            &B_SPLINE
        } else {
            &CATMULL_ROM
        };
        let pow = [1.0, s, s * s, s * s * s];
        let (mut c, mut r) = (DVec3::ZERO, 0.0);
        let w: [f64; 4] = std::array::from_fn(|j| (0..4).map(|k| pow[k] * m[k][j]).sum());
        for ((w, p), q) in w
            .iter()
            .zip(&self.centres[i..i + 4])
            .zip(&self.radii[i..i + 4])
        {
            c += *w * *p;
            r += *w * *q;
        }
        (c, r)
    }

    /// The least of `f(i, s)` over every segment, sampled `samples` times per segment and
    /// refined; `f` is `+inf` where it is undefined.
    fn least(&self, samples: usize, f: impl Fn(usize, f64) -> f64) -> f64 {
        let mut best = f64::INFINITY;
        for i in 0..self.segments() {
            let (mut k_best, mut v_best) = (usize::MAX, f64::INFINITY);
            for k in 0..=samples {
                let v = f(i, k as f64 / samples as f64);
                if v < v_best {
                    (k_best, v_best) = (k, v);
                }
            }
            if k_best == usize::MAX {
                continue;
            }
            let step = 1.0 / samples as f64;
            let (mut a, mut b) = (
                (k_best as f64 * step - step).max(0.0),
                (k_best as f64 * step + step).min(1.0),
            );
            let g = 0.5 * (5f64.sqrt() - 1.0);
            for _ in 0..100 {
                let (x1, x2) = (b - g * (b - a), a + g * (b - a));
                if f(i, x1) < f(i, x2) {
                    b = x2;
                } else {
                    a = x1;
                }
                v_best = v_best.min(f(i, x1)).min(f(i, x2));
            }
            best = best.min(v_best);
        }
        best
    }

    /// `b` and `D` of segment `i`'s sphere at `s` along the unit ray, when it meets the ray.
    fn meets(&self, o: DVec3, d: DVec3, i: usize, s: f64) -> Option<(f64, f64)> {
        let (c, r) = self.at(i, s);
        if r <= 0.0 {
            return None;
        }
        let q = c - o;
        let b = q.dot(d);
        let disc = r * r - (q - b * d).length_squared();
        (disc >= 0.0).then_some((b, disc))
    }

    /// Entry and exit of the unit ray `o + t d` (from a point outside), if it meets a sphere.
    pub fn span(&self, o: DVec3, d: DVec3, samples: usize) -> Option<RefSpan> {
        let entry = self.least(samples, |i, s| {
            self.meets(o, d, i, s)
                .map_or(f64::INFINITY, |(b, disc)| b - disc.sqrt())
        });
        let exit = -self.least(samples, |i, s| {
            self.meets(o, d, i, s)
                .map_or(f64::INFINITY, |(b, disc)| -b - disc.sqrt())
        });
        entry.is_finite().then_some(RefSpan { entry, exit })
    }

    /// How far the unit ray reaches into the spheres: the greatest `r(s)` less the ray's
    /// distance from `c(s)` (negative: the ray passes that far outside every sphere).
    pub fn reach(&self, o: DVec3, d: DVec3, samples: usize) -> f64 {
        -self.least(samples, |i, s| {
            let (c, r) = self.at(i, s);
            let q = c - o;
            (q - q.dot(d) * d).length() - r
        })
    }

    /// The signed distance-like `min_s |p - c(s)| - r(s)` over spheres of positive radius:
    /// negative inside.
    pub fn distance(&self, p: DVec3, samples: usize) -> f64 {
        self.least(samples, |i, s| {
            let (c, r) = self.at(i, s);
            if r <= 0.0 {
                f64::INFINITY
            } else {
                (p - c).length() - r
            }
        })
    }
}
