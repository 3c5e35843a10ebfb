//! Axis-aligned box, as six outward-facing quads (any affine transform maps each face to a
//! parallelogram, so transformed boxes stay exact).

use glam::Vec3A;

use super::quad::Quad;

/// The six faces of the box `[min, max]`, outward normals, mapped by `xf` (a point map).
/// `mirrored`: the map flips orientation (negative determinant), so edges are swapped to keep
/// the normals outward.
pub fn cuboid_faces(
    min: Vec3A,
    max: Vec3A,
    xf: impl Fn(Vec3A) -> Vec3A,
    mirrored: bool,
) -> Result<Vec<Quad>, String> {
    if !(min.cmplt(max).all()) {
        return Err("box corners must differ on every axis (min < max)".into());
    }
    let d = max - min;
    let (x, y, z) = (Vec3A::X * d.x, Vec3A::Y * d.y, Vec3A::Z * d.z);
    // (origin, edge_u, edge_v) with edge_u x edge_v pointing out of the box.
    let faces = [
        (min, z, y),
        (min + x, y, z),
        (min, x, z),
        (min + y, z, x),
        (min, y, x),
        (min + z, x, y),
    ];
    faces
        .into_iter()
        .map(|(o, u, v)| {
            let (u, v) = if mirrored { (v, u) } else { (u, v) };
            let o2 = xf(o);
            Quad::new(o2, xf(o + u) - o2, xf(o + v) - o2)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Shape;

    #[test]
    fn faces_point_outwards() {
        let faces = cuboid_faces(Vec3A::ZERO, Vec3A::ONE, |p| p, false).unwrap();
        let c = Vec3A::splat(0.5);
        for f in &faces {
            let s = f.sample(glam::Vec2::splat(0.5)).unwrap();
            assert!((s.p - c).dot(s.n) > 0.0);
        }
        let area: f32 = faces.iter().map(|f| f.area()).sum();
        assert!((area - 6.0).abs() < 1e-5);
    }
}
