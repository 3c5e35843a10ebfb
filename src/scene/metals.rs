//! Named metals for `conductor metal "Au"`: complex indices of refraction `eta + i k` per RGB
//! channel, and the artist-friendly parametrisation (reflectance and edge tint) mapped to them.
//!
//! The values are measured spectral data sampled at one wavelength per channel, not averages
//! over the CIE matching functions: Ag, Al, Au, Cr, Cu, Fe, Ni, Pt and Ti are refractiveindex.info
//! measurements at 642, 529 and 464 nm (as tabulated for 3Delight's metal presets); brass is the
//! RGB reduction of the CuZn spectrum pbrt-v4 ships. A spectral renderer would integrate each
//! channel; at these wavelengths the normal-incidence reflectances match the familiar metal
//! colours (gold about 0.93/0.61/0.25).

use super::Color;

/// A named metal: its chemical symbol and its English name (either names it in the
/// language), `eta` and `k`.
pub struct Metal {
    pub name: &'static str,
    pub long_name: &'static str,
    pub eta: [f64; 3],
    pub k: [f64; 3],
}

const fn m(name: &'static str, long_name: &'static str, eta: [f64; 3], k: [f64; 3]) -> Metal {
    Metal {
        name,
        long_name,
        eta,
        k,
    }
}

/// Every metal `conductor metal "..."` knows.
pub static METALS: [Metal; 10] = [
    m(
        "Ag",
        "silver",
        [0.13708, 0.12945, 0.14075],
        [4.0625, 3.1692, 2.6034],
    ),
    m(
        "Al",
        "aluminium",
        [1.50694, 0.926041, 0.68251],
        [7.6307, 6.3849, 5.6230],
    ),
    m(
        "Au",
        "gold",
        [0.18267, 0.49447, 1.3761],
        [3.1178, 2.3515, 1.8324],
    ),
    m(
        "Cr",
        "chromium",
        [3.11847, 3.02492, 2.44207],
        [3.3190, 3.3322, 3.2034],
    ),
    m(
        "Cu",
        "copper",
        [0.23268, 1.075714, 1.15753],
        [3.5315, 2.5945, 2.4473],
    ),
    m(
        "Fe",
        "iron",
        [2.9038, 2.8857, 2.6420],
        [3.0798, 2.9157, 2.8025],
    ),
    m(
        "Ni",
        "nickel",
        [1.99412, 1.73204, 1.64542],
        [3.7682, 3.1316, 2.7371],
    ),
    m(
        "Pt",
        "platinum",
        [2.35423, 2.06875, 1.88085],
        [4.1988, 3.6120, 3.2271],
    ),
    m(
        "Ti",
        "titanium",
        [2.18385, 1.8364, 1.72103],
        [2.9550, 2.5188, 2.3034],
    ),
    m(
        "brass",
        "brass",
        [0.444, 0.527, 1.094],
        [3.695, 2.765, 1.829],
    ),
];

/// The metal called `name` (its symbol or its English name), if the table has it.
pub fn metal(name: &str) -> Option<&'static Metal> {
    METALS
        .iter()
        .find(|m| m.name == name || m.long_name == name)
}

/// Every name [`metal`] accepts, symbols first.
pub fn metal_names() -> impl Iterator<Item = &'static str> + Clone {
    METALS
        .iter()
        .map(|m| m.name)
        .chain(METALS.iter().map(|m| m.long_name).filter(|n| *n != "brass"))
}

/// The largest reflectance the artist mapping accepts: at 1 the index of refraction is
/// unbounded.
pub const MAX_ARTIST_REFLECTANCE: f64 = 0.99;

/// Gulbrandsen 2014, "Artist Friendly Metallic Fresnel": the `eta` and `k` whose Fresnel
/// reflectance is `r` at normal incidence and bends toward `g` (the edge tint) near grazing.
/// `r` is clamped to [0, 0.99] and `g` to [0, 1] per channel.
pub fn artist_to_eta_k(r: Color, g: Color) -> (Color, Color) {
    let r = r.clamp(Color::ZERO, Color::splat(MAX_ARTIST_REFLECTANCE));
    let g = g.clamp(Color::ZERO, Color::ONE);
    let sr = r.map(f64::sqrt);
    let n_min = (Color::ONE - r) / (Color::ONE + r);
    let n_max = (Color::ONE + sr) / (Color::ONE - sr);
    let eta = g * n_min + (Color::ONE - g) * n_max;
    let np1 = eta + Color::ONE;
    let nm1 = eta - Color::ONE;
    let k2 = (r * np1 * np1 - nm1 * nm1) / (Color::ONE - r);
    (eta, k2.max(Color::ZERO).map(f64::sqrt))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Normal-incidence reflectance of a complex index: `((n-1)^2 + k^2) / ((n+1)^2 + k^2)`.
    fn f0(eta: f64, k: f64) -> f64 {
        ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k)
    }

    /// The artist mapping reproduces its reflectance at normal incidence (its defining
    /// property), for every edge tint.
    #[test]
    fn artist_mapping_keeps_the_reflectance() {
        for r in [0.05, 0.3, 0.6, 0.9, 0.98] {
            for g in [0.0, 0.5, 1.0] {
                let (eta, k) = artist_to_eta_k(Color::splat(r), Color::splat(g));
                let got = f0(eta.x, k.x);
                assert!((got - r).abs() < 1e-9, "r {r}, g {g}: {got}");
            }
        }
    }

    /// Gold is yellow at normal incidence (red > green > blue) and silver is near white:
    /// the table's channels are in R, G, B order.
    #[test]
    fn table_colours_are_in_rgb_order() {
        let au = metal("Au").unwrap();
        let f: Vec<f64> = (0..3).map(|i| f0(au.eta[i], au.k[i])).collect();
        assert!(f[0] > 0.85 && f[0] > f[1] && f[1] > f[2], "{f:?}");
        let ag = metal("Ag").unwrap();
        assert!((0..3).all(|i| f0(ag.eta[i], ag.k[i]) > 0.85));
    }
}
