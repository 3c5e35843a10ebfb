//! Refinement of a sign change of a general function (not a polynomial) inside a bracket.
//!
//! The lathe uses it on the factors of its polynomial, which may be NaN where the ray does not
//! reach (see `lathe::RayFrame::candidates`).

/// How a sign change of a factor is refined to the last bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refine {
    /// False position with the Illinois modification, a bisection every third step (the bracket
    /// at least halves every three steps); plain bisection from the start once a NaN is met.
    FalsePosition,
    /// Plain bisection (about 50 evaluations): the reference's method.
    Bisection,
}

/// A root of `g` in `[lo, hi]` (`ga`, `gb`: the values at the ends) if `g` changes sign there.
/// Where one end is not reachable (NaN: the ray does not get to that radius), that end is first
/// moved to the edge of the reachable part, where the two sides of the ray meet (`w = 0`); a sign
/// change between the other end and that edge is a hit close to the ray's closest approach to
/// the axis.
///
/// With one sign change in the bracket both refinements find the same root (to the last bit).
/// With several (roots closer than a sixteenth of the bracket of `F`'s root) each finds one of
/// them, not necessarily the same one; neither promises the nearest. A NaN met inside the
/// bracket sends false position back to plain bisection of the whole bracket, so that case
/// gives bisection's answer; a NaN stretch that false position steps over is not seen, and then
/// it may return a root where bisection returns the edge of the stretch (which is not one).
pub(crate) fn bracketed_root(
    g: &dyn Fn(f64) -> f64,
    lo: f64,
    hi: f64,
    ga: f64,
    gb: f64,
    refine: Refine,
) -> Option<f64> {
    let (mut lo, mut hi, mut ga, mut gb) = (lo, hi, ga, gb);
    if ga.is_nan() != gb.is_nan() {
        let (mut ok, mut bad) = if ga.is_nan() { (hi, lo) } else { (lo, hi) };
        for _ in 0..200 {
            let m = 0.5 * (ok + bad);
            if m == ok || m == bad {
                break;
            }
            if g(m).is_nan() {
                bad = m;
            } else {
                ok = m;
            }
        }
        if ga.is_nan() {
            (lo, ga) = (ok, g(ok));
        } else {
            (hi, gb) = (ok, g(ok));
        }
    }
    if ga * gb > 0.0 || (ga * gb).is_nan() {
        return None;
    }
    if ga == 0.0 {
        return Some(lo);
    }
    if gb == 0.0 {
        return Some(hi);
    }
    match refine {
        Refine::Bisection => Some(bisection(g, lo, hi, ga)),
        Refine::FalsePosition => Some(false_position(g, lo, hi, ga, gb)),
    }
}

/// Bisection of a bracket with `g(lo) = ga` of the other sign than `g(hi)`, to the last bit. A NaN
/// counts as the sign opposite to `ga`'s when `ga` is negative, as `ga`'s otherwise.
fn bisection(g: &dyn Fn(f64) -> f64, lo: f64, hi: f64, ga: f64) -> f64 {
    let (mut a, mut b) = (lo, hi);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let gm = g(m);
        if gm == 0.0 {
            return m;
        }
        if (gm < 0.0) == (ga < 0.0) {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// False position with the Illinois modification on a bracket with `g(lo) = ga` and
/// `g(hi) = gb` of opposite signs, a bisection every third step; falls back to
/// [`bisection`] of the whole bracket when it meets a NaN.
fn false_position(g: &dyn Fn(f64) -> f64, lo: f64, hi: f64, ga: f64, gb: f64) -> f64 {
    let (mut a, mut b, mut fa, mut fb) = (lo, hi, ga, gb);
    let a_negative = ga < 0.0;
    let mut last_side = 0i8;
    for step in 0..300 {
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            break;
        }
        let m = if step % 3 == 2 {
            mid
        } else {
            let m = (a * fb - b * fa) / (fb - fa);
            if m > a && m < b { m } else { mid }
        };
        let gm = g(m);
        if gm == 0.0 {
            return m;
        }
        if gm.is_nan() {
            return bisection(g, lo, hi, ga);
        }
        if (gm < 0.0) == a_negative {
            a = m;
            fa = gm;
            if last_side == -1 {
                fb *= 0.5;
            }
            last_side = -1;
        } else {
            b = m;
            fb = gm;
            if last_side == 1 {
                fa *= 0.5;
            }
            last_side = 1;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// False position stalls on one end for convex functions and crawls on flat ones; the
    /// forced bisections bound that. Each case must land within a few ulps of bisection's root.
    #[test]
    fn bracketed_root_agrees_with_bisection_where_false_position_is_slow() {
        type Case = (&'static str, Box<dyn Fn(f64) -> f64>, f64, f64);
        let cases: Vec<Case> = vec![
            ("linear", Box::new(|s| s - 0.3), 0.0, 1.0),
            (
                "steep convex",
                Box::new(|s: f64| s.powi(20) - 1e-3),
                0.0,
                1.0,
            ),
            ("flat cubic", Box::new(|s: f64| (s - 0.7).powi(3)), 0.0, 1.0),
            (
                "decreasing",
                Box::new(|s: f64| (1.0 - s).exp() - 1.5),
                0.0,
                1.0,
            ),
            (
                "tiny bracket",
                Box::new(|s: f64| s - 0.5),
                0.5 - 1e-15,
                0.5 + 1e-15,
            ),
            (
                "huge slope",
                Box::new(|s: f64| 1e12 * (s - 0.123456789)),
                0.0,
                1.0,
            ),
        ];
        for (name, g, a, b) in &cases {
            let fp = Refine::FalsePosition;
            let got = bracketed_root(g.as_ref(), *a, *b, g(*a), g(*b), fp).expect(name);
            let want =
                bracketed_root(g.as_ref(), *a, *b, g(*a), g(*b), Refine::Bisection).expect(name);
            assert!(
                (got - want).abs() <= 4.0 * f64::EPSILON * want.abs().max(1e-300) || g(got) == 0.0,
                "{name}: {got} vs {want}"
            );
        }
        // No sign change: no root; both ends NaN: no root.
        assert_eq!(
            bracketed_root(&|s| s + 1.0, 0.0, 1.0, 1.0, 2.0, Refine::FalsePosition),
            None
        );
        assert_eq!(
            bracketed_root(
                &|_| f64::NAN,
                0.0,
                1.0,
                f64::NAN,
                f64::NAN,
                Refine::FalsePosition
            ),
            None
        );
    }

    /// One end unreachable (NaN beyond s = 0.6): the bracket is first cut back to the edge of
    /// the reachable part, and the sign change between the other end and the edge is found.
    #[test]
    fn bracketed_root_finds_a_root_at_the_edge_of_reach() {
        let g = |s: f64| if s > 0.6 { f64::NAN } else { s - 0.4 };
        let got = bracketed_root(&g, 0.0, 1.0, g(0.0), g(1.0), Refine::FalsePosition).unwrap();
        assert!((got - 0.4).abs() < 1e-15, "{got}");
        // The sign change only at the edge itself: the root is the edge.
        let g = |s: f64| if s > 0.6 { f64::NAN } else { s - 0.6 };
        let got = bracketed_root(&g, 0.0, 1.0, g(0.0), g(1.0), Refine::FalsePosition).unwrap();
        assert!((got - 0.6).abs() < 1e-15, "{got}");
    }

    /// NaN stretches inside the bracket. Where false position meets one it falls back to
    /// bisection of the whole bracket and gives bisection's answer. Where it steps over one
    /// (here its first step lands on the root) it returns that root, while bisection stops at
    /// the edge of the stretch, which is not a root: the two differ, false position for the
    /// better.
    #[test]
    fn nan_stretches_inside_the_bracket() {
        let nan_between = |lo: f64, hi: f64, root: f64| {
            move |s: f64| {
                if s > lo && s < hi { f64::NAN } else { s - root }
            }
        };
        let both = |g: &dyn Fn(f64) -> f64| {
            (
                bracketed_root(g, 0.0, 1.0, g(0.0), g(1.0), Refine::FalsePosition).unwrap(),
                bracketed_root(g, 0.0, 1.0, g(0.0), g(1.0), Refine::Bisection).unwrap(),
            )
        };
        let g = nan_between(0.25, 0.35, 0.3);
        let (fp, bi) = both(&g);
        assert_eq!(fp, bi);
        let g = nan_between(0.45, 0.55, 0.9);
        let (fp, bi) = both(&g);
        assert_eq!(g(fp), 0.0, "{fp}");
        assert!((bi - 0.45).abs() < 1e-15 && g(bi) != 0.0, "{bi}");
    }
}
