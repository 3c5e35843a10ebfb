//! Coated diffuse (plastic, varnish, glaze): a dielectric coat of relative index `eta` over a
//! Lambertian base of albedo `c`, the layered model of Weidlich and Wilkie as Mitsuba's
//! `plastic` (smooth coat) and `roughplastic` (GGX coat) formulate it with `nonlinear` on:
//!
//! `f = spec + c t(cos_o) t(cos_i) / (eta^2 (1 - c Ri) pi)`
//!
//! where `spec` is the coat's reflection (a delta lobe with weight `F(cos_o)` when smooth, the
//! GGX lobe `F(wo.h) D G1 G1 / (4 cos_o cos_i)` when rough), `t` the light the coat lets
//! through (its transmission albedo from outside: `1 - F` when smooth, the mean of
//! `(1 - F(wo.h)) G1(refracted)` over the visible normals when rough, which leaves out what
//! masking loses) and `Ri = 2 int E_inside(mu) mu dmu` the base's light the coat sends back
//! down (`E_inside` its reflection albedo from inside, total internal reflection included).
//! Light bounces between base and coat, times `c Ri` each round, hence `1 - c Ri`.
//!
//! For a Lambertian base and a coat without thickness this is exact in albedo: the base forgets
//! the direction light arrived from, so the light reaching it is `t(cos_o)`, the share leaving
//! per bounce `2 int t mu dmu / eta^2` and the share sent back `Ri`. A random walk through the
//! same layer (`sppm-measure coat`, docs/measurements.md, "Coated against a random walk")
//! agrees within its noise, where the former form (`1 - E` for `t`, and `1 - Ri` for
//! `1 - c Ri`) was up to 73 % too bright. So a white base reflects at most what reaches it; the
//! divisor is kept at least `2 int t mu dmu` against the tables' rounding.
//!
//! `E`, `t` and `Ri` of a rough coat have no closed form: they are tabulated once per process
//! over (eta, roughness, cos) by quadrature over the visible normals, and interpolated.
//! Sampling picks the coat's lobe with probability proportional to `E(cos_o) w` against the
//! base's `t(cos_o) (1 - w)`, `w = 1 / (1 + mean(albedo))` (Mitsuba's weights), the GGX lobe
//! by its visible normals, the base by the cosine.

use std::f32::consts::FRAC_1_PI;
use std::sync::OnceLock;

use glam::{Vec2, Vec3A};

use super::BsdfSample;
use super::dielectric::fresnel;
use super::glossy::{d_ggx, flip, g1, sample_visible_normal, unflipped_sample};
use crate::sampling::cosine_hemisphere;

/// The coat's index of refraction is kept in `[1, MAX_ETA]` (the tables' range).
pub const MAX_ETA: f32 = 3.0;
/// A rough coat's GGX alpha is at least this (as the glossy lobe: smaller ones overflow `D`).
const MIN_ALPHA: f32 = 1e-3;

const N_ETA: usize = 21;
const N_R: usize = 33;
const N_COS: usize = 33;
/// Visible-normal quadrature points per side for one directional albedo.
const N_QUAD: usize = 24;
/// Cosine points for the internal reflectance of a rough coat.
const N_MU: usize = 96;

struct Tables {
    /// `E(eta, r, cos)`: the coat's directional albedo from outside, `r = sqrt(alpha)`,
    /// over nodes even in `sqrt(cos)`.
    ext: Vec<f32>,
    /// `t(eta, r, cos)`: the coat's transmission albedo from outside, over the same nodes.
    trans: Vec<f32>,
    /// `(Ri, 2 int t mu dmu)` over `(eta, r)`: the coat's hemispherical internal reflectance
    /// and the share of light leaving the base that the coat would let out were `eta` 1.
    internal: Vec<(f32, f32)>,
}

fn eta_at(i: usize) -> f32 {
    1.0 + (MAX_ETA - 1.0) * i as f32 / (N_ETA - 1) as f32
}

fn r_at(j: usize) -> f32 {
    j as f32 / (N_R - 1) as f32
}

/// The coat interface's directional albedo for light from a side where the relative index is
/// `eta` (`eta < 1`: from inside), at incidence `cos`: exact Fresnel when smooth, else the mean
/// of `F(wo.h) G1(wi)` (the visible-normal sample weight) over a stratified grid.
fn interface_albedo(cos: f32, alpha: f32, eta: f32) -> f32 {
    interface_albedos(cos, alpha, eta).0
}

/// The interface's (reflection, transmission) albedos for light from a side where the
/// relative index is `eta`, at incidence `cos`: the transmission is the mean of
/// `(1 - F(wo.h)) G1(refracted)` over the visible normals (exactly `1 - F` when smooth).
fn interface_albedos(cos: f32, alpha: f32, eta: f32) -> (f32, f32) {
    let cos = cos.clamp(1e-4, 1.0);
    if alpha == 0.0 {
        let f = fresnel(cos, eta);
        return (f, 1.0 - f);
    }
    let wo = Vec3A::new((1.0 - cos * cos).max(0.0).sqrt(), 0.0, cos);
    let a2 = alpha * alpha;
    let mut sum = 0.0f64;
    let mut through = 0.0f64;
    for a in 0..N_QUAD {
        for b in 0..N_QUAD {
            let u = Vec2::new(
                (a as f32 + 0.5) / N_QUAD as f32,
                (b as f32 + 0.5) / N_QUAD as f32,
            );
            let h = sample_visible_normal(wo, alpha, u);
            let oh = wo.dot(h);
            let f = fresnel(oh, eta);
            let wi = h * (2.0 * oh) - wo;
            if wi.z > 0.0 {
                sum += f64::from(f * g1(wi, a2));
            }
            // The refracted direction through h (below the surface), when there is one.
            let sin2_t = (1.0 - oh * oh).max(0.0) / (eta * eta);
            if f < 1.0 && sin2_t < 1.0 {
                let cos_t = (1.0 - sin2_t).sqrt();
                let wt = (-wo / eta + h * (oh / eta - cos_t)).normalize();
                if wt.z < 0.0 {
                    through += f64::from((1.0 - f) * g1(-wt, a2));
                }
            }
        }
    }
    let n = (N_QUAD * N_QUAD) as f64;
    ((sum / n) as f32, (through / n) as f32)
}

fn build() -> Tables {
    let mut ext = Vec::with_capacity(N_ETA * N_R * N_COS);
    let mut trans = Vec::with_capacity(N_ETA * N_R * N_COS);
    let mut internal = Vec::with_capacity(N_ETA * N_R);
    for i in 0..N_ETA {
        let eta = eta_at(i);
        for j in 0..N_R {
            let r = r_at(j);
            let alpha = if j == 0 { 0.0 } else { (r * r).max(MIN_ALPHA) };
            for k in 0..N_COS {
                let x = k as f32 / (N_COS - 1) as f32;
                let (e, t) = interface_albedos(x * x, alpha, eta);
                ext.push(e);
                trans.push(t);
            }
            // Midpoint rule in mu on each side of the critical angle, where total internal
            // reflection puts a kink in the integrand; the smooth case is cheap, so it gets
            // many more points.
            let n = if j == 0 { 2048 } else { N_MU / 2 };
            let mu_c = (1.0 - 1.0 / (eta * eta)).max(0.0).sqrt();
            let mut s = 0.0f64;
            for (lo, hi) in [(0.0, mu_c), (mu_c, 1.0)] {
                for m in 0..n {
                    let mu = lo + (hi - lo) * (m as f32 + 0.5) / n as f32;
                    s += f64::from(interface_albedo(mu, alpha, 1.0 / eta) * mu * (hi - lo));
                }
            }
            let ri = (2.0 * s / n as f64) as f32;
            // 2 int t mu dmu: the share of the base's light that leaves through the coat (times
            // eta^2), from the row just stored (fine midpoint rule over its interpolation).
            let row = &trans[trans.len() - N_COS..];
            let m = 4096;
            let mut t = 0.0f64;
            for q in 0..m {
                let mu = (q as f32 + 0.5) / m as f32;
                let (k, tk) = cell(mu.sqrt(), N_COS);
                t += f64::from((row[k] * (1.0 - tk) + row[k + 1] * tk) * mu);
            }
            internal.push((ri, (2.0 * t / m as f64) as f32));
        }
    }
    Tables {
        ext,
        trans,
        internal,
    }
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(build)
}

/// Grid position of `x` in `[0, 1]` over `n` nodes: lower index and weight of the upper one.
fn cell(x: f32, n: usize) -> (usize, f32) {
    let t = x.clamp(0.0, 1.0) * (n - 1) as f32;
    let i = (t as usize).min(n - 2);
    (i, t - i as f32)
}

fn eta_r(eta: f32, alpha: f32) -> ((usize, f32), (usize, f32)) {
    (
        cell((eta - 1.0) / (MAX_ETA - 1.0), N_ETA),
        cell(alpha.max(0.0).sqrt(), N_R),
    )
}

/// `E(cos)` of a coat: exact for a smooth one, interpolated from the table for a rough one.
fn coat_albedo(eta: f32, alpha: f32, cos: f32) -> f32 {
    if alpha == 0.0 {
        return fresnel(cos.clamp(1e-4, 1.0), eta);
    }
    interpolate(&tables().ext, eta, alpha, cos)
}

/// `t(cos)` of a coat: `1 - F` for a smooth one, interpolated from the table for a rough one.
fn coat_transmission(eta: f32, alpha: f32, cos: f32) -> f32 {
    if alpha == 0.0 {
        return 1.0 - fresnel(cos.clamp(1e-4, 1.0), eta);
    }
    interpolate(&tables().trans, eta, alpha, cos)
}

/// A table over (eta, r, cos) at a point, trilinearly.
fn interpolate(table: &[f32], eta: f32, alpha: f32, cos: f32) -> f32 {
    let ((i, ti), (j, tj)) = eta_r(eta, alpha);
    // Nodes are even in sqrt(cos): dense at grazing angles, where E changes fastest.
    let (k, tk) = cell(cos.max(0.0).sqrt(), N_COS);
    let at = |i: usize, j: usize| {
        let row = &table[(i * N_R + j) * N_COS..][..N_COS];
        row[k] * (1.0 - tk) + row[k + 1] * tk
    };
    let lo = at(i, j) * (1.0 - tj) + at(i, j + 1) * tj;
    let hi = at(i + 1, j) * (1.0 - tj) + at(i + 1, j + 1) * tj;
    lo * (1.0 - ti) + hi * ti
}

/// The base's divisor per channel, `eta^2 (1 - c Ri)`, at least `2 int t mu dmu` (see
/// [`Tables::internal`]).
fn base_divisor(albedo: Vec3A, eta: f32, alpha: f32) -> Vec3A {
    let (ri, exit) = internal(eta, alpha);
    (eta * eta * (Vec3A::ONE - albedo * ri)).max(Vec3A::splat(exit))
}

/// `(Ri, 2 int t mu dmu)` at `(eta, alpha)`, interpolated.
fn internal(eta: f32, alpha: f32) -> (f32, f32) {
    let t = &tables().internal;
    let ((i, ti), (j, tj)) = if alpha == 0.0 {
        let (e, _) = eta_r(eta, 0.0);
        (e, (0, 0.0))
    } else {
        eta_r(eta, alpha)
    };
    let lerp = |a: (f32, f32), b: (f32, f32), t: f32| {
        (a.0 * (1.0 - t) + b.0 * t, a.1 * (1.0 - t) + b.1 * t)
    };
    let at = |i: usize, j: usize| t[i * N_R + j];
    let lo = lerp(at(i, j), at(i, (j + 1).min(N_R - 1)), tj);
    let hi = lerp(at(i + 1, j), at(i + 1, (j + 1).min(N_R - 1)), tj);
    lerp(lo, hi, ti)
}

/// The parameters the BSDF functions take, cleaned: `eta` in `[1, MAX_ETA]`, `alpha` zero
/// (smooth) or at least [`MIN_ALPHA`].
fn clean(eta: f32, alpha: f32) -> (f32, f32) {
    let eta = if eta.is_finite() {
        eta.clamp(1.0, MAX_ETA)
    } else {
        1.5
    };
    let alpha = if alpha > 0.0 {
        alpha.clamp(MIN_ALPHA, 1.0)
    } else {
        0.0
    };
    (eta, alpha)
}

/// The base's part of `f` (no cosine).
fn base(albedo: Vec3A, eta: f32, alpha: f32, cos_o: f32, cos_i: f32) -> Vec3A {
    let t_o = coat_transmission(eta, alpha, cos_o);
    let t_i = coat_transmission(eta, alpha, cos_i);
    albedo * (t_o * t_i * FRAC_1_PI) / base_divisor(albedo, eta, alpha).max(Vec3A::splat(1e-3))
}

/// The probability of sampling the coat's lobe for outgoing `cos_o`.
fn coat_probability(albedo: Vec3A, eta: f32, alpha: f32, cos_o: f32) -> f32 {
    let w = 1.0 / (1.0 + albedo.element_sum() / 3.0);
    let e = coat_albedo(eta, alpha, cos_o);
    let (ps, pd) = (e * w, coat_transmission(eta, alpha, cos_o) * (1.0 - w));
    if ps + pd > 0.0 { ps / (ps + pd) } else { 0.5 }
}

/// `f` without the smooth coat's delta lobe (a rough coat's GGX lobe is included).
pub fn f(albedo: Vec3A, eta: f32, alpha: f32, wo: Vec3A, wi: Vec3A) -> Vec3A {
    let (eta, alpha) = clean(eta, alpha);
    let (wo, wi) = flip(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3A::ZERO;
    }
    let diffuse = base(albedo, eta, alpha, wo.z, wi.z);
    let h = (wo + wi).normalize_or_zero();
    if alpha == 0.0 || h == Vec3A::ZERO {
        return diffuse;
    }
    let a2 = alpha * alpha;
    let spec = fresnel(wo.dot(h).clamp(0.0, 1.0), eta) * d_ggx(h, a2) * g1(wo, a2) * g1(wi, a2)
        / (4.0 * wo.z * wi.z);
    diffuse + Vec3A::splat(spec)
}

/// Density of [`sample`] choosing `wi` (without the smooth coat's delta lobe).
pub fn pdf(albedo: Vec3A, eta: f32, alpha: f32, wo: Vec3A, wi: Vec3A) -> f32 {
    let (eta, alpha) = clean(eta, alpha);
    let (wo, wi) = flip(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let ps = coat_probability(albedo, eta, alpha, wo.z);
    let h = (wo + wi).normalize_or_zero();
    let spec = if alpha == 0.0 || h == Vec3A::ZERO || wo.dot(h) <= 0.0 {
        0.0
    } else {
        let a2 = alpha * alpha;
        g1(wo, a2) * d_ggx(h, a2) / (4.0 * wo.z)
    };
    ps * spec + (1.0 - ps) * wi.z * FRAC_1_PI
}

pub fn sample(
    albedo: Vec3A,
    eta: f32,
    alpha: f32,
    wo: Vec3A,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    let (eta, alpha) = clean(eta, alpha);
    let (wof, _) = flip(wo, wo);
    let unflip = |wi: Vec3A| {
        if wo.z < 0.0 {
            Vec3A::new(wi.x, wi.y, -wi.z)
        } else {
            wi
        }
    };
    let ps = coat_probability(albedo, eta, alpha, wof.z);
    if uc < ps && alpha == 0.0 {
        // The smooth coat's mirror reflection: F / (probability of choosing it).
        let wi = Vec3A::new(-wof.x, -wof.y, wof.z);
        return Some(BsdfSample {
            wi: unflip(wi),
            weight: Vec3A::splat(fresnel(wof.z, eta) / ps),
            pdf: ps,
            specular: true,
        });
    }
    let wi = if uc < ps {
        let h = sample_visible_normal(wof, alpha, u);
        h * (2.0 * wof.dot(h)) - wof
    } else {
        cosine_hemisphere(u)
    };
    if wi.z <= 0.0 {
        return None;
    }
    let p = pdf(albedo, eta, alpha, wof, wi);
    if p <= 0.0 {
        return None;
    }
    let value = f(albedo, eta, alpha, wof, wi);
    Some(unflipped_sample(wo, wi, value, p))
}

#[cfg(test)]
mod tests {
    use std::f32::consts::PI;

    use super::*;
    use crate::sampling::Rng;

    fn dir(cos: f32, phi: f32) -> Vec3A {
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        Vec3A::new(sin * phi.cos(), sin * phi.sin(), cos)
    }

    /// The albedo the model gives a base of albedo `c`: `E(o) + c t(o) X / divisor(c)`,
    /// `X = 2 int t(mu) mu dmu` by a fine midpoint rule.
    fn predicted_albedo(c: f32, eta: f32, alpha: f32, cos_o: f32) -> f64 {
        let (eta, alpha) = clean(eta, alpha);
        let n = 20_000;
        let mut s = 0.0f64;
        for m in 0..n {
            let mu = (m as f32 + 0.5) / n as f32;
            s += f64::from(coat_transmission(eta, alpha, mu) * mu);
        }
        let exit = 2.0 * s / n as f64;
        let e = f64::from(coat_albedo(eta, alpha, cos_o));
        let t = f64::from(coat_transmission(eta, alpha, cos_o));
        let div = f64::from(base_divisor(Vec3A::splat(c), eta, alpha).x);
        e + f64::from(c) * t * exit / div
    }

    /// White furnace: with a white base the mean sample weight (the directional albedo) never
    /// exceeds one and is what the model predicts (and so with a grey base of 0.5, where the
    /// light bouncing between base and coat is dimmed at each round); a smooth coat conserves energy exactly
    /// (the prediction is one: `1 - Fdr_out = eta^2 (1 - Fdr_in)`). The tolerance beyond the
    /// Monte Carlo error (5 standard errors) is 0.01: the rough coat's tabulated `E` is
    /// interpolated, the lobe sampled exactly.
    #[test]
    fn white_furnace_albedo_is_at_most_one_and_as_predicted() {
        let mut rng = Rng::new(7);
        for eta in [1.3f32, 1.5, 2.2] {
            for alpha in [0.0f32, 0.01, 0.1, 0.3, 1.0] {
                for cos_o in [1.0f32, 0.7, 0.3, 0.05] {
                    for c in [1.0f32, 0.5] {
                        let wo = dir(cos_o, 0.3);
                        let n = 40_000;
                        let (mut s, mut s2) = (0.0f64, 0.0f64);
                        for _ in 0..n {
                            let w = sample(Vec3A::splat(c), eta, alpha, wo, rng.f32(), rng.vec2())
                                .map_or(0.0, |b| f64::from(b.weight.x));
                            s += w;
                            s2 += w * w;
                        }
                        let mean = s / n as f64;
                        let se = ((s2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
                        let want = predicted_albedo(c, eta, alpha, cos_o);
                        let at = format!("base {c}, eta {eta}, alpha {alpha}, cos_o {cos_o}");
                        assert!(mean <= 1.0 + 5.0 * se, "{at}: albedo {mean} (se {se})");
                        assert!(want <= 1.0 + 1e-3, "{at}: predicted {want}");
                        assert!(
                            (mean - want).abs() <= 5.0 * se + 0.01,
                            "{at}: {mean} vs predicted {want} (se {se})"
                        );
                        if alpha == 0.0 && c == 1.0 {
                            assert!((want - 1.0).abs() < 2e-3, "{at}: predicted {want}");
                        }
                    }
                }
            }
        }
    }

    /// `f` (the rough coat's lobe and the base) is symmetric in its two directions.
    #[test]
    fn f_is_reciprocal() {
        let mut rng = Rng::new(11);
        let albedo = Vec3A::new(0.8, 0.3, 0.1);
        for alpha in [0.0f32, 0.02, 0.2, 0.7] {
            for _ in 0..5000 {
                let wo = dir(rng.f32(), 2.0 * PI * rng.f32());
                let wi = dir(rng.f32(), 2.0 * PI * rng.f32());
                let (a, b) = (f(albedo, 1.5, alpha, wo, wi), f(albedo, 1.5, alpha, wi, wo));
                assert!(
                    (a - b).abs().max_element() <= 1e-4 * a.max_element().max(1e-3),
                    "alpha {alpha}: {a} vs {b}"
                );
            }
        }
    }

    /// A sample's weight is `f cos / pdf` and its density is [`pdf`]'s; a smooth coat's
    /// mirror sample weighs `F / P(coat)` with that probability as its `pdf`.
    #[test]
    fn sample_weight_is_f_cos_over_pdf() {
        let mut rng = Rng::new(13);
        let albedo = Vec3A::new(0.7, 0.4, 0.2);
        let (mut mirror, mut other) = (0, 0);
        for alpha in [0.0f32, 0.05, 0.4, 1.0] {
            for _ in 0..20_000 {
                let wo = dir(rng.f32(), 2.0 * PI * rng.f32());
                let Some(s) = sample(albedo, 1.5, alpha, wo, rng.f32(), rng.vec2()) else {
                    continue;
                };
                if s.specular {
                    mirror += 1;
                    assert_eq!(alpha, 0.0);
                    assert!((s.wi - Vec3A::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
                    let ps = coat_probability(albedo, 1.5, 0.0, wo.z);
                    assert!((s.pdf - ps).abs() < 1e-6);
                    let want = fresnel(wo.z, 1.5) / ps;
                    assert!((s.weight.x - want).abs() <= 1e-5 * want, "{s:?}");
                    continue;
                }
                other += 1;
                let p = pdf(albedo, 1.5, alpha, wo, s.wi);
                assert!((s.pdf / p - 1.0).abs() < 1e-5, "{} vs {p}", s.pdf);
                let want = f(albedo, 1.5, alpha, wo, s.wi) * s.wi.z / p;
                assert!(
                    (s.weight - want).abs().max_element() <= 1e-4 * want.max_element(),
                    "{} vs {want}",
                    s.weight
                );
            }
        }
        assert!(mirror > 1000 && other > 50_000, "{mirror} {other}");
    }

    /// Sampling follows `pdf` (rough coats): a chi-square test over 16 x 24 bins in
    /// `(cos theta, phi)`, expected counts from `pdf` integrated by a 24 x 24 midpoint rule
    /// per bin (`dw = dcos dphi`), bins expected below 5 pooled. The statistic must stay below
    /// `dof + 5 sqrt(2 dof)` (about a 1e-5 chance for a correct sampler).
    #[test]
    fn chi_square_sample_matches_pdf() {
        const NC: usize = 16;
        const NP: usize = 24;
        const SUB: usize = 24;
        let mut rng = Rng::new(23);
        let albedo = Vec3A::new(0.5, 0.5, 0.5);
        for alpha in [0.15f32, 0.4, 1.0] {
            for cos_o in [0.9f32, 0.4, 0.1] {
                let wo = dir(cos_o, 0.0);
                let n = 300_000usize;
                let mut observed = [0f64; NC * NP];
                for _ in 0..n {
                    if let Some(s) = sample(albedo, 1.5, alpha, wo, rng.f32(), rng.vec2()) {
                        let c = ((s.wi.z * NC as f32) as usize).min(NC - 1);
                        let phi = s.wi.y.atan2(s.wi.x).rem_euclid(2.0 * PI);
                        let p = ((phi / (2.0 * PI) * NP as f32) as usize).min(NP - 1);
                        observed[c * NP + p] += 1.0;
                    }
                }
                let (dc, dp) = (1.0 / NC as f64, 2.0 * std::f64::consts::PI / NP as f64);
                let mut expected = [0f64; NC * NP];
                for c in 0..NC {
                    for p in 0..NP {
                        let mut sum = 0.0f64;
                        for a in 0..SUB {
                            for b in 0..SUB {
                                let cos = (c as f64 + (a as f64 + 0.5) / SUB as f64) * dc;
                                let phi = (p as f64 + (b as f64 + 0.5) / SUB as f64) * dp;
                                let wi = dir(cos as f32, phi as f32);
                                sum += f64::from(pdf(albedo, 1.5, alpha, wo, wi));
                            }
                        }
                        expected[c * NP + p] = sum / (SUB * SUB) as f64 * dc * dp * n as f64;
                    }
                }
                let (mut chi2, mut dof) = (0.0f64, 0usize);
                let (mut pool_o, mut pool_e) = (0.0f64, 0.0f64);
                for (o, e) in observed.iter().zip(&expected) {
                    if *e < 5.0 {
                        pool_o += o;
                        pool_e += e;
                    } else {
                        chi2 += (o - e) * (o - e) / e;
                        dof += 1;
                    }
                }
                if pool_e >= 5.0 {
                    chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                    dof += 1;
                }
                let dof = (dof - 1) as f64;
                let limit = dof + 5.0 * (2.0 * dof).sqrt();
                assert!(
                    chi2 < limit,
                    "alpha {alpha}, cos_o {cos_o}: chi2 {chi2} over {dof} dof (limit {limit})"
                );
            }
        }
    }

    /// No NaN, infinity or negative value from `f`, `pdf` or `sample` over a million random
    /// inputs: directions anywhere on the sphere (grazing ones included), roughness down to
    /// 1e-4, indices out of range and not finite.
    #[test]
    fn random_inputs_give_finite_non_negative_values() {
        let mut rng = Rng::new(29);
        let etas = [1.0f32, 1.0001, 1.5, 3.0, 0.5, 40.0, f32::NAN];
        let alphas = [0.0f32, 1e-8, 1e-4, 0.01, 0.3, 1.0, 2.0];
        for k in 0..1_000_000u32 {
            let eta = etas[k as usize % etas.len()];
            let alpha = alphas[(k as usize / etas.len()) % alphas.len()];
            let albedo = Vec3A::new(rng.f32(), rng.f32(), rng.f32());
            // Every fourth direction grazes the surface.
            let graze = |c: f32, k: u32| {
                if k.is_multiple_of(4) {
                    c * 1e-5
                } else {
                    2.0 * c - 1.0
                }
            };
            let wo = dir(graze(rng.f32(), k), 2.0 * PI * rng.f32()).normalize();
            let wi = dir(graze(rng.f32(), k / 2), 2.0 * PI * rng.f32()).normalize();
            let v = f(albedo, eta, alpha, wo, wi);
            let p = pdf(albedo, eta, alpha, wo, wi);
            assert!(
                v.is_finite() && v.min_element() >= 0.0,
                "f {v} at {eta} {alpha}"
            );
            assert!(p.is_finite() && p >= 0.0, "pdf {p} at {eta} {alpha}");
            if let Some(s) = sample(albedo, eta, alpha, wo, rng.f32(), rng.vec2()) {
                assert!(
                    s.weight.is_finite() && s.weight.min_element() >= 0.0,
                    "weight {} at {eta} {alpha}",
                    s.weight
                );
                assert!(s.pdf.is_finite() && s.pdf > 0.0 && s.wi.is_finite());
            }
        }
    }
}
