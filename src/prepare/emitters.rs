//! Photon emission from a rectangular area light with what is the same for every photon
//! computed once: the frames around the light's normal (and its reverse, for a two-sided
//! light) and the photon's power. A photon from [`QuadEmitter::sample_photon`] is, bit for
//! bit, the one [`Light::sample_photon`] gives for the same numbers: the same operations on the
//! same values, minus the repeated ones (the shape's dispatch, the frame, two divisions).

use std::f32::consts::PI;

use glam::{Vec2, Vec3A};

use crate::geometry::Frame;
use crate::lights::{Light, PhotonSample};
use crate::sampling::cosine_hemisphere;
use crate::shapes::SplitShape;
use crate::shapes::primitive::AnyShape;
use crate::shapes::quad::Quad;

/// The photons of one rectangular area light.
pub struct QuadEmitter {
    quad: Quad,
    /// The frame around the light's normal, and around its reverse (the back of a two-sided
    /// light).
    frames: [Frame; 2],
    two_sided: bool,
    /// Every photon's power: `radiance * (pi * sides / pdf)`, `pdf` the point's density by area.
    beta: Vec3A,
}

impl QuadEmitter {
    /// The emitter of `light`, if it is an area light on a rectangle.
    pub fn of(light: &Light) -> Option<Self> {
        let Light::Area(a) = light else {
            return None;
        };
        let AnyShape::Quad(quad) = &a.shape else {
            return None;
        };
        // The normal and density of every point of the rectangle.
        let s = quad.sample(Vec2::ZERO)?;
        let side = if a.two_sided { 2.0 } else { 1.0 };
        Some(Self {
            quad: *quad,
            frames: [Frame::from_normal(s.n), Frame::from_normal(-s.n)],
            two_sided: a.two_sided,
            beta: a.radiance * (PI * side / s.pdf),
        })
    }

    /// [`crate::lights::AreaLight::sample_photon`] for this light.
    #[inline]
    pub fn sample_photon(&self, u1: Vec2, u2: Vec2) -> Option<PhotonSample> {
        let p = self.quad.sample(u1)?.p;
        let (mut u2, mut back) = (u2, 0);
        if self.two_sided {
            // The side from `u2.x`, which is reused.
            if u2.x < 0.5 {
                u2.x *= 2.0;
            } else {
                u2.x = (u2.x - 0.5) * 2.0;
                back = 1;
            }
        }
        let l = cosine_hemisphere(u2);
        if l.z <= 0.0 {
            return None;
        }
        let frame = &self.frames[back];
        Some(PhotonSample {
            p,
            n: frame.n,
            dir: frame.to_world(l),
            beta: self.beta,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::{AreaLight, LightSampling};
    use crate::sampling::Rng;

    /// The emitter's photons are the light's own, bit for bit, one- and two-sided, for
    /// rectangles of any orientation (normals along an axis, as the Cornell box's, included).
    #[test]
    fn the_emitter_gives_the_light_s_photons() {
        let mut rng = Rng::new(3);
        let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
        let mut photons = 0;
        for case in 0..40 {
            let (eu, ev) = if case % 4 == 0 {
                (Vec3A::X * 0.5, Vec3A::Z * 0.5)
            } else {
                (v(&mut rng), v(&mut rng))
            };
            let quad = Quad::new(v(&mut rng), eu, ev).unwrap();
            let light = Light::Area(AreaLight {
                shape: AnyShape::Quad(quad),
                radiance: Vec3A::new(17.0, 12.0, 4.0) * rng.f32(),
                two_sided: case % 2 == 1,
                area: quad.area(),
                sampling: LightSampling::SolidAngle,
            });
            let emitter = QuadEmitter::of(&light).unwrap();
            for _ in 0..500 {
                let (u1, u2) = (rng.vec2(), rng.vec2());
                let bits = |s: Option<PhotonSample>| {
                    s.map(|s| [s.p, s.n, s.dir, s.beta].map(|v| v.to_array().map(f32::to_bits)))
                };
                let want = light.sample_photon(u1, u2);
                photons += usize::from(want.is_some());
                assert_eq!(
                    bits(emitter.sample_photon(u1, u2)),
                    bits(want),
                    "case {case}"
                );
            }
        }
        assert!(photons > 19_000, "{photons} photons");
        // Not a rectangle: no emitter.
        let sphere = crate::shapes::sphere::Sphere::new(Vec3A::ZERO, 1.0).unwrap();
        let light = Light::Area(AreaLight {
            shape: AnyShape::Sphere(sphere),
            radiance: Vec3A::ONE,
            two_sided: false,
            area: 4.0 * PI,
            sampling: LightSampling::SolidAngle,
        });
        assert!(QuadEmitter::of(&light).is_none());
    }
}
