//! What a ray that leaves the scene carries back: the one rule every integrator applies.
//!
//! The background (`background rgb`, `background texture { ... }`, `environment { ... }`) is
//! the environment light: it lights the scene and is seen. The backdrop is only seen: a camera
//! ray that escapes, directly or after specular bounces alone (mirrors, glass), shows the
//! backdrop in place of the background; any path that has met a diffuse or glossy surface, and
//! every photon, sees the background (or black) instead. Direct lighting and photon emission
//! use the environment light, which the backdrop is not part of, so they never see it.

use glam::Vec3A;

use super::PreparedScene;
use crate::scene::ColorParam;
use crate::textures::sky;

impl PreparedScene<'_> {
    /// The radiance a ray leaving the scene in direction `dir` brings back. `camera_chain`: the
    /// ray is a camera ray or followed one through specular bounces only (no diffuse or glossy
    /// vertex, not a gather or photon path); then the backdrop, if the scene has one, is what
    /// it sees.
    #[inline]
    pub fn escaped_radiance(&self, dir: Vec3A, camera_chain: bool) -> Vec3A {
        match &self.scene.backdrop {
            Some(backdrop) if camera_chain => self.backdrop_radiance(backdrop, dir),
            _ => self.background_radiance(dir),
        }
    }

    fn backdrop_radiance(&self, backdrop: &ColorParam, dir: Vec3A) -> Vec3A {
        match backdrop {
            ColorParam::Const(c) => {
                let c = c.as_vec3a();
                if c.is_finite() {
                    c.max(Vec3A::ZERO)
                } else {
                    Vec3A::ZERO
                }
            }
            ColorParam::Texture(id) => self
                .scene
                .textures
                .get(id.0 as usize)
                .map_or(Vec3A::ZERO, |t| sky::radiance(t, dir)),
        }
    }
}
