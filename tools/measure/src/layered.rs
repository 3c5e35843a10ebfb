//! Directional albedos of the coated and rough-metal BSDFs against references that simulate
//! what the product's closed forms approximate (`sppm-measure coat`, `sppm-measure furnace`).
//!
//! The coat's reference is a stochastic random walk through the layer, as pbrt-v4's
//! `LayeredBxDF` evaluates one (written here from the model, not from its code): a rough
//! dielectric interface (GGX, the product's separable Smith masking, visible-normal sampling,
//! Walter et al. 2007 reflection and refraction by the Fresnel equations on each microfacet)
//! over a Lambertian base of albedo `c`, with nothing between them (no thickness, no
//! absorption). A path enters at `wo`, and every time it meets the interface it reflects or
//! refracts with the interface's own sampling weight; every time it meets the base it is
//! scattered up by the cosine and multiplied by `c`. Its mean weight on leaving is the layer's
//! directional albedo, exactly (no approximation beyond the interface's single-scattering
//! microfacet model, which the product's coat lobe shares), to within the Monte Carlo error.
//!
//! The product's values are the mean sample weights of its own `Bsdf::sample`.

use glam::{Vec2, Vec3A};
use sppm_lang::internals::materials::{Bsdf, Lobes, TransportMode};
use sppm_lang::internals::sampling::Rng;

/// Fresnel reflectance of a smooth dielectric interface for light arriving at `cos` (> 0)
/// from the side where the relative index (far side over near side) is `eta`.
fn fresnel(cos: f64, eta: f64) -> f64 {
    let sin2_t = (1.0 - cos * cos).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos - eta * cos_t) / (cos + eta * cos_t);
    let rp = (eta * cos - cos_t) / (eta * cos + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Smith's masking of the GGX distribution for direction `w` (upper hemisphere).
fn g1(w: [f64; 3], alpha: f64) -> f64 {
    let cos2 = w[2] * w[2];
    if cos2 <= 0.0 {
        return 0.0;
    }
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / l, v[1] / l, v[2] / l]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A GGX normal visible from `wo` (upper hemisphere), Heitz 2018, "Sampling the GGX
/// Distribution of Visible Normals".
fn visible_normal(wo: [f64; 3], alpha: f64, u1: f64, u2: f64) -> [f64; 3] {
    let vh = normalize([alpha * wo[0], alpha * wo[1], wo[2]]);
    let len2 = vh[0] * vh[0] + vh[1] * vh[1];
    let t1 = if len2 > 0.0 {
        let l = len2.sqrt();
        [-vh[1] / l, vh[0] / l, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let t2 = [
        vh[1] * t1[2] - vh[2] * t1[1],
        vh[2] * t1[0] - vh[0] * t1[2],
        vh[0] * t1[1] - vh[1] * t1[0],
    ];
    let r = u1.sqrt();
    let phi = 2.0 * std::f64::consts::PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh[2]);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh = [
        p1 * t1[0] + p2 * t2[0] + p3 * vh[0],
        p1 * t1[1] + p2 * t2[1] + p3 * vh[1],
        p1 * t1[2] + p2 * t2[2] + p3 * vh[2],
    ];
    normalize([alpha * nh[0], alpha * nh[1], nh[2].max(1e-9)])
}

/// One meeting of the path with the interface: `wo` points back along the path (away from
/// the interface, on the side the path comes from), `eta` is the inside's index over the
/// outside's. Returns the direction the path leaves in and its weight (`f |cos| / pdf` of the
/// rough dielectric, importance transport), or `None` where the sample is lost (a microfacet
/// sends it into the macro-surface).
fn interface(wo: [f64; 3], eta: f64, alpha: f64, rng: &mut Rng) -> Option<([f64; 3], f64)> {
    let s = if wo[2] > 0.0 { 1.0 } else { -1.0 };
    let o = [wo[0] * s, wo[1] * s, wo[2] * s];
    let etap = if s > 0.0 { eta } else { 1.0 / eta };
    let m = visible_normal(o, alpha, f64::from(rng.f32()), f64::from(rng.f32()));
    let om = dot(o, m);
    if om <= 0.0 {
        return None;
    }
    let wi = if f64::from(rng.f32()) < fresnel(om, etap) {
        let wi = [
            2.0 * om * m[0] - o[0],
            2.0 * om * m[1] - o[1],
            2.0 * om * m[2] - o[2],
        ];
        if wi[2] <= 0.0 {
            return None;
        }
        wi
    } else {
        let sin2_t = (1.0 - om * om).max(0.0) / (etap * etap);
        let cos_t = (1.0 - sin2_t).sqrt();
        let k = om / etap - cos_t;
        let wi = normalize([
            -o[0] / etap + k * m[0],
            -o[1] / etap + k * m[1],
            -o[2] / etap + k * m[2],
        ]);
        if wi[2] >= 0.0 {
            return None;
        }
        wi
    };
    // Separable Smith: f |cos_i| / pdf of visible-normal sampling is G1(wi), reflected or
    // refracted (importance transport: no 1/eta^2, which cancels over a path that enters and
    // leaves).
    let w = g1([wi[0], wi[1], wi[2].abs()], alpha);
    Some(([wi[0] * s, wi[1] * s, wi[2] * s], w))
}

/// Directional albedo of a rough dielectric coat (GGX `alpha`, index `eta`) over a Lambertian
/// base of albedo `c`, seen at `cos`, by `n` random walks: (mean, standard error).
pub fn layered_albedo(cos: f64, eta: f64, alpha: f64, c: f64, n: u64, seed: u64) -> (f64, f64) {
    let mut rng = Rng::new(seed);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    for _ in 0..n {
        let mut wo = [sin, 0.0, cos];
        let mut beta = 1.0f64;
        let mut out = 0.0;
        for depth in 0..256 {
            let Some((wi, w)) = interface(wo, eta, alpha, &mut rng) else {
                break;
            };
            beta *= w;
            if wi[2] > 0.0 {
                out = beta;
                break;
            }
            // Down to the base: scattered up by the cosine, times the base's albedo.
            beta *= c;
            let u = (f64::from(rng.f32()), f64::from(rng.f32()));
            let r = u.0.sqrt();
            let phi = 2.0 * std::f64::consts::PI * u.1;
            let up = [r * phi.cos(), r * phi.sin(), (1.0 - u.0).max(0.0).sqrt()];
            // Back at the interface from inside: wo points down, back along the path.
            wo = [-up[0], -up[1], -up[2]];
            // Russian roulette once the path has bounced a few times.
            if depth > 4 {
                let q = beta.min(0.95);
                if f64::from(rng.f32()) >= q {
                    break;
                }
                beta /= q;
            }
        }
        sum += out;
        sum2 += out * out;
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(0.0);
    (mean, (var / n as f64).sqrt())
}

/// Mean sample weight (red channel) of the product's BSDF `lobes` seen at `cos`, over `n`
/// samples: its directional albedo, (mean, standard error).
pub fn product_albedo(lobes: Lobes, cos: f64, n: u64, seed: u64) -> (f64, f64) {
    let b = Bsdf::new(lobes, Vec3A::Z, Vec3A::X, Vec3A::Z);
    let mut rng = Rng::new(seed);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let wo = Vec3A::new(sin as f32, 0.0, cos as f32);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let uc = rng.f32();
        let u = Vec2::new(rng.f32(), rng.f32());
        let w = b
            .sample(wo, uc, u, TransportMode::Radiance)
            .map_or(0.0, |s| f64::from(s.weight.x));
        sum += w;
        sum2 += w * w;
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(0.0);
    (mean, (var / n as f64).sqrt())
}

/// The coat table: for each roughness, base albedo and angle, the random walk's albedo and the
/// product's, as Markdown rows.
pub fn coat_table(eta: f64, n: u64) -> String {
    let mut out = String::from(
        "| roughness | base c | cos | random walk | ours | ours / walk |\n|---|---|---|---|---|---|\n",
    );
    for r in [0.2f64, 0.45, 0.8] {
        let alpha = r * r;
        for c in [1.0f64, 0.7, 0.15] {
            for cos in [1.0f64, 0.7, 0.4, 0.15] {
                let (t, te) = layered_albedo(cos, eta, alpha, c, n, 17);
                let lobes = Lobes::Coated {
                    albedo: Vec3A::splat(c as f32),
                    eta: eta as f32,
                    alpha: alpha as f32,
                };
                let (o, oe) = product_albedo(lobes, cos, n, 23);
                out += &format!(
                    "| {r} | {c} | {cos} | {t:.4} ± {te:.4} | {o:.4} ± {oe:.4} | {:.4} |\n",
                    o / t
                );
            }
        }
    }
    out
}

/// White-furnace albedo of the rough metal lobe with a Fresnel of one (the `glossy` lobe with
/// `specular` 1, the same GGX lobe as `conductor`'s): the energy its single scattering loses.
pub fn furnace_table(n: u64) -> String {
    let cosines = [1.0f64, 0.7, 0.4, 0.15, 0.05];
    let mut out = String::from("| roughness | alpha |");
    for c in cosines {
        out += &format!(" cos {c} |");
    }
    out += "\n|---|---|";
    out += &"---|".repeat(cosines.len());
    out += "\n";
    for r in [0.1f64, 0.2, 0.35, 0.5, 0.65, 0.8, 1.0] {
        let alpha = r * r;
        out += &format!("| {r} | {alpha:.4} |");
        for cos in cosines {
            let lobes = Lobes::Glossy {
                albedo: Vec3A::ZERO,
                specular: Vec3A::ONE,
                alpha: alpha as f32,
            };
            let (a, _) = product_albedo(lobes, cos, n, 31);
            out += &format!(" {a:.4} |");
        }
        out += "\n";
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With a white base the layer loses nothing but what the interface's masking loses, so at
    /// low roughness the walk's albedo is close to one; with a black base it is the interface's
    /// own reflection albedo, which at roughness ~0 is the Fresnel reflectance (0.04 head-on for
    /// n = 1.5).
    #[test]
    fn walk_limits() {
        let (a, e) = layered_albedo(1.0, 1.5, 1e-3, 1.0, 40_000, 1);
        assert!((a - 1.0).abs() < 0.005 + 4.0 * e, "{a}");
        let (a, e) = layered_albedo(1.0, 1.5, 1e-3, 0.0, 40_000, 2);
        assert!((a - 0.04).abs() < 4.0 * e + 1e-3, "{a}");
    }
}
