//! How wide a pixel is where its camera path reaches its visible point, through mirrors and
//! glass: the initial SPPM/PPM radius follows it (docs/integrators.md, "The initial radius").
//!
//! Ray differentials as finite differences (pbrt's ray differentials through specular
//! reflection and refraction are the model): two neighbour rays, a fraction of a pixel
//! apart, follow the path's own ray through every specular bounce with the same random numbers
//! (so the same lobe), and the pixel's footprint is where they meet the tangent plane at the
//! visible point. Traced rather than differentiated, they need no surface's normal derivative,
//! and a neighbour that leaves the path's surfaces (a silhouette) or its lobe gives up.

use glam::{Vec2, Vec3A};

use crate::camera::Camera;
use crate::geometry::Ray;
use crate::materials::TransportMode;
use crate::prepare::{EffectiveSettings, InitialRadius, PreparedScene};
use crate::sampling::Rng;

/// The neighbour rays' offset from the path's ray, in pixels: small, so that away from
/// silhouettes they meet the surfaces the path meets.
const OFFSET: f32 = 0.125;

/// The footprint's ratio to a straight ray's is kept within `[MIN_RATIO, 1]`. Below: where
/// the glass focuses the pixel's beam onto the visible point, its footprint in one direction
/// shrinks toward zero, and a radius that small would find no photons. Above: where a convex
/// mirror or the edge of a ball spreads the beam, a radius grown with it blurred the light
/// nearby into the pixel (the Cornell box's glass ball over its caustic: 15 % more squared
/// error at equal CPU time), while the straight rule's smaller radius measured better.
const MIN_RATIO: f64 = 0.125;

/// The initial radius of a pixel whose camera path, traced from the stream `rng` (a copy of
/// the camera pass's, before the path drew from it) through the pixel's centre if `centered`,
/// reached `distance` along itself: the rule's value there, times
/// [`footprint_ratio`] for the footprint rule. `None` where the rule has no usable value.
#[allow(clippy::too_many_arguments)]
pub(crate) fn initial_radius(
    rule: InitialRadius,
    scene: &PreparedScene,
    camera: &Camera,
    settings: &EffectiveSettings,
    (x, y): (u32, u32),
    centered: bool,
    rng: Rng,
    distance: f64,
) -> Option<f64> {
    let r = rule.at(distance)?;
    match rule {
        InitialRadius::Footprint { .. } => {
            let mut rng = rng;
            let ratio = footprint_ratio(scene, camera, settings, (x, y), centered, &mut rng);
            Some(r * ratio.unwrap_or(1.0))
        }
        InitialRadius::Fixed(_) | InitialRadius::Orthographic(_) => Some(r),
    }
}

/// The width of pixel (x, y)'s footprint at the visible point of the camera path `rng` traces
/// (as `camera_path` does: the jitter, the lens, then one BSDF sample per specular bounce),
/// measured across the path's last segment, over the width a straight ray of the path's length
/// would have: exactly 1 where the camera sees the point directly, below 1 where glass or a curved
/// mirror narrows the beam, above 1 where it widens it; kept within `[MIN_RATIO, 1]`. `None`
/// where a neighbour ray parts from the path, the path passes a glossy surface, or the camera
/// is orthographic: the caller keeps the straight-ray rule.
pub(crate) fn footprint_ratio(
    scene: &PreparedScene,
    camera: &Camera,
    settings: &EffectiveSettings,
    (x, y): (u32, u32),
    centered: bool,
    rng: &mut Rng,
) -> Option<f64> {
    let (jitter, lens) = (rng.vec2(), rng.vec2());
    let (jitter, lens) = if centered {
        (Vec2::splat(0.5), Vec2::splat(0.5))
    } else {
        (jitter, lens)
    };
    // Offsets toward the pixel's centre, so that the neighbours stay inside the pixel.
    let step = |j: f32| if j < 0.5 { OFFSET } else { -OFFSET };
    let mut rays = [
        camera.ray(x, y, jitter, lens),
        camera.ray(x, y, jitter + Vec2::new(step(jitter.x), 0.0), lens),
        camera.ray(x, y, jitter + Vec2::new(0.0, step(jitter.y)), lens),
    ];
    let dir = rays.map(|r| r.d.normalize());
    // The straight footprint's width per unit length.
    let spread = perpendicular_width(dir[1] - dir[0], dir[2] - dir[0], dir[0]);
    if !(spread.is_finite() && spread > 0.0) {
        return None;
    }
    let mut length = 0.0f64;
    for depth in 0..settings.max_depth {
        let sh = scene.intersect(&rays[0], f32::INFINITY)?;
        length += f64::from(sh.hit.t * rays[0].d.length());
        let bsdf = scene.bsdf(&sh);
        if !bsdf.is_specular() {
            // Seen directly, the footprint is the straight ray's by definition. Measured
            // instead, the neighbours' crossing of the tangent plane near a silhouette or at
            // a grazing angle gave ratios from 0.2 to infinity, and ones that changed with the
            // scene's scale (1 against 1e10).
            if depth == 0 {
                return Some(1.0);
            }
            if bsdf.is_glossy() && depth + 1 < settings.max_depth {
                return None;
            }
            // The neighbours meet the tangent plane at the visible point.
            let (p, n) = (sh.hit.p, sh.hit.n);
            let on_plane = |r: &Ray| {
                let dn = r.d.dot(n);
                (dn != 0.0).then(|| r.o + r.d * ((p - r.o).dot(n) / dn) - p)
            };
            let (a, b) = (on_plane(&rays[1])?, on_plane(&rays[2])?);
            let ratio = perpendicular_width(a, b, rays[0].d.normalize()) / (length * spread);
            return (ratio.is_finite() && ratio > 0.0).then(|| ratio.clamp(MIN_RATIO, 1.0));
        }
        // A specular bounce: every ray must meet the same object and take the same lobe.
        let (uc, u) = (rng.f32(), rng.vec2());
        let object = scene.prim_object[sh.prim as usize];
        let s = bsdf.sample(-rays[0].d, uc, u, TransportMode::Radiance)?;
        let side = s.wi.dot(sh.hit.n) > 0.0;
        let mut next = [scene.spawn_ray(sh.hit.p, sh.hit.n, s.wi); 3];
        for (ray, out) in rays.iter().zip(next.iter_mut()).skip(1) {
            let h = scene.intersect(ray, f32::INFINITY)?;
            if scene.prim_object[h.prim as usize] != object {
                return None;
            }
            let sk = scene
                .bsdf(&h)
                .sample(-ray.d, uc, u, TransportMode::Radiance)?;
            if (sk.wi.dot(h.hit.n) > 0.0) != side {
                return None;
            }
            *out = scene.spawn_ray(h.hit.p, h.hit.n, sk.wi);
        }
        rays = next;
    }
    None
}

/// The square root of the area that offsets `a` and `b` span across the unit direction `d`.
fn perpendicular_width(a: Vec3A, b: Vec3A, d: Vec3A) -> f64 {
    let across = |v: Vec3A| v - d * v.dot(d);
    f64::from(across(a).cross(across(b)).length()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::EvalOptions;
    use crate::eval::load_file;
    use crate::prepare::{RenderOptions, effective_settings};

    /// On `tools/reference/caustic.scn` (a glass ball over a floor): the ratio is 1 wherever
    /// the camera sees the floor or the wall directly, and through the ball it is what the
    /// pixel-centre camera paths of neighbouring pixels measure (their visible points' spacing
    /// across the last segment, over the straight rule's, held within the same bounds), where
    /// all three take the same lobes.
    #[test]
    fn the_footprint_follows_the_beam_through_the_glass() {
        let path = crate::repo_root().join("tools/reference/caustic.scn");
        let scene = load_file(&path, &EvalOptions::default())
            .unwrap()
            .scene
            .unwrap();
        let settings = effective_settings(&scene, &RenderOptions::default()).unwrap();
        let prepared = PreparedScene::new(&scene).unwrap();
        let (w, h) = settings.resolution;
        let camera = Camera::new(&scene.camera, scene.settings.handedness, w, h).unwrap();
        let pixel = 2.0 * (0.5 * scene.camera.fov.to_radians()).tan() / f64::from(h);
        // Pixel (x, y)'s centre path with the random numbers of `seed`: its visible point, the
        // direction it arrived from, its length and its ratio.
        let centre = |x: u32, y: u32| {
            let mut rng = Rng::new(7);
            let r = footprint_ratio(&prepared, &camera, &settings, (x, y), true, &mut rng);
            let mut rng = Rng::new(7);
            let (_, vp) = crate::integrators::common::camera_path::fixed_camera_path(
                &prepared, &camera, &settings, x, y, &mut rng,
            );
            (vp, r)
        };
        let (mut direct, mut through) = (Vec::new(), Vec::new());
        for y in 0..h - 1 {
            for x in 0..w - 1 {
                let ray = camera.ray(x, y, Vec2::splat(0.5), Vec2::splat(0.5));
                let Some(sh) = prepared.intersect(&ray, f32::INFINITY) else {
                    continue;
                };
                let (Some(vp), Some(r)) = centre(x, y) else {
                    continue;
                };
                if !prepared.bsdf(&sh).is_specular() {
                    direct.push(r);
                    continue;
                }
                let (Some(a), _) = centre(x + 1, y) else {
                    continue;
                };
                let (Some(b), _) = centre(x, y + 1) else {
                    continue;
                };
                let d = -vp.wo;
                let width = perpendicular_width(a.p - vp.p, b.p - vp.p, d);
                let measured = (width / (f64::from(vp.distance) * pixel)).clamp(MIN_RATIO, 1.0);
                // Only where the neighbours' points lie on the same surface, close by.
                if (a.p - vp.p).length() < 0.05 && (b.p - vp.p).length() < 0.05 {
                    through.push((r, measured));
                }
            }
        }
        let worst = direct.iter().fold(0.0f64, |m, r| m.max((r - 1.0).abs()));
        println!(
            "direct: {} pixels, worst |ratio - 1| {worst:.4}",
            direct.len()
        );
        assert!(direct.len() > 1000 && worst < 0.02);
        let mut errors: Vec<f64> = through.iter().map(|(r, m)| (r / m).ln().abs()).collect();
        errors.sort_by(f64::total_cmp);
        let median_ratio = {
            let mut r: Vec<f64> = through.iter().map(|(r, _)| *r).collect();
            r.sort_by(f64::total_cmp);
            r[r.len() / 2]
        };
        let q90 = errors[errors.len() * 9 / 10].exp();
        println!(
            "through the ball: {} pixels, median ratio {median_ratio:.3}, 90 % within a factor {q90:.3} of the neighbours'",
            through.len()
        );
        assert!(through.len() > 300);
        assert!(q90 < 1.25);
    }
}
