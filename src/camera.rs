//! Pinhole and thin-lens cameras: perspective (a vertical field of view) or orthographic
//! (parallel rays from a rectangle of the scene's size).
//!
//! An orthographic camera's lens is telecentric: the ray of a pixel starts at a point of a disk
//! of the aperture's radius around the pixel's own point on the view rectangle and aims at the
//! point the pixel's central ray reaches at the focus distance, so points at that distance are
//! sharp and others blur in proportion to their distance from it, as with the perspective lens.

use glam::{Vec2, Vec3A};

use crate::geometry::Ray;
use crate::sampling::concentric_disk;
use crate::scene;

#[derive(Debug, Clone, Copy)]
pub struct Camera {
    origin: Vec3A,
    forward: Vec3A,
    right: Vec3A,
    up: Vec3A,
    /// Half-extent of the image plane at distance 1 (perspective) or of the view rectangle in
    /// scene units (orthographic).
    half_w: f32,
    half_h: f32,
    orthographic: bool,
    lens_radius: f32,
    focus: f32,
    width: u32,
    height: u32,
}

impl Camera {
    /// The camera of a scene, for an image of `width` x `height` pixels. The checks are the
    /// scene's own ([`scene::Camera::validate`]): the one place a camera is validated.
    ///
    /// With `handedness` left (or a camera `right` with a positive x) the screen's x axis is
    /// mirrored: the image is the mirror image of the right-handed camera's, which is exactly
    /// the picture of the scene with every x coordinate negated (and every rotation, pattern,
    /// uv and winding with it), since a mirror maps the scene's light transport onto itself.
    pub fn new(
        c: &scene::Camera,
        handedness: scene::Handedness,
        width: u32,
        height: u32,
    ) -> Result<Self, crate::diag::Diagnostic> {
        c.validate()?;
        let fwd = (c.look_at - c.location).normalize();
        let right = fwd.cross(c.up).normalize();
        let up = right.cross(fwd);
        let right = if c.mirrored(handedness) {
            -right
        } else {
            right
        };
        let (half_w, half_h) = if c.orthographic {
            let (w, h) = c.view_size(width, height);
            (0.5 * w as f32, 0.5 * h as f32)
        } else {
            let half_h = (c.fov.to_radians() * 0.5).tan() as f32;
            (half_h * width as f32 / height.max(1) as f32, half_h)
        };
        let focus = c
            .focus_distance
            .unwrap_or_else(|| (c.look_at - c.location).length());
        Ok(Self {
            origin: c.location.as_vec3a(),
            forward: fwd.as_vec3a(),
            right: right.as_vec3a(),
            up: up.as_vec3a(),
            half_w,
            half_h,
            orthographic: c.orthographic,
            lens_radius: c.aperture as f32,
            focus: focus as f32,
            width,
            height,
        })
    }

    /// The distance in focus (the scene's `focus_distance`, else the look-at distance).
    pub fn focus_distance(&self) -> f64 {
        f64::from(self.focus)
    }

    /// The ray through pixel `(x, y)` (row 0 at the top) offset by `jitter` in [0,1)^2, with lens
    /// sample `lens` in [0,1)^2. The direction is unit length.
    pub fn ray(&self, x: u32, y: u32, jitter: Vec2, lens: Vec2) -> Ray {
        let sx = ((x as f32 + jitter.x) / self.width as f32) * 2.0 - 1.0;
        let sy = 1.0 - ((y as f32 + jitter.y) / self.height as f32) * 2.0;
        if self.orthographic {
            let o = self.origin + self.right * (sx * self.half_w) + self.up * (sy * self.half_h);
            if self.lens_radius == 0.0 {
                return Ray::new(o, self.forward);
            }
            let focus_point = o + self.forward * self.focus;
            let l = concentric_disk(lens) * self.lens_radius;
            let lo = o + self.right * l.x + self.up * l.y;
            return Ray::new(lo, (focus_point - lo).normalize());
        }
        let d = (self.forward + self.right * (sx * self.half_w) + self.up * (sy * self.half_h))
            .normalize();
        if self.lens_radius == 0.0 {
            return Ray::new(self.origin, d);
        }
        let focus_point = self.origin + d * (self.focus / d.dot(self.forward));
        let l = concentric_disk(lens) * self.lens_radius;
        let o = self.origin + self.right * l.x + self.up * l.y;
        Ray::new(o, (focus_point - o).normalize())
    }

    /// Distance from the eye to an image plane on which a pixel is one unit wide: the camera's
    /// importance and densities below are per pixel, so that a pixel's value is the mean of
    /// its samples.
    fn plane_distance(&self) -> f32 {
        self.height as f32 / (2.0 * self.half_h)
    }

    /// Solid-angle density of [`Camera::ray`] choosing unit direction `d` (from whichever lens
    /// point) for a jitter uniform over one pixel: `D^2 / cos^3`, `D` the plane distance and
    /// `cos` the angle to the view direction. Zero behind the camera.
    pub fn pdf_dir(&self, d: Vec3A) -> f32 {
        let cos = d.dot(self.forward);
        if cos <= 0.0 {
            return 0.0;
        }
        let dist = self.plane_distance();
        dist * dist / (cos * cos * cos)
    }

    /// The camera seen from the scene point `p` (light tracing): a lens point chosen with
    /// `lens` in [0,1)^2 (uniformly over the lens; the eye for a pinhole), the pixel whose rays
    /// through that lens point pass through `p`, and the density of the camera choosing that
    /// direction ([`Camera::pdf_dir`]). `None` when `p` is behind the camera or outside the
    /// picture.
    ///
    /// The importance of a lens point and direction is `D^2 / cos^4 / lens area` per pixel, and
    /// the lens point is drawn with density `1 / lens area`, so a light path vertex with flux
    /// `beta` scattering `f` toward the lens adds `beta f cos_surface / dist^2 * pdf_dir` to the
    /// pixel (per light path): [`CameraSample::pdf_dir`] is both the density and that factor.
    pub fn sample_toward(&self, p: Vec3A, lens: Vec2) -> Option<CameraSample> {
        let o = if self.lens_radius == 0.0 {
            self.origin
        } else {
            let l = concentric_disk(lens) * self.lens_radius;
            self.origin + self.right * l.x + self.up * l.y
        };
        let to_p = p - o;
        let dist = to_p.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return None;
        }
        let d = to_p / dist;
        let cos = d.dot(self.forward);
        if cos <= 1e-6 {
            return None;
        }
        // The camera ray through lens point o toward p crosses the plane in focus at q; the
        // pixel is the one whose central ray (through the eye) passes q.
        let q = o + d * (self.focus / cos);
        let c = q - self.origin;
        let depth = c.dot(self.forward);
        if depth <= 0.0 {
            return None;
        }
        let sx = c.dot(self.right) / (depth * self.half_w);
        let sy = c.dot(self.up) / (depth * self.half_h);
        let fx = (sx + 1.0) * 0.5 * self.width as f32;
        let fy = (1.0 - sy) * 0.5 * self.height as f32;
        if !(fx >= 0.0 && fy >= 0.0 && fx < self.width as f32 && fy < self.height as f32) {
            return None;
        }
        let (x, y) = (
            (fx as u32).min(self.width - 1),
            (fy as u32).min(self.height - 1),
        );
        Some(CameraSample {
            pixel: y * self.width + x,
            lens: o,
            to_camera: -d,
            dist,
            pdf_dir: self.pdf_dir(d),
        })
    }
}

/// The camera as seen from a scene point ([`Camera::sample_toward`]).
#[derive(Debug, Clone, Copy)]
pub struct CameraSample {
    /// Pixel index (row-major, row 0 at the top).
    pub pixel: u32,
    /// The lens point (the eye for a pinhole).
    pub lens: Vec3A,
    /// Unit direction from the scene point to the lens point, and the distance.
    pub to_camera: Vec3A,
    pub dist: f32,
    /// The camera's density of the direction from the lens point to the scene point, per
    /// solid angle and per pixel ([`Camera::pdf_dir`]).
    pub pdf_dir: f32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn camera(aperture: f64) -> Camera {
        let c = scene::Camera {
            aperture,
            focus_distance: Some(4.0),
            ..Default::default()
        };
        Camera::new(&c, scene::Handedness::Right, 40, 30).unwrap()
    }

    /// A point a camera ray passes is mapped back to that ray's pixel through the same lens
    /// point, for a pinhole and a thin lens.
    #[test]
    fn sample_toward_finds_the_pixel_of_the_ray() {
        let mut rng = Rng::new(7);
        for aperture in [0.0, 0.3] {
            let cam = camera(aperture);
            for _ in 0..2000 {
                let (x, y) = (rng.f32() * 40.0, rng.f32() * 30.0);
                let (px, py) = (x as u32, y as u32);
                let jitter = Vec2::new(x - px as f32, y - py as f32);
                let lens = rng.vec2();
                let ray = cam.ray(px, py, jitter, lens);
                let p = ray.o + ray.d * (1.0 + 8.0 * rng.f32());
                let s = cam.sample_toward(p, lens).expect("in the picture");
                let err = (s.lens - ray.o).length();
                assert!(err < 1e-4, "lens point off by {err}");
                // Points on a pixel edge may round to the neighbour.
                if jitter.min_element() > 1e-3 && jitter.max_element() < 1.0 - 1e-3 {
                    assert_eq!(s.pixel, py * 40 + px, "aperture {aperture}");
                }
                assert!((s.to_camera + ray.d).length() < 1e-4);
            }
        }
    }

    /// `pdf_dir` integrates to one over the directions of one pixel: summed over the picture
    /// (directions drawn uniformly on the sphere) it is the pixel count.
    #[test]
    fn pdf_dir_integrates_to_the_pixel_count() {
        let cam = camera(0.0);
        let mut rng = Rng::new(3);
        let n = 400_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let d = crate::sampling::uniform_sphere(rng.vec2());
            if cam.sample_toward(cam.origin + d, Vec2::ZERO).is_some() {
                sum += f64::from(cam.pdf_dir(d)) * 4.0 * std::f64::consts::PI;
            }
        }
        let pixels = sum / f64::from(n);
        assert!((pixels / 1200.0 - 1.0).abs() < 0.02, "{pixels}");
    }
}
