//! CSG ray intersection against an independent oracle: random trees of spheres and boxes
//! (`merge`, `intersection`, `difference`, `inverse`, with translations and rotations on the
//! operations), random rays, and a brute-force point-membership classifier that knows nothing
//! of the renderer. The oracle samples the ray every `STEP` inside the region that holds all
//! geometry, finds the first sample whose membership differs from the one before, and bisects
//! that step down to 1e-10. The renderer's first hit (through the whole prepared scene: BVH,
//! CSG classification, part ids) must be at the same distance, with a normal pointing out of
//! the solid (against the ray when it enters), and on the part the oracle finds nearest.
//!
//! Sampling can miss a membership interval shorter than `STEP` (a sliver between two
//! surfaces, a grazing ray). A disagreement where the renderer is earlier counts as such a
//! miss only when the oracle, bisecting around the renderer's hit, confirms a membership change
//! there and the interval it starts is shorter than `STEP`; every other disagreement fails.

use crate::common;

use common::empty_scene;
use std::sync::Arc;

use glam::{DAffine3, DQuat, DVec2, DVec3};
use sppm_lang::Span;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::prepare::PreparedScene;
use sppm_lang::internals::scene::function::{Binary, Unary};
use sppm_lang::internals::scene::text::text_glyphs;
use sppm_lang::internals::scene::{
    Blob, BlobComponent, ColorParam, Container, Csg, CsgOp, Function, HeightField, HeightGrid,
    Isosurface, Material, MaterialId, Object, Op, Prism, PrismSpline, Scene, ShapeDecl,
    prism_segments,
};

/// Oracle sampling step along a unit-direction ray; the geometry spans about 4 units.
const STEP: f64 = 2e-3;
/// Distance tolerance: the renderer works in f32 on coordinates up to ~4 (ulp ~5e-7), and
/// quadric roots lose up to a few hundred ulps on grazing rays.
const T_TOL: f64 = 2e-4;
/// Everything lies inside [-HALF, HALF]^3 (centres within 1.2, radii and half-sides under 0.8,
/// translations under 0.3, rotations about the origin: at most 2.3 * sqrt(3)).
const HALF: f64 = 4.0;

struct Rand(u64);

impl Rand {
    fn f(&mut self) -> f64 {
        // SplitMix64.
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.f()
    }
    fn v(&mut self, a: f64, b: f64) -> DVec3 {
        DVec3::new(self.range(a, b), self.range(a, b), self.range(a, b))
    }
    fn unit(&mut self) -> DVec3 {
        loop {
            let v = self.v(-1.0, 1.0);
            if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

/// The oracle's own tree: world transforms applied to points by hand.
enum Tree {
    Sphere {
        c: DVec3,
        r: f64,
        id: usize,
    },
    Box {
        lo: DVec3,
        hi: DVec3,
        id: usize,
    },
    /// A curved sphere sweep: the oracle evaluates its spline itself (see [`Sweep`]).
    Sweep(Sweep, usize),
    Op {
        op: CsgOp,
        kids: Vec<Tree>,
        to_world: DAffine3,
    },
    /// Any other shape, by its own membership test (see [`Leaf`]).
    Solid {
        leaf: Leaf,
        id: usize,
    },
}

/// The oracle's sphere sweep: the spline from POV-Ray's basis matrices in power form, and
/// the distance `min_s |p - c(s)| - r(s)` (over positive radii) from 400 samples per segment,
/// the best refined by golden-section search.
struct Sweep {
    b_spline: bool,
    pts: Vec<(DVec3, f64)>,
    lo: DVec3,
    hi: DVec3,
    /// (segment, s, centre, radius) at the samples.
    samples: Vec<(usize, f64, DVec3, f64)>,
}

/// Samples per segment of the oracle's sweep; between two, a sphere moves and grows by less
/// than `FAR` (the test's sweeps change by less than 8 units per unit of `s`).
const SAMPLES: usize = 400;
const FAR: f64 = 0.02;

impl Sweep {
    fn new(b_spline: bool, pts: Vec<(DVec3, f64)>) -> Sweep {
        let r = pts.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
        let lo = pts.iter().fold(DVec3::INFINITY, |m, p| m.min(p.0)) - r;
        let hi = pts.iter().fold(DVec3::NEG_INFINITY, |m, p| m.max(p.0)) + r;
        let mut w = Sweep {
            b_spline,
            pts,
            lo,
            hi,
            samples: Vec::new(),
        };
        for i in 0..w.pts.len() - 3 {
            for k in 0..=SAMPLES {
                let s = k as f64 / SAMPLES as f64;
                let (c, r) = w.at(i, s);
                w.samples.push((i, s, c, r));
            }
        }
        w
    }

    fn at(&self, i: usize, s: f64) -> (DVec3, f64) {
        let m: [[f64; 4]; 4] = if self.b_spline {
            [
                [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0, 0.0],
                [-0.5, 0.0, 0.5, 0.0],
                [0.5, -1.0, 0.5, 0.0],
                [-1.0 / 6.0, 0.5, -0.5, 1.0 / 6.0],
            ]
        } else {
            [
                [0.0, 1.0, 0.0, 0.0],
                [-0.5, 0.0, 0.5, 0.0],
                [1.0, -2.5, 2.0, -0.5],
                [-0.5, 1.5, -1.5, 0.5],
            ]
        };
        let pow = [1.0, s, s * s, s * s * s];
        let (mut c, mut r) = (DVec3::ZERO, 0.0);
        let w: [f64; 4] = std::array::from_fn(|j| (0..4).map(|k| pow[k] * m[k][j]).sum());
        for (w, p) in w.iter().zip(&self.pts[i..i + 4]) {
            c += *w * p.0;
            r += *w * p.1;
        }
        (c, r)
    }

    /// The distance and the centre of the sphere that gives it (`+inf` outside the box).
    fn distance(&self, p: DVec3) -> (f64, DVec3) {
        if p.cmplt(self.lo).any() || p.cmpgt(self.hi).any() {
            return (f64::INFINITY, p - DVec3::X);
        }
        let f = |i: usize, s: f64| {
            let (c, r) = self.at(i, s);
            if r <= 0.0 {
                f64::INFINITY
            } else {
                (p - c).length() - r
            }
        };
        let mut best = (f64::INFINITY, 0, 0.0);
        for &(i, s, c, r) in &self.samples {
            if r > 0.0 {
                let v = (p - c).length() - r;
                if v < best.0 {
                    best = (v, i, s);
                }
            }
        }
        // Far outside: no sphere between two samples reaches `p`.
        if best.0 > FAR {
            return (best.0, self.at(best.1, best.2).0);
        }
        let (i, step) = (best.1, 1.0 / SAMPLES as f64);
        let (mut a, mut b) = ((best.2 - step).max(0.0), (best.2 + step).min(1.0));
        let g = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..80 {
            let (x1, x2) = (b - g * (b - a), a + g * (b - a));
            if f(i, x1) < f(i, x2) {
                b = x2;
            } else {
                a = x1;
            }
        }
        let s = 0.5 * (a + b);
        let v = f(i, s);
        if v < best.0 {
            (v, self.at(i, s).0)
        } else {
            (best.0, self.at(i, best.2).0)
        }
    }
}

fn inside(t: &Tree, p: DVec3) -> bool {
    match t {
        Tree::Sphere { c, r, .. } => (p - *c).length_squared() < r * r,
        Tree::Box { lo, hi, .. } => p.cmpgt(*lo).all() && p.cmplt(*hi).all(),
        Tree::Solid { leaf, .. } => (leaf.field)(p) < 0.0,
        Tree::Sweep(w, _) => w.distance(p).0 < 0.0,
        Tree::Op { op, kids, to_world } => {
            let q = to_world.inverse().transform_point3(p);
            let mut k = kids.iter().map(|k| inside(k, q));
            match op {
                CsgOp::Merge | CsgOp::Union => k.any(|x| x),
                CsgOp::Intersection => k.all(|x| x),
                CsgOp::Difference => k.next().unwrap_or(false) && !k.any(|x| x),
                CsgOp::Inverse => !k.next().unwrap(),
            }
        }
    }
}

/// Every leaf as (id, distance from `p` to its surface, outward normal there), in world space.
fn surfaces(t: &Tree, to_world: DAffine3, p: DVec3, out: &mut Vec<(usize, f64, DVec3)>) {
    let q = to_world.inverse().transform_point3(p);
    let rot = |n: DVec3| to_world.transform_vector3(n).normalize();
    match t {
        Tree::Sphere { c, r, id } => {
            let d = q - *c;
            out.push((*id, (d.length() - r).abs(), rot(d.normalize())));
        }
        Tree::Box { lo, hi, id } => {
            // Nearest face: distance to each face plane, clamped to the face.
            let mut best = (f64::INFINITY, DVec3::ZERO);
            for axis in 0..3 {
                for (plane, sign) in [(lo[axis], -1.0), (hi[axis], 1.0)] {
                    let mut f = q;
                    f[axis] = plane;
                    let f = f.clamp(*lo, *hi);
                    let d = (q - f).length();
                    if d < best.0 {
                        let mut n = DVec3::ZERO;
                        n[axis] = sign;
                        best = (d, n);
                    }
                }
            }
            out.push((*id, best.0, rot(best.1)));
        }
        // Measured by `flips` instead.
        Tree::Solid { .. } => {}
        Tree::Sweep(w, id) => {
            let (dist, c) = w.distance(q);
            out.push((*id, dist.abs(), rot((q - c).normalize())));
        }
        Tree::Op {
            kids,
            to_world: own,
            ..
        } => {
            for k in kids {
                surfaces(k, to_world * *own, p, out);
            }
        }
    }
}

/// A random tree of `depth` levels at most, as the oracle's tree and the scene's object.
fn random_tree(rng: &mut Rand, depth: u32, next_id: &mut usize) -> (Tree, Object) {
    let object = |shape, transform, id: usize| Object {
        shape,
        transform,
        material: MaterialId(id as u32),
        emission: None,
        span: Span::detached(),
    };
    if depth == 0 || rng.f() < 0.3 {
        let id = *next_id;
        *next_id += 1;
        let c = rng.v(-0.8, 0.8);
        return if rng.f() < 0.5 {
            let r = rng.range(0.2, 0.8);
            (
                Tree::Sphere { c, r, id },
                object(
                    ShapeDecl::Sphere {
                        center: c,
                        radius: r,
                    },
                    DAffine3::IDENTITY,
                    id,
                ),
            )
        } else {
            let h = rng.v(0.15, 0.7);
            let (lo, hi) = (c - h, c + h);
            (
                Tree::Box { lo, hi, id },
                object(ShapeDecl::Box { min: lo, max: hi }, DAffine3::IDENTITY, id),
            )
        };
    }
    let op = match rng.f() {
        x if x < 0.3 => CsgOp::Merge,
        x if x < 0.6 => CsgOp::Intersection,
        x if x < 0.9 => CsgOp::Difference,
        _ => CsgOp::Inverse,
    };
    let n = if op == CsgOp::Inverse {
        1
    } else {
        2 + (rng.f() * 2.0) as usize
    };
    let (kids, objects): (Vec<Tree>, Vec<Object>) =
        (0..n).map(|_| random_tree(rng, depth - 1, next_id)).unzip();
    let to_world = if rng.f() < 0.5 {
        DAffine3::from_rotation_translation(
            DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 3.0)),
            rng.v(-0.3, 0.3),
        )
    } else {
        DAffine3::IDENTITY
    };
    let node = object(
        ShapeDecl::Csg(Csg {
            op,
            children: objects,
        }),
        to_world,
        0,
    );
    (Tree::Op { op, kids, to_world }, node)
}

/// The first membership change along `o + t d` for t in (0, t_end), bisected.
fn oracle_hit(tree: &Tree, o: DVec3, d: DVec3, t_end: f64) -> Option<f64> {
    let at = |t: f64| inside(tree, o + d * t);
    let m0 = at(1e-9);
    let steps = (t_end / STEP).ceil() as usize;
    let k = (1..=steps).find(|&k| at(k as f64 * STEP) != m0)?;
    let (mut a, mut b) = ((k - 1) as f64 * STEP, k as f64 * STEP);
    while b - a > 1e-10 {
        let m = 0.5 * (a + b);
        if at(m) == m0 { a = m } else { b = m }
    }
    Some(0.5 * (a + b))
}

/// Far end of the ray inside the cube that holds all geometry.
fn exit_distance(o: DVec3, d: DVec3) -> f64 {
    exit_from(HALF, o, d)
}

/// Far end of the ray inside the cube `[-half, half]^3`.
fn exit_from(half: f64, o: DVec3, d: DVec3) -> f64 {
    let t = (DVec3::splat(half) * d.signum() - o) / d;
    t.min_element().max(0.0)
}

/// Counts of the rays the renderer and the oracle agree on.
#[derive(Default)]
struct Tally {
    hits: usize,
    misses: usize,
    slivers: usize,
    normals: usize,
}

/// Judges one ray `o + t d` through `prepared` against the oracle's `tree`: the same first
/// hit (or a sliver the oracle's step missed), the normal out of the solid and the part.
fn judge(
    tree: &Tree,
    prepared: &PreparedScene,
    o: DVec3,
    d: DVec3,
    case: String,
    tally: &mut Tally,
    failures: &mut Vec<String>,
) {
    let ray = Ray::new(o.as_vec3a(), d.as_vec3a());
    let got = prepared.intersect(&ray, f32::INFINITY);
    let want = oracle_hit(tree, o, d, exit_distance(o, d));
    match (got, want) {
        (None, None) => tally.misses += 1,
        (Some(g), Some(w)) if (g.hit.t as f64 - w).abs() <= T_TOL => {
            tally.hits += 1;
            // The normal: the nearest part's outward normal, turned to point out of the
            // tree's solid. Skipped near an edge, where two parts are about as near.
            let p = o + d * w;
            let mut s = Vec::new();
            surfaces(tree, DAffine3::IDENTITY, p, &mut s);
            s.sort_by(|a, b| a.1.total_cmp(&b.1));
            if s.len() > 1 && s[1].1 < 1e-3 {
                return;
            }
            let (id, _, n) = s[0];
            let entering = !inside(tree, o + d * (w - 1e-6));
            let want_n = if (n.dot(d) < 0.0) == entering { n } else { -n };
            let got_n = DVec3::from(g.hit.n.to_array().map(f64::from));
            if got_n.dot(want_n) < 0.999 {
                failures.push(format!("{case}: normal {got_n:?}, want {want_n:?}"));
            }
            let part = prepared.material(g.prim).expect("a hit's primitive");
            let want_part = Material::Diffuse {
                albedo: ColorParam::Const(DVec3::splat(id as f64)),
            };
            if *part != want_part {
                failures.push(format!("{case}: hit {part:?}, want part {id}"));
            }
            tally.normals += 1;
        }
        (Some(g), w) if w.is_none_or(|w| (g.hit.t as f64) < w) => {
            // A sliver the sampling stepped over? Membership must change within
            // `T_TOL` of the renderer's hit (sampled at T_TOL / 20), and change back
            // within one step after that.
            let t = g.hit.t as f64;
            let at = |t: f64| inside(tree, o + d * t);
            let before = at(t - T_TOL);
            let opened = (1..=40)
                .map(|k| t - T_TOL + k as f64 * T_TOL / 20.0)
                .find(|&s| at(s) != before);
            let closes = opened
                .is_some_and(|s| (1..=200).any(|k| at(s + k as f64 * STEP / 200.0) == before));
            if closes {
                tally.slivers += 1;
            } else {
                failures.push(format!("{case}: renderer {t}, oracle {w:?}"));
            }
        }
        (g, w) => failures.push(format!(
            "{case}: renderer {:?}, oracle {w:?}",
            g.map(|g| g.hit.t)
        )),
    }
}

#[test]
fn random_trees_match_a_point_membership_oracle() {
    let mut rng = Rand(0x5eed_c5a6);
    let mut tally = Tally::default();
    let mut failures = Vec::new();
    for tree_no in 0..300 {
        let mut next_id = 0;
        let (tree, object) = random_tree(&mut rng, 3, &mut next_id);
        if !matches!(object.shape, ShapeDecl::Csg(_)) {
            continue;
        }
        let mut scene: Scene = empty_scene((8, 8));
        for id in 0..next_id {
            scene.materials.push(Material::Diffuse {
                albedo: ColorParam::Const(DVec3::splat(id as f64)),
            });
        }
        scene.objects.push(object);
        let prepared = PreparedScene::new(&scene).expect("valid tree");
        for _ in 0..100 {
            // Half the rays start near the shapes (often inside some), all aim at them.
            let o = if rng.f() < 0.5 {
                rng.v(-1.0, 1.0)
            } else {
                rng.v(-2.5, 2.5)
            };
            let d = (rng.v(-0.8, 0.8) - o).normalize();
            let case = format!("tree {tree_no}, ray {o:?} + t {d:?}");
            judge(&tree, &prepared, o, d, case, &mut tally, &mut failures);
        }
    }
    let Tally {
        hits,
        misses,
        slivers,
        normals,
    } = tally;
    println!(
        "{hits} hits agree ({normals} normals and parts checked), {misses} misses agree, \
         {slivers} slivers thinner than the oracle's step, {} failures",
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{}",
        failures[..failures.len().min(20)].join("\n")
    );
    assert!(
        hits > 4000 && misses > 1000 && normals > 4000,
        "{hits} {misses} {normals}"
    );
    assert!(slivers * 100 < hits, "too many slivers: {slivers}");
}

// The newer shapes as operands: blob, isosurface, height_field (closed down to its water
// level), text (a merge of glyph prisms), prism and superellipsoid, each in every operation
// with a sphere or a box, placed and turned at random. The oracle knows each shape by a
// membership test written here from the shape's definition (a field below zero inside); the
// part a hit is on is the leaf whose membership changes there, and its normal, where the
// oracle can tell it, the gradient of the leaf's field.

/// A shape the oracle knows by a field, negative inside (in the shape's own space), and where
/// it can tell, its outward normal.
struct Leaf {
    field: Box<dyn Fn(DVec3) -> f64>,
    normal: Box<dyn Fn(DVec3) -> Option<DVec3>>,
}

/// Everything of the newer shapes' trees lies inside [-HALF_NEW, HALF_NEW]^3 (shapes within
/// about 1.1 of their centre, translations under 0.3, the other operand within 1.5).
const HALF_NEW: f64 = 2.2;

const DEJAVU: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// The unit outward normal of a field by central differences (`None` where it has none).
fn gradient(f: &dyn Fn(DVec3) -> f64, p: DVec3) -> Option<DVec3> {
    let h = 1e-6;
    let g = DVec3::new(
        f(p + DVec3::X * h) - f(p - DVec3::X * h),
        f(p + DVec3::Y * h) - f(p - DVec3::Y * h),
        f(p + DVec3::Z * h) - f(p - DVec3::Z * h),
    );
    (g.is_finite() && g.length() > 0.0).then(|| g.normalize())
}

fn field_leaf(f: impl Fn(DVec3) -> f64 + Clone + 'static) -> Leaf {
    let g = f.clone();
    Leaf {
        field: Box::new(f),
        normal: Box::new(move |p| gradient(&g, p)),
    }
}

/// The outward normal of a leaf in its own space, where the oracle knows it.
fn leaf_normal(t: &Tree, q: DVec3) -> Option<DVec3> {
    match t {
        Tree::Sphere { c, .. } => Some((q - *c).normalize()),
        Tree::Box { lo, hi, .. } => {
            // The face whose plane is nearest, unless another is about as near (an edge).
            let c = 0.5 * (*lo + *hi);
            let e = (q - c).abs() - 0.5 * (*hi - *lo);
            let mut k = [0, 1, 2];
            k.sort_by(|a, b| e[*b].total_cmp(&e[*a]));
            (e[k[0]] - e[k[1]] > 1e-3).then(|| {
                let mut n = DVec3::ZERO;
                n[k[0]] = (q - c)[k[0]].signum();
                n
            })
        }
        Tree::Solid { leaf, .. } => (leaf.normal)(q),
        Tree::Sweep(w, _) => Some((q - w.distance(q).1).normalize()),
        Tree::Op { .. } => None,
    }
}

fn leaf_id(t: &Tree) -> usize {
    match t {
        Tree::Sphere { id, .. }
        | Tree::Box { id, .. }
        | Tree::Solid { id, .. }
        | Tree::Sweep(_, id) => *id,
        Tree::Op { .. } => unreachable!("an operation is no leaf"),
    }
}

/// The leaves whose membership differs at the world points `a` and `b`: their ids and world
/// normals at the midpoint, where known.
fn flips(t: &Tree, to_world: DAffine3, a: DVec3, b: DVec3, out: &mut Vec<(usize, Option<DVec3>)>) {
    if let Tree::Op {
        kids,
        to_world: own,
        ..
    } = t
    {
        for k in kids {
            flips(k, to_world * *own, a, b, out);
        }
        return;
    }
    let inv = to_world.inverse();
    if inside(t, inv.transform_point3(a)) != inside(t, inv.transform_point3(b)) {
        let n = leaf_normal(t, inv.transform_point3(0.5 * (a + b)))
            .map(|n| (inv.matrix3.transpose() * n).normalize());
        out.push((leaf_id(t), n));
    }
}

/// The de Casteljau halves of a cubic.
fn halves(c: [DVec2; 4]) -> ([DVec2; 4], [DVec2; 4]) {
    let m = |a: DVec2, b: DVec2| 0.5 * (a + b);
    let (p01, p12, p23) = (m(c[0], c[1]), m(c[1], c[2]), m(c[2], c[3]));
    let (p012, p123) = (m(p01, p12), m(p12, p23));
    let mid = m(p012, p123);
    ([c[0], p01, p012, mid], [mid, p123, p23, c[3]])
}

/// Crossings of the ray from `p` toward +x with a cubic Bezier curve (an end counts when it
/// lies strictly above `p`, so joined segments count a shared end once), by subdivision
/// down to chords of 1e-12.
fn crossings(c: [DVec2; 4], p: DVec2, depth: u32) -> u32 {
    let above = |q: &DVec2| q.y > p.y;
    if c.iter().all(above) || !c.iter().any(above) {
        return 0;
    }
    let (lo, hi) = c
        .iter()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(l, h), q| {
            (l.min(*q), h.max(*q))
        });
    let odd = u32::from(above(&c[0]) != above(&c[3]));
    if hi.x < p.x {
        return 0;
    }
    if lo.x > p.x {
        return odd;
    }
    if depth == 0 || (hi - lo).max_element() < 1e-12 {
        let x = c[0].x + (p.y - c[0].y) * (c[3].x - c[0].x) / (c[3].y - c[0].y);
        return odd * u32::from(x > p.x);
    }
    let (a, b) = halves(c);
    crossings(a, p, depth - 1) + crossings(b, p, depth - 1)
}

/// A closed prism: between its heights, inside its profile by the even-odd rule.
fn prism_leaf(segments: Vec<[DVec2; 4]>, heights: (f64, f64)) -> Leaf {
    let (lo, hi) = segments
        .iter()
        .flatten()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(l, h), q| {
            (l.min(*q), h.max(*q))
        });
    let (y0, y1) = (heights.0.min(heights.1), heights.0.max(heights.1));
    Leaf {
        field: Box::new(move |q: DVec3| {
            let p = DVec2::new(q.x, q.z);
            let within = q.y > y0 && q.y < y1 && p.cmpgt(lo).all() && p.cmplt(hi).all();
            let odd = within && segments.iter().map(|s| crossings(*s, p, 48)).sum::<u32>() % 2 == 1;
            if odd { -1.0 } else { 1.0 }
        }),
        normal: Box::new(|_| None),
    }
}

/// POV-Ray's blob field: the threshold less the sum of `strength (1 - (d / r)^2)^2`.
fn blob_shape() -> (Leaf, ShapeDecl) {
    let comps = [
        (
            DVec3::new(-0.35, 0.0, 0.0),
            DVec3::new(-0.35, 0.0, 0.0),
            0.75,
            1.0,
        ),
        (
            DVec3::new(0.35, 0.1, 0.05),
            DVec3::new(0.35, 0.1, 0.05),
            0.65,
            1.0,
        ),
        (
            DVec3::new(0.0, -0.6, 0.25),
            DVec3::new(0.1, 0.6, -0.2),
            0.35,
            1.5,
        ),
        (
            DVec3::new(0.15, 0.35, 0.3),
            DVec3::new(0.15, 0.35, 0.3),
            0.35,
            -1.0,
        ),
    ];
    let threshold = 0.35;
    let field = move |p: DVec3| {
        let density: f64 = comps
            .iter()
            .map(|&(a, b, r, s)| {
                let ab = b - a;
                let h = if ab == DVec3::ZERO {
                    0.0
                } else {
                    ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
                };
                let d2 = (p - a - ab * h).length_squared() / (r * r);
                if d2 < 1.0 {
                    s * (1.0 - d2).powi(2)
                } else {
                    0.0
                }
            })
            .sum();
        threshold - density
    };
    let blob = Blob {
        threshold,
        components: comps
            .iter()
            .map(|&(a, b, radius, strength)| BlobComponent {
                a,
                b,
                radius,
                strength,
                transform: DAffine3::IDENTITY,
            })
            .collect(),
    };
    (field_leaf(field), ShapeDecl::Blob(blob))
}

/// `sqrt(x^2 + y^2 + z^2) + 0.15 sin(5 x) cos(4 y) < 0.75` in a box that cuts it at
/// y = +-0.55 (closed there by the walls).
fn isosurface_shape() -> (Leaf, ShapeDecl) {
    let mut code = Vec::new();
    for k in 0..3 {
        code.extend([Op::Load(k), Op::Load(k), Op::Binary(Binary::Mul)]);
    }
    code.extend([
        Op::Binary(Binary::Add),
        Op::Binary(Binary::Add),
        Op::Unary(Unary::Sqrt),
        Op::Const(0.15),
        Op::Const(5.0),
        Op::Load(0),
        Op::Binary(Binary::Mul),
        Op::Unary(Unary::Sin),
        Op::Binary(Binary::Mul),
        Op::Const(4.0),
        Op::Load(1),
        Op::Binary(Binary::Mul),
        Op::Unary(Unary::Cos),
        Op::Binary(Binary::Mul),
        Op::Binary(Binary::Add),
    ]);
    let (min, max) = (DVec3::new(-1.1, -0.55, -1.1), DVec3::new(1.1, 0.55, 1.1));
    let f = |p: DVec3| p.length() + 0.15 * (5.0 * p.x).sin() * (4.0 * p.y).cos() - 0.75;
    let wall = move |p: DVec3| ((p - 0.5 * (min + max)).abs() - 0.5 * (max - min)).max_element();
    let leaf = Leaf {
        field: Box::new(move |p| f(p).max(wall(p))),
        normal: Box::new(move |p| {
            let (s, w) = (f(p), wall(p));
            if s > w + 1e-3 {
                gradient(&f, p)
            } else if w > s + 1e-3 {
                gradient(&wall, p)
            } else {
                None
            }
        }),
    };
    let iso = Isosurface {
        function: Arc::new(Function::new(3, 3, code).expect("a valid program")),
        threshold: 0.0,
        container: Container::Box { min, max },
        open: false,
        accuracy: 1e-6,
    };
    // The program's value is f + 0.75; the threshold moves it to f.
    let iso = Isosurface {
        threshold: 0.75,
        ..iso
    };
    (leaf, ShapeDecl::Isosurface(iso))
}

/// `(|x|^(2/e) + |y|^(2/e))^(e/n) + |z|^(2/n) < 1`: a rounded box pinched toward its poles.
fn superellipsoid_shape() -> (Leaf, ShapeDecl) {
    let (e, n) = (0.35, 2.3);
    let f = move |p: DVec3| {
        (p.x.abs().powf(2.0 / e) + p.y.abs().powf(2.0 / e)).powf(e / n) + p.z.abs().powf(2.0 / n)
            - 1.0
    };
    (field_leaf(f), ShapeDecl::Superellipsoid { e, n })
}

/// A 14 x 11 terrain, part of it under the water level 0.25, over the unit square; the
/// solid is between the water and the triangles (the diagonal of cell (i, j) from (i + 1, j)
/// to (i, j + 1)), the samples raised to the water where below it.
fn height_field_shape() -> (Leaf, ShapeDecl) {
    let (nx, nz, water) = (14u32, 11u32, 0.25);
    let heights: Vec<f32> = (0..nz)
        .flat_map(|j| {
            (0..nx).map(move |i| {
                let (i, j) = (f64::from(i), f64::from(j));
                (0.45 + 0.3 * (0.9 * i).sin() * (0.7 * j).cos() + 0.15 * (1.3 * (i + j)).cos())
                    .clamp(0.0, 1.0) as f32
            })
        })
        .collect();
    let grid = Arc::new(HeightGrid { nx, nz, heights });
    let g = grid.clone();
    let h = move |i: u32, j: u32| f64::from(g.at(i, j)).max(water);
    let field = move |p: DVec3| {
        if !(p.x > 0.0 && p.x < 1.0 && p.z > 0.0 && p.z < 1.0 && p.y > water) {
            return 1.0;
        }
        let (u, v) = (p.x * f64::from(nx - 1), p.z * f64::from(nz - 1));
        let (i, j) = ((u as u32).min(nx - 2), (v as u32).min(nz - 2));
        let (u, v) = (u - f64::from(i), v - f64::from(j));
        let top = if u + v <= 1.0 {
            h(i, j) + u * (h(i + 1, j) - h(i, j)) + v * (h(i, j + 1) - h(i, j))
        } else {
            h(i + 1, j + 1)
                + (1.0 - u) * (h(i, j + 1) - h(i + 1, j + 1))
                + (1.0 - v) * (h(i + 1, j) - h(i + 1, j + 1))
        };
        if p.y < top { -1.0 } else { 1.0 }
    };
    let leaf = Leaf {
        field: Box::new(field),
        normal: Box::new(|_| None),
    };
    let shape = ShapeDecl::HeightField(HeightField {
        grid,
        water,
        smooth: false,
    });
    (leaf, shape)
}

/// A quadratic-spline star with a round hole, 0.95 high.
fn prism_shape() -> (Leaf, ShapeDecl) {
    let star: Vec<DVec2> = (0..10)
        .map(|k| {
            let a = std::f64::consts::TAU * f64::from(k) / 10.0;
            let r = if k % 2 == 0 { 0.95 } else { 0.4 };
            DVec2::new(r * a.cos(), r * a.sin())
        })
        .collect();
    let hole: Vec<DVec2> = (0..6)
        .map(|k| {
            let a = std::f64::consts::TAU * f64::from(k) / 6.0;
            DVec2::new(0.2 * a.cos(), 0.2 * a.sin())
        })
        .collect();
    // Quadratic: a shaping point first, then the points, closing on the second.
    let mut points = vec![star[9]];
    points.extend(&star);
    points.push(star[0]);
    points.push(hole[5]);
    points.extend(&hole);
    points.push(hole[0]);
    let segments = prism_segments(PrismSpline::Quadratic, &points).expect("a valid profile");
    let heights = (-0.5, 0.45);
    let leaf = prism_leaf(segments.clone(), heights);
    let shape = ShapeDecl::Prism(Prism {
        segments,
        heights,
        conic: false,
        open: false,
    });
    (leaf, shape)
}

/// The new shape of `kind` (0..6) as the oracle's tree and the scene's object, material `id`.
fn new_shape(kind: usize, id: usize, font: &[u8]) -> (&'static str, Tree, Object) {
    let object = |shape, transform| Object {
        shape,
        transform,
        material: MaterialId(id as u32),
        emission: None,
        span: Span::detached(),
    };
    let wrap = |leaf: Leaf, transform: DAffine3| Tree::Op {
        op: CsgOp::Merge,
        kids: vec![Tree::Solid { leaf, id }],
        to_world: transform,
    };
    let (name, (leaf, shape), transform) = match kind {
        0 => ("blob", blob_shape(), DAffine3::IDENTITY),
        1 => ("isosurface", isosurface_shape(), DAffine3::IDENTITY),
        2 => (
            "height_field",
            height_field_shape(),
            DAffine3::from_scale(DVec3::splat(1.6))
                * DAffine3::from_translation(DVec3::new(-0.5, -0.45, -0.5)),
        ),
        3 => ("prism", prism_shape(), DAffine3::IDENTITY),
        4 => ("superellipsoid", superellipsoid_shape(), DAffine3::IDENTITY),
        _ => {
            // "Rg&" about 2 em wide, 0.4 em deep, centred: a merge of its glyphs' prisms.
            let glyphs = text_glyphs(font, "Rg&", 0.4, DVec3::ZERO).expect("a font");
            let place = DAffine3::from_translation(DVec3::new(-0.85, -0.25, -0.16))
                * DAffine3::from_scale(DVec3::splat(0.85));
            let (kids, children) = glyphs
                .glyphs
                .into_iter()
                .map(|g| {
                    let leaf = prism_leaf(g.prism.segments.clone(), g.prism.heights);
                    (
                        wrap(leaf, g.transform),
                        object(ShapeDecl::Prism(g.prism), g.transform),
                    )
                })
                .unzip();
            let tree = Tree::Op {
                op: CsgOp::Merge,
                kids,
                to_world: place,
            };
            let shape = ShapeDecl::Csg(Csg {
                op: CsgOp::Merge,
                children,
            });
            return ("text", tree, object(shape, place));
        }
    };
    (name, wrap(leaf, transform), object(shape, transform))
}

#[test]
fn the_newer_shapes_as_operands_match_a_point_membership_oracle() {
    let font = std::fs::read(DEJAVU)
        .unwrap_or_else(|_| panic!("{DEJAVU} is missing: install fonts-dejavu-core"));
    let mut rng = Rand(0x0be7_a5d5);
    // (operation, whether the new shape comes second: the subtracted one in a difference).
    let ops = [
        (CsgOp::Union, false),
        (CsgOp::Merge, true),
        (CsgOp::Intersection, false),
        (CsgOp::Difference, false),
        (CsgOp::Difference, true),
    ];
    let mut failures = Vec::new();
    let mut summary = Vec::new();
    for kind in 0..6 {
        let (mut rays, mut hits, mut misses, mut slivers, mut parts, mut normals) =
            (0usize, 0usize, 0usize, 0usize, 0usize, 0usize);
        let mut name = "";
        for (op, second) in ops {
            for config in 0..4 {
                let (shape_name, mut shape_tree, mut shape_obj) = new_shape(kind, 0, &font);
                name = shape_name;
                // The new shape turned and moved at random (its own placement kept).
                let place = DAffine3::from_rotation_translation(
                    DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 3.0)),
                    rng.v(-0.3, 0.3),
                );
                shape_obj.transform = place * shape_obj.transform;
                shape_tree = Tree::Op {
                    op: CsgOp::Merge,
                    kids: vec![shape_tree],
                    to_world: place,
                };
                // The other operand: a sphere or a box about the new shape.
                let c = rng.v(-0.7, 0.7);
                let (other_tree, other_shape) = if rng.f() < 0.5 {
                    let r = rng.range(0.3, 0.8);
                    (
                        Tree::Sphere { c, r, id: 1 },
                        ShapeDecl::Sphere {
                            center: c,
                            radius: r,
                        },
                    )
                } else {
                    let h = rng.v(0.2, 0.7);
                    (
                        Tree::Box {
                            lo: c - h,
                            hi: c + h,
                            id: 1,
                        },
                        ShapeDecl::Box {
                            min: c - h,
                            max: c + h,
                        },
                    )
                };
                let other_obj = Object {
                    shape: other_shape,
                    transform: DAffine3::IDENTITY,
                    material: MaterialId(1),
                    emission: None,
                    span: Span::detached(),
                };
                let (kids, children) = if second {
                    (vec![other_tree, shape_tree], vec![other_obj, shape_obj])
                } else {
                    (vec![shape_tree, other_tree], vec![shape_obj, other_obj])
                };
                // A union keeps every child's surfaces: its first hit is the nearest of its
                // children's, each child an oracle of its own.
                let alternatives: Vec<Tree> = if op == CsgOp::Union {
                    kids.into_iter()
                        .map(|k| Tree::Op {
                            op: CsgOp::Merge,
                            kids: vec![k],
                            to_world: DAffine3::IDENTITY,
                        })
                        .collect()
                } else {
                    vec![Tree::Op {
                        op,
                        kids,
                        to_world: DAffine3::IDENTITY,
                    }]
                };
                let mut scene: Scene = empty_scene((8, 8));
                for id in 0..2 {
                    scene.materials.push(Material::Diffuse {
                        albedo: ColorParam::Const(DVec3::splat(id as f64)),
                    });
                }
                scene.objects.push(Object {
                    shape: ShapeDecl::Csg(Csg { op, children }),
                    transform: DAffine3::IDENTITY,
                    material: MaterialId(0),
                    emission: None,
                    span: Span::detached(),
                });
                let prepared = PreparedScene::new(&scene).expect("a valid tree");
                for _ in 0..150 {
                    rays += 1;
                    let o = if rng.f() < 0.5 {
                        rng.v(-1.0, 1.0)
                    } else {
                        rng.v(-2.0, 2.0)
                    };
                    let d = (rng.v(-0.8, 0.8) - o).normalize();
                    let ray = Ray::new(o.as_vec3a(), d.as_vec3a());
                    let got = prepared.intersect(&ray, f32::INFINITY);
                    let t_end = exit_from(HALF_NEW, o, d);
                    let want = alternatives
                        .iter()
                        .enumerate()
                        .filter_map(|(k, t)| oracle_hit(t, o, d, t_end).map(|w| (w, k)))
                        .min_by(|a, b| a.0.total_cmp(&b.0));
                    let case = format!(
                        "{name} {op:?}{} config {config}, ray {o:?} + t {d:?}",
                        if second { " (second)" } else { "" }
                    );
                    match (got, want) {
                        (None, None) => misses += 1,
                        (Some(g), Some((w, k))) if (g.hit.t as f64 - w).abs() <= T_TOL => {
                            hits += 1;
                            let tree = &alternatives[k];
                            let p = o + d * w;
                            let entering = !inside(tree, p - d * 1e-7);
                            let got_n = DVec3::from(g.hit.n.to_array().map(f64::from));
                            // The normal points out of the solid: against the ray entering.
                            if got_n.dot(d).abs() > 1e-3 && (got_n.dot(d) < 0.0) != entering {
                                failures.push(format!(
                                    "{case}: normal {got_n:?} points {} the solid",
                                    if entering { "into" } else { "out of" }
                                ));
                            }
                            // The part: the one leaf that changes there, with no other leaf
                            // changing within 1e-3 (an edge).
                            let mut here = Vec::new();
                            flips(
                                tree,
                                DAffine3::IDENTITY,
                                p - d * 1e-7,
                                p + d * 1e-7,
                                &mut here,
                            );
                            let mut near = Vec::new();
                            flips(
                                tree,
                                DAffine3::IDENTITY,
                                p - d * 1e-3,
                                p - d * 1e-7,
                                &mut near,
                            );
                            flips(
                                tree,
                                DAffine3::IDENTITY,
                                p + d * 1e-7,
                                p + d * 1e-3,
                                &mut near,
                            );
                            let [(id, n)] = here[..] else { continue };
                            if near.iter().any(|&(other, _)| other != id) {
                                continue;
                            }
                            parts += 1;
                            let part = prepared.material(g.prim).expect("a hit's primitive");
                            let want_part = Material::Diffuse {
                                albedo: ColorParam::Const(DVec3::splat(id as f64)),
                            };
                            if *part != want_part {
                                failures.push(format!("{case}: hit {part:?}, want part {id}"));
                            }
                            if let Some(n) = n {
                                normals += 1;
                                let want_n = if (n.dot(d) < 0.0) == entering { n } else { -n };
                                if got_n.dot(want_n) < 0.999 {
                                    failures
                                        .push(format!("{case}: normal {got_n:?}, want {want_n:?}"));
                                }
                            }
                        }
                        (Some(g), w) if w.is_none_or(|w| (g.hit.t as f64) < w.0) => {
                            // A sliver thinner than the oracle's step, in some alternative?
                            let t = g.hit.t as f64;
                            let sliver = alternatives.iter().any(|tree| {
                                let at = |t: f64| inside(tree, o + d * t);
                                let before = at(t - T_TOL);
                                let opened = (1..=40)
                                    .map(|k| t - T_TOL + k as f64 * T_TOL / 20.0)
                                    .find(|&s| at(s) != before);
                                opened.is_some_and(|s| {
                                    (1..=200).any(|k| at(s + k as f64 * STEP / 200.0) == before)
                                })
                            });
                            if sliver {
                                slivers += 1;
                            } else {
                                failures.push(format!("{case}: renderer {t}, oracle {w:?}"));
                            }
                        }
                        (g, w) => failures.push(format!(
                            "{case}: renderer {:?}, oracle {w:?}",
                            g.map(|g| g.hit.t)
                        )),
                    }
                }
            }
        }
        summary.push(format!(
            "{name}: {rays} rays, {hits} hits agree ({parts} parts, {normals} normals checked), \
             {misses} misses agree, {slivers} slivers"
        ));
        assert!(
            hits * 4 > rays && misses * 20 > rays && parts * 2 > hits && slivers * 50 < hits,
            "{}",
            summary.last().unwrap()
        );
    }
    println!("{}", summary.join("\n"));
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures[..failures.len().min(30)].join("\n")
    );
}

/// A curved sphere sweep as a CSG operand (taken from, subtracted, intersected, merged under
/// a rotation): the renderer's first hits, normals and parts against the oracle, whose sweep
/// evaluates the spline itself.
#[test]
fn a_sphere_sweep_operand_matches_the_oracle() {
    use sppm_lang::internals::scene::{SphereSweep, SweepSpline};
    let v = DVec3::new;
    let cubic = vec![
        (v(-1.6, -0.3, 0.2), 0.3),
        (v(-1.0, 0.4, -0.2), 0.35),
        (v(-0.2, -0.4, 0.3), 0.5),
        (v(0.5, 0.5, -0.3), 0.3),
        (v(1.1, -0.2, 0.1), 0.45),
        (v(1.6, 0.3, 0.0), 0.3),
    ];
    // A b-spline loop around the origin with a radius that dips below 0 on one side.
    let looped = vec![
        (v(-1.0, 0.0, -0.5), 0.4),
        (v(1.0, 0.0, -0.8), 0.5),
        (v(1.0, 0.2, 0.8), -0.3),
        (v(-1.0, 0.0, 0.8), 0.5),
        (v(-1.0, -0.2, -0.5), 0.4),
        (v(1.0, 0.0, -0.8), 0.5),
    ];
    let leaf = |tree: Tree, shape: ShapeDecl, id: usize| {
        let object = Object {
            shape,
            transform: DAffine3::IDENTITY,
            material: MaterialId(id as u32),
            emission: None,
            span: Span::detached(),
        };
        (tree, object)
    };
    let sweep = |b_spline: bool, pts: &[(DVec3, f64)], id: usize| {
        let spline = if b_spline {
            SweepSpline::BSpline
        } else {
            SweepSpline::CatmullRom
        };
        leaf(
            Tree::Sweep(Sweep::new(b_spline, pts.to_vec()), id),
            ShapeDecl::SphereSweep(SphereSweep {
                spline,
                centres: pts.iter().map(|p| p.0).collect(),
                radii: pts.iter().map(|p| p.1).collect(),
            }),
            id,
        )
    };
    let sphere = |c: DVec3, r: f64, id: usize| {
        leaf(
            Tree::Sphere { c, r, id },
            ShapeDecl::Sphere {
                center: c,
                radius: r,
            },
            id,
        )
    };
    let cuboid = |lo: DVec3, hi: DVec3, id: usize| {
        leaf(
            Tree::Box { lo, hi, id },
            ShapeDecl::Box { min: lo, max: hi },
            id,
        )
    };
    let turn = DAffine3::from_rotation_translation(
        DQuat::from_axis_angle(v(0.3, 1.0, 0.2).normalize(), 0.7),
        v(0.1, -0.2, 0.05),
    );
    let cases = [
        (
            CsgOp::Difference,
            DAffine3::IDENTITY,
            vec![sweep(false, &cubic, 0), sphere(v(-0.2, -0.2, 0.0), 0.55, 1)],
        ),
        (
            CsgOp::Difference,
            turn,
            vec![
                cuboid(v(-1.5, -0.6, -0.6), v(1.5, 0.3, 0.6), 0),
                sweep(false, &cubic, 1),
            ],
        ),
        (
            CsgOp::Intersection,
            turn,
            vec![
                sweep(true, &looped, 0),
                cuboid(v(-2.0, -0.15, -2.0), v(0.6, 2.0, 2.0), 1),
            ],
        ),
        (
            CsgOp::Merge,
            turn,
            vec![sweep(true, &looped, 0), sphere(v(0.9, 0.1, -0.6), 0.4, 1)],
        ),
    ];
    let mut rng = Rand(0x5ee9_c5a6);
    let mut tally = Tally::default();
    let mut failures = Vec::new();
    for (k, (op, to_world, kids)) in cases.into_iter().enumerate() {
        let (trees, objects): (Vec<Tree>, Vec<Object>) = kids.into_iter().unzip();
        let tree = Tree::Op {
            op,
            kids: trees,
            to_world,
        };
        let mut scene: Scene = empty_scene((8, 8));
        for id in 0..2 {
            scene.materials.push(Material::Diffuse {
                albedo: ColorParam::Const(DVec3::splat(id as f64)),
            });
        }
        scene.objects.push(Object {
            shape: ShapeDecl::Csg(Csg {
                op,
                children: objects,
            }),
            transform: to_world,
            material: MaterialId(0),
            emission: None,
            span: Span::detached(),
        });
        let prepared = PreparedScene::new(&scene).expect("valid tree");
        for _ in 0..150 {
            let o = if rng.f() < 0.5 {
                rng.v(-1.0, 1.0)
            } else {
                rng.v(-2.5, 2.5)
            };
            let d = (rng.v(-0.8, 0.8) - o).normalize();
            let case = format!("sweep case {k}, ray {o:?} + t {d:?}");
            judge(&tree, &prepared, o, d, case, &mut tally, &mut failures);
        }
    }
    println!(
        "{} hits agree ({} normals and parts checked), {} misses agree, {} slivers, {} failures",
        tally.hits,
        tally.normals,
        tally.misses,
        tally.slivers,
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{}",
        failures[..failures.len().min(20)].join("\n")
    );
    assert!(tally.hits > 250 && tally.normals > 150, "{}", tally.hits);
    assert!(tally.slivers * 20 < tally.hits, "too many slivers");
}
