//! Bump and normal mapping as a microsurface (Schüssler, Hanika, Jakob and Dachsbacher 2017,
//! "Microfacet-based Normal Mapping for Robust Monte Carlo Path Tracing").
//!
//! Shading a surface with a perturbed normal as if it were the surface loses energy and leaves
//! black fringes where the perturbed normal leans away from the shading one (light from below
//! the true surface, or light sent below it). Instead, the surface point is taken to be a
//! microsurface of two facets: the *perturbed facet* (normal `wp`, carrying the material's
//! lobes) and the *tangent facet* (normal `wt`, horizontal, a perfect mirror), in the
//! proportions that make its mean normal the shading normal. A ray meets the perturbed facet
//! with probability `lambda_p` (its share of the projected area seen from the ray), else the
//! tangent facet, which mirrors it onto the perturbed facet; the lobes scatter it there; it
//! escapes with the facet's shadowing `G1`, else it meets the tangent facet once more and
//! leaves mirrored. Paths that would still head into the surface after that (the lobe's share
//! below the shading horizon) are dropped: the only energy the model loses, a few percent at
//! strong tilts (measured in the tests).
//!
//! The value and the density are sums over these paths (two choices of first facet, two of
//! exit), so `f`, `pdf` and `sample` agree for every lobe. The walk is not reciprocal, so
//! paths carrying importance (photons) use the adjoint value `f*(wo, wi) = f(wi, wo)`, exact
//! for every lobe that is not a delta; a delta lobe's photon takes the walk from its own side.
//!
//! Everything here is in the shading frame (z the shading normal); the lobes' own frame is
//! the perturbed facet's.

use glam::{Vec2, Vec3A};

use super::{BsdfSample, Lobes, TransportMode};
use crate::geometry::Frame;

/// A perturbed normal leaning less than this (its sine) is the shading normal.
const MIN_SIN: f32 = 1e-4;
/// The lowest cosine a perturbed normal keeps: one leaning to or below the shading horizon
/// (a normal map's, or a steep bump's) is raised to it.
const MIN_COS: f32 = 1e-3;
/// The sampler's one number for the lobe choice is shared with the exit choice: this many
/// steps for the exit, the rest of the bits for the lobes.
const EXIT_STEPS: f32 = 4096.0;

/// A perturbed normal in the shading frame (`z > 0`, leaning from `z`), with the two facets'
/// geometry every evaluation uses, derived once when it is built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Microsurface {
    /// The perturbed facet's normal.
    wp: Vec3A,
    /// The tangent facet's normal (horizontal, facing away from `wp`'s lean).
    wt: Vec3A,
    /// The sine of `wp`'s lean.
    sin_p: f32,
    /// The perturbed facet's frame, where the lobes are evaluated.
    facet: Frame,
}

impl Microsurface {
    /// The microsurface for perturbed normal `wp` (local), or `None` when it does not lean
    /// (or is not a direction).
    pub fn new(wp: Vec3A) -> Option<Self> {
        let wp = wp.normalize_or_zero();
        let h = Vec2::new(wp.x, wp.y);
        let sin = h.length();
        if !wp.is_finite() || wp == Vec3A::ZERO || sin < MIN_SIN {
            return None;
        }
        let wp = if wp.z < MIN_COS {
            let h = h / sin * (1.0 - MIN_COS * MIN_COS).sqrt();
            Vec3A::new(h.x, h.y, MIN_COS)
        } else {
            wp
        };
        Some(Self::from_normal(wp))
    }

    /// The microsurface of a perturbed normal that [`Self::new`] gave (a [`Self::normal`]):
    /// the same microsurface, bit for bit, from a compact copy of it.
    pub fn from_normal(wp: Vec3A) -> Self {
        let sin_p = (wp.x * wp.x + wp.y * wp.y).sqrt();
        Self {
            wp,
            wt: Vec3A::new(-wp.x / sin_p, -wp.y / sin_p, 0.0),
            sin_p,
            facet: Frame::from_normal(wp),
        }
    }

    /// The perturbed normal (local).
    pub fn normal(&self) -> Vec3A {
        self.wp
    }

    /// `f` for a pair passing the side tests (`o.z`, `i.z` nonzero).
    pub fn f(&self, lobes: &Lobes, o: Vec3A, i: Vec3A, mode: TransportMode) -> Vec3A {
        match mode {
            TransportMode::Radiance => self.walk(lobes, o, i).0 / i.z.abs(),
            TransportMode::Importance => self.walk(lobes, i, o).0 / o.z.abs(),
        }
    }

    pub fn pdf(&self, lobes: &Lobes, o: Vec3A, i: Vec3A) -> f32 {
        self.walk(lobes, o, i).1
    }

    /// [`Self::f`], [`Self::pdf`] and the reverse pair's `pdf(i, o)` from two walks (the one
    /// that gives `f` gives one of the densities too): the same values as the three calls.
    pub fn eval(
        &self,
        lobes: &Lobes,
        o: Vec3A,
        i: Vec3A,
        mode: TransportMode,
    ) -> (Vec3A, f32, f32) {
        let (forward, reverse) = (self.walk(lobes, o, i), self.walk(lobes, i, o));
        let f = match mode {
            TransportMode::Radiance => forward.0 / i.z.abs(),
            TransportMode::Importance => reverse.0 / o.z.abs(),
        };
        (f, forward.1, reverse.1)
    }

    /// Samples the walk from `o`: the first facet, the lobes, the exit.
    pub fn sample(
        &self,
        lobes: &Lobes,
        o: Vec3A,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        if let Lobes::Diffuse { .. } = lobes {
            let i = self.sample_diffuse(o, uc, u)?;
            return self.weigh(lobes, o, i, mode);
        }
        let lp = self.lambda_p(o);
        let (ob, v) = if uc < lp {
            (o, uc / lp)
        } else {
            (self.reflect(o), (uc - lp) / (1.0 - lp))
        };
        let x = v.clamp(0.0, 1.0) * EXIT_STEPS;
        let steps = x.floor().min(EXIT_STEPS - 1.0);
        let (u_exit, u_lobe) = (
            (steps + 0.5) / EXIT_STEPS,
            (x - steps).min(1.0 - f32::EPSILON),
        );
        let bs = lobes.sample_local(self.facet.to_local(ob), u_lobe, u, mode)?;
        let d = self.facet.to_world(bs.wi);
        let (g, wall) = self.exit(d);
        let i = if u_exit < g {
            d
        } else if wall {
            self.reflect(d)
        } else {
            return None;
        };
        if i.z == 0.0 {
            return None;
        }
        if bs.specular {
            return Some(BsdfSample { wi: i, ..bs });
        }
        self.weigh(lobes, o, i, mode)
    }
}

impl Microsurface {
    /// A sample toward `i` weighted by the whole walk's `f |cos| / pdf` (the importance value
    /// for importance).
    fn weigh(&self, lobes: &Lobes, o: Vec3A, i: Vec3A, mode: TransportMode) -> Option<BsdfSample> {
        let (value, pdf) = self.walk(lobes, o, i);
        let value = match mode {
            TransportMode::Radiance => value,
            TransportMode::Importance => self.walk(lobes, i, o).0 * (i.z / o.z).abs(),
        };
        (pdf > 0.0).then(|| BsdfSample {
            wi: i,
            weight: value / pdf,
            pdf,
            specular: false,
        })
    }

    fn reflect(&self, w: Vec3A) -> Vec3A {
        w - 2.0 * w.dot(self.wt) * self.wt
    }

    /// The facets' projected areas seen from `w` on the side `s` (1 above, -1 below).
    fn areas(&self, w: Vec3A, s: f32) -> (f32, f32) {
        let ap = (s * w.dot(self.wp)).max(0.0);
        let at = (s * w.dot(self.wt)).max(0.0) * self.sin_p;
        (ap, at)
    }

    /// The probability that a ray arriving from `w` meets the perturbed facet first.
    fn lambda_p(&self, w: Vec3A) -> f32 {
        let (ap, at) = self.areas(w, w.z.signum());
        if ap + at > 0.0 { ap / (ap + at) } else { 0.0 }
    }

    /// For a ray leaving the perturbed facet in direction `d`: the probability that it escapes
    /// (the facet's shadowing `G1` on the side it leaves by), and whether, mirrored by the
    /// tangent facet otherwise, it then heads away from the surface.
    fn exit(&self, d: Vec3A) -> (f32, bool) {
        let s = if d.dot(self.wp) >= 0.0 { 1.0 } else { -1.0 };
        let (ap, at) = self.areas(d, s);
        let up = (s * d.z).max(0.0);
        let g = if ap + at > 0.0 {
            (up * self.wp.z / (ap + at)).min(1.0)
        } else {
            0.0
        };
        (g, up > 0.0)
    }

    /// The walk's value `f |cos|` (cosine to the shading normal) and density for arriving
    /// from `o` and leaving toward `i`, over its four paths. The lobes are evaluated for
    /// radiance: [`Microsurface::f`] swaps the directions for importance.
    fn walk(&self, lobes: &Lobes, o: Vec3A, i: Vec3A) -> (Vec3A, f32) {
        if let Lobes::Diffuse { albedo } = *lobes {
            return self.walk_diffuse(albedo, o, i);
        }
        let lp = self.lambda_p(o);
        let (mut value, mut pdf) = (Vec3A::ZERO, 0.0);
        let i_local = self.facet.to_local(i);
        let d = self.reflect(i);
        let d_local = self.facet.to_local(d);
        let (g_direct, _) = self.exit(i);
        let (g_d, wall) = self.exit(d);
        let g_wall = if wall { 1.0 - g_d } else { 0.0 };
        for (lambda, ob) in [(lp, o), (1.0 - lp, self.reflect(o))] {
            if lambda <= 0.0 {
                continue;
            }
            let ob = self.facet.to_local(ob);
            for (g, w) in [(g_direct, i_local), (g_wall, d_local)] {
                if g <= 0.0 {
                    continue;
                }
                let (f, p) = lobes.eval_local(ob, w, TransportMode::Radiance);
                value += lambda * g * w.z.abs() * f;
                pdf += lambda * g * p;
            }
        }
        (value, pdf)
    }
}

/// A Lambertian perturbed facet sends light the same way whatever it arrived from, so the walk
/// can go on where the two-facet walk stops: light the tangent facet turns back into the
/// surface meets the perturbed facet again and is scattered anew. Summed over every number of
/// such returns the walk is closed: the share `L = (1 - cos theta_p) / 2` of the cosine lobe
/// that heads below the shading horizon returns, so a white facet loses nothing.
impl Microsurface {
    /// The share of a cosine lobe around `wp` that heads below the shading horizon.
    fn returning(&self) -> f32 {
        0.5 * (1.0 - self.wp.z)
    }

    /// One scattering's density of leaving toward `i` (without its returns), for light on
    /// side `s` (1 above, -1 below).
    fn diffuse_exit_density(&self, s: f32, i: Vec3A) -> f32 {
        let d = self.reflect(i);
        let (g_direct, _) = self.exit(i);
        let (g_d, wall) = self.exit(d);
        let g_wall = if wall { 1.0 - g_d } else { 0.0 };
        let cos = |w: Vec3A| (s * w.dot(self.wp)).max(0.0);
        (g_direct * cos(i) + g_wall * cos(d)) * std::f32::consts::FRAC_1_PI
    }

    fn walk_diffuse(&self, albedo: Vec3A, o: Vec3A, i: Vec3A) -> (Vec3A, f32) {
        if o.z * i.z <= 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        let e = self.diffuse_exit_density(o.z.signum(), i);
        let l = self.returning();
        (albedo * e / (Vec3A::ONE - albedo * l), e / (1.0 - l))
    }

    /// Samples the closed walk: cosine directions around the facet until one leaves (its
    /// returns draw their numbers from a hash of the sampler's, at most [`MAX_RETURNS`]).
    fn sample_diffuse(&self, o: Vec3A, uc: f32, u: Vec2) -> Option<Vec3A> {
        let s = o.z.signum();
        let facet_n = self.wp * s;
        let frame = Frame::from_normal(facet_n);
        let mut key = (u64::from(u.x.to_bits()) << 32) ^ u64::from(u.y.to_bits());
        key ^= u64::from(uc.to_bits()).rotate_left(17);
        let (mut u, mut u_exit) = (u, uc);
        for _ in 0..MAX_RETURNS {
            let d = frame.to_world(crate::sampling::cosine_hemisphere(u));
            let (g, wall) = self.exit(d);
            let i = if u_exit < g {
                Some(d)
            } else if wall {
                Some(self.reflect(d))
            } else {
                None
            };
            if let Some(i) = i.filter(|i| i.z * s > 0.0) {
                return Some(i);
            }
            key = crate::sampling::splitmix64(key).1;
            u = Vec2::new(unit(key), unit(key >> 24));
            u_exit = unit(key >> 40);
        }
        None
    }
}

/// Returns a sampled diffuse walk follows before it gives up (a share `L^64`, below `1e-19`).
const MAX_RETURNS: usize = 64;

/// A number in [0, 1) from the low 24 bits of `k`.
fn unit(k: u64) -> f32 {
    (k & 0xff_ffff) as f32 * (1.0 / (1u64 << 24) as f32)
}

#[cfg(test)]
mod tests;
