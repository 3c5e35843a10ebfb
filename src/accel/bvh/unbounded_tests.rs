//! The unbounded shapes' side list against brute force.

use glam::Vec3A;

use super::*;
use crate::sampling::{Rng, uniform_sphere};
use crate::shapes::plane::Plane;
use crate::shapes::sphere::Sphere;

/// A room of six planes (as `smallppm`'s walls) with spheres in it: the nearest hit (its `t`
/// bit for bit, and its id) and the shadow query agree with each shape's own tests, for rays
/// from inside, from outside, from points on a wall (`t_min` 0 and small) and grazing a wall.
#[test]
fn planes_match_brute_force() {
    let mut rng = Rng::new(41);
    let v = |rng: &mut Rng| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3A::ONE;
    let walls = [
        (Vec3A::X, -1.0),
        (-Vec3A::X, -1.0),
        (Vec3A::Y, -1.0),
        (-Vec3A::Y, -1.0),
        (Vec3A::Z, -1.0),
        (-Vec3A::Z, -1.5),
    ];
    let mut shapes: Vec<AnyShape> = walls
        .iter()
        .map(|&(n, o)| AnyShape::Plane(Plane::new(n, o).unwrap()))
        .collect();
    for _ in 0..6 {
        let c = 0.7 * v(&mut rng);
        shapes.push(AnyShape::Sphere(
            Sphere::new(c, 0.1 + 0.2 * rng.f32()).unwrap(),
        ));
    }
    let copy = |s: &AnyShape| match s {
        AnyShape::Plane(p) => AnyShape::Plane(*p),
        AnyShape::Sphere(s) => AnyShape::Sphere(*s),
        _ => unreachable!("only planes and spheres here"),
    };
    let bvh = Bvh::new(
        shapes
            .iter()
            .enumerate()
            .map(|(i, s)| (copy(s), i as u32))
            .collect(),
    )
    .expect("a BVH of test size");
    assert_eq!(bvh.unbounded_len(), walls.len());
    let (mut wall_hits, mut blocked, mut open) = (0, 0, 0);
    for i in 0..20_000 {
        let mut o = 2.0 * v(&mut rng);
        let mut d = uniform_sphere(rng.vec2());
        if i % 4 == 1 {
            // On a wall: a point of the plane `n.p = offset`.
            let (n, off) = walls[i % walls.len()];
            o -= n * (n.dot(o) - off);
        }
        if i % 4 == 2 {
            // Grazing a wall: the direction nearly in its plane.
            let n = walls[i % walls.len()].0;
            d = (d - n * (n.dot(d) - 1e-6 * rng.f32())).normalize();
        }
        let ray = Ray::new(o, d);
        let t_min = [0.0, 1e-4, 0.0, 1e-3][i % 4];
        let t_max = if i % 3 == 0 {
            0.5 + rng.f32()
        } else {
            f32::INFINITY
        };
        let mut brute: Option<(f32, u32)> = None;
        let mut limit = t_max;
        for (k, s) in shapes.iter().enumerate() {
            if let Some(h) = s.intersect(&ray, t_min, limit) {
                limit = h.t;
                brute = Some((h.t, k as u32));
            }
        }
        let got = bvh.intersect(&ray, t_min, t_max).map(|(h, id)| (h.t, id));
        assert_eq!(
            got.map(|(t, id)| (t.to_bits(), id)),
            brute.map(|(t, id)| (t.to_bits(), id)),
            "ray {i}"
        );
        let any = shapes.iter().any(|s| s.occluded(&ray, t_min, t_max));
        assert_eq!(bvh.occluded(&ray, t_min, t_max), any, "ray {i}");
        assert_eq!(any, brute.is_some(), "ray {i}");
        wall_hits += usize::from(brute.is_some_and(|(_, id)| (id as usize) < walls.len()));
        if any {
            blocked += 1;
        } else {
            open += 1;
        }
    }
    // Both answers of each query seen many times.
    assert!(wall_hits > 5000, "{wall_hits} wall hits");
    assert!(
        blocked > 5000 && open > 2000,
        "{blocked} blocked, {open} open"
    );
}
