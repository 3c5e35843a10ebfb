use glam::Vec3A;

use super::Ray;

/// Axis-aligned bounding box. The empty box has `min > max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    pub fn new(a: Vec3A, b: Vec3A) -> Self {
        Self {
            min: a.min(b),
            max: a.max(b),
        }
    }

    pub fn from_points(points: impl IntoIterator<Item = Vec3A>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.with_point(p))
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn with_point(self, p: Vec3A) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn centroid(&self) -> Vec3A {
        (self.min + self.max) * 0.5
    }

    pub fn diagonal(&self) -> Vec3A {
        self.max - self.min
    }

    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.diagonal();
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// Grows the box by `eps` times its largest extent (at least `eps`) on every side, so that
    /// flat boxes (a quad, a plane) still have volume.
    pub fn padded(self, eps: f32) -> Self {
        let pad = Vec3A::splat(eps * self.diagonal().max_element().max(1.0));
        Self {
            min: self.min - pad,
            max: self.max + pad,
        }
    }

    /// Slab test with a precomputed reciprocal direction; returns the entry distance.
    #[inline]
    pub fn hit(&self, ray: &Ray, inv_d: Vec3A, t_min: f32, t_max: f32) -> Option<f32> {
        let t0 = (self.min - ray.o) * inv_d;
        let t1 = (self.max - ray.o) * inv_d;
        let near = t0.min(t1).max_element().max(t_min);
        // Scale the far bound up by 1 + 2*gamma(3) (pbrt) so that rounding never culls a hit.
        let far = t0.max(t1).min_element().min(t_max) * 1.000_000_4;
        (near <= far).then_some(near)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_test_hits_and_misses() {
        let b = Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        let r = Ray::new(Vec3A::new(0.0, 0.0, -5.0), Vec3A::Z);
        assert_eq!(b.hit(&r, r.d.recip(), 0.0, f32::INFINITY), Some(4.0));
        let miss = Ray::new(Vec3A::new(2.0, 0.0, -5.0), Vec3A::Z);
        assert_eq!(b.hit(&miss, miss.d.recip(), 0.0, f32::INFINITY), None);
        assert_eq!(b.hit(&r, r.d.recip(), 0.0, 3.0), None);
    }

    #[test]
    fn flat_box_is_hit_edge_on_after_padding() {
        let b = Aabb::new(Vec3A::new(-1.0, 0.0, -1.0), Vec3A::new(1.0, 0.0, 1.0)).padded(1e-4);
        let r = Ray::new(Vec3A::new(0.0, 5.0, 0.0), -Vec3A::Y);
        assert!(b.hit(&r, r.d.recip(), 0.0, f32::INFINITY).is_some());
    }
}
