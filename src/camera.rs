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
    ) -> Result<Self, scene::Invalid> {
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
}
