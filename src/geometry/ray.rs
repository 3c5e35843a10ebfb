use glam::{Vec2, Vec3A, Vec4};

/// A ray `o + t d`. `d` need not be unit length; `t` is in units of `d`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub o: Vec3A,
    pub d: Vec3A,
}

impl Ray {
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        Self { o, d }
    }

    pub fn at(&self, t: f32) -> Vec3A {
        self.o + self.d * t
    }
}

/// A ray–surface intersection, in the space of the ray that produced it.
///
/// `repr(C)`, in this order (the order the compiler chose for it before): four `Vec3A`, then
/// `uv` and `t` in one 16-byte slot, which [`Hit::from_parts`] writes with one store.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Hit {
    /// Hit point.
    pub p: Vec3A,
    /// Unit geometric normal (the shape's outward side; not flipped toward the ray).
    pub n: Vec3A,
    /// Unit shading normal (interpolated / from the exact surface), same hemisphere as `n`.
    pub ns: Vec3A,
    /// Partial derivative of the surface point along u (tangent), not necessarily unit.
    pub dpdu: Vec3A,
    /// Surface (u, v) texture coordinates.
    pub uv: Vec2,
    /// Ray parameter of the hit.
    pub t: f32,
}

/// [`Hit`]'s layout with `uv` and `t` as one vector (the last lane is the padding).
#[repr(C)]
struct HitParts {
    p: Vec3A,
    n: Vec3A,
    ns: Vec3A,
    dpdu: Vec3A,
    uv_t: Vec4,
}

// The layout `Hit::from_parts` relies on, checked by the compiler.
const _: () = {
    use std::mem::{offset_of, size_of};
    assert!(size_of::<Hit>() == size_of::<HitParts>());
    assert!(offset_of!(Hit, dpdu) == offset_of!(HitParts, dpdu));
    assert!(offset_of!(Hit, uv) == offset_of!(HitParts, uv_t));
    assert!(offset_of!(Hit, t) == offset_of!(HitParts, uv_t) + 8);
};

impl Hit {
    /// The record of these parts, the same as the struct literal, but with `uv` and `t` put
    /// together in a register and stored at once. Built field by field, they are two stores
    /// (8 and 4 bytes), and a caller that copies the record soon after (an `Option` unpacked)
    /// reads that slot as one 16-byte load, which cannot take its data from two pending stores
    /// and waits for them to reach the cache (docs/measurements.md, "Two stalled loads and the
    /// grid build's keys").
    #[inline(always)]
    pub fn from_parts(t: f32, p: Vec3A, n: Vec3A, ns: Vec3A, uv: Vec2, dpdu: Vec3A) -> Hit {
        let parts = HitParts {
            p,
            n,
            ns,
            dpdu,
            uv_t: Vec4::new(uv.x, uv.y, t, 0.0),
        };
        // SAFETY: both types are `repr(C)` with the same four `Vec3A` first (16 bytes each,
        // 16-byte aligned) and then 16 bytes: `Vec4`'s four `f32`, against `uv` (two `f32`),
        // `t` and four bytes of padding; `transmute` checks that the sizes agree, and any bits
        // are a valid `f32`.
        unsafe { std::mem::transmute::<HitParts, Hit>(parts) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Hit::from_parts` gives the struct literal's record, field by field and bit for bit (a
    /// NaN `uv` included, as spheres leave it when no texture asks).
    #[test]
    fn from_parts_is_the_literal() {
        let v = |k: f32| Vec3A::new(k, -2.5 * k, 1e-30 + k);
        for (k, uv) in [(1.0, Vec2::new(0.25, 0.75)), (-3.0, Vec2::NAN)] {
            let got = Hit::from_parts(0.5 * k, v(k), v(k + 1.0), v(k + 2.0), uv, v(k + 3.0));
            let want = Hit {
                t: 0.5 * k,
                p: v(k),
                n: v(k + 1.0),
                ns: v(k + 2.0),
                uv,
                dpdu: v(k + 3.0),
            };
            let bits = |h: &Hit| {
                let vs = [h.p, h.n, h.ns, h.dpdu].map(|x| x.to_array().map(f32::to_bits));
                (vs, h.uv.to_array().map(f32::to_bits), h.t.to_bits())
            };
            assert_eq!(bits(&got), bits(&want));
        }
    }
}
