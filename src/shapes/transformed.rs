//! A shape under a general affine transform: rays go to object space, hits come back. The
//! inner shape is shared, so one object-space shape (a mesh's own BVH) can be placed many times.
//! The inner shape's type is a parameter: `Transformed<Revolve>` calls its shape directly (no
//! second dynamic call per ray), `Transformed` (of `dyn Shape`) holds any shape.

use std::sync::Arc;

use glam::{Affine3A, Mat3A, Vec2};

use super::{AreaSample, BoxedHit, Deferred, Shape};
use crate::geometry::{Aabb, Hit, Ray};

pub struct Transformed<S: Shape + ?Sized = dyn Shape> {
    inner: Arc<S>,
    to_world: Affine3A,
    to_object: Affine3A,
    /// Inverse transpose of the linear part: maps normals.
    normal_matrix: Mat3A,
}

impl<S: Shape + ?Sized> Transformed<S> {
    /// Fails only when the transform has no f32 inverse. How flat or small a transform may be
    /// is decided before (the evaluator's matrix check, the scene's size limits): a bound on
    /// the determinant here would refuse a uniformly small object (`scale 1e-4` has
    /// determinant 1e-12) that renders like a large one.
    pub fn new(inner: Arc<S>, to_world: Affine3A) -> Result<Self, String> {
        let det = to_world.matrix3.determinant();
        let to_object = to_world.inverse();
        if !(det.is_finite() && det != 0.0 && to_object.is_finite()) {
            return Err("the object's transform is singular (a zero scale?)".into());
        }
        Ok(Self {
            inner,
            to_world,
            to_object,
            normal_matrix: to_object.matrix3.transpose(),
        })
    }
}

impl<S: Shape + ?Sized> Transformed<S> {
    /// The ray in object space (an affine map keeps the ray parameter `t`).
    #[inline]
    fn object_ray(&self, ray: &Ray) -> Ray {
        Ray::new(
            self.to_object.transform_point3a(ray.o),
            self.to_object.transform_vector3a(ray.d),
        )
    }

    /// An object-space hit in world space.
    #[inline]
    fn world_hit(&self, h: Hit) -> Hit {
        Hit {
            t: h.t,
            p: self.to_world.transform_point3a(h.p),
            n: (self.normal_matrix * h.n).normalize(),
            ns: (self.normal_matrix * h.ns).normalize(),
            uv: h.uv,
            dpdu: self.to_world.transform_vector3a(h.dpdu),
        }
    }
}

impl<S: Shape + ?Sized> Shape for Transformed<S> {
    fn bounds(&self) -> Aabb {
        let b = self.inner.bounds();
        if b.is_empty() {
            return b;
        }
        Aabb::from_points((0..8).map(|i| {
            let c = glam::Vec3A::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            self.to_world.transform_point3a(c)
        }))
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let h = self.inner.intersect(&self.object_ray(ray), t_min, t_max)?;
        Some(self.world_hit(h))
    }

    fn intersect_boxed(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<BoxedHit> {
        Some(
            match self
                .inner
                .intersect_boxed(&self.object_ray(ray), t_min, t_max)?
            {
                BoxedHit::Full(h) => BoxedHit::Full(self.world_hit(h)),
                deferred => deferred,
            },
        )
    }

    fn complete(&self, ray: &Ray, t: f32, rec: Deferred, uv: bool) -> Hit {
        // The same object-space ray as `intersect_boxed` gave the inner shape.
        self.world_hit(self.inner.complete(&self.object_ray(ray), t, rec, uv))
    }

    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.inner.occluded(&self.object_ray(ray), t_min, t_max)
    }

    /// Not known in closed form for a general affine map: emissive objects need a transform
    /// the renderer can bake (see `render::prepared`).
    fn area(&self) -> f32 {
        0.0
    }

    fn sample(&self, _u: Vec2) -> Option<AreaSample> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::sphere::Sphere;
    use glam::Vec3A;

    /// A unit sphere scaled by `s` about the origin, hit from `<0, 0, -3 s>` along +z.
    fn hit_scaled(s: f32) -> Result<Option<Hit>, String> {
        let sphere = Arc::new(Sphere::new(Vec3A::ZERO, 1.0)?);
        let t = Transformed::new(sphere, Affine3A::from_scale(glam::Vec3::splat(s)))?;
        let ray = Ray::new(Vec3A::new(0.0, 0.0, -3.0 * s), Vec3A::Z);
        Ok(t.intersect(&ray, 0.0, f32::INFINITY))
    }

    #[test]
    fn a_small_uniform_scale_is_not_singular() {
        // Determinants 1e-12 to 1e-27: each a well-conditioned transform.
        for s in [1e-4f32, 1e-5, 1e-7, 1e-9] {
            let h = hit_scaled(s)
                .unwrap_or_else(|e| panic!("scale {s}: {e}"))
                .unwrap_or_else(|| panic!("scale {s}: the ray missed"));
            assert!((h.t / s - 2.0).abs() < 1e-5, "scale {s}: t = {}", h.t);
            assert!(
                (h.n - Vec3A::NEG_Z).length() < 1e-5,
                "scale {s}: n = {}",
                h.n
            );
        }
    }

    #[test]
    fn a_transform_without_an_f32_inverse_is_refused() {
        assert!(hit_scaled(0.0).is_err());
        // Determinant 1e-45 (subnormal): its inverse overflows f32.
        assert!(hit_scaled(1e-15).is_err());
        let flat = Affine3A::from_scale(glam::Vec3::new(1.0, 0.0, 1.0));
        let sphere = Arc::new(Sphere::new(Vec3A::ZERO, 1.0).unwrap());
        assert!(Transformed::new(sphere, flat).is_err());
    }
}
