//! POV-Ray's `height_field` in its own space: the solid between the water level and a grid of
//! heights over the unit square of the (x, z) plane.
//!
//! The surface is made of triangles, two to a cell as POV-Ray splits them (the diagonal runs
//! from `(i + 1, j)` to `(i, j + 1)`): the top at the samples' heights (raised to the water
//! level where they lie below it), the bottom at the water level under each top triangle, and
//! the four sides down to it. A triangle whose three corners lie at or below the water level
//! has no solid above it: its top and bottom are left out together, so the surface stays
//! closed. Every triangle is tested by the watertight test of Woop, Benthin and Wald (the
//! vertices sheared into the ray's frame, each edge's function computed from the same two
//! vertices in both triangles that share it), so no ray slips between two triangles.
//!
//! A ray does not test every cell: the top is found by walking a quadtree of height ranges
//! (a min/max mip hierarchy: each node the box of its cells between their lowest and highest
//! sample), nearest child first, pruning every node whose box the ray meets only beyond the
//! nearest hit so far; its leaves are blocks of 2x2 cells. The bottom and the sides are planes:
//! the cells around the point where the ray meets each are tested.

use std::sync::Arc;

use arrayvec::ArrayVec;
use glam::{DVec3, Vec2, Vec3A};
use rayon::prelude::*;

use super::{AreaSample, Shape};
use crate::geometry::{Aabb, Hit, Ray};
use crate::scene::{self, HeightGrid};

/// What a triangle of the surface belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    Top,
    Bottom,
    /// The side at x = 0, x = 1, z = 0, z = 1.
    Side(u8),
}

impl Face {
    fn outward(self) -> DVec3 {
        match self {
            Face::Top => DVec3::Y,
            Face::Bottom => -DVec3::Y,
            Face::Side(0) => -DVec3::X,
            Face::Side(1) => DVec3::X,
            Face::Side(2) => -DVec3::Z,
            Face::Side(_) => DVec3::Z,
        }
    }
}

/// A ray prepared for the watertight triangle test: its origin, and the shear that turns its
/// direction into the +z axis of a frame whose z axis is its largest component.
#[derive(Debug, Clone, Copy)]
pub struct WatertightRay {
    o: DVec3,
    k: [usize; 3],
    s: DVec3,
}

impl WatertightRay {
    pub fn new(o: DVec3, d: DVec3) -> Self {
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self {
            o,
            k: [kx, ky, kz],
            s: DVec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
        }
    }

    /// A vertex in the ray's sheared frame (the same bits whichever triangle asks).
    #[inline]
    pub fn vertex(&self, p: DVec3) -> DVec3 {
        let a = p - self.o;
        let [kx, ky, kz] = self.k;
        DVec3::new(
            a[kx] - self.s.x * a[kz],
            a[ky] - self.s.y * a[kz],
            self.s.z * a[kz],
        )
    }

    /// The ray's `t` and the barycentric weights of `a`, `b`, `c` where it crosses the triangle
    /// of the sheared vertices (either side facing; edges and corners count as inside).
    #[inline]
    pub fn hit(&self, a: DVec3, b: DVec3, c: DVec3) -> Option<(f64, [f64; 3])> {
        let u = c.x * b.y - c.y * b.x;
        let v = a.x * c.y - a.y * c.x;
        let w = b.x * a.y - b.y * a.x;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let t = (u * a.z + v * b.z + w * c.z) / det;
        Some((t, [u / det, v / det, w / det]))
    }
}

/// One level of the hierarchy: `w x h` nodes, each the (min, max) of its samples' heights.
#[derive(Debug, Clone)]
struct Level {
    w: u32,
    h: u32,
    range: Vec<[f32; 2]>,
}

#[derive(Debug, Clone)]
pub struct HeightField {
    grid: Arc<HeightGrid>,
    water: f64,
    smooth: bool,
    /// Cells along x and z.
    cx: u32,
    cz: u32,
    /// `levels[0]`: blocks of 2x2 cells; each next level groups 2x2 nodes of the one before;
    /// the last holds one node.
    levels: Vec<Level>,
    bounds: Aabb,
}

/// The nearest hit found so far.
#[derive(Debug, Clone, Copy)]
struct Best {
    t: f64,
    face: Face,
    /// The triangle's corners (object space) and the hit's weights of them.
    tri: [DVec3; 3],
    w: [f64; 3],
    /// Sample indices of the corners (top triangles; for smooth normals).
    idx: [(u32, u32); 3],
}

impl HeightField {
    pub fn new(field: &scene::HeightField) -> Result<Self, String> {
        let grid = field.grid.clone();
        if grid.nx < 2 || grid.nz < 2 {
            return Err("a height field needs at least 2x2 samples".into());
        }
        if grid.heights.len() != grid.nx as usize * grid.nz as usize
            || grid.heights.iter().any(|h| !h.is_finite())
        {
            return Err("a height field's heights must be finite, one per sample".into());
        }
        let (cx, cz) = (grid.nx - 1, grid.nz - 1);
        let mut levels = vec![Self::blocks(&grid)];
        while levels.last().is_some_and(|l| l.w > 1 || l.h > 1) {
            let next = Self::coarser(levels.last().unwrap());
            levels.push(next);
        }
        let top = levels.last().unwrap().range[0];
        let water = field.water;
        if f64::from(top[1]) <= water {
            return Err("the height field lies at or below its water level everywhere".into());
        }
        let bounds = Aabb::new(
            Vec3A::new(0.0, water as f32, 0.0),
            Vec3A::new(1.0, top[1], 1.0),
        )
        .padded(1e-6);
        Ok(Self {
            grid,
            water,
            smooth: field.smooth,
            cx,
            cz,
            levels,
            bounds,
        })
    }

    /// The finest level: the height range of each block of 2x2 cells (its 3x3 samples).
    fn blocks(g: &HeightGrid) -> Level {
        let (cx, cz) = (g.nx - 1, g.nz - 1);
        let (w, h) = (cx.div_ceil(2), cz.div_ceil(2));
        let range: Vec<[f32; 2]> = (0..h)
            .into_par_iter()
            .flat_map_iter(|b| {
                (0..w).map(move |a| {
                    let mut r = [f32::INFINITY, f32::NEG_INFINITY];
                    for j in 2 * b..=(2 * b + 2).min(cz) {
                        for i in 2 * a..=(2 * a + 2).min(cx) {
                            let y = g.at(i, j);
                            r = [r[0].min(y), r[1].max(y)];
                        }
                    }
                    r
                })
            })
            .collect();
        Level { w, h, range }
    }

    fn coarser(l: &Level) -> Level {
        let (w, h) = (l.w.div_ceil(2), l.h.div_ceil(2));
        let mut range = Vec::with_capacity(w as usize * h as usize);
        for b in 0..h {
            for a in 0..w {
                let mut r = [f32::INFINITY, f32::NEG_INFINITY];
                for j in 2 * b..(2 * b + 2).min(l.h) {
                    for i in 2 * a..(2 * a + 2).min(l.w) {
                        let c = l.range[(j * l.w + i) as usize];
                        r = [r[0].min(c[0]), r[1].max(c[1])];
                    }
                }
                range.push(r);
            }
        }
        Level { w, h, range }
    }

    /// Bytes of the hierarchy (the grid's heights are the scene's).
    pub fn hierarchy_bytes(&self) -> usize {
        self.levels
            .iter()
            .map(|l| l.range.len() * std::mem::size_of::<[f32; 2]>())
            .sum()
    }

    /// The sample's height (as stored).
    #[inline]
    fn h(&self, i: u32, j: u32) -> f64 {
        f64::from(self.grid.at(i, j))
    }

    /// The top vertex over sample `(i, j)` (raised to the water level) or the bottom one under
    /// it: computed the same way wherever it is used, so shared edges have the same bits.
    #[inline]
    fn vertex(&self, i: u32, j: u32, top: bool) -> DVec3 {
        let y = if top {
            self.h(i, j).max(self.water)
        } else {
            self.water
        };
        DVec3::new(
            f64::from(i) / f64::from(self.cx),
            y,
            f64::from(j) / f64::from(self.cz),
        )
    }

    /// The two triangles of cell `(i, j)` as sample indices: POV-Ray's split.
    #[inline]
    fn cell_triangles(i: u32, j: u32) -> [[(u32, u32); 3]; 2] {
        [
            [(i, j), (i + 1, j), (i, j + 1)],
            [(i + 1, j + 1), (i, j + 1), (i + 1, j)],
        ]
    }

    /// Whether a triangle of the top has solid under it (a corner above the water level).
    #[inline]
    fn solid(&self, idx: &[(u32, u32); 3]) -> bool {
        idx.iter().any(|&(i, j)| self.h(i, j) > self.water)
    }

    /// The side triangles between border samples `a` and `b` of side `s`, as (sample, top)
    /// corners; a triangle with two equal corners (a top corner at the water level) left out.
    fn side_triangles(&self, a: (u32, u32), b: (u32, u32)) -> ArrayVec<[((u32, u32), bool); 3], 2> {
        let mut out = ArrayVec::new();
        let (ha, hb) = (self.h(a.0, a.1), self.h(b.0, b.1));
        if ha <= self.water && hb <= self.water {
            return out;
        }
        if hb > self.water {
            out.push([(a, false), (b, false), (b, true)]);
        }
        if ha > self.water {
            out.push([(a, false), (b, true), (a, true)]);
        }
        out
    }

    /// Every triangle of the closed surface, with its face: the definition the hierarchy must
    /// agree with (the slow reference tests each of them).
    pub fn surface_triangles(&self) -> Vec<([DVec3; 3], Face)> {
        let mut out = Vec::new();
        for j in 0..self.cz {
            for i in 0..self.cx {
                for idx in Self::cell_triangles(i, j) {
                    if self.solid(&idx) {
                        out.push((idx.map(|(a, b)| self.vertex(a, b, true)), Face::Top));
                        out.push((idx.map(|(a, b)| self.vertex(a, b, false)), Face::Bottom));
                    }
                }
            }
        }
        for (side, n) in [(0u8, self.cz), (1, self.cz), (2, self.cx), (3, self.cx)] {
            for k in 0..n {
                let (a, b) = self.side_edge(side, k);
                for tri in self.side_triangles(a, b) {
                    out.push((
                        tri.map(|(s, top)| self.vertex(s.0, s.1, top)),
                        Face::Side(side),
                    ));
                }
            }
        }
        out
    }

    /// The border samples of segment `k` of side `side`.
    #[inline]
    fn side_edge(&self, side: u8, k: u32) -> ((u32, u32), (u32, u32)) {
        match side {
            0 => ((0, k), (0, k + 1)),
            1 => ((self.cx, k), (self.cx, k + 1)),
            2 => ((k, 0), (k + 1, 0)),
            _ => ((k, self.cz), (k + 1, self.cz)),
        }
    }

    /// Tests one triangle given by sample corners, keeping it when nearer than `best`.
    #[inline]
    fn test(
        &self,
        r: &WatertightRay,
        corners: [((u32, u32), bool); 3],
        face: Face,
        lo: f64,
        best: &mut Option<Best>,
    ) {
        let tri = corners.map(|((i, j), top)| self.vertex(i, j, top));
        let [a, b, c] = tri.map(|p| r.vertex(p));
        if let Some((t, w)) = r.hit(a, b, c)
            && t > lo
            && best.is_none_or(|b| t < b.t)
        {
            *best = Some(Best {
                t,
                face,
                tri,
                w,
                idx: corners.map(|(s, _)| s),
            });
        }
    }

    /// The nearest hit in `(lo, hi)` (f64, object space).
    fn nearest(&self, o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<Best> {
        let r = WatertightRay::new(o, d);
        let mut best: Option<Best> = None;
        let limit = |best: &Option<Best>| best.map_or(hi, |b| b.t);
        // The top, through the hierarchy.
        let inv = d.recip();
        let pad = 1e-9 * o.abs().max_element().max(1.0);
        let top = self.levels.len() - 1;
        let mut stack: ArrayVec<(usize, u32, u32, f64), 128> = ArrayVec::new();
        if let Some(near) = self.node_hit(top, 0, 0, o, inv, pad, lo, hi) {
            stack.push((top, 0, 0, near));
        }
        while let Some((level, a, b, near)) = stack.pop() {
            if near > limit(&best) {
                continue;
            }
            if level == 0 {
                for j in 2 * b..(2 * b + 2).min(self.cz) {
                    for i in 2 * a..(2 * a + 2).min(self.cx) {
                        for idx in Self::cell_triangles(i, j) {
                            if self.solid(&idx) {
                                self.test(&r, idx.map(|s| (s, true)), Face::Top, lo, &mut best);
                            }
                        }
                    }
                }
                continue;
            }
            let child = &self.levels[level - 1];
            let mut kids: ArrayVec<(u32, u32, f64), 4> = ArrayVec::new();
            for cb in 2 * b..(2 * b + 2).min(child.h) {
                for ca in 2 * a..(2 * a + 2).min(child.w) {
                    if let Some(n) = self.node_hit(level - 1, ca, cb, o, inv, pad, lo, limit(&best))
                    {
                        kids.push((ca, cb, n));
                    }
                }
            }
            // Farthest first on the stack, so the nearest is walked first.
            kids.sort_unstable_by(|x, y| y.2.total_cmp(&x.2));
            for (ca, cb, n) in kids {
                stack.push((level - 1, ca, cb, n));
            }
        }
        // The bottom and the sides: the cells around the point where the ray meets each plane.
        let near_cells = |v: f64, n: u32| {
            let c = (v * f64::from(n)).floor().clamp(0.0, f64::from(n - 1)) as u32;
            c.saturating_sub(1)..=(c + 1).min(n - 1)
        };
        if d.y != 0.0 {
            let t = (self.water - o.y) / d.y;
            let p = o + d * t;
            if t.is_finite() && (-0.5..=1.5).contains(&p.x) && (-0.5..=1.5).contains(&p.z) {
                for j in near_cells(p.z, self.cz) {
                    for i in near_cells(p.x, self.cx) {
                        for idx in Self::cell_triangles(i, j) {
                            if self.solid(&idx) {
                                let c = idx.map(|s| (s, false));
                                self.test(&r, c, Face::Bottom, lo, &mut best);
                            }
                        }
                    }
                }
            }
        }
        for side in 0..4u8 {
            let (axis, at, along, n) = match side {
                0 => (o.x, 0.0, 2, self.cz),
                1 => (o.x, 1.0, 2, self.cz),
                2 => (o.z, 0.0, 0, self.cx),
                _ => (o.z, 1.0, 0, self.cx),
            };
            let dn = if side < 2 { d.x } else { d.z };
            if dn == 0.0 {
                continue;
            }
            let t = (at - axis) / dn;
            let v = o[along] + d[along] * t;
            if !(t.is_finite() && (-0.5..=1.5).contains(&v)) {
                continue;
            }
            for k in near_cells(v, n) {
                let (a, b) = self.side_edge(side, k);
                for tri in self.side_triangles(a, b) {
                    self.test(&r, tri, Face::Side(side), lo, &mut best);
                }
            }
        }
        best.filter(|b| b.t < hi)
    }

    /// The entry distance of the ray into node `(a, b)` of `level` (its box padded by `pad`)
    /// within `(lo, hi)`, or `None`; a node whose samples all lie at or below the water level
    /// holds no surface.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn node_hit(
        &self,
        level: usize,
        a: u32,
        b: u32,
        o: DVec3,
        inv: DVec3,
        pad: f64,
        lo: f64,
        hi: f64,
    ) -> Option<f64> {
        let l = &self.levels[level];
        let [ymin, ymax] = l.range[(b * l.w + a) as usize];
        let (ymin, ymax) = (f64::from(ymin), f64::from(ymax));
        if ymax <= self.water {
            return None;
        }
        let span = 2u32 << level;
        let x0 = f64::from(a * span) / f64::from(self.cx);
        let x1 = f64::from(((a + 1) * span).min(self.cx)) / f64::from(self.cx);
        let z0 = f64::from(b * span) / f64::from(self.cz);
        let z1 = f64::from(((b + 1) * span).min(self.cz)) / f64::from(self.cz);
        let min = DVec3::new(x0, ymin.max(self.water), z0) - pad;
        let max = DVec3::new(x1, ymax, z1) + pad;
        let t0 = (min - o) * inv;
        let t1 = (max - o) * inv;
        let near = t0.min(t1).max_element().max(lo);
        let far = t0.max(t1).min_element().min(hi);
        (near <= far).then_some(near)
    }

    /// The nearest hit's `t` in `(lo, hi)` (f64, object space) and its face: what the stress
    /// tests compare with every triangle tested one by one.
    pub fn hit_t(&self, o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<(f64, Face)> {
        self.nearest(o, d, lo, hi).map(|b| (b.t, b.face))
    }

    /// The unit normal at sample `(i, j)` of the top, from the slopes to its neighbours.
    fn sample_normal(&self, i: u32, j: u32) -> DVec3 {
        let (i0, i1) = (i.saturating_sub(1), (i + 1).min(self.cx));
        let (j0, j1) = (j.saturating_sub(1), (j + 1).min(self.cz));
        let dx = (self.h(i1, j) - self.h(i0, j)) / (f64::from(i1 - i0) / f64::from(self.cx));
        let dz = (self.h(i, j1) - self.h(i, j0)) / (f64::from(j1 - j0) / f64::from(self.cz));
        DVec3::new(-dx, 1.0, -dz).normalize()
    }

    fn full_hit(&self, b: &Best) -> Hit {
        let [p0, p1, p2] = b.tri;
        let p = p0 * b.w[0] + p1 * b.w[1] + p2 * b.w[2];
        let mut n = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let out = b.face.outward();
        if n.dot(out) < 0.0 {
            n = -n;
        }
        if n == DVec3::ZERO {
            n = out;
        }
        let ns = if self.smooth && b.face == Face::Top {
            let [a, c, e] = b.idx.map(|(i, j)| self.sample_normal(i, j));
            let s = (a * b.w[0] + c * b.w[1] + e * b.w[2]).normalize_or_zero();
            if s.dot(n) > 0.0 { s } else { n }
        } else {
            n
        };
        // Along u = x: the surface's slope in x on the top, a tangent elsewhere.
        let dpdu = match b.face {
            Face::Top if n.y.abs() > 1e-12 => DVec3::new(1.0, -n.x / n.y, 0.0),
            Face::Side(0) | Face::Side(1) => DVec3::Z,
            _ => DVec3::X,
        };
        Hit {
            t: b.t as f32,
            p: p.as_vec3a(),
            n: n.as_vec3a(),
            ns: ns.as_vec3a(),
            uv: Vec2::new(p.x as f32, p.z as f32),
            dpdu: dpdu.as_vec3a(),
        }
    }
}

impl Shape for HeightField {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let (lo, hi) = super::f64_range(t_min, t_max);
        let b = self.nearest(ray.o.as_dvec3(), ray.d.as_dvec3(), lo, hi)?;
        Some(self.full_hit(&b))
    }

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
    use crate::sampling::Rng;

    fn field(nx: u32, nz: u32, water: f64, f: impl Fn(f64, f64) -> f64) -> HeightField {
        let mut heights = Vec::new();
        for j in 0..nz {
            for i in 0..nx {
                let (x, z) = (
                    f64::from(i) / f64::from(nx - 1),
                    f64::from(j) / f64::from(nz - 1),
                );
                heights.push(f(x, z) as f32);
            }
        }
        HeightField::new(&scene::HeightField {
            grid: Arc::new(HeightGrid { nx, nz, heights }),
            water,
            smooth: true,
        })
        .unwrap()
    }

    fn brute(hf: &HeightField, o: DVec3, d: DVec3) -> Option<(f64, Face)> {
        let r = WatertightRay::new(o, d);
        hf.surface_triangles()
            .iter()
            .filter_map(|(t, face)| {
                let [a, b, c] = t.map(|p| r.vertex(p));
                r.hit(a, b, c).map(|(t, _)| (t, *face))
            })
            .filter(|(t, _)| *t > 0.0)
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    #[test]
    fn the_hierarchy_finds_what_every_triangle_finds() {
        let hf = field(23, 17, 0.2, |x, z| {
            0.5 + 0.4 * (9.0 * x).sin() * (7.0 * z).cos()
        });
        let mut rng = Rng::new(7);
        for _ in 0..4000 {
            let o = DVec3::new(
                f64::from(rng.f32()) * 3.0 - 1.0,
                f64::from(rng.f32()) * 3.0 - 1.0,
                f64::from(rng.f32()) * 3.0 - 1.0,
            );
            let target = DVec3::new(
                f64::from(rng.f32()),
                f64::from(rng.f32()),
                f64::from(rng.f32()),
            );
            let d = target - o;
            let fast = hf.hit_t(o, d, 0.0, f64::INFINITY);
            let slow = brute(&hf, o, d);
            assert_eq!(fast.map(|h| h.0), slow.map(|h| h.0), "{o} {d}");
        }
    }

    #[test]
    fn every_ray_through_the_solid_enters_and_leaves() {
        // A closed surface: along a line through it, the hits alternate in and out and pair up.
        let hf = field(9, 12, 0.3, |x, z| (x * 5.0 + z * 3.0).sin().abs());
        let mut rng = Rng::new(3);
        for _ in 0..2000 {
            let o = DVec3::new(
                f64::from(rng.f32()) * 4.0 - 1.5,
                f64::from(rng.f32()) * 4.0 - 1.5,
                f64::from(rng.f32()) * 4.0 - 1.5,
            );
            let d = DVec3::new(
                f64::from(rng.f32()),
                f64::from(rng.f32()),
                f64::from(rng.f32()),
            ) - o;
            let mut t = 0.0;
            let mut signs = Vec::new();
            while let Some(b) = hf.nearest(o, d, t, f64::INFINITY) {
                let h = hf.full_hit(&b);
                signs.push(h.n.as_dvec3().dot(d) < 0.0);
                t = b.t;
                if signs.len() > 100 {
                    break;
                }
            }
            // Entering and leaving alternate, starting outside (the origin may be inside only
            // when it lies in the unit box).
            let inside = (0.0..=1.0).contains(&o.x) && (0.0..=1.0).contains(&o.z);
            if !inside {
                assert!(signs.len().is_multiple_of(2), "{o} {d}: {signs:?}");
                assert!(signs.iter().step_by(2).all(|s| *s), "{o} {d}: {signs:?}");
            }
        }
    }
}
