//! A prepared scene's ray queries: rays spawned off a surface, the closest hit (with its `uv`
//! only where a texture reads it), shadow rays, and whether a ray may end on an area light.

use glam::Vec3A;

use super::{PreparedScene, SurfaceHit, finite};
use crate::accel;
use crate::geometry::Ray;

impl PreparedScene<'_> {
    /// A ray leaving the surface point `p` (geometric normal `n`) in direction `dir`, its origin
    /// moved off the surface ([`accel::spawn_ray`]).
    #[inline]
    pub fn spawn_ray(&self, p: Vec3A, n: Vec3A, dir: Vec3A) -> Ray {
        accel::spawn_ray(p, n, dir, self.offset_floor)
    }

    /// A shadow ray from `p` to `target` (on a surface with normal `nt`), `t` up to the returned
    /// bound ([`accel::spawn_ray_to`]).
    #[inline]
    pub fn spawn_ray_to(&self, p: Vec3A, n: Vec3A, target: Vec3A, nt: Vec3A) -> (Ray, f32) {
        accel::spawn_ray_to(p, n, target, nt, self.offset_floor)
    }

    /// Inlined (always): each caller runs the choice of the query (a flat leaf, or the tree
    /// with AVX or without; each one out-of-line copy) and the tree's check of the ray, and the
    /// query writes its record into the caller's frame. (The traversal itself inlined into
    /// each caller ran fewer instructions but fewer photons/s: docs/measurements.md, "Tried and
    /// not kept".)
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        // A CSG tree names the part hit: its material and texture space are that part's. A ray
        // with a non-finite origin or direction hits nothing.
        let (hit, prim) = self
            .bvh
            .intersect_finite_uv(ray, 0.0, t_max, |prim| self.reads_uv(prim))?;
        Some(SurfaceHit { hit, prim })
    }

    /// Whether anything may read the `uv` of a hit on `prim`: only textures do (through
    /// [`Self::tex_coord`], for the lobes or a glass's absorption), so a primitive whose
    /// material has no texture gets hits without it (spheres, disks and cylinders then skip
    /// their trigonometry, revolves their arc length and angle; `uv` is NaN).
    #[inline]
    fn reads_uv(&self, prim: u32) -> bool {
        let m = self.prim_material[prim as usize] as usize;
        self.textured.get(m).copied().unwrap_or(true)
    }

    /// Whether the closest hit of `ray` may be on an area light: false only where the ray
    /// misses every (padded) box around the lights' primitives. A ray for which this is false
    /// ends on no light whatever [`Self::intersect`] finds (if anything).
    #[inline]
    pub fn may_hit_light(&self, ray: &Ray) -> bool {
        self.light_bounds.may_reach(ray)
    }

    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        finite(ray) && self.bvh.occluded(ray, 0.0, t_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::eval::{EvalOptions, load_file, load_source};
    use crate::geometry::Hit;
    use crate::sampling::{Rng, uniform_sphere};
    use crate::shapes::primitive::{AnyShape, LazyHit};

    /// A hit from [`PreparedScene::intersect`] is the full hit of the same shape, field for
    /// field and bit for bit, except that `uv` is NaN on spheres, disks, cylinders and revolves
    /// whose material reads no texture. Checked on the examples with textured and plain spheres,
    /// cylinders, disks, quads and revolves, and on glass whose absorption is textured, with
    /// camera rays and rays from random points in random directions (back faces, insides);
    /// fails if `uv` is left out where a texture could read it, or if leaving it out changed
    /// anything else.
    #[test]
    fn hits_leave_out_uv_only_where_no_texture_reads_it() {
        let root = crate::repo_root().join("examples");
        let (mut kept, mut left_out, mut absorbing_kept) = (0usize, 0usize, 0usize);
        // Revolve hits with `uv` kept and left out.
        let mut revolves = (0usize, 0usize);
        // Glass whose absorption is a uv-mapped texture reads `uv` too (its lobes do not).
        let absorbing = r#"
            camera { location <0, 1.2, -4>  look_at <0, 0.5, 0>  fov 60 }
            #declare Inked = material { glass absorb texture { checker rgb 3, rgb 0 map uv scale 0.1 } }
            #declare Clear = material { glass absorb rgb 0.5 }
            sphere { <-1.2, 0.5, 0>, 0.5  material { Inked } }
            cylinder { <0, 0, 0>, <0, 1, 0>, 0.4  material { Inked } }
            disk { <1.2, 0.5, 0>, <0, 0, -1>, 0.5  material { Inked } }
            sphere { <-1.2, 0.5, 1.5>, 0.5  material { Clear } }
            cylinder { <0, 0, 1.5>, <0, 1, 1.5>, 0.4  material { Clear } }
        "#;
        let examples = [
            "textures.scn",
            "room.scn",
            "crystal_tree.scn",
            "cornell.scn",
            "goblet.scn",
        ]
        .map(|name| {
            let loaded = load_file(&root.join(name), &EvalOptions::default()).unwrap();
            (name, loaded.scene.unwrap())
        });
        let inline = load_source("absorbing.scn", absorbing, &EvalOptions::default());
        for (name, scene) in examples
            .into_iter()
            .chain([("absorbing glass", inline.scene.unwrap())])
        {
            let prepared = PreparedScene::new(&scene).unwrap();
            let camera = Camera::new(&scene.camera, scene.settings.handedness, 64, 64).unwrap();
            let bounds = prepared.bvh.bounds();
            let mut rng = Rng::new(17);
            let mut rays: Vec<Ray> = (0..64 * 64)
                .map(|i| camera.ray(i % 64, i / 64, rng.vec2(), rng.vec2()))
                .collect();
            for _ in 0..4096 {
                let u = Vec3A::new(rng.f32(), rng.f32(), rng.f32());
                let o = bounds.min + u * (bounds.max - bounds.min);
                rays.push(Ray::new(o, uniform_sphere(rng.vec2())));
            }
            for ray in &rays {
                let full = prepared.bvh.intersect(ray, 0.0, f32::INFINITY);
                let got = prepared.intersect(ray, f32::INFINITY);
                let (Some((full, id)), Some(got)) = (full, got) else {
                    assert!(full.is_none() && got.is_none(), "{name}: {ray:?}");
                    continue;
                };
                assert_eq!(id, got.prim, "{name}");
                let bits = |h: &Hit| {
                    let v = [h.p, h.n, h.ns, h.dpdu].map(|v| v.to_array().map(f32::to_bits));
                    (h.t.to_bits(), v)
                };
                assert_eq!(bits(&full), bits(&got.hit), "{name}: {ray:?}");
                let lazy = prepared.bvh.intersect_lazy(ray, 0.0, f32::INFINITY);
                // A revolve's hit is deferred (its `uv` needs the arc length and an angle).
                let deferred = matches!(lazy, Some((LazyHit::Deferred(..), _, _)));
                let trig = deferred
                    || matches!(
                        lazy.and_then(|(_, s, _)| s.shape()),
                        Some(AnyShape::Sphere(_) | AnyShape::Disk(_) | AnyShape::Cylinder(_))
                    );
                if trig && !prepared.reads_uv(id) {
                    assert!(got.hit.uv.is_nan(), "{name}");
                    left_out += 1;
                    revolves.1 += usize::from(deferred);
                } else {
                    let uv_bits = |h: &Hit| h.uv.to_array().map(f32::to_bits);
                    assert_eq!(uv_bits(&full), uv_bits(&got.hit), "{name}: {ray:?}");
                    kept += usize::from(trig);
                    revolves.0 += usize::from(deferred);
                    if name == "absorbing glass" {
                        absorbing_kept += usize::from(trig);
                    }
                }
            }
        }
        println!(
            "uv kept on {kept} textured trig-shape hits ({absorbing_kept} on glass with textured \
             absorption), left out on {left_out}"
        );
        println!(
            "revolve hits: uv kept on {}, left out on {}",
            revolves.0, revolves.1
        );
        assert!(kept > 1000 && left_out > 1000, "{kept} {left_out}");
        assert!(revolves.0 > 300 && revolves.1 > 300, "{revolves:?}");
        assert!(absorbing_kept > 300, "{absorbing_kept}");
    }
}
