//! Orthonormal frames around a normal (Duff et al. 2017 branchless construction).

use glam::Vec3A;

/// An orthonormal basis `(s, t, n)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub s: Vec3A,
    pub t: Vec3A,
    pub n: Vec3A,
}

impl Frame {
    /// A frame whose third axis is the unit vector `n`.
    pub fn from_normal(n: Vec3A) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// A frame with third axis `n` and first axis as close to `s` as possible. Inline: every
    /// BSDF is built with one (a call per photon bounce otherwise).
    #[inline]
    pub fn from_normal_tangent(n: Vec3A, s: Vec3A) -> Self {
        let s = s - n * n.dot(s);
        if s.length_squared() < 1e-12 || !s.is_finite() {
            return Self::from_normal(n);
        }
        let s = s.normalize();
        Self {
            s,
            t: n.cross(s),
            n,
        }
    }

    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}
