//! Texture mappings: where the coordinates a pattern sees come from.
//!
//! Every mapping turns a [`TexCoord`] (object-space point and normal, surface `uv`) into a 3-D
//! texture-space point; the texture's own transform is applied after that (see
//! [`super::evaluate`]). Image patterns read the `(x, y)` of the result as `(u, v)`.
//!
//! | mapping       | produces                                                               |
//! |---------------|------------------------------------------------------------------------|
//! | `Solid`       | the object-space point `(x, y, z)` itself                              |
//! | `Uv`          | `(u, v, 0)`: the shape's own surface coordinates                       |
//! | `Planar`      | `(-x, y, 0)`: projection along z onto the x-y plane (map_type 0)        |
//! | `Spherical`   | `(u, v, 0)`, `u` longitude around y, `v` latitude (POV-Ray map_type 1)  |
//! | `Cylindrical` | `(u, y, 0)`, `u` longitude around y, height unchanged (map_type 2)      |
//!
//! Longitude: `u = 0.5 - atan2(x, -z) / 2π`, so `u = 0.5` faces -z (towards the default camera),
//! `u` grows towards -x, which is to the right seen from the default camera (the camera is
//! right-handed), so an image is not mirrored seen from outside; the seam `u = 0 = 1` lies on
//! the +z side. Latitude: `v = 1 - θ / π` with `θ = acos(y / |p|)`, 1 at the north pole (+y), 0 at
//! the south pole; the image's top row is at the north pole.

use std::f64::consts::PI;

use glam::DVec3;

use super::TexCoord;
use crate::scene::Mapping;

/// The texture-space point of `at` under `mapping`, before the texture's transform.
#[inline]
pub fn map(mapping: Mapping, at: &TexCoord) -> DVec3 {
    let p = at.p.as_dvec3();
    match mapping {
        Mapping::Solid => p,
        Mapping::Uv => DVec3::new(at.uv.x as f64, at.uv.y as f64, 0.0),
        // `u` grows toward -x, to the right seen from the default camera (on -z; the camera
        // is right-handed): the image is not mirrored from there, and sits where POV-Ray's
        // `map_type 0` puts it once a scene is ported by negating x.
        Mapping::Planar => DVec3::new(-p.x, p.y, 0.0),
        Mapping::Spherical => {
            // atan2 of the horizontal radius keeps its precision near the poles.
            let theta = (p.x * p.x + p.z * p.z).sqrt().atan2(p.y);
            let v = if theta.is_finite() && p != DVec3::ZERO {
                1.0 - theta / PI
            } else {
                0.5
            };
            DVec3::new(longitude(p), v, 0.0)
        }
        Mapping::Cylindrical => DVec3::new(longitude(p), p.y, 0.0),
    }
}

/// `u` in [0, 1) around the y axis; 0.5 on the -z axis, growing towards -x.
#[inline]
pub fn longitude(p: DVec3) -> f64 {
    // `0.0 - z` rather than `-z`: on the axis itself (x = z = 0) atan2 sees +0 and gives 0.
    let u = 0.5 - p.x.atan2(0.0 - p.z) / (2.0 * PI);
    // atan2 is in [-π, π]: fold the single value 1.0 onto 0.0; NaN (a NaN input) to 0.5.
    if u >= 1.0 {
        0.0
    } else if u.is_nan() {
        0.5
    } else {
        u
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3A};

    use super::*;

    fn at(p: [f32; 3], uv: [f32; 2]) -> TexCoord {
        TexCoord {
            p: Vec3A::from(p),
            n: Vec3A::from(p).normalize_or(Vec3A::Y),
            uv: Vec2::from(uv),
        }
    }

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).abs().max_element() < 1e-6
    }

    #[test]
    fn solid_and_uv_and_planar() {
        let c = at([1.0, 2.0, 3.0], [0.25, 0.75]);
        assert!(close(map(Mapping::Solid, &c), DVec3::new(1.0, 2.0, 3.0)));
        assert!(close(map(Mapping::Uv, &c), DVec3::new(0.25, 0.75, 0.0)));
        assert!(close(map(Mapping::Planar, &c), DVec3::new(-1.0, 2.0, 0.0)));
    }

    #[test]
    fn spherical_landmarks() {
        let m = |p| map(Mapping::Spherical, &at(p, [0.0, 0.0]));
        // Facing the default camera: image centre.
        assert!(close(m([0.0, 0.0, -2.0]), DVec3::new(0.5, 0.5, 0.0)));
        assert!(close(m([3.0, 0.0, 0.0]), DVec3::new(0.25, 0.5, 0.0)));
        assert!(close(m([-1.0, 0.0, 0.0]), DVec3::new(0.75, 0.5, 0.0)));
        assert!(close(m([0.0, 0.0, 1.0]), DVec3::new(0.0, 0.5, 0.0)));
        assert!(close(m([0.0, 1.0, 0.0]), DVec3::new(0.5, 1.0, 0.0)));
        assert!(close(m([0.0, -1.0, 0.0]), DVec3::new(0.5, 0.0, 0.0)));
        // 45 degrees north: v = 0.75.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        assert!((m([0.0, s, -s]).y - 0.75).abs() < 1e-6);
        // The origin and NaN do not produce NaN.
        assert!(m([0.0, 0.0, 0.0]).is_finite());
        assert!(m([f32::NAN, 0.0, 1.0]).is_finite());
    }

    #[test]
    fn cylindrical_keeps_height() {
        let m = map(Mapping::Cylindrical, &at([2.0, 0.3, 0.0], [0.0, 0.0]));
        assert!(close(m, DVec3::new(0.25, 0.3, 0.0)));
        // Just either side of the seam on +z: u near 0 on the +x side, near 1 on the -x side.
        let l = map(Mapping::Cylindrical, &at([1e-4, 0.0, 1.0], [0.0, 0.0])).x;
        let r = map(Mapping::Cylindrical, &at([-1e-4, 0.0, 1.0], [0.0, 0.0])).x;
        assert!((0.0..0.001).contains(&l), "{l}");
        assert!(r > 0.999 && r < 1.0, "{r}");
    }
}
