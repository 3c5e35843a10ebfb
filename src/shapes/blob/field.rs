//! The numerical heart of the blob: its field along a ray as a piecewise quartic, and the first
//! crossing of the threshold found by exact root isolation.
//!
//! A component's density `s * (1 - d^2 / r^2)^2` depends on the squared distance `d^2` to its
//! centre (a sphere) or to its segment (a capsule). Along a ray `p(t)` (in the component's own
//! space, where the ray is still a straight line in the same `t`), `d^2` is a quadratic in `t`
//! on each region of the component: for a capsule the distance is to the end `a` where the
//! projection on the axis falls before it, to the axis along the body, to the end `b` beyond
//! it, so the ray's parameters where the projection meets the ends split it into up to three
//! terms. Each term is a quartic on the interval where the ray is within the radius. Sorting
//! the ends of the terms cuts the ray into pieces on which the field minus the threshold is one
//! quartic; on each, in order, its Bernstein form on the piece is handed to the root isolator
//! (`bezier::roots`), which cannot miss a sign change. A root where the field only touches the
//! threshold (a double root: a ray grazing the surface) is not a crossing.

use glam::{DAffine3, DMat3, DVec3};

use crate::bezier::bernstein::Bernstein;
use crate::bezier::roots::{Root, RootKind, find_roots};

/// One component in the blob's space, ready for rays.
#[derive(Debug, Clone, Copy)]
pub struct Component {
    /// From the blob's space to the component's own.
    to_local: DAffine3,
    /// The transpose of `to_local`'s linear part: takes a gradient back to the blob's space.
    grad_back: DMat3,
    a: DVec3,
    /// Unit axis from `a` to `b` and the segment's length (0: a sphere).
    axis: DVec3,
    len: f64,
    r2: f64,
    pub strength: f64,
}

/// Which part of a component a term is: the sphere around `a` or `b`, or the body around the axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Region {
    EndA,
    Body,
    EndB,
}

/// A component's contribution on an interval of the ray: there `d^2` is one quadratic.
#[derive(Debug, Clone, Copy)]
pub struct Term {
    pub t0: f64,
    pub t1: f64,
    comp: u32,
    region: Region,
}

/// The `t` interval where `|q + t e| < r` (`r2 = r^2`), if any.
fn within(q: DVec3, e: DVec3, r2: f64) -> Option<(f64, f64)> {
    let a = e.length_squared();
    let c = q.length_squared() - r2;
    if a == 0.0 {
        return (c < 0.0).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let b = q.dot(e);
    let disc = b * b - a * c;
    if disc.is_nan() || disc <= 0.0 {
        return None;
    }
    // The stable pair of roots: no cancellation in either.
    let k = -(b + b.signum() * disc.sqrt());
    let (t0, t1) = if k == 0.0 {
        let h = (-c / a).sqrt();
        (-h, h)
    } else {
        (k / a, c / k)
    };
    Some((t0.min(t1), t0.max(t1)))
}

impl Component {
    /// A sphere (`a == b`) or capsule of radius `r` with `strength`, placed by `from_local`
    /// (the component's space to the blob's; invertible).
    pub fn new(a: DVec3, b: DVec3, r: f64, strength: f64, from_local: DAffine3) -> Self {
        let to_local = from_local.inverse();
        let len = (b - a).length();
        let axis = if len > 0.0 { (b - a) / len } else { DVec3::X };
        Component {
            to_local,
            grad_back: to_local.matrix3.transpose(),
            a,
            axis,
            len,
            r2: r * r,
            strength,
        }
    }

    /// The component's box in the blob's space: its own box's corners placed.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let r = DVec3::splat(self.r2.sqrt());
        let b = self.a + self.len * self.axis;
        let (lo, hi) = (self.a.min(b) - r, self.a.max(b) + r);
        let from = self.to_local.inverse();
        let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for i in 0..8 {
            let pick = |bit: i32, u: f64, v: f64| if i & bit == 0 { u } else { v };
            let c = DVec3::new(
                pick(1, lo.x, hi.x),
                pick(2, lo.y, hi.y),
                pick(4, lo.z, hi.z),
            );
            let p = from.transform_point3(c);
            min = min.min(p);
            max = max.max(p);
        }
        (min, max)
    }

    /// The offset from the nearest point of the component's centre (segment) to the local
    /// point `l`, in the region's sense.
    #[inline]
    fn offset(&self, l: DVec3, region: Region) -> DVec3 {
        let q = l - self.a;
        match region {
            Region::EndA => q,
            Region::Body => q - q.dot(self.axis) * self.axis,
            Region::EndB => q - self.len * self.axis,
        }
    }

    fn region_of(&self, l: DVec3) -> Region {
        let s = (l - self.a).dot(self.axis);
        if self.len == 0.0 || s < 0.0 {
            Region::EndA
        } else if s > self.len {
            Region::EndB
        } else {
            Region::Body
        }
    }

    /// The density at the point `p` (blob space).
    pub fn density(&self, p: DVec3) -> f64 {
        let l = self.to_local.transform_point3(p);
        let d2 = self.offset(l, self.region_of(l)).length_squared();
        if d2 >= self.r2 {
            return 0.0;
        }
        let w = 1.0 - d2 / self.r2;
        self.strength * w * w
    }

    /// The density's gradient at `p` (blob space).
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        let l = self.to_local.transform_point3(p);
        let q = self.offset(l, self.region_of(l));
        let d2 = q.length_squared();
        if d2 >= self.r2 {
            return DVec3::ZERO;
        }
        let w = 1.0 - d2 / self.r2;
        // d/dq of s (1 - |q|^2/r^2)^2 = -4 s w q / r^2.
        self.grad_back * (q * (-4.0 * self.strength * w / self.r2))
    }

    /// Appends this component's terms along the ray `o + t d` (blob space) within `[lo, hi]`.
    pub fn terms(&self, comp: u32, o: DVec3, d: DVec3, lo: f64, hi: f64, out: &mut Vec<Term>) {
        let ol = self.to_local.transform_point3(o);
        let dl = self.to_local.transform_vector3(d);
        let mut push = |iv: Option<(f64, f64)>, from: f64, to: f64, region: Region| {
            if let Some((t0, t1)) = iv {
                let (t0, t1) = (t0.max(from).max(lo), t1.min(to).min(hi));
                if t0 < t1 {
                    out.push(Term {
                        t0,
                        t1,
                        comp,
                        region,
                    });
                }
            }
        };
        let q = ol - self.a;
        if self.len == 0.0 {
            push(within(q, dl, self.r2), lo, hi, Region::EndA);
            return;
        }
        // The projection on the axis, s(t) = s0 + t ds: where it meets 0 and len.
        let (s0, ds) = (q.dot(self.axis), dl.dot(self.axis));
        let (before_a, past_b) = if ds == 0.0 {
            // Parallel to the ends' planes: one region for the whole ray.
            let region = if s0 < 0.0 {
                Region::EndA
            } else if s0 > self.len {
                Region::EndB
            } else {
                Region::Body
            };
            let iv = within(
                self.offset(ol, region),
                self.offset_dir(dl, region),
                self.r2,
            );
            push(iv, lo, hi, region);
            return;
        } else {
            (-s0 / ds, (self.len - s0) / ds)
        };
        let (first, second) = (before_a.min(past_b), before_a.max(past_b));
        let (r_first, r_last) = if ds > 0.0 {
            (Region::EndA, Region::EndB)
        } else {
            (Region::EndB, Region::EndA)
        };
        let inf = f64::INFINITY;
        for (region, from, to) in [
            (r_first, -inf, first),
            (Region::Body, first, second),
            (r_last, second, inf),
        ] {
            let iv = within(
                self.offset(ol, region),
                self.offset_dir(dl, region),
                self.r2,
            );
            push(iv, from, to, region);
        }
    }

    /// How the region's offset changes along the local direction `dl`.
    #[inline]
    fn offset_dir(&self, dl: DVec3, region: Region) -> DVec3 {
        match region {
            Region::Body => dl - dl.dot(self.axis) * self.axis,
            _ => dl,
        }
    }

    /// The Bernstein coefficients (degree 4, on `u` in [0, 1] for `t = t0 + u (t1 - t0)`) of the
    /// term's density over the piece `[t0, t1]` of the ray `o + t d`, added to `acc`.
    fn add_piece(&self, region: Region, o: DVec3, d: DVec3, t0: f64, t1: f64, acc: &mut [f64; 5]) {
        let ol = self.to_local.transform_point3(o + t0 * d);
        let dl = self.to_local.transform_vector3(d) * (t1 - t0);
        let (q, e) = (self.offset(ol, region), self.offset_dir(dl, region));
        // w(u) = 1 - |q + u e|^2 / r^2 = m0 + m1 u + m2 u^2, in Bernstein form (degree 2).
        let inv = 1.0 / self.r2;
        let m0 = 1.0 - q.length_squared() * inv;
        let m1 = -2.0 * q.dot(e) * inv;
        let m2 = -e.length_squared() * inv;
        let (b0, b1, b2) = (m0, m0 + 0.5 * m1, m0 + m1 + m2);
        // w^2 in Bernstein form (degree 4): the product rule of Bernstein coefficients.
        let s = self.strength;
        acc[0] += s * b0 * b0;
        acc[1] += s * b0 * b1;
        acc[2] += s * (2.0 * b0 * b2 + 4.0 * b1 * b1) / 6.0;
        acc[3] += s * b1 * b2;
        acc[4] += s * b2 * b2;
    }
}

/// Per-ray working space of [`first_crossing`] (kept by the caller between rays, so that a ray
/// allocates nothing once the vectors have grown).
#[derive(Default)]
pub struct Scratch {
    pub terms: Vec<Term>,
    events: Vec<(f64, u32)>,
    live: Vec<bool>,
    active: Vec<u32>,
    roots: Vec<Root>,
}

/// The first `t` where the field of `comps` crosses `threshold` along `o + t d`, given in
/// `s.terms` the terms of the components the ray meets (clipped to the range searched).
pub fn first_crossing(
    comps: &[Component],
    s: &mut Scratch,
    threshold: f64,
    o: DVec3,
    d: DVec3,
) -> Option<f64> {
    let Scratch {
        terms,
        events,
        live,
        active,
        roots,
    } = s;
    events.clear();
    for (i, term) in terms.iter().enumerate() {
        events.push((term.t0, i as u32));
        events.push((term.t1, i as u32));
    }
    events.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    // The terms of the current piece (t0 <= its start < t1); `live[i]` says whether term i is.
    live.clear();
    live.resize(terms.len(), false);
    active.clear();
    for k in 0..events.len() {
        let (t, i) = events[k];
        let iu = i as usize;
        if !live[iu] && terms[iu].t0 == t {
            live[iu] = true;
            active.push(i);
        } else if live[iu] && terms[iu].t1 <= t {
            live[iu] = false;
            if let Some(pos) = active.iter().position(|&a| a == i) {
                active.swap_remove(pos);
            }
        }
        let Some(&(next, _)) = events.get(k + 1) else {
            break;
        };
        if next <= t || active.is_empty() {
            continue;
        }
        // The field never exceeds the sum of the positive strengths here: skip the piece if
        // that stays below the threshold.
        let top: f64 = active
            .iter()
            .map(|&a| comps[terms[a as usize].comp as usize].strength.max(0.0))
            .sum();
        if top < threshold {
            continue;
        }
        let mut acc = [-threshold; 5];
        for &a in active.iter() {
            let term = &terms[a as usize];
            comps[term.comp as usize].add_piece(term.region, o, d, t, next, &mut acc);
        }
        let Some(poly) = Bernstein::new(&acc) else {
            continue;
        };
        roots.clear();
        find_roots(&poly, roots);
        for r in roots.iter() {
            let crossing = match r.kind {
                RootKind::Simple => true,
                // A cluster is a crossing only if the field lies on both sides of it (an odd
                // multiplicity); a touch is a graze.
                RootKind::Multiple => {
                    let (a, b) = (poly.eval(r.lo), poly.eval(r.hi));
                    (a < 0.0) != (b < 0.0) && a != 0.0 && b != 0.0
                }
            };
            if crossing {
                return Some((t + r.t * (next - t)).clamp(t, next));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(c: DVec3, r: f64, s: f64) -> Component {
        Component::new(c, c, r, s, DAffine3::IDENTITY)
    }

    fn crossing(comps: &[Component], t: f64, o: DVec3, d: DVec3) -> Option<f64> {
        let mut s = Scratch::default();
        for (i, c) in comps.iter().enumerate() {
            c.terms(i as u32, o, d, 0.0, 1e30, &mut s.terms);
        }
        first_crossing(comps, &mut s, t, o, d)
    }

    #[test]
    fn a_single_sphere_is_a_sphere_of_the_threshold_radius() {
        // s (1 - d^2/r^2)^2 = t at d = r sqrt(1 - sqrt(t/s)).
        let c = [sphere(DVec3::ZERO, 2.0, 1.0)];
        let want = 2.0 * (1.0 - 0.5f64.sqrt()).sqrt();
        let o = DVec3::new(0.0, 0.0, -5.0);
        let t = crossing(&c, 0.5, o, DVec3::Z).unwrap();
        assert!((t - (5.0 - want)).abs() < 1e-12, "{t}");
        // From inside, the exit.
        let t = crossing(&c, 0.5, DVec3::ZERO, DVec3::Z).unwrap();
        assert!((t - want).abs() < 1e-12, "{t}");
        // A strength below the threshold: nothing.
        let weak = [sphere(DVec3::ZERO, 2.0, 0.4)];
        assert_eq!(crossing(&weak, 0.5, o, DVec3::Z), None);
    }

    #[test]
    fn two_spheres_merge_between_them_where_each_alone_is_below() {
        // Centres 2 apart, radius 1.5, strength 1, threshold 0.3: at the midpoint each gives
        // (1 - 1/2.25)^2 = 0.309, the sum 0.617 > 0.3, so the segment between them is inside.
        let c = [
            sphere(DVec3::new(-1.0, 0.0, 0.0), 1.5, 1.0),
            sphere(DVec3::new(1.0, 0.0, 0.0), 1.5, 1.0),
        ];
        let field = |p: DVec3| c.iter().map(|k| k.density(p)).sum::<f64>();
        assert!(field(DVec3::ZERO) > 0.3);
        let o = DVec3::new(0.0, -5.0, 0.0);
        let t = crossing(&c, 0.3, o, DVec3::Y).unwrap();
        let p = o + t * DVec3::Y;
        assert!((field(p) - 0.3).abs() < 1e-9, "{}", field(p));
        // A negative component at the midpoint cuts them apart.
        let mut cut = c.to_vec();
        cut.push(sphere(DVec3::ZERO, 0.8, -2.0));
        assert_eq!(crossing(&cut, 0.3, o, DVec3::Y), None);
        let along = crossing(&cut, 0.3, DVec3::new(-5.0, 0.0, 0.0), DVec3::X).unwrap();
        let p = DVec3::new(-5.0 + along, 0.0, 0.0);
        let f = cut.iter().map(|k| k.density(p)).sum::<f64>();
        assert!((f - 0.3).abs() < 1e-9 && p.x < -1.0, "{p} {f}");
    }

    #[test]
    fn a_capsule_is_a_capsule_across_its_regions() {
        // Axis from (0,0,0) to (4,0,0), r = 1, s = 1, threshold 0.25: surface at
        // d = sqrt(1 - 0.5) from the segment.
        let c = [Component::new(
            DVec3::ZERO,
            DVec3::new(4.0, 0.0, 0.0),
            1.0,
            1.0,
            DAffine3::IDENTITY,
        )];
        let rad = 0.5f64.sqrt();
        // Along the axis from beyond b: hits the hemisphere around b.
        let t = crossing(&c, 0.25, DVec3::new(10.0, 0.0, 0.0), -DVec3::X).unwrap();
        assert!((t - (6.0 - rad)).abs() < 1e-12, "{t}");
        // Down onto the body.
        let t = crossing(&c, 0.25, DVec3::new(2.0, 5.0, 0.0), -DVec3::Y).unwrap();
        assert!((t - (5.0 - rad)).abs() < 1e-12, "{t}");
        // A diagonal ray through cap and body: the hit lies on the surface.
        let (o, d) = (
            DVec3::new(-3.0, 3.0, 0.3),
            DVec3::new(1.0, -0.8, 0.0).normalize(),
        );
        let t = crossing(&c, 0.25, o, d).unwrap();
        assert!((c[0].density(o + t * d) - 0.25).abs() < 1e-9);
    }

    #[test]
    fn grazing_a_sphere_tangentially_is_not_a_hit_but_just_inside_is() {
        let c = [sphere(DVec3::ZERO, 1.0, 1.0)];
        let rs = (1.0 - 0.5f64.sqrt()).sqrt(); // the surface's radius at threshold 0.5
        let o = |y: f64| DVec3::new(-5.0, y, 0.0);
        assert!(crossing(&c, 0.5, o(rs * (1.0 - 1e-7)), DVec3::X).is_some());
        assert_eq!(crossing(&c, 0.5, o(rs * (1.0 + 1e-7)), DVec3::X), None);
    }

    #[test]
    fn the_gradient_points_up_the_field_and_matches_differences() {
        let tr = DAffine3::from_scale_rotation_translation(
            DVec3::new(1.0, 2.0, 0.5),
            glam::DQuat::from_rotation_z(0.3),
            DVec3::new(0.2, 0.1, 0.0),
        );
        let c = Component::new(DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), 0.8, 1.5, tr);
        let p = DVec3::new(0.6, 0.5, 0.1);
        let g = c.gradient(p);
        let h = 1e-6;
        for k in 0..3 {
            let mut e = DVec3::ZERO;
            e[k] = h;
            let fd = (c.density(p + e) - c.density(p - e)) / (2.0 * h);
            assert!((fd - g[k]).abs() < 1e-6, "{k}: {fd} vs {}", g[k]);
        }
        let (lo, hi) = c.bounds();
        assert!(p.cmpge(lo).all() && p.cmple(hi).all());
    }
}
