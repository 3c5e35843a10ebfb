//! A bump or normal map's normal at a hit: the height's slopes along the shading frame's
//! tangents, taken in the hit object's space (textures/bump.rs does the differencing).

use glam::{Vec2, Vec3A};

use super::{PreparedScene, SurfaceHit};
use crate::geometry::Frame;
use crate::scene::{Normal, NormalKind};
use crate::textures::{TexCoord, bump};

impl PreparedScene<'_> {
    /// The shading normal at a hit as a bump or normal map leans it (world space): a height's
    /// slopes along the shading frame's tangents tilt it, or a normal map's texel replaces it
    /// in that frame (textures/bump.rs). `frame` is the shading frame, `tc` the hit's texture
    /// coordinates and `scale` the height's pattern scale, all worked out once by the caller.
    pub(super) fn perturbed_normal(
        &self,
        normal: &Normal,
        scale: f32,
        sh: &SurfaceHit,
        frame: &Frame,
        tc: &TexCoord,
    ) -> Vec3A {
        let ns = sh.hit.ns;
        let textures = &self.scene.textures;
        if let NormalKind::Map(_) = normal.kind {
            return match bump::mapped_normal(normal, textures, tc) {
                Some(n) => frame.to_world(n),
                None => ns,
            };
        }
        let to_object = self
            .prim_object
            .get(sh.prim as usize)
            .and_then(|&o| self.objects.get(o as usize))
            .map(|o| o.to_object);
        // u (and, as shapes give no dpdv, v) moves by 1 / |dpdu| per world unit.
        let uv_rate = 1.0 / sh.hit.dpdu.length();
        let uv_rate = if uv_rate.is_finite() { uv_rate } else { 0.0 };
        let tangent = |w: Vec3A, duv: Vec2| {
            let d = to_object.map_or(w, |m| m.transform_vector3a(w));
            let len = d.length();
            if !(len.is_finite() && len > 0.0) {
                return bump::Tangent {
                    dir: Vec3A::ZERO,
                    per_world: 0.0,
                    duv: Vec2::ZERO,
                };
            }
            bump::Tangent {
                dir: d / len,
                per_world: len,
                duv: duv * uv_rate / len,
            }
        };
        let tangents = [tangent(frame.s, Vec2::X), tangent(frame.t, Vec2::Y)];
        let [hs, ht] = bump::slopes(normal, scale, textures, tc, tangents);
        let a = normal.amount as f32;
        let np = (ns - a * (hs * frame.s + ht * frame.t)).normalize_or_zero();
        if np == Vec3A::ZERO || !np.is_finite() {
            ns
        } else {
            np
        }
    }
}
