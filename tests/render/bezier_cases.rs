//! Special cases of the lathe (surface of revolution) intersector, each against a closed form.

use glam::{DVec2, DVec3};
use sppm_lang::internals::bezier::Solver;
use sppm_lang::internals::bezier::lathe::{Lathe, Part};

const R: Solver = Solver::Robust;

fn lathe(segs: &[&[(f64, f64)]], sweep: Option<(f64, f64)>) -> Lathe {
    let segs: Vec<Vec<DVec2>> = segs
        .iter()
        .map(|s| s.iter().map(|&(r, h)| DVec2::new(r, h)).collect())
        .collect();
    Lathe::new(&segs, sweep).unwrap()
}

/// y = x^2 + z^2 for r in [0, 1]: r = s, h = s^2.
fn paraboloid() -> Lathe {
    lathe(&[&[(0.0, 0.0), (0.5, 0.0), (1.0, 1.0)]], None)
}

fn cylinder() -> Lathe {
    lathe(&[&[(1.0, 0.0), (1.0, 2.0)]], None)
}

fn t_of(l: &Lathe, o: DVec3, d: DVec3) -> Option<f64> {
    l.intersect(o, d, 1e-9, f64::INFINITY, R).map(|h| h.t)
}

/// Nearest root > 1e-9 of the paraboloid y = x^2 + z^2 along o + t d, with y <= 1.
fn paraboloid_exact(o: DVec3, d: DVec3) -> Option<f64> {
    let a = d.x * d.x + d.z * d.z;
    let b = 2.0 * (o.x * d.x + o.z * d.z) - d.y;
    let c = o.x * o.x + o.z * o.z - o.y;
    let mut ts = vec![];
    if a == 0.0 {
        ts.push(-c / b);
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            ts.push((-b - disc.sqrt()) / (2.0 * a));
            ts.push((-b + disc.sqrt()) / (2.0 * a));
        }
    }
    ts.into_iter()
        .filter(|&t| t > 1e-9 && o.y + t * d.y <= 1.0)
        .min_by(f64::total_cmp)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs().max(1.0)
}

#[test]
fn axis_parallel_rays() {
    let p = paraboloid();
    for (x, z) in [(0.3, 0.4), (0.0, 0.7), (0.99, 0.0), (1e-9, 0.0)] {
        let o = DVec3::new(x, 5.0, z);
        let t = t_of(&p, o, -DVec3::Y).unwrap();
        assert!(close(t, 5.0 - (x * x + z * z)), "{x} {z}: {t}");
        // Upward from below the bottom: same surface from the other side.
        let t = t_of(&p, DVec3::new(x, -1.0, z), DVec3::Y).unwrap();
        assert!(close(t, 1.0 + x * x + z * z));
    }
    // Inside the cylinder along its axis: never reaches the wall.
    assert!(t_of(&cylinder(), DVec3::new(0.5, -1.0, 0.2), DVec3::Y).is_none());
    // Outside the radius: miss.
    assert!(t_of(&p, DVec3::new(1.01, 5.0, 0.0), -DVec3::Y).is_none());
}

#[test]
fn rays_perpendicular_to_the_axis() {
    let p = paraboloid();
    for y in [0.49, 0.01, 1e-6, 0.999] {
        let o = DVec3::new(-5.0, y, 0.0);
        let t = t_of(&p, o, DVec3::X).unwrap();
        assert!(close(t, 5.0 - y.sqrt()), "y={y} t={t}");
        // Offset sideways: the chord at height y.
        let o = DVec3::new(-5.0, y, 0.3 * y.sqrt());
        let t = t_of(&p, o, DVec3::X).unwrap();
        assert!(close(t, 5.0 - (y - 0.09 * y).sqrt()), "y={y} t={t}");
        // From inside: the far wall.
        let t = t_of(&p, DVec3::new(0.0, y, 0.0), DVec3::X).unwrap();
        assert!(close(t, y.sqrt()));
    }
    // Above the top: miss.
    assert!(t_of(&p, DVec3::new(-5.0, 1.01, 0.0), DVec3::X).is_none());
    // Cylinder, perpendicular through the axis and off it.
    let c = cylinder();
    assert!(close(
        t_of(&c, DVec3::new(0.0, 1.0, -3.0), DVec3::Z).unwrap(),
        2.0
    ));
    let t = t_of(&c, DVec3::new(0.6, 1.0, -3.0), DVec3::Z).unwrap();
    assert!(close(t, 3.0 - 0.8));
}

#[test]
fn rays_through_the_axis_and_random_tilts_match_the_closed_form() {
    let p = paraboloid();
    let mut k = 0u64;
    let mut rnd = || {
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (k >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut hits = 0;
    for _ in 0..20000 {
        let target = DVec3::new(0.0, rnd() * 1.2 - 0.1, 0.0);
        let o = DVec3::new(rnd() * 6.0 - 3.0, rnd() * 6.0 - 3.0, rnd() * 6.0 - 3.0);
        let d = (target - o) * (0.5 + rnd());
        let want = paraboloid_exact(o, d);
        let got = t_of(&p, o, d);
        match (want, got) {
            (Some(w), Some(g)) => {
                hits += 1;
                assert!((w - g).abs() <= 1e-9 * w.max(1.0), "{o} {d}: {w} vs {g}")
            }
            (None, None) => {}
            _ => panic!("{o} {d}: {want:?} vs {got:?}"),
        }
    }
    assert!(hits > 5000, "{hits}");
}

#[test]
fn grazing_rays_at_the_silhouette() {
    // y = x - 0.25 touches y = x^2 at x = 0.5 (a double root).
    let p = paraboloid();
    let d = DVec3::new(1.0, 1.0, 0.0).normalize();
    let o = DVec3::new(-1.0, -1.25, 0.0);
    let t = t_of(&p, o, d).expect("the tangent ray touches");
    assert!((t - 1.5 * 2f64.sqrt()).abs() < 1e-6, "{t}");
    for delta in [1e-3, 1e-5, 1e-7] {
        // Shifted up (toward the inside): two close roots, the nearer one.
        let o2 = o + DVec3::new(0.0, delta, 0.0);
        let want = paraboloid_exact(o2, d).unwrap();
        let got = t_of(&p, o2, d).unwrap();
        assert!((got - want).abs() < 1e-6 * want, "{delta}: {got} vs {want}");
        // Shifted down: a clean miss.
        let o3 = o - DVec3::new(0.0, delta, 0.0);
        assert!(t_of(&p, o3, d).is_none(), "{delta}");
    }
    // The cylinder's silhouette, perpendicular to the axis: x = 1 exactly touches.
    let c = cylinder();
    assert!(close(
        t_of(&c, DVec3::new(1.0, 1.0, -5.0), DVec3::Z).unwrap(),
        5.0
    ));
    assert!(t_of(&c, DVec3::new(1.0 + 1e-7, 1.0, -5.0), DVec3::Z).is_none());
    let t = t_of(&c, DVec3::new(1.0 - 1e-6, 1.0, -5.0), DVec3::Z).unwrap();
    assert!(close(t, 5.0 - (1.0 - (1.0 - 1e-6f64).powi(2)).sqrt()));
}

#[test]
fn poles_where_the_profile_touches_the_axis() {
    // Cone with its apex on the axis at y = 1.
    let cone = lathe(&[&[(1.0, 0.0), (0.0, 1.0)]], None);
    let h = cone
        .intersect(DVec3::new(0.0, 5.0, 0.0), -DVec3::Y, 0.0, 1e9, R)
        .unwrap();
    assert!(close(h.t, 4.0) && h.n.is_finite());
    for e in [1e-3, 1e-7, 1e-12] {
        let t = t_of(&cone, DVec3::new(e, 5.0, 0.0), -DVec3::Y).unwrap();
        assert!(close(t, 4.0 + e), "{e}: {t}");
        // Slanted rays through points near the apex.
        let target = DVec3::new(0.0, 1.0 - e, 0.0);
        let o = DVec3::new(2.0, 3.0, 1.0);
        let t = t_of(&cone, o, target - o).unwrap();
        assert!(t < 1.0 && t > 0.5, "{e}: {t}");
    }
    // The paraboloid's bottom pole: horizontal tangent, normal straight down (outward).
    let p = paraboloid();
    let h = p
        .intersect(DVec3::new(0.0, -2.0, 0.0), DVec3::Y, 0.0, 1e9, R)
        .unwrap();
    assert!(close(h.t, 2.0));
    assert!(
        (h.n - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-9,
        "{}",
        h.n
    );
}

#[test]
fn horizontal_and_vertical_tangents_give_axis_aligned_normals() {
    let disk = lathe(&[&[(0.0, 1.0), (1.0, 1.0)]], None);
    let h = disk
        .intersect(DVec3::new(0.3, 4.0, 0.2), -DVec3::Y, 0.0, 1e9, R)
        .unwrap();
    assert!(close(h.t, 3.0));
    assert!((h.n - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-12);
    // The same disk hit edge-on misses (measure zero) without hanging.
    let _ = disk.intersect(DVec3::new(-5.0, 1.0, 0.0), DVec3::X, 0.0, 1e9, R);
    let c = cylinder();
    let h = c
        .intersect(DVec3::new(3.0, 0.5, 0.0), -DVec3::X, 0.0, 1e9, R)
        .unwrap();
    assert!(close(h.t, 2.0));
    assert!((h.n - DVec3::X).length() < 1e-12);
    assert!((h.dpdu.normalize() - DVec3::Y).length() < 1e-12);
    assert!((h.uv.x - 0.25).abs() < 1e-9 && h.uv.y.abs() < 1e-9);
}

#[test]
fn degenerate_segments_with_repeated_control_points() {
    // A cylinder as a cubic with doubled end points (P' = 0 at the ends), then a point segment.
    let l = lathe(
        &[
            &[(1.0, 0.0), (1.0, 0.0), (1.0, 2.0), (1.0, 2.0)],
            &[(1.0, 2.0), (1.0, 2.0), (1.0, 2.0)],
            &[(1.0, 2.0), (0.0, 2.0)],
        ],
        None,
    );
    for y in [1e-9, 0.5, 1.0, 2.0 - 1e-9] {
        let h = l
            .intersect(DVec3::new(3.0, y, 0.0), -DVec3::X, 0.0, 1e9, R)
            .unwrap();
        assert!(close(h.t, 2.0), "{y}: {}", h.t);
        assert!((h.n - DVec3::X).length() < 1e-6, "{y}: {}", h.n);
    }
    let h = l
        .intersect(DVec3::new(0.2, 5.0, 0.1), -DVec3::Y, 0.0, 1e9, R)
        .unwrap();
    assert!(close(h.t, 3.0) && (h.n - DVec3::Y).length() < 1e-12);
    // u by arc length: the wall is 2 long, the lid 1.
    assert!(
        (h.uv.x - (3.0 - 0.2f64.hypot(0.1)) / 3.0).abs() < 1e-6,
        "{}",
        h.uv.x
    );
}

#[test]
fn partial_sweep_with_flat_caps() {
    // A solid quarter cylinder: closed profile axis -> rim -> top -> axis, swept 0..90 degrees.
    let l = lathe(
        &[
            &[(0.0, 0.0), (1.0, 0.0)],
            &[(1.0, 0.0), (1.0, 1.0)],
            &[(1.0, 1.0), (0.0, 1.0)],
        ],
        Some((0.0, 90.0)),
    );
    // Side wall at x = 0.5 from +z.
    let h = l
        .intersect(DVec3::new(0.5, 0.5, 5.0), -DVec3::Z, 0.0, 1e9, R)
        .unwrap();
    assert!(close(h.t, 5.0 - 0.75f64.sqrt()) && h.part == Part::Side(1));
    // Start cap (plane z = 0, x >= 0) from -z: outward normal -z.
    let h = l
        .intersect(DVec3::new(0.5, 0.5, -5.0), DVec3::Z, 0.0, 1e9, R)
        .unwrap();
    assert!(close(h.t, 5.0) && h.part == Part::StartCap);
    assert!((h.n + DVec3::Z).length() < 1e-12);
    // End cap (plane x = 0, z >= 0) from -x: outward normal -x.
    let h = l
        .intersect(DVec3::new(-5.0, 0.5, 0.5), DVec3::X, 0.0, 1e9, R)
        .unwrap();
    assert!(close(h.t, 5.0) && h.part == Part::EndCap);
    assert!((h.n + DVec3::X).length() < 1e-12);
    // Outside the sweep: the missing three quarters are empty.
    assert!(t_of(&l, DVec3::new(-0.5, 0.5, -5.0), DVec3::Z).is_none());
    // Outside the profile's region on the cap plane: miss.
    assert!(t_of(&l, DVec3::new(0.5, 1.5, -5.0), DVec3::Z).is_none());
    let (lo, hi) = l.bounds();
    assert!(lo.x >= -1e-12 && lo.z >= -1e-12 && hi.x >= 1.0 && hi.z >= 1.0);
}

#[test]
fn newton_method_is_selectable_and_finds_easy_hits() {
    let p = paraboloid();
    let newton = Solver::Newton {
        iterations: 20,
        starts: 4,
    };
    let h = p
        .intersect(DVec3::new(0.3, 5.0, 0.4), -DVec3::Y, 0.0, 1e9, newton)
        .unwrap();
    assert!(close(h.t, 4.75));
}

/// `RayFrame::candidates` with a window `(t_min, t_max)` skips the sides whose hits provably lie
/// outside it and the scans of factors that keep one sign. It must keep every candidate inside
/// the window, bit for bit, against the full search, on the rays where the bounds are tight or
/// the sides meet: rays starting on the surface (their own root at `t = 0`, which the window
/// drops) in random, near-tangent, through-the-axis, nearly perpendicular and nearly
/// axis-parallel directions, on a goblet-like profile with corners, a pole, a flat disk and a
/// cusp.
#[test]
fn candidate_window_keeps_every_candidate_inside_it() {
    use sppm_lang::internals::bezier::lathe::RayFrame;
    use sppm_lang::internals::bezier::roots::bracket::Refine;
    use sppm_lang::internals::bezier::roots::{find_roots_with_noise, root_uncertainty};
    use sppm_lang::internals::sampling::SplitMix64;
    let shapes = [goblet_like(), bulge_cusp_dome()];
    let (mut compared, mut skipped) = (0usize, 0usize);
    for (n, l) in shapes.iter().enumerate() {
        let (lo, hi) = l.bounds();
        let mut rng = SplitMix64::for_item(23, n, 0);
        for _ in 0..20_000 {
            let (o, normal) = l.sample(DVec2::new(rng.f(), rng.f())).unwrap();
            let axis_dir = DVec3::new(-o.x, 0.0, -o.z).normalize_or(DVec3::X);
            let tangent = normal.cross(DVec3::Y).normalize_or(DVec3::Z);
            let small = 10f64.powf(rng.range(-12.0, -3.0));
            let d = match (rng.f() * 5.0) as usize {
                0 => rng.unit(),
                1 => (tangent + normal * small * rng.range(-1.0, 1.0)).normalize(),
                2 => (axis_dir + DVec3::Y * rng.range(-2.0, 2.0)).normalize(),
                3 => (rng.unit() * DVec3::new(1.0, small, 1.0)).normalize(),
                _ => (DVec3::Y * rng.range(-1.0, 1.0).signum() + rng.unit() * small).normalize(),
            };
            let frame = RayFrame::new(o, d, lo.y, hi.y);
            let far = rng.range(0.0, 2.0) * (hi - lo).length();
            let windows = [(1e-9, f64::INFINITY), (1e-4, f64::INFINITY), (1e-9, far)];
            for seg in l.segments() {
                let (f, noise) = frame.polynomial(seg);
                let mut roots = Vec::new();
                find_roots_with_noise(&f, noise, &mut roots);
                for root in &roots {
                    let ds = root_uncertainty(&f, root.t, noise);
                    let cand = |after, w| {
                        let refine = Refine::FalsePosition;
                        frame.candidates(seg, root, ds, l.size(), refine, after, w, false)
                    };
                    for w in windows {
                        let all = cand(w.0, None);
                        let inside = |c: [(f64, f64); 2]| {
                            c.map(|(t, s)| {
                                (t > w.0 && t < w.1).then_some((t.to_bits(), s.to_bits()))
                            })
                        };
                        let got = cand(w.0, Some(w));
                        assert_eq!(
                            inside(got),
                            inside(all),
                            "o {o:?} d {d:?} window {w:?} root {root:?}: {got:?} vs {all:?}"
                        );
                        compared += 1;
                        let nan = |c: [(f64, f64); 2]| c.iter().filter(|c| c.0.is_nan()).count();
                        skipped += nan(got).saturating_sub(nan(all));
                    }
                }
            }
        }
    }
    println!("{compared} windowed candidate pairs compared, {skipped} sides skipped");
    assert!(compared > 100_000, "{compared}");
}

/// A goblet-like profile with corners, a flat disk and a pole.
fn goblet_like() -> Lathe {
    lathe(
        &[
            &[(0.0, 0.0), (0.1, 0.0), (0.2, 0.0), (0.3, 0.0)],
            &[(0.3, 0.0), (0.3, 0.03), (0.1, 0.04), (0.04, 0.08)],
            &[(0.04, 0.08), (0.03, 0.2), (0.03, 0.35), (0.05, 0.42)],
            &[(0.05, 0.42), (0.3, 0.45), (0.32, 0.7), (0.27, 0.9)],
            &[(0.27, 0.9), (0.3, 0.7), (0.27, 0.47), (0.0, 0.46)],
        ],
        None,
    )
}

/// The bulge, cusp and dome of the stress test's culling profile (its flat disk and annulus
/// left out).
fn bulge_cusp_dome() -> Lathe {
    lathe(
        &[
            &[(0.6, 0.0), (0.6, 0.3), (0.2, 0.4), (0.5, 0.6)],
            &[(0.3, 0.6), (0.6, 0.9), (0.3, 0.9), (0.6, 0.6)],
            &[(0.6, 0.6), (0.6, 1.0), (0.3, 1.2), (0.0, 1.2)],
        ],
        None,
    )
}

/// Rays #511630 and #958799 of the stress case "lathe culling: from inside the shells" (at 10^6
/// rays; the culling profile there, of which only the bulge and the dome matter here): they
/// start on the surface and meet it again within 1e-4, nearly tangent. The true `t` of each hit
/// was computed with 60-digit decimal arithmetic (2D Newton on `h(s) = o_y + t d_y`,
/// `r(s)^2 = |o_xz + t d_xz|^2`, from the exact f64 inputs).
///
/// The first ray, on the dome: the two roots of `F` (the origin's at `t` 1.4e-12 and the hit
/// at 8.03e-5) are 1.8e-6 apart in `s`, inside one widened bracket; the nearest sign change
/// of the factor there is the origin's own, below `t_min`, and the hit was lost (`None`).
/// The second ray, on the bulge: the hit's `t` is conditioned to about 1e-11 in f64 (a
/// surface error of 1e-16 along a ray at 2e-5 rad to it); the robust answer must be within
/// the stress test's 1e-6 of the true value.
#[test]
fn rays_from_the_surface_that_meet_it_again_within_1e_4() {
    let l = bulge_cusp_dome();
    let cases = [
        (
            DVec3::new(0.15499278632492244, 1.11773005683808, 0.27770696273279466),
            DVec3::new(
                0.8812907105528318,
                -0.009759570623935848,
                -0.4724737392432739,
            ),
            8.031_811_035_709_652e-5,
            2,
        ),
        (
            DVec3::new(-0.3957217192652609, 0.5494280490929794, 0.18403506912486725),
            DVec3::new(0.6103946907962211, -0.703731515944941, -0.3635660530269854),
            5.047_383_840_691_549e-6,
            0,
        ),
    ];
    for (o, d, want, seg) in cases {
        let hit = l.intersect(o, d, 1e-9, f64::INFINITY, Solver::Robust);
        let hit = hit.unwrap_or_else(|| panic!("o {o:?} d {d:?}: missed the hit at {want}"));
        let rel = (hit.t - want).abs() / want;
        assert!(
            rel < 1e-6,
            "o {o:?}: t {} want {want} (rel {rel:.2e})",
            hit.t
        );
        assert_eq!(hit.part, Part::Side(seg), "o {o:?}");
    }
}

/// The factor search's shortcut (`candidates` with `monotone`: the factor at the bracket's two
/// ends, then a bisection over the scan's points) against the full 16-piece scan, on every
/// root of `F` the certificate accepts: random rays through a goblet-like profile and the
/// culling profile's bulge, cusp and dome, and rays starting on their surfaces (random and
/// nearly tangent directions). The candidates are the same bit for bit (allowed to differ
/// within the factor's rounding where a sample falls inside it, on at most 1 in 1000); most
/// roots are certified.
#[test]
fn factor_shortcut_matches_the_full_scan_where_f_is_monotone() {
    use sppm_lang::internals::bezier::lathe::RayFrame;
    use sppm_lang::internals::bezier::roots::bracket::Refine;
    use sppm_lang::internals::bezier::roots::{
        RootKind, find_roots_with_noise, root_spread, strictly_monotone_on, widened,
    };
    use sppm_lang::internals::sampling::SplitMix64;
    let shapes = [goblet_like(), bulge_cusp_dome()];
    let (mut simple, mut certified, mut same_bits, mut compared) = (0, 0, 0usize, 0usize);
    let mut max_dt = 0.0f64;
    for (n, l) in shapes.iter().enumerate() {
        let (lo, hi) = l.bounds();
        let mut rng = SplitMix64::for_item(29, n, 0);
        for k in 0..20_000 {
            let (o, d) = if k % 2 == 0 {
                let target = lo + (hi - lo) * DVec3::new(rng.f(), rng.f(), rng.f());
                let o = target + rng.unit() * 3.0 * (hi - lo).length();
                (o, (target - o).normalize())
            } else {
                let (o, normal) = l.sample(DVec2::new(rng.f(), rng.f())).unwrap();
                let tangent = normal.cross(DVec3::Y).normalize_or(DVec3::Z);
                let small = 10f64.powf(rng.range(-9.0, -2.0));
                let d = if rng.f() < 0.5 {
                    rng.unit()
                } else {
                    (tangent + normal * small * rng.range(-1.0, 1.0)).normalize()
                };
                (o, d)
            };
            let frame = RayFrame::new(o, d, lo.y, hi.y);
            for seg in l.segments() {
                let (f, noise) = frame.polynomial(seg);
                let mut roots = Vec::new();
                find_roots_with_noise(&f, noise, &mut roots);
                for root in roots.iter().filter(|r| r.kind == RootKind::Simple) {
                    simple += 1;
                    let (ds, slope) = root_spread(&f, root.t, noise);
                    let (a, b) = widened(root, ds);
                    let bound = f.second_derivative_bound();
                    if !strictly_monotone_on(f.degree(), slope, bound, noise, root.t, a, b) {
                        continue;
                    }
                    certified += 1;
                    let refine = Refine::FalsePosition;
                    let cand = |m| frame.candidates(seg, root, ds, l.size(), refine, 1e-9, None, m);
                    let (got, want) = (cand(true), cand(false));
                    for (g, w) in got.iter().zip(&want) {
                        assert_eq!(
                            g.0.is_nan(),
                            w.0.is_nan(),
                            "o {o:?} d {d:?}: {got:?} {want:?}"
                        );
                        if g.0.is_nan() {
                            continue;
                        }
                        // The same sign change refined from another bracket: `t` and `s`
                        // within their conditioning (near-tangent chords from the surface,
                        // whose `t` is conditioned to 1e-8 and worse; the origin's own root,
                        // `t` within 1e-11 of 0), far inside the stress test's 1e-6.
                        let dt = (g.0 - w.0).abs() / (w.0.abs() + 1e-3 * l.size());
                        max_dt = max_dt.max(dt);
                        assert!(
                            dt <= 1e-7 && (g.1 - w.1).abs() <= 1e-10,
                            "o {o:?} d {d:?} root {root:?}: {got:?} vs {want:?}"
                        );
                        same_bits += usize::from(g.0 == w.0 && g.1 == w.1);
                        compared += 1;
                    }
                }
            }
        }
    }
    println!(
        "{simple} simple roots, {certified} certified, {same_bits} of {compared} candidates \
         bit-equal, largest relative t difference {max_dt:.2e}"
    );
    assert!(certified * 10 > simple * 8, "{certified} of {simple}");
    assert!(
        same_bits * 1000 >= compared * 999,
        "{same_bits} of {compared}"
    );
}

/// The case the certificate must refuse: two roots of `F` in one widened bracket. The nearly
/// tangent ray from the dome of `rays_from_the_surface_that_meet_it_again_within_1e_4` starts
/// on the surface and meets it again at `t = 8.03e-5`; the two roots of `F` (the origin's and
/// the hit's) are 1.8e-6 apart in `s`. Each root's own bracket is refused (the other root is
/// within what the slope and the bound of `F''` allow). A bracket holding both (as an earlier
/// polish left them) is refused too: there the factor changes sign twice, and the full scan
/// finds both (a factor with one sign at both ends would read as no sign change).
#[test]
fn factor_shortcut_is_refused_where_two_roots_of_f_share_a_bracket() {
    use sppm_lang::internals::bezier::lathe::RayFrame;
    use sppm_lang::internals::bezier::roots::bracket::Refine;
    use sppm_lang::internals::bezier::roots::{
        Root, RootKind, find_roots_with_noise, root_spread, strictly_monotone_on, widened,
    };
    let l = bulge_cusp_dome();
    let o = DVec3::new(0.15499278632492244, 1.11773005683808, 0.27770696273279466);
    let d = DVec3::new(
        0.8812907105528318,
        -0.009759570623935848,
        -0.4724737392432739,
    );
    let hit = l.intersect(o, d, 1e-9, f64::INFINITY, R).expect("the hit");
    assert!((hit.t - 8.0318e-5).abs() < 1e-8, "{}", hit.t);
    let (lo, hi) = l.bounds();
    let frame = RayFrame::new(o, d.normalize(), lo.y, hi.y);
    let seg = &l.segments()[2];
    let (f, noise) = frame.polynomial(seg);
    let mut roots = Vec::new();
    find_roots_with_noise(&f, noise, &mut roots);
    assert_eq!(roots.len(), 2, "{roots:?}");
    let bound = f.second_derivative_bound();
    let certified = |root: &Root| {
        let (ds, slope) = root_spread(&f, root.t, noise);
        let (a, b) = widened(root, ds);
        strictly_monotone_on(f.degree(), slope, bound, noise, root.t, a, b)
    };
    assert!(roots.iter().all(|r| !certified(r)), "{roots:?}");
    // One bracket around both roots.
    let both = Root {
        t: roots[0].t,
        lo: roots[0].t - 1e-6,
        hi: roots[1].t + 1e-6,
        kind: RootKind::Simple,
    };
    assert!(!certified(&both));
    let (ds, _) = root_spread(&f, both.t, noise);
    let refine = Refine::FalsePosition;
    let cand = |after, m| frame.candidates(seg, &both, ds, l.size(), refine, after, None, m);
    let nearest = |c: [(f64, f64); 2]| c.iter().map(|c| c.0).fold(f64::NAN, f64::min);
    // The full scan sees both: the origin's own root overall, the hit beyond `t_min` (its `t`
    // conditioned to about 1e-8 here: another bracket, other last digits).
    assert!(nearest(cand(f64::NEG_INFINITY, false)).abs() < 1e-9);
    let t = nearest(cand(1e-9, false));
    assert!((t - hit.t).abs() < 1e-6 * hit.t, "{t} vs {}", hit.t);
}
