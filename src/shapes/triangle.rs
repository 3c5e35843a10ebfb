//! Triangle (Möller–Trumbore), with optional per-vertex normals and uvs (mesh triangles).

use glam::{Vec2, Vec3A};

use super::{AreaSample, SplitShape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::sampling::uniform_triangle;

#[derive(Debug, Clone, Copy)]
pub struct Triangle {
    p: [Vec3A; 3],
    n: Vec3A,
    normals: Option<[Vec3A; 3]>,
    uvs: [Vec2; 3],
    area: f32,
}

impl Triangle {
    pub fn new(
        p: [Vec3A; 3],
        normals: Option<[Vec3A; 3]>,
        uvs: Option<[Vec2; 3]>,
    ) -> Result<Self, String> {
        let c = (p[1] - p[0]).cross(p[2] - p[0]);
        let len = crate::geometry::scaled_length(c);
        if !(len.is_finite() && len > 0.0) {
            return Err("triangle is degenerate (zero area)".into());
        }
        let normals = normals.filter(|ns| ns.iter().all(|v| v.is_finite() && v.length() > 0.0));
        Ok(Self {
            p,
            n: c / len,
            normals: normals.map(|ns| ns.map(|v| v.normalize())),
            uvs: uvs.unwrap_or([Vec2::ZERO, Vec2::X, Vec2::Y]),
            area: 0.5 * len,
        })
    }
}

impl Triangle {
    /// Möller–Trumbore: `(t, b1, b2)` when the ray crosses the triangle (any `t`).
    #[inline]
    pub(crate) fn solve(&self, ray: &Ray) -> Option<(f32, f32, f32)> {
        let e1 = self.p[1] - self.p[0];
        let e2 = self.p[2] - self.p[0];
        let pv = ray.d.cross(e2);
        let det = e1.dot(pv);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let tv = ray.o - self.p[0];
        let b1 = tv.dot(pv) * inv;
        if !(0.0..=1.0).contains(&b1) {
            return None;
        }
        let qv = tv.cross(e1);
        let b2 = ray.d.dot(qv) * inv;
        if b2 < 0.0 || b1 + b2 > 1.0 {
            return None;
        }
        Some((e2.dot(qv) * inv, b1, b2))
    }
}

impl SplitShape for Triangle {
    /// Nearest `t` with `t_min < t < t_max`, without the surface data (see [`Triangle::hit_at`]).
    #[inline]
    fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let (t, _, _) = self.solve(ray)?;
        (t > t_min && t < t_max).then_some(t)
    }

    /// The full surface data at ray parameter `t` (a value [`Triangle::hit_t`] returned).
    fn hit_at(&self, ray: &Ray, t: f32) -> Hit {
        let (b1, b2) = self.solve(ray).map_or((0.0, 0.0), |(_, b1, b2)| (b1, b2));
        let e1 = self.p[1] - self.p[0];
        let e2 = self.p[2] - self.p[0];
        let b0 = 1.0 - b1 - b2;
        let p = self.p[0] * b0 + self.p[1] * b1 + self.p[2] * b2;
        let ns = shading_normal(self.normals, [b0, b1, b2], self.n);
        let (uv, dpdu) = uv_and_dpdu(self.uvs, [b0, b1, b2], e1, e2);
        Hit {
            t,
            p,
            n: self.n,
            ns,
            uv,
            dpdu,
        }
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_points(self.p)
    }

    fn area(&self) -> f32 {
        self.area
    }

    fn sample(&self, u: Vec2) -> Option<AreaSample> {
        let b = uniform_triangle(u);
        Some(AreaSample {
            p: self.p[0] * b.x + self.p[1] * b.y + self.p[2] * (1.0 - b.x - b.y),
            n: self.n,
            pdf: 1.0 / self.area,
        })
    }
}

/// The shading normal at barycentric coordinates `b` from the vertex normals `ns` (none: the
/// geometric normal `n`), kept on `n`'s side. Shared with the mesh's hit, which must give the
/// same bits.
#[inline(always)]
pub(super) fn shading_normal(ns: Option<[Vec3A; 3]>, b: [f32; 3], n: Vec3A) -> Vec3A {
    match ns {
        Some(ns) => {
            let s = (ns[0] * b[0] + ns[1] * b[1] + ns[2] * b[2]).normalize_or_zero();
            if s == Vec3A::ZERO {
                n
            } else if s.dot(n) < 0.0 {
                // Keep the shading normal on the geometric normal's side.
                (s - n * (2.0 * s.dot(n))).normalize()
            } else {
                s
            }
        }
        None => n,
    }
}

/// A triangle's `uv` at barycentric coordinates `b` from its vertices' `uvs`, and dp/du from
/// its edges `e1`, `e2` where that parameterisation is not degenerate (`e1` where it is).
#[inline(always)]
pub(super) fn uv_and_dpdu(uvs: [Vec2; 3], b: [f32; 3], e1: Vec3A, e2: Vec3A) -> (Vec2, Vec3A) {
    let uv = uvs[0] * b[0] + uvs[1] * b[1] + uvs[2] * b[2];
    let duv1 = uvs[1] - uvs[0];
    let duv2 = uvs[2] - uvs[0];
    let d = duv1.x * duv2.y - duv1.y * duv2.x;
    let dpdu = if d.abs() > 1e-12 {
        (e1 * duv2.y - e2 * duv1.y) / d
    } else {
        e1
    };
    (uv, dpdu)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Shape;

    /// Edges 1e11 long are legal (world coordinates go to 1e12), but the square of their cross
    /// product (1e44) overflows f32: the triangle was refused as "degenerate (zero area)", and
    /// a mesh silently dropped it.
    #[test]
    fn a_triangle_with_edges_1e11_long_is_built_and_hit() {
        for s in [1e-4f32, 1.0, 1e11] {
            let tri = Triangle::new([Vec3A::ZERO, s * Vec3A::X, s * Vec3A::Y], None, None)
                .unwrap_or_else(|e| panic!("size {s}: {e}"));
            assert!((tri.area / (0.5 * s * s) - 1.0).abs() < 1e-5, "size {s}");
            assert_eq!(tri.n, Vec3A::Z);
            let ray = Ray::new(Vec3A::new(0.25 * s, 0.25 * s, -s), Vec3A::Z);
            let hit = tri.intersect(&ray, 0.0, f32::INFINITY).expect("a hit");
            assert!((hit.t / s - 1.0).abs() < 1e-5, "size {s}: t = {}", hit.t);
        }
    }
}
