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
use glam::{DAffine3, DQuat, DVec3};
use sppm_lang::geometry::Ray;
use sppm_lang::prepare::PreparedScene;
use sppm_lang::scene::{ColorParam, Csg, CsgOp, Material, MaterialId, Object, Scene, Shape};
use sppm_lang::span::Span;

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
                    Shape::Sphere {
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
                object(Shape::Box { min: lo, max: hi }, DAffine3::IDENTITY, id),
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
        Shape::Csg(Csg {
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
    let t = (DVec3::splat(HALF) * d.signum() - o) / d;
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
        if !matches!(object.shape, Shape::Csg(_)) {
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

/// A curved sphere sweep as a CSG operand (taken from, subtracted, intersected, merged under
/// a rotation): the renderer's first hits, normals and parts against the oracle, whose sweep
/// evaluates the spline itself.
#[test]
fn a_sphere_sweep_operand_matches_the_oracle() {
    use sppm_lang::scene::{SphereSweep, SweepSpline};
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
    let leaf = |tree: Tree, shape: Shape, id: usize| {
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
            Shape::SphereSweep(SphereSweep {
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
            Shape::Sphere {
                center: c,
                radius: r,
            },
            id,
        )
    };
    let cuboid = |lo: DVec3, hi: DVec3, id: usize| {
        leaf(
            Tree::Box { lo, hi, id },
            Shape::Box { min: lo, max: hi },
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
            shape: Shape::Csg(Csg {
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
