//! POV-Ray's curved `sphere_sweep` (`cubic_spline`, `b_spline`) in its own space: the union of
//! the spheres along a chain of cubic segments (see [`crate::scene::SphereSweep`]). Where a ray
//! meets one segment's spheres is in [`envelope`]; here are the hierarchy of the segments'
//! boxes (a ray visits the segments whose boxes it meets), the union of their intervals along
//! the ray, and the hit.
//!
//! A hit's normal points from the centre of the sphere it touches. Its uv: u along the curve
//! (0 at the first segment's start, 1 at the last one's end), v around it, 0 where the
//! direction from the centre is nearest +y (+x where the curve runs along y), a quarter turn
//! later toward the tangent's cross product with that direction.

pub mod envelope;

use std::cell::RefCell;
use std::f64::consts::TAU;

use glam::{DVec2, DVec3, Vec2};

use super::blob::{LEAF_SIZE, Node, build, clip};
use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::{self, SweepSegment};
use envelope::{Span, ray_spans};

pub struct SphereSweep {
    segs: Vec<SweepSegment>,
    /// Each segment's box and size (the diagonal of its box), in the hierarchy's order.
    boxes: Vec<(DVec3, DVec3, f64)>,
    /// Each segment's index along the curve, in the hierarchy's order.
    index: Vec<u32>,
    /// The hierarchy's position of each segment along the curve (`u32::MAX`: absent).
    slot: Vec<u32>,
    nodes: Vec<Node>,
    min: DVec3,
    max: DVec3,
}

thread_local! {
    static SPANS: RefCell<Vec<Span>> = const { RefCell::new(Vec::new()) };
}

/// A crossing of the sweep's surface along a ray: its distance, the curve parameter of the
/// sphere touched there (segment index plus `s`), and whether the ray enters there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    pub t: f64,
    pub s: f64,
    pub entering: bool,
}

impl SphereSweep {
    pub fn new(sweep: &scene::SphereSweep) -> Result<Self, String> {
        sweep.check()?;
        let all = sweep.segments();
        // Segments whose radius is nowhere positive are absent (their Bernstein coefficients
        // bound the radius from above).
        let mut segs = Vec::new();
        let mut index = Vec::new();
        let mut boxes = Vec::new();
        for (i, s) in all.iter().enumerate() {
            let rmax = s.radii.iter().fold(f64::NEG_INFINITY, |m, &r| m.max(r));
            if rmax <= 0.0 {
                continue;
            }
            let lo = s.centres.iter().fold(DVec3::INFINITY, |m, &c| m.min(c)) - rmax;
            let hi = s.centres.iter().fold(DVec3::NEG_INFINITY, |m, &c| m.max(c)) + rmax;
            segs.push(*s);
            index.push(i as u32);
            boxes.push((lo, hi, (hi - lo).length()));
        }
        if segs.is_empty() {
            return Err("the sphere_sweep's radius is nowhere positive".into());
        }
        let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for b in &boxes {
            min = min.min(b.0);
            max = max.max(b.1);
        }
        let pairs: Vec<(DVec3, DVec3)> = boxes.iter().map(|b| (b.0, b.1)).collect();
        let mut order: Vec<u32> = (0..segs.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * segs.len() / LEAF_SIZE + 1);
        build(&pairs, &mut order, 0, &mut nodes);
        let mut slot = vec![u32::MAX; all.len()];
        for (k, &i) in order.iter().enumerate() {
            slot[index[i as usize] as usize] = k as u32;
        }
        Ok(SphereSweep {
            slot,
            segs: order.iter().map(|&i| segs[i as usize]).collect(),
            boxes: order.iter().map(|&i| boxes[i as usize]).collect(),
            index: order.iter().map(|&i| index[i as usize]).collect(),
            nodes,
            min,
            max,
        })
    }

    /// The segment (by index along the curve) and its local parameter of curve parameter `s`.
    fn segment_of(&self, s: f64) -> (&SweepSegment, f64) {
        let i = (s.floor().max(0.0) as usize).min(self.slot.len() - 1);
        // A crossing's segment is present; the fallback only guards a caller's stray `s`.
        let k = match self.slot[i] {
            u32::MAX => 0,
            k => k as usize,
        };
        (&self.segs[k], s - f64::from(self.index[k]))
    }

    /// Whether `p` lies inside the sweep.
    pub fn inside(&self, p: DVec3) -> bool {
        self.segs
            .iter()
            .zip(&self.boxes)
            .any(|(s, b)| p.cmpge(b.0).all() && p.cmple(b.1).all() && envelope::inside(s, p))
    }

    /// The nearest crossing of the surface with `lo < t < hi` along `o + t d`. A stretch
    /// inside from `t_in` to `t_out` for which `thin(t_in, t_out)` holds is left out, entry
    /// and exit.
    pub fn nearest(
        &self,
        o: DVec3,
        d: DVec3,
        lo: f64,
        hi: f64,
        thin: impl Fn(f64, f64) -> bool,
    ) -> Option<Crossing> {
        let len = d.length();
        if !(o.is_finite() && len.is_finite() && len > 0.0) {
            return None;
        }
        let u = d / len;
        let (lo_u, hi_u) = (lo * len, hi * len);
        clip(self.min, self.max, o, u, lo_u, hi_u)?;
        SPANS.with(|spans| {
            let spans = &mut *spans.borrow_mut();
            spans.clear();
            let mut stack = [0u32; 64];
            let mut sp = 1;
            while sp > 0 {
                sp -= 1;
                let at = stack[sp];
                let n = &self.nodes[at as usize];
                if clip(n.min, n.max, o, u, lo_u, hi_u).is_none() {
                    continue;
                }
                if n.count > 0 {
                    for k in n.first as usize..(n.first + n.count) as usize {
                        let (bmin, bmax, size) = self.boxes[k];
                        if clip(bmin, bmax, o, u, lo_u, hi_u).is_none() {
                            continue;
                        }
                        let from = spans.len();
                        ray_spans(&self.segs[k], o, u, size, spans);
                        let base = f64::from(self.index[k]);
                        for s in &mut spans[from..] {
                            s.s_in += base;
                            s.s_out += base;
                        }
                    }
                } else if sp + 2 <= stack.len() {
                    stack[sp] = n.next;
                    stack[sp + 1] = at + 1;
                    sp += 2;
                }
            }
            first_crossing(spans, lo_u, hi_u, |a, b| thin(a / len, b / len))
                .map(|c| Crossing { t: c.t / len, ..c })
        })
    }

    /// The outward unit normal at `p` on the sphere of curve parameter `s`.
    pub fn normal(&self, p: DVec3, s: f64) -> DVec3 {
        let (seg, local) = self.segment_of(s);
        let (c, _) = seg.at(local);
        (p - c).normalize_or(DVec3::Y)
    }

    fn hit(&self, t: f32, p: DVec3, s: f64) -> Hit {
        let (seg, local) = self.segment_of(s);
        let (c, _) = seg.at(local);
        let (tangent, _) = seg.derivative(local);
        let w = p - c;
        let n = w.normalize_or(DVec3::Y);
        let along = tangent.normalize_or(DVec3::ZERO);
        let reference = if along.y.abs() > 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let x = (reference - reference.dot(along) * along).normalize_or(reference);
        let y = along.cross(x);
        let v = w.dot(y).atan2(w.dot(x)).rem_euclid(TAU) / TAU;
        let segments = self.slot.len() as u32;
        let u = (s / f64::from(segments)).clamp(0.0, 1.0);
        let dpdu = tangent * f64::from(segments);
        let nf = n.as_vec3a();
        Hit {
            t,
            p: p.as_vec3a(),
            n: nf,
            ns: nf,
            uv: DVec2::new(u, v).as_vec2(),
            dpdu: if dpdu.length_squared() > 0.0 {
                dpdu.as_vec3a()
            } else {
                nf.any_orthonormal_vector()
            },
        }
    }
}

/// The first crossing in `(lo, hi)` of the union of the intervals `spans` (sorted here);
/// intervals the union makes `thin(t_in, t_out)` are left out.
fn first_crossing(
    spans: &mut [Span],
    lo: f64,
    hi: f64,
    thin: impl Fn(f64, f64) -> bool,
) -> Option<Crossing> {
    spans.sort_by(|a, b| a.t_in.total_cmp(&b.t_in));
    let mut it = spans.iter();
    let mut cur = *it.next()?;
    let pick = |c: &Span| -> Option<Crossing> {
        if thin(c.t_in, c.t_out) {
            return None;
        }
        if c.t_in > lo && c.t_in < hi {
            return Some(Crossing {
                t: c.t_in,
                s: c.s_in,
                entering: true,
            });
        }
        (c.t_out > lo && c.t_out < hi).then_some(Crossing {
            t: c.t_out,
            s: c.s_out,
            entering: false,
        })
    };
    for next in it {
        if next.t_in <= cur.t_out {
            if next.t_out > cur.t_out {
                cur.t_out = next.t_out;
                cur.s_out = next.s_out;
            }
            continue;
        }
        if let Some(c) = pick(&cur) {
            return Some(c);
        }
        cur = *next;
    }
    pick(&cur)
}

impl Shape for SphereSweep {
    fn bounds(&self) -> Aabb {
        Aabb::new(self.min.as_vec3a(), self.max.as_vec3a()).padded(1e-6)
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        let (lo, hi) = super::f64_range(t_min, t_max);
        // An interval whose entry and exit round to the same f32 distance is a touch: a CSG
        // that took its entry could never see its exit.
        let c = self.nearest(o, d, lo, hi, |a, b| a as f32 >= b as f32)?;
        let tf = c.t as f32;
        if !(tf > t_min && tf < t_max) {
            return None;
        }
        let p = o + c.t * d;
        Some(self.hit(tf, p, c.s))
    }

    /// A sphere sweep is not a light's shape: it is never sampled.
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
    use scene::SweepSpline;

    fn sweep(spline: SweepSpline, pts: &[(DVec3, f64)]) -> SphereSweep {
        SphereSweep::new(&scene::SphereSweep {
            spline,
            centres: pts.iter().map(|p| p.0).collect(),
            radii: pts.iter().map(|p| p.1).collect(),
        })
        .unwrap()
    }

    fn nearest(s: &SphereSweep, o: DVec3, d: DVec3, lo: f64) -> Option<Crossing> {
        s.nearest(o, d, lo, f64::INFINITY, |_, _| false)
    }

    #[test]
    fn a_straight_catmull_rom_is_a_capsule_and_its_crossings_alternate() {
        // Evenly spaced points on a line, equal radii: the curve runs from x = 1 to x = 4.
        let pts: Vec<(DVec3, f64)> = (0..6)
            .map(|i| (DVec3::new(f64::from(i), 0.0, 0.0), 0.5))
            .collect();
        let s = sweep(SweepSpline::CatmullRom, &pts);
        let o = DVec3::new(-2.0, 0.0, 0.0);
        let a = nearest(&s, o, DVec3::X, 0.0).unwrap();
        assert!(a.entering && (a.t - 2.5).abs() < 1e-9, "{a:?}");
        let b = nearest(&s, o, DVec3::X, a.t + 1e-9).unwrap();
        assert!(!b.entering && (b.t - 6.5).abs() < 1e-9, "{b:?}");
        assert!(nearest(&s, o, DVec3::X, b.t + 1e-9).is_none());
        // A direction of any length gives the same point.
        let c = nearest(&s, o, DVec3::X * 4.0, 0.0).unwrap();
        assert!((c.t * 4.0 - 2.5).abs() < 1e-9);
        assert!(s.inside(DVec3::new(2.5, 0.3, 0.0)) && !s.inside(DVec3::new(0.4, 0.0, 0.0)));
        let n = s.normal(o + a.t * DVec3::X, a.s);
        assert!((n + DVec3::X).length() < 1e-6, "{n}");
    }

    #[test]
    fn overlapping_segments_make_one_interval() {
        // A b-spline that loops back on itself: where its segments overlap along a ray, the ray
        // crosses the surface only where the union's boundary is.
        let pts = [
            (DVec3::new(0.0, 0.0, 0.0), 0.4),
            (DVec3::new(2.0, 0.0, 0.0), 0.4),
            (DVec3::new(2.0, 2.0, 0.0), 0.4),
            (DVec3::new(0.0, 2.0, 0.0), 0.4),
            (DVec3::new(0.0, 0.0, 0.0), 0.4),
            (DVec3::new(2.0, 0.0, 0.0), 0.4),
            (DVec3::new(2.0, 2.0, 0.0), 0.4),
        ];
        let s = sweep(SweepSpline::BSpline, &pts);
        // Down onto the joint of the last segment and the first, and along the bottom side.
        for (o, d) in [
            (DVec3::new(1.0, 1.0, 5.0), DVec3::new(0.667, -0.667, -5.0)),
            (DVec3::new(-3.0, 0.34, 0.05), DVec3::X),
        ] {
            let (mut lo, mut seen) = (0.0, Vec::new());
            while let Some(c) = nearest(&s, o, d, lo) {
                seen.push(c.entering);
                // Each crossing is on the boundary: just before it and after it the inside
                // test disagrees.
                let e = 1e-6;
                let (before, after) = (o + (c.t - e) * d, o + (c.t + e) * d);
                assert_eq!(s.inside(before), !c.entering, "{c:?}");
                assert_eq!(s.inside(after), c.entering, "{c:?}");
                lo = c.t + 1e-7;
            }
            // From outside: in, out, in, out...
            assert!(seen.len() >= 2 && seen.len() % 2 == 0, "{seen:?}");
            assert!(
                seen.iter().enumerate().all(|(i, &e)| e == (i % 2 == 0)),
                "{seen:?}"
            );
        }
    }
}
