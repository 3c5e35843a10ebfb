use super::*;
use crate::sampling::Rng;

/// A bumpy height field over [0, 3]^2 whose rows also lean (not a graph along every ray).
fn bumpy() -> Patch {
    let z = [
        [0.0, 0.8, -0.6, 0.2],
        [0.5, -1.2, 1.4, -0.3],
        [-0.4, 1.5, -1.1, 0.6],
        [0.3, -0.2, 0.7, 0.0],
    ];
    Patch::new(&std::array::from_fn(|k| {
        let (i, j) = (k / 4, k % 4);
        DVec3::new(i as f64 + 0.3 * z[i][j], j as f64, z[i][j])
    }))
    .unwrap()
}

fn f(rng: &mut Rng) -> f64 {
    f64::from(rng.f32())
}

#[test]
fn a_restricted_cubic_is_the_same_curve() {
    let c = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 2.0, -1.0),
        DVec3::new(2.0, -1.0, 0.5),
        DVec3::new(3.0, 1.0, 2.0),
    ];
    let at = |c: &[DVec3; 4], t: f64| {
        let (b, _) = bern3(t);
        (0..4).map(|k| c[k] * b[k]).sum::<DVec3>()
    };
    for (a, b) in [
        (0.0, 1.0),
        (0.0, 0.375),
        (0.3, 0.7),
        (0.625, 1.0),
        (0.875, 1.0),
    ] {
        let r = restrict4(c, a, b);
        for s in [0.0, 0.1, 0.5, 0.93, 1.0] {
            let (want, got) = (at(&c, a + s * (b - a)), at(&r, s));
            assert!(
                (want - got).length() < 1e-14,
                "[{a}, {b}] at {s}: {got} vs {want}"
            );
        }
    }
}

/// A random unit direction.
fn dir(rng: &mut Rng) -> DVec3 {
    let d = DVec3::new(f(rng) - 0.5, f(rng) - 0.5, f(rng) - 0.5);
    d.try_normalize().unwrap_or(DVec3::X)
}

/// The oriented box drops only rays that miss: on pieces of a bumpy, a flat, a tiny and a
/// far-away patch, rays aimed at surface points (the pieces' corners among them, which lie on
/// the box's faces), rays leaving surface points, rays in a surface point's tangent plane
/// and random rays through the axis-aligned box get the same answer, bit for bit, as the
/// subdivision without the box; and the box does drop a share of the random rays.
#[test]
fn the_oriented_box_drops_only_rays_that_miss() {
    let flat = Patch::new(&std::array::from_fn(|k| {
        DVec3::new((k / 4) as f64, (k % 4) as f64 * 0.7, 0.0)
    }))
    .unwrap();
    let moved = |p: &Patch, scale: f64, shift: DVec3| {
        Patch::new(&p.points().map(|q| q * scale + shift)).unwrap()
    };
    let b = bumpy();
    let patches = [
        b.clone(),
        flat.clone(),
        moved(&b, 1e-4, DVec3::new(0.3, -2.0, 1.0)),
        moved(&b, 1.0, DVec3::new(1e6, -3e5, 2e6)),
        moved(&flat, 1.0, DVec3::splat(-1e5)),
    ];
    let mut rng = Rng::new(31);
    let (mut random, mut missed, mut dropped) = (0u32, 0u32, 0u32);
    for whole in &patches {
        let size = whole.size();
        for piece in whole.pieces(8) {
            let ob = piece.oriented.expect("the pieces span a plane");
            let (lo, hi) = piece.bounds();
            for i in 0..400 {
                let (uv, corner) = if i % 8 == 0 {
                    let c = DVec2::new((i / 8 % 2) as f64, (i / 16 % 2) as f64);
                    (c, true)
                } else {
                    (DVec2::new(f(&mut rng), f(&mut rng)), false)
                };
                let (q, pu, pv) = piece.eval(uv.x, uv.y);
                let (o, d, tmin) = match i % 4 {
                    // Aimed at the surface point from three sizes away.
                    0 | 1 => {
                        let d = dir(&mut rng);
                        (q - 3.0 * size * d, d, 1e-9)
                    }
                    // Leaving the surface point.
                    2 if !corner => (q, dir(&mut rng), 1e-9 * size),
                    // In the tangent plane, passing through the point.
                    2 => {
                        let t = (pu.normalize() + pv.normalize()).normalize();
                        (q - 2.0 * size * t, t, 1e-9)
                    }
                    // Random rays through the piece's axis-aligned box.
                    _ => {
                        let at = lo + (hi - lo) * DVec3::new(f(&mut rng), f(&mut rng), f(&mut rng));
                        let d = dir(&mut rng);
                        random += 1;
                        (at - 2.0 * size * d, d, 1e-9)
                    }
                };
                // As `intersect` frames the ray.
                let dl = d.length();
                let dn = d / dl;
                let (e1, e2) = dn.any_orthonormal_pair();
                let want = piece
                    .subdivide(o, [e1, e2, dn], tmin * dl, f64::INFINITY, LEAF, true)
                    .map(|(uv, t)| (uv, t / dl));
                let got = piece.intersect(o, d, tmin, f64::INFINITY, Solver::Robust);
                assert_eq!(
                    want.map(|(_, t)| t),
                    got.map(|h| h.t),
                    "o {o} d {d} (case {})",
                    i % 4
                );
                if want.is_some() {
                    assert!(ob.may_meet(o, dn, tmin * dl, f64::INFINITY));
                } else if i % 4 == 3 {
                    missed += 1;
                    dropped += u32::from(!ob.may_meet(o, dn, tmin * dl, f64::INFINITY));
                }
            }
        }
    }
    println!("random rays {random}, missing {missed}, dropped by the box {dropped}");
    // Measured: about half of them (1643 of 3252).
    assert!(
        dropped * 3 > missed,
        "the box dropped {dropped} of the {missed} random rays that miss"
    );
}

/// The nearest hit over a patch's pieces is the whole patch's hit, reported in the whole
/// patch's parameters: random rays through its box, and rays aimed at the seams between
/// pieces (where a gap or an overlap would show), for dyadic and non-dyadic cuts.
#[test]
fn pieces_hit_where_the_whole_patch_does() {
    let whole = bumpy();
    let (lo, hi) = whole.bounds();
    let size = whole.size();
    let mut rng = Rng::new(9);
    for n in [3u32, 8] {
        let pieces = whole.pieces(n);
        let (mut hits, mut seam_hits, mut worst) = (0, 0, 0.0f64);
        for i in 0..6000 {
            let seam = i % 2 == 1;
            let target = if seam {
                // A point on a seam: u (or v) a multiple of 1/n.
                let k = f64::from(1 + (rng.f32() * (n - 1) as f32) as u32) / f64::from(n);
                let w = f(&mut rng);
                let (u, v) = if i % 4 == 1 { (k, w) } else { (w, k) };
                whole.eval(u, v).0
            } else {
                lo + (hi - lo) * DVec3::new(f(&mut rng), f(&mut rng), f(&mut rng))
            };
            let d = DVec3::new(f(&mut rng) - 0.5, f(&mut rng) - 0.5, f(&mut rng) - 0.5);
            if d.length() < 1e-3 {
                continue;
            }
            let d = d.normalize();
            let o = target - d * 3.0 * size;
            let want = whole.intersect(o, d, 1e-9, f64::INFINITY, Solver::Robust);
            let mut got: Option<PatchHit> = None;
            for p in &pieces {
                let t_max = got.map_or(f64::INFINITY, |h| h.t);
                if let Some(h) = p.intersect(o, d, 1e-9, t_max, Solver::Robust) {
                    got = Some(h);
                }
            }
            match (want, got) {
                (None, None) => {}
                (Some(w), Some(g)) => {
                    hits += 1;
                    seam_hits += seam as usize;
                    // Both are hits to the method's tolerance (residual 1e-12 of the size
                    // across the ray; along a grazing ray that is more in t).
                    worst = worst.max((w.t - g.t).abs() / w.t);
                    assert!(
                        (w.t - g.t).abs() <= 1e-7 * w.t,
                        "ray {i}: t {} vs {}",
                        g.t,
                        w.t
                    );
                    // The pieces report the whole patch's (u, v): it evaluates to the hit.
                    let (q, pu, pv) = whole.eval(g.uv.x, g.uv.y);
                    assert!((q - g.p).length() <= 1e-7 * size, "ray {i}: uv {}", g.uv);
                    assert!((pu - g.dpdu).length() <= 1e-9 * pu.length().max(size));
                    assert!((pv - g.dpdv).length() <= 1e-9 * pv.length().max(size));
                    assert!(g.n.dot(w.n) > 1.0 - 1e-6);
                }
                _ => panic!("ray {i} (n = {n}, seam {seam}): whole {want:?}, pieces {got:?}"),
            }
        }
        println!("n = {n}: {hits} hits, {seam_hits} on seams, largest relative t gap {worst:.1e}");
        assert!(
            hits > 2000 && seam_hits > 1000,
            "n = {n}: {hits} hits, {seam_hits} on seams"
        );
    }
}

/// A net whose control points differ by eleven orders of magnitude (two of them 1e11 from a
/// unit patch) made one ray's search visit sub-patches without end: each ray's robust search
/// now stops at [`MAX_VISITS`], which the bumpy patch's rays stay far below (the stress tests'
/// worst ray needs about 150).
#[test]
fn a_ray_visits_a_bounded_number_of_sub_patches() {
    let mut p: [DVec3; 16] = std::array::from_fn(|k| {
        let (i, j) = (k / 4, k % 4);
        DVec3::new(
            -1.0 + 2.0 * i as f64 / 3.0,
            -1.0 + 2.0 * j as f64 / 3.0,
            0.0,
        )
    });
    (p[4].y, p[9].y) = (-1e11, 1e11);
    let wild = Patch::new(&p).unwrap();
    let frame = |o: DVec3, at: DVec3| {
        let dn = (at - o).normalize();
        let (e1, e2) = dn.any_orthonormal_pair();
        [e1, e2, dn]
    };
    let mut rng = Rng::new(9);
    let mut capped = 0;
    for _ in 0..16 {
        let o = DVec3::new(0.0, 0.0, -5.0);
        let at = DVec3::new(2.0 * f(&mut rng) - 1.0, 2.0 * f(&mut rng) - 1.0, 0.0);
        let s = wild.search(o, frame(o, at), (0.0, f64::INFINITY), LEAF, true);
        capped += usize::from(s.visits_left == 0);
    }
    assert!(
        capped > 0,
        "no ray reached the bound: the case no longer tests it"
    );
    let bumpy = bumpy();
    for _ in 0..200 {
        let o = DVec3::new(1.5, 1.5, -6.0);
        let at = DVec3::new(3.0 * f(&mut rng), 3.0 * f(&mut rng), 0.0);
        let s = bumpy.search(o, frame(o, at), (0.0, f64::INFINITY), LEAF, true);
        assert!(
            MAX_VISITS - s.visits_left < 500,
            "{}",
            MAX_VISITS - s.visits_left
        );
    }
}
