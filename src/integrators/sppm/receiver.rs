//! A visible point's BSDF with its `wo` fixed, reduced for the photon gather: one point is
//! evaluated against every photon near it.

use glam::{Vec3A, Vec4};

use crate::integrators::common::camera_path::VisiblePoint;

/// [`crate::materials::Bsdf::f`] for a fixed `wo`. For a Lambertian point only the two side
/// tests remain, kept in the same form (`(wo . n) * (wi . n) <= 0` rejects), so the result is
/// bit-identical to calling the BSDF; other lobes call it.
pub(super) struct Receiver {
    vp: VisiblePoint,
    /// Geometric normal, and `wo . ng` in `w`.
    ng: Vec4,
    /// Shading normal, and `wo . ns` in `w`.
    ns: Vec4,
    /// The BSDF's value when it does not depend on the directions.
    constant: Option<Vec3A>,
}

impl Receiver {
    pub(super) fn new(vp: VisiblePoint) -> Self {
        let (ng, ns) = (vp.bsdf.ng, vp.bsdf.frame.n);
        Receiver {
            vp,
            ng: ng.extend(vp.wo.dot(ng)),
            ns: ns.extend(vp.wo.dot(ns)),
            constant: vp.bsdf.constant_f(),
        }
    }

    /// The BSDF for light arriving from `wi` (toward the point's `wo`).
    #[inline]
    pub(super) fn f(&self, wi: Vec3A) -> Vec3A {
        let Some(f) = self.constant else {
            return self.vp.bsdf.f(self.vp.wo, wi);
        };
        let (ng, ns) = (
            Vec3A::from(self.ng.truncate()),
            Vec3A::from(self.ns.truncate()),
        );
        if self.ng.w * wi.dot(ng) <= 0.0 || self.ns.w * wi.dot(ns) <= 0.0 {
            return Vec3A::ZERO;
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::{Bsdf, Lobes};
    use crate::sampling::{Rng, uniform_sphere};

    /// A receiver gives exactly what the BSDF gives, for every side combination (front and
    /// back, shading normal tilted away from the geometric one) and both kinds of lobes.
    #[test]
    fn receivers_match_the_bsdf_bit_for_bit() {
        let mut rng = Rng::new(5);
        let mut nonzero = 0;
        for i in 0..2000 {
            let ng = uniform_sphere(rng.vec2());
            let ns = (ng + 0.6 * uniform_sphere(rng.vec2())).normalize();
            let lobes = if i % 2 == 0 {
                Lobes::Diffuse {
                    albedo: Vec3A::new(0.7, 0.5, 0.2),
                }
            } else {
                Lobes::Glossy {
                    albedo: Vec3A::splat(0.3),
                    specular: Vec3A::splat(0.5),
                    alpha: 0.2,
                }
            };
            let wo = uniform_sphere(rng.vec2());
            let vp = VisiblePoint {
                p: Vec3A::ZERO,
                wo,
                bsdf: Bsdf::new(lobes, ns, ns.any_orthonormal_vector(), ng),
                beta: Vec3A::ONE,
                distance: 1.0,
                medium: Vec3A::ZERO,
            };
            let r = Receiver::new(vp);
            assert_eq!(r.constant.is_some(), i % 2 == 0);
            for _ in 0..8 {
                let wi = uniform_sphere(rng.vec2());
                let (got, want) = (r.f(wi), vp.bsdf.f(wo, wi));
                assert_eq!(
                    got.to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits)
                );
                nonzero += usize::from(got != Vec3A::ZERO && r.constant.is_some());
            }
        }
        assert!(nonzero > 1000, "{nonzero}");
    }
}
