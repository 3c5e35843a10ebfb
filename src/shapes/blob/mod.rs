//! POV-Ray's `blob` in its own space: the points where the sum of the components' densities
//! exceeds the threshold (see [`crate::scene::Blob`]). The field along a ray and its first
//! crossing are in [`field`]; here are the hierarchy of the components' boxes (a ray visits the
//! components whose boxes it meets, not all of them), the normal (the field's gradient), the
//! uv and the shape's glue.
//!
//! The uv is spherical about the centre of the blob's box, as the sphere's: u around the y
//! axis (0 toward +z, ¼ toward +x), v from 0 below to 1 above.

pub mod field;

use std::cell::RefCell;
use std::f64::consts::{PI, TAU};

use glam::{DVec2, DVec3, Vec2};

use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene;
use field::{Component, Scratch, first_crossing};

/// Components per leaf of the hierarchy.
pub(super) const LEAF_SIZE: usize = 4;

/// A node of the components' hierarchy: a box, and either two children (`count == 0`, the
/// first at the next index, the second at `next`) or `count` components from `first`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Node {
    pub(super) min: DVec3,
    pub(super) max: DVec3,
    pub(super) next: u32,
    pub(super) first: u32,
    pub(super) count: u32,
}

pub struct Blob {
    comps: Vec<Component>,
    nodes: Vec<Node>,
    threshold: f64,
    /// The union of the boxes of the components of positive strength (the field exceeds the
    /// threshold nowhere else).
    min: DVec3,
    max: DVec3,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

impl Blob {
    pub fn new(blob: &scene::Blob) -> Result<Self, String> {
        blob.check()?;
        let comps: Vec<Component> = blob
            .components
            .iter()
            .map(|c| Component::new(c.a, c.b, c.radius, c.strength, c.transform))
            .collect();
        let boxes: Vec<(DVec3, DVec3)> = comps.iter().map(Component::bounds).collect();
        let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for (c, b) in comps.iter().zip(&boxes) {
            if c.strength > 0.0 {
                min = min.min(b.0);
                max = max.max(b.1);
            }
        }
        let mut order: Vec<u32> = (0..comps.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * comps.len() / LEAF_SIZE + 1);
        build(&boxes, &mut order, 0, &mut nodes);
        let comps = order.iter().map(|&i| comps[i as usize]).collect();
        Ok(Blob {
            comps,
            nodes,
            threshold: blob.threshold,
            min,
            max,
        })
    }

    /// The sum of the densities at `p`.
    pub fn field(&self, p: DVec3) -> f64 {
        let mut f = 0.0;
        self.visit_point(p, |c| f += c.density(p));
        f
    }

    /// The field's gradient at `p`.
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        let mut g = DVec3::ZERO;
        self.visit_point(p, |c| g += c.gradient(p));
        g
    }

    fn visit_point(&self, p: DVec3, mut f: impl FnMut(&Component)) {
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let at = stack[sp];
            let n = &self.nodes[at as usize];
            if p.cmplt(n.min).any() || p.cmpgt(n.max).any() {
                continue;
            }
            if n.count > 0 {
                for c in &self.comps[n.first as usize..(n.first + n.count) as usize] {
                    f(c);
                }
            } else if sp + 2 <= stack.len() {
                stack[sp] = n.next;
                stack[sp + 1] = at + 1;
                sp += 2;
            }
        }
    }

    /// The nearest crossing of the surface with `lo < t < hi` along `o + t d`.
    pub fn nearest(&self, o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<f64> {
        if !(o.is_finite() && d.is_finite()) || d == DVec3::ZERO {
            return None;
        }
        let (lo, hi) = clip(self.min, self.max, o, d, lo, hi)?;
        SCRATCH.with(|s| {
            let s = &mut *s.borrow_mut();
            s.terms.clear();
            let mut stack = [0u32; 64];
            let mut sp = 1;
            while sp > 0 {
                sp -= 1;
                let at = stack[sp];
                let n = &self.nodes[at as usize];
                if clip(n.min, n.max, o, d, lo, hi).is_none() {
                    continue;
                }
                if n.count > 0 {
                    for k in n.first..n.first + n.count {
                        self.comps[k as usize].terms(k, o, d, lo, hi, &mut s.terms);
                    }
                } else if sp + 2 <= stack.len() {
                    stack[sp] = n.next;
                    stack[sp + 1] = at + 1;
                    sp += 2;
                }
            }
            first_crossing(&self.comps, s, self.threshold, o, d).filter(|t| *t > lo && *t < hi)
        })
    }

    /// The outward unit normal at `p`: against the field's gradient (the field grows inward).
    pub fn normal(&self, p: DVec3) -> DVec3 {
        (-self.gradient(p)).normalize_or((p - 0.5 * (self.min + self.max)).normalize_or(DVec3::Y))
    }
}

/// A hit at `p` with normal `n` and uv spherical about `centre`, as the sphere's (around the y
/// axis, 0 toward +z, 1/4 toward +x; v from 0 below to 1 above): the blob's and the
/// isosurface's.
pub(super) fn spherical_hit(t: f32, p: DVec3, n: glam::Vec3A, centre: DVec3) -> Hit {
    let q = p - centre;
    let u = q.x.atan2(q.z).rem_euclid(TAU) / TAU;
    let len = q.length();
    let v = if len > 0.0 {
        1.0 - (q.y / len).clamp(-1.0, 1.0).acos() / PI
    } else {
        0.5
    };
    let around = DVec3::new(q.z, 0.0, -q.x) * TAU;
    let dpdu = if around.length_squared() > 0.0 {
        around.as_vec3a()
    } else {
        n.any_orthonormal_vector()
    };
    Hit {
        t,
        p: p.as_vec3a(),
        n,
        ns: n,
        uv: DVec2::new(u, v).as_vec2(),
        dpdu,
    }
}

/// The part of `[lo, hi]` where `o + t d` lies in the box, if any.
pub(super) fn clip(
    min: DVec3,
    max: DVec3,
    o: DVec3,
    d: DVec3,
    lo: f64,
    hi: f64,
) -> Option<(f64, f64)> {
    let (mut a, mut b) = (lo, hi);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < min[k] || o[k] > max[k] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d[k];
        let (t0, t1) = ((min[k] - o[k]) * inv, (max[k] - o[k]) * inv);
        a = a.max(t0.min(t1));
        b = b.min(t0.max(t1));
    }
    (a <= b).then_some((a, b))
}

/// Builds the hierarchy over `order[..]` (indices into `boxes`) depth first, median split on
/// the longest axis of the boxes' centres; returns the node's index.
pub(super) fn build(
    boxes: &[(DVec3, DVec3)],
    order: &mut [u32],
    offset: u32,
    nodes: &mut Vec<Node>,
) -> u32 {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut cmin, mut cmax) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &i in order.iter() {
        let (lo, hi) = boxes[i as usize];
        min = min.min(lo);
        max = max.max(hi);
        cmin = cmin.min(lo + hi);
        cmax = cmax.max(lo + hi);
    }
    let at = nodes.len() as u32;
    nodes.push(Node {
        min,
        max,
        next: 0,
        first: offset,
        count: order.len() as u32,
    });
    if order.len() <= LEAF_SIZE {
        return at;
    }
    let ext = cmax - cmin;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        let (ca, cb) = (boxes[a as usize], boxes[b as usize]);
        (ca.0[axis] + ca.1[axis]).total_cmp(&(cb.0[axis] + cb.1[axis]))
    });
    let (left, right) = order.split_at_mut(mid);
    build(boxes, left, offset, nodes);
    let second = build(boxes, right, offset + mid as u32, nodes);
    nodes[at as usize].next = second;
    nodes[at as usize].count = 0;
    at
}

impl Shape for Blob {
    fn bounds(&self) -> Aabb {
        Aabb::new(self.min.as_vec3a(), self.max.as_vec3a()).padded(1e-6)
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        let (lo, hi) = super::f64_range(t_min, t_max);
        let t = self.nearest(o, d, lo, hi)?;
        let tf = t as f32;
        if !(tf > t_min && tf < t_max) {
            return None;
        }
        let p = o + t * d;
        let n = self.normal(p).as_vec3a();
        Some(spherical_hit(tf, p, n, 0.5 * (self.min + self.max)))
    }

    /// A blob is not a light's shape: it is never sampled.
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
    use glam::DAffine3;

    fn component(
        a: DVec3,
        b: DVec3,
        radius: f64,
        strength: f64,
        transform: DAffine3,
    ) -> scene::BlobComponent {
        scene::BlobComponent {
            a,
            b,
            radius,
            strength,
            transform,
        }
    }

    fn blob(threshold: f64, comps: Vec<scene::BlobComponent>) -> Blob {
        Blob::new(&scene::Blob {
            threshold,
            components: comps,
        })
        .unwrap()
    }

    #[test]
    fn many_components_are_found_through_the_hierarchy() {
        // A row of 1000 small spheres along x: a ray down onto each hits it, and the hit lies
        // on the surface; a ray between two (beyond their reach) misses.
        let comps = (0..1000)
            .map(|i| {
                let c = DVec3::new(i as f64, 0.0, 0.0);
                component(c, c, 0.3, 1.0, DAffine3::IDENTITY)
            })
            .collect();
        let b = blob(0.5, comps);
        for i in [0, 1, 499, 998, 999] {
            let o = DVec3::new(i as f64, 5.0, 0.0);
            let t = b.nearest(o, -DVec3::Y, 0.0, f64::INFINITY).unwrap();
            assert!((b.field(o - t * DVec3::Y) - 0.5).abs() < 1e-9);
        }
        let o = DVec3::new(10.5, 5.0, 0.0);
        assert_eq!(b.nearest(o, -DVec3::Y, 0.0, f64::INFINITY), None);
        // Along the row: the first sphere.
        let o = DVec3::new(-5.0, 0.0, 0.0);
        let t = b.nearest(o, DVec3::X, 0.0, f64::INFINITY).unwrap();
        assert!(t > 4.7 && t < 5.0, "{t}");
    }

    #[test]
    fn the_normal_points_out_and_the_bounds_hold_the_positive_components() {
        let c = DVec3::new(1.0, 2.0, 3.0);
        let b = blob(
            0.5,
            vec![
                component(c, c, 1.0, 1.0, DAffine3::IDENTITY),
                component(
                    DVec3::splat(50.0),
                    DVec3::splat(50.0),
                    1.0,
                    -1.0,
                    DAffine3::IDENTITY,
                ),
            ],
        );
        let o = c + DVec3::new(0.0, 0.0, -5.0);
        let t = b.nearest(o, DVec3::Z, 0.0, f64::INFINITY).unwrap();
        let n = b.normal(o + t * DVec3::Z);
        assert!((n - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-9, "{n}");
        let bb = Shape::bounds(&b);
        assert!(bb.max.x < 3.0 && bb.min.x > -1.0, "{bb:?}");
    }
}
