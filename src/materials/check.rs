//! A test harness for every lobe (test builds only). For a BSDF in the shading frame z-up and
//! an outgoing direction it checks:
//! (a) `sample` draws directions distributed as `pdf` says: a chi-square goodness-of-fit test
//!     on the sphere binned in (cos theta, phi), the expected counts integrating `pdf` over
//!     each bin (composite Simpson, adaptive; a bin that got samples where it found no
//!     density is integrated again on a grid 64 times finer), bins expecting fewer than 5
//!     samples pooled (after Mitsuba 3's `ChiSquareTest`); the p-value must stay above a significance divided by
//!     the number of tests the caller runs (Bonferroni);
//! (b) `pdf` integrates to at most one;
//! (c) `f(wo, wi) = f(wi, wo)`; for frosted glass, which transmits, the generalized form
//!     `f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2` over the whole sphere (`n` the index on each
//!     direction's side, radiance mode), and the importance value equal to `f(wi, wo)`; for a
//!     bumped BSDF, which is not reciprocal, only the importance value's identity;
//! (d) the directional albedo (mean sample weight) is at most one; in radiance mode a
//!     refracted sample's weight is first turned into importance (times `(n_i / n_o)^2`),
//!     since radiance entering a denser medium is concentrated, not created;
//! (e) each sample's weight is `f |cos| / pdf` (`f` in the sample's transport mode) and its
//!     density is `pdf(wo, wi)`;
//! [`delta_choice`] checks (a) for a delta lobe that reflects or passes light (the choice's
//! frequency), and [`no_nan`] checks (f): finite, non-negative values on random inputs.

use std::f64::consts::PI;

use glam::{Vec2, Vec3A};

use super::{Bsdf, Lobes, TransportMode};
use crate::sampling::{Rng, uniform_sphere};

/// Bins in cos theta (over [-1, 1]) and phi.
const COS_BINS: usize = 40;
const PHI_BINS: usize = 80;
/// Simpson intervals per bin side (even).
const SUB: usize = 4;
const SAMPLES: usize = 200_000;
/// Overall false-failure rate of a run of chi-square tests.
pub(super) const SIGNIFICANCE: f64 = 0.01;

pub(super) fn bsdf(lobes: Lobes) -> Bsdf {
    Bsdf::new(lobes, Vec3A::Z, Vec3A::X, Vec3A::Z)
}

/// The direction with `cos theta = cos_o` in the xz plane.
pub(super) fn wo_at(cos_o: f32) -> Vec3A {
    Vec3A::new((1.0 - cos_o * cos_o).max(0.0).sqrt(), 0.0, cos_o)
}

fn direction(c: f64, phi: f64) -> Vec3A {
    let s = (1.0 - c * c).max(0.0).sqrt();
    Vec3A::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32)
}

fn bin_of(w: Vec3A) -> usize {
    let c = ((f64::from(w.z) + 1.0) / 2.0 * COS_BINS as f64).floor() as isize;
    let mut phi = f64::from(w.y).atan2(f64::from(w.x));
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let p = (phi / (2.0 * PI) * PHI_BINS as f64).floor() as isize;
    let c = c.clamp(0, COS_BINS as isize - 1) as usize;
    let p = p.clamp(0, PHI_BINS as isize - 1) as usize;
    c * PHI_BINS + p
}

/// `pdf` integrated over every bin (solid angle is `d cos dphi`), by adaptive Simpson: a cell
/// whose rule disagrees with the sum over its four quarters by more than [`TOLERANCE`] (about a
/// twentieth of a sample) is split, so that the sharp ridge of a grazing lobe against the
/// horizon is resolved.
fn expected_mass(b: &Bsdf, wo: Vec3A) -> Vec<f64> {
    let (dc, dp) = (2.0 / COS_BINS as f64, 2.0 * PI / PHI_BINS as f64);
    let mut mass = vec![0.0; COS_BINS * PHI_BINS];
    for ci in 0..COS_BINS {
        for pi in 0..PHI_BINS {
            let (c0, p0) = (-1.0 + dc * ci as f64, dp * pi as f64);
            let whole = simpson(b, wo, c0, p0, dc, dp);
            mass[ci * PHI_BINS + pi] = adaptive(b, wo, (c0, p0, dc, dp), whole, 0);
        }
    }
    mass
}

const TOLERANCE: f64 = 0.05 / SAMPLES as f64;
const MAX_SPLITS: u32 = 7;

fn adaptive(b: &Bsdf, wo: Vec3A, cell: (f64, f64, f64, f64), whole: f64, depth: u32) -> f64 {
    let (c0, p0, dc, dp) = cell;
    let (hc, hp) = (dc / 2.0, dp / 2.0);
    let quarters = [(c0, p0), (c0 + hc, p0), (c0, p0 + hp), (c0 + hc, p0 + hp)];
    let parts = quarters.map(|(c, p)| simpson(b, wo, c, p, hc, hp));
    let refined: f64 = parts.iter().sum();
    if depth >= MAX_SPLITS || (refined - whole).abs() <= TOLERANCE / f64::from(1u32 << (2 * depth))
    {
        return refined;
    }
    quarters
        .iter()
        .zip(parts)
        .map(|(&(c, p), part)| adaptive(b, wo, (c, p, hc, hp), part, depth + 1))
        .sum()
}

/// How many times [`finely`] halves a cell's sides.
const SLIVER_SPLITS: u32 = 6;

/// `pdf` over a cell by Simpson on each of its `4^splits` sub-cells.
fn finely(b: &Bsdf, wo: Vec3A, cell: (f64, f64, f64, f64), splits: u32) -> f64 {
    let (c0, p0, dc, dp) = cell;
    if splits == 0 {
        return simpson(b, wo, c0, p0, dc, dp);
    }
    let (hc, hp) = (dc / 2.0, dp / 2.0);
    [(c0, p0), (c0 + hc, p0), (c0, p0 + hp), (c0 + hc, p0 + hp)]
        .iter()
        .map(|&(c, p)| finely(b, wo, (c, p, hc, hp), splits - 1))
        .sum()
}

/// Composite Simpson over one cell with [`SUB`] intervals a side.
fn simpson(b: &Bsdf, wo: Vec3A, c0: f64, p0: f64, dc: f64, dp: f64) -> f64 {
    let weight = |i: usize| match i {
        0 => 1.0,
        i if i == SUB => 1.0,
        i if i % 2 == 1 => 4.0,
        _ => 2.0,
    };
    let mut sum = 0.0;
    for a in 0..=SUB {
        let c = c0 + dc * a as f64 / SUB as f64;
        for q in 0..=SUB {
            let phi = p0 + dp * q as f64 / SUB as f64;
            sum += weight(a) * weight(q) * f64::from(b.pdf(wo, direction(c, phi)));
        }
    }
    sum * dc * dp / (SUB * SUB * 9) as f64
}

/// Upper tail of the chi-square distribution with `dof` degrees of freedom at `x`, by the
/// Wilson-Hilferty cube-root normal approximation (accurate to a few percent of the p-value
/// for the hundreds of degrees of freedom these tests have).
fn chi2_p_value(x: f64, dof: f64) -> f64 {
    let t = 2.0 / (9.0 * dof);
    let z = ((x / dof).powf(1.0 / 3.0) - (1.0 - t)) / t.sqrt();
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

/// Complementary error function (Numerical Recipes' `erfcc`, relative error below 1.2e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// The index of refraction on the side of local direction `w` (one but inside a glass).
fn index_at(b: &Bsdf, w: Vec3A) -> f32 {
    match b.lobes {
        Lobes::Glass { eta, .. } if w.z < 0.0 => eta,
        _ => 1.0,
    }
}

/// Runs (a) to (e) for `b` at `wo`, in radiance mode; `tests` is how many chi-square tests the
/// caller runs in all (for the Bonferroni correction). Returns a description of the first
/// failure.
pub(super) fn check(b: &Bsdf, wo: Vec3A, tests: usize, seed: u64) -> Result<(), String> {
    check_mode(b, wo, tests, seed, TransportMode::Radiance)
}

/// [`check`] for paths carrying `mode`.
pub(super) fn check_mode(
    b: &Bsdf,
    wo: Vec3A,
    tests: usize,
    seed: u64,
    mode: TransportMode,
) -> Result<(), String> {
    let mut rng = Rng::new(seed);
    let mut counts = vec![0u64; COS_BINS * PHI_BINS];
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..SAMPLES {
        let Some(s) = b.sample(wo, rng.f32(), rng.vec2(), mode) else {
            continue;
        };
        let to_importance = match mode {
            TransportMode::Radiance => (index_at(b, s.wi) / index_at(b, wo)).powi(2),
            TransportMode::Importance => 1.0,
        };
        let w = f64::from(s.weight.max_element() * to_importance);
        sum += w;
        sum2 += w * w;
        if s.specular {
            continue;
        }
        // (e) The weight and density agree with f and pdf.
        let pdf = b.pdf(wo, s.wi);
        let want = b.f_mode(wo, s.wi, mode) * s.wi.dot(b.frame.n).abs() / pdf;
        let rel = |x: f32, y: f32| (x - y).abs() <= 1e-3 * x.abs().max(y.abs()) + 1e-6;
        if !(rel(s.pdf, pdf) && (0..3).all(|i| rel(s.weight[i], want[i]))) {
            return Err(format!(
                "sample weight {} / pdf {} but f cos / pdf = {want} / {pdf} at wi {}",
                s.weight, s.pdf, s.wi
            ));
        }
        counts[bin_of(s.wi)] += 1;
    }
    // (d) Directional albedo of the brightest channel's samples, within sampling error.
    let n = SAMPLES as f64;
    let mean = sum / n;
    let se = ((sum2 / n - mean * mean).max(0.0) / n).sqrt();
    if mean > 1.0 + 4.0 * se + 1e-3 {
        return Err(format!("directional albedo {mean} > 1 (se {se})"));
    }
    if b.is_specular() {
        return Ok(());
    }
    let mut mass = expected_mass(b, wo);
    // A bin that got samples where the quadrature found no density holds a sliver of the
    // lobe narrower than its evaluation points (light refracted out of glass at grazing
    // incidence from inside): integrate it again on a grid [`SLIVER_SPLITS`] times finer.
    for (i, m) in mass.iter_mut().enumerate() {
        if *m == 0.0 && counts[i] > 0 {
            let (ci, pi) = (i / PHI_BINS, i % PHI_BINS);
            let (dc, dp) = (2.0 / COS_BINS as f64, 2.0 * PI / PHI_BINS as f64);
            let cell = (-1.0 + dc * ci as f64, dp * pi as f64, dc, dp);
            *m = finely(b, wo, cell, SLIVER_SPLITS);
        }
    }
    // (b) The density integrates to at most one.
    let total: f64 = mass.iter().sum();
    if total > 1.0 + 2e-3 {
        return Err(format!("pdf integrates to {total}"));
    }
    // (a) Chi-square, low-expectation bins pooled.
    let (mut chi2, mut dof) = (0.0, 0usize);
    let (mut pool_exp, mut pool_obs) = (0.0, 0.0);
    // Samples in bins where even the finer quadrature found no density: (e) proved
    // `pdf > 0` at each sample, so these are slivers narrower still; a few join the pool,
    // more fail.
    let mut unresolved = 0.0;
    for (&m, &c) in mass.iter().zip(&counts) {
        let (e, o) = (m * n, c as f64);
        if e == 0.0 && o > 0.0 {
            unresolved += o;
        }
        if e < 5.0 {
            pool_exp += e;
            pool_obs += o;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if unresolved > n * 1e-4 {
        return Err(format!("{unresolved} samples fell where pdf is zero"));
    }
    if pool_exp >= 5.0 {
        chi2 += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        dof += 1;
    }
    if dof < 2 {
        return Ok(());
    }
    let p = chi2_p_value(chi2, (dof - 1) as f64);
    let threshold = SIGNIFICANCE / tests as f64;
    if p < threshold {
        return Err(format!(
            "chi-square {chi2:.1} over {dof} bins: p = {p:.3e} < {threshold:.1e}"
        ));
    }
    if b.bump.is_some() {
        return adjoint(b, &mut rng);
    }
    if matches!(b.lobes, Lobes::Glass { .. }) {
        return generalized_reciprocity(b, &mut rng);
    }
    // (c) Reciprocity on random pairs of the upper hemisphere.
    for _ in 0..2000 {
        let (a, c) = (uniform_sphere(rng.vec2()), uniform_sphere(rng.vec2()));
        let (a, c) = (a.with_z(a.z.abs()), c.with_z(c.z.abs()));
        let (x, y) = (b.f(a, c), b.f(c, a));
        if (x - y).abs().max_element() > 1e-4 * x.max_element().max(1.0) {
            return Err(format!("f({a}, {c}) = {x} but f({c}, {a}) = {y}"));
        }
    }
    Ok(())
}

/// (c) for a BSDF that refracts: `f(a, c) / n_a^2 = f(c, a) / n_c^2` on random pairs of the
/// whole sphere (radiance), and the importance value `f*(a, c) = f(c, a)`. Pairs whose half
/// vector lies within a few alphas of the lobe's peak are evaluated to about 1e-3 in `f32`,
/// hence the tolerance.
fn generalized_reciprocity(b: &Bsdf, rng: &mut Rng) -> Result<(), String> {
    let mut nonzero = 0;
    for _ in 0..4000 {
        let (a, c) = (uniform_sphere(rng.vec2()), uniform_sphere(rng.vec2()));
        let (na, nc) = (index_at(b, a), index_at(b, c));
        let (x, y) = (b.f(a, c) / (na * na), b.f(c, a) / (nc * nc));
        let close = |x: Vec3A, y: Vec3A| {
            (x - y).abs().max_element() <= 1e-3 * x.max_element().max(y.max_element()) + 1e-6
        };
        if !close(x, y) {
            return Err(format!(
                "f({a}, {c}) / {na}^2 = {x} but f({c}, {a}) / {nc}^2 = {y}"
            ));
        }
        let adjoint = b.f_mode(a, c, TransportMode::Importance);
        if !close(adjoint, b.f(c, a)) {
            return Err(format!(
                "importance f({a}, {c}) = {adjoint} but f({c}, {a}) = {y}"
            ));
        }
        nonzero += usize::from(x != Vec3A::ZERO && a.z * c.z < 0.0);
    }
    if nonzero < 100 {
        return Err(format!("only {nonzero} refracting pairs had a value"));
    }
    Ok(())
}

/// (c) for a bumped BSDF, which is not reciprocal (bump.rs): the importance value is the
/// adjoint `f*(a, c) = f(c, a)` on random pairs of the whole sphere, bit for bit.
fn adjoint(b: &Bsdf, rng: &mut Rng) -> Result<(), String> {
    let mut nonzero = 0;
    for _ in 0..4000 {
        let (a, c) = (uniform_sphere(rng.vec2()), uniform_sphere(rng.vec2()));
        let (x, y) = (b.f_mode(a, c, TransportMode::Importance), b.f(c, a));
        if x != y {
            return Err(format!(
                "importance f({a}, {c}) = {x} but f({c}, {a}) = {y}"
            ));
        }
        nonzero += usize::from(x != Vec3A::ZERO);
    }
    if nonzero < 100 {
        return Err(format!("only {nonzero} pairs had a value"));
    }
    Ok(())
}

/// (f) `f`, `pdf` and `sample` give finite, non-negative values for `n` random inputs from
/// `lobes` (which draws the parameters), with a quarter of the outgoing directions grazing.
pub(super) fn no_nan(n: usize, seed: u64, mut lobes: impl FnMut(&mut Rng) -> Lobes) {
    let mut rng = Rng::new(seed);
    for i in 0..n {
        let b = bsdf(lobes(&mut rng));
        let wo = if i % 4 == 0 {
            let c = [1e-3f32, 1e-5, 1e-7, -1e-3][i / 4 % 4];
            let phi = rng.f32() * std::f32::consts::TAU;
            let s = (1.0 - c * c).sqrt();
            Vec3A::new(s * phi.cos(), s * phi.sin(), c)
        } else {
            uniform_sphere(rng.vec2())
        };
        let wi = uniform_sphere(rng.vec2());
        let (f, p) = (b.f(wo, wi), b.pdf(wo, wi));
        assert!(
            f.is_finite() && f.min_element() >= 0.0,
            "{:?}: f = {f}",
            b.lobes
        );
        assert!(p.is_finite() && p >= 0.0, "{:?}: pdf = {p}", b.lobes);
        let u = Vec2::new(rng.f32(), rng.f32());
        let mode = if i % 2 == 0 {
            TransportMode::Radiance
        } else {
            TransportMode::Importance
        };
        if let Some(s) = b.sample(wo, rng.f32(), u, mode) {
            assert!(
                s.weight.is_finite() && s.weight.min_element() >= 0.0 && s.pdf >= 0.0,
                "{:?} at wo {wo}: {s:?}",
                b.lobes
            );
        }
    }
}

/// (a) for a delta BSDF that reflects or passes light on (smooth glass, a thin pane): a
/// chi-square test (one degree of freedom) of how often `sample` reflects against the share
/// `reflected` computed independently by the caller, and each sample's direction (the mirror
/// image of `wo`, or `transmitted`) and importance weight (one for a clear lobe: the choice's
/// probability is its share). A choice of probability zero (total internal reflection) must
/// never be made.
pub(super) fn delta_choice(
    b: &Bsdf,
    wo: Vec3A,
    reflected: f64,
    transmitted: Option<Vec3A>,
    tests: usize,
    seed: u64,
) -> Result<(), String> {
    let mut rng = Rng::new(seed);
    let mirror = Vec3A::new(-wo.x, -wo.y, wo.z);
    let close = |a: Vec3A, c: Vec3A| (a - c).abs().max_element() <= 1e-5;
    let mut refl = 0u64;
    for _ in 0..SAMPLES {
        let Some(s) = b.sample(wo, rng.f32(), rng.vec2(), TransportMode::Importance) else {
            return Err("no sample".into());
        };
        if !s.specular || (s.weight - Vec3A::ONE).abs().max_element() > 1e-5 {
            return Err(format!("sample {s:?} is not a clear delta lobe's"));
        }
        if s.wi.z * wo.z > 0.0 {
            if !close(s.wi, mirror) {
                return Err(format!("reflected to {} instead of {mirror}", s.wi));
            }
            refl += 1;
        } else {
            match transmitted {
                Some(t) if close(s.wi, t) => {}
                _ => return Err(format!("passed to {} instead of {transmitted:?}", s.wi)),
            }
        }
    }
    let n = SAMPLES as f64;
    let (o, e) = (refl as f64, reflected * n);
    if e < 5.0 || n - e < 5.0 {
        // One choice is all but certain: the other may be made only as often as expected.
        let (rare_o, rare_e) = if e < 5.0 { (o, e) } else { (n - o, n - e) };
        if rare_o > 5.0 + 10.0 * rare_e {
            return Err(format!(
                "{rare_o} samples of a choice expected {rare_e} times"
            ));
        }
        return Ok(());
    }
    let chi2 = (o - e).powi(2) / e + (o - e).powi(2) / (n - e);
    let p = erfc((chi2 / 2.0).sqrt());
    let threshold = SIGNIFICANCE / tests as f64;
    if p < threshold {
        return Err(format!(
            "reflected {o} of {n} samples, expected {e:.1}: p = {p:.3e} < {threshold:.1e}"
        ));
    }
    Ok(())
}

/// Unpolarised Fresnel reflectance in `f64`, for checking the lobes' own: `cos_i` of the
/// incident direction to the normal on its side, `eta` the index across over the index on
/// its side.
pub(super) fn fresnel64(cos_i: f64, eta: f64) -> f64 {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rp * rp + rs * rs)
}

/// Roughness to GGX alpha as the materials map it.
pub(super) fn alpha(roughness: f32) -> f32 {
    roughness * roughness
}

/// The outgoing directions every lobe is checked at (cosines), down to grazing.
pub(super) const COS_O: [f32; 4] = [1.0, 0.6, 0.15, 1e-3];

#[cfg(test)]
mod tests {
    use super::*;

    /// The p-value approximation is right where it matters: the median of chi-square(k) is
    /// about k (1 - 2/(9k))^3, and a statistic of 2k has a tiny p-value.
    #[test]
    fn p_values_are_sane() {
        let k = 300.0f64;
        let median = k * (1.0 - 2.0 / (9.0 * k)).powi(3);
        assert!((chi2_p_value(median, k) - 0.5).abs() < 1e-3);
        assert!(chi2_p_value(2.0 * k, k) < 1e-12);
        assert!((erfc(0.0) - 1.0).abs() < 1e-7 && (erfc(1.0) - 0.157_299_2).abs() < 1e-6);
    }

    /// Lambertian reflection passes every check.
    #[test]
    fn diffuse_passes() {
        let cases = COS_O.len() * 2;
        for (i, &c) in COS_O.iter().enumerate() {
            for albedo in [Vec3A::splat(1.0), Vec3A::new(0.8, 0.3, 0.1)] {
                let b = bsdf(Lobes::Diffuse { albedo });
                check(&b, wo_at(c), cases, 100 + i as u64).unwrap();
            }
        }
        no_nan(250_000, 1, |r| Lobes::Diffuse {
            albedo: Vec3A::new(r.f32(), r.f32(), r.f32()),
        });
    }

    /// The glossy lobe (GGX over Lambert) passes every check, smooth to rough, with and
    /// without its base, at every angle.
    #[test]
    fn glossy_passes() {
        let params = [
            (0.0, 1.0, 0.3),
            (0.5, 0.04, 0.5),
            (0.5, 0.5, 0.7),
            (0.3, 0.2, 1.0),
        ];
        let cases = COS_O.len() * params.len();
        for (i, &c) in COS_O.iter().enumerate() {
            for (j, &(albedo, specular, roughness)) in params.iter().enumerate() {
                let b = bsdf(Lobes::Glossy {
                    albedo: Vec3A::splat(albedo),
                    specular: Vec3A::splat(specular),
                    alpha: alpha(roughness),
                });
                if let Err(e) = check(&b, wo_at(c), cases, (10 * i + j) as u64) {
                    panic!("glossy {albedo}/{specular}/{roughness} at cos {c}: {e}");
                }
            }
        }
        no_nan(250_000, 2, |r| Lobes::Glossy {
            albedo: Vec3A::splat(r.f32()),
            specular: Vec3A::splat(r.f32()),
            alpha: [1e-8, 1e-3, r.f32()][(r.f32() * 3.0) as usize % 3],
        });
    }
}
