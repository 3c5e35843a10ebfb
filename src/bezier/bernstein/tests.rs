//! Unit tests of the Bernstein polynomials.

use super::*;

/// One pass gives `eval_with_derivative`'s value and slope bit for bit, and the second
/// derivative of the derivative polynomial within rounding; the bound of `|p''|` holds.
#[test]
fn two_derivatives_in_one_pass() {
    let mut x = 0.271_828f64;
    let mut next = || {
        x = (x * 3.987_654_321 + 0.314_159).fract();
        x - 0.5
    };
    for n in 0..=MAX_DEGREE {
        for _ in 0..200 {
            let c: Vec<f64> = (0..=n).map(|_| next()).collect();
            let p = Bernstein::new(&c).unwrap();
            let bound = p.second_derivative_bound();
            let d2p = p.derivative().derivative();
            for k in 0..=16 {
                let t = (k as f64 / 16.0 + 1e-3 * next()).clamp(0.0, 1.0);
                let (v, d1, d2) = p.eval_with_two_derivatives(t);
                let (v0, d0) = p.eval_with_derivative(t);
                assert_eq!((v.to_bits(), d1.to_bits()), (v0.to_bits(), d0.to_bits()));
                let want = p.derivative().eval_with_derivative(t).1;
                let scale = (n * n) as f64 * 1e-14 * (1.0 + d2p.max_abs());
                assert!((d2 - want).abs() <= scale, "n {n} t {t}: {d2} vs {want}");
                assert!(d2.abs() <= bound * (1.0 + 1e-12), "n {n}: {d2} > {bound}");
            }
        }
    }
}

/// The cubic path of `square_sum` gives the general one's result bit for bit.
#[test]
fn cubic_square_sum_is_square_sum() {
    let mut x = 0.123_456_789f64;
    let mut next = || {
        x = (x * 3.987_654_321 + 0.314_159).fract();
        (x - 0.5) * 10f64.powi((x * 8.0) as i32 - 4)
    };
    for _ in 0..10_000 {
        let a: [f64; 4] = std::array::from_fn(|_| next());
        let b: [f64; 4] = std::array::from_fn(|_| next());
        let c: [f64; 7] = std::array::from_fn(|_| next());
        let w = next();
        let (pa, pb, pc) = (
            Bernstein::new(&a).unwrap(),
            Bernstein::new(&b).unwrap(),
            Bernstein::new(&c).unwrap(),
        );
        let want = Bernstein::square_sum(&pa, &pb, &pc, w).unwrap();
        let got = Bernstein::cubic_square_sum(&a, &b, &c, w);
        assert_eq!(got.n, want.n);
        for (g, w) in got.c.iter().zip(want.c) {
            assert_eq!(g.to_bits(), w.to_bits());
        }
    }
}

#[test]
fn binomial_table_is_pascals_triangle() {
    for n in 0..=MAX_DEGREE {
        let row: f64 = (0..=n).map(|k| binomial(n, k)).sum();
        assert_eq!(row, (1u64 << n) as f64, "row {n}");
        for k in 0..=n {
            assert_eq!(binomial(n, k), binomial(n, n - k));
        }
    }
    assert_eq!(binomial(15, 7), 6435.0);
    assert_eq!(binomial(6, 3), 20.0);
}

/// `left_of` and `right_of` are the halves of `split`, bit for bit (the root finder's
/// results must not depend on which is used).
#[test]
fn one_sided_splits_are_the_halves_of_split() {
    let p = cubic().mul(&cubic()).unwrap().add_constant(0.3);
    for t in [0.0, 1e-9, 0.125, 0.3, 0.5, 0.77, 1.0 - 1e-12, 1.0] {
        let (l, r) = p.split(t);
        assert_eq!(p.left_of(t), l, "{t}");
        assert_eq!(p.right_of(t), r, "{t}");
    }
}

fn power_eval(p: &[f64], t: f64) -> f64 {
    p.iter().rev().fold(0.0, |acc, c| acc * t + c)
}

/// (t - 0.25)(t - 0.5)(t - 0.75) in the Bernstein basis, built from products.
fn cubic() -> Bernstein {
    let f = |r: f64| Bernstein::new(&[-r, 1.0 - r]).unwrap();
    f(0.25).mul(&f(0.5)).unwrap().mul(&f(0.75)).unwrap()
}

#[test]
fn product_matches_power_basis() {
    let p = cubic();
    assert_eq!(p.degree(), 3);
    for k in 0..=20 {
        let t = k as f64 / 20.0;
        let want = (t - 0.25) * (t - 0.5) * (t - 0.75);
        assert!((p.eval(t) - want).abs() < 1e-15, "t={t}");
    }
}

#[test]
fn derivative_matches_finite_difference_and_de_casteljau() {
    let p = cubic();
    let dp = p.derivative();
    for k in 1..20 {
        let t = k as f64 / 20.0;
        // p' = 3t^2 - 3t + 0.6875 (expanded by hand)
        let want = power_eval(&[0.6875, -3.0, 3.0], t);
        assert!((dp.eval(t) - want).abs() < 1e-14);
        assert!((p.eval_with_derivative(t).1 - want).abs() < 1e-14);
    }
}

#[test]
fn split_and_restrict_reparameterise() {
    let p = cubic();
    let (l, r) = p.split(0.3);
    let q = p.restrict(0.2, 0.7);
    for k in 0..=10 {
        let s = k as f64 / 10.0;
        assert!((l.eval(s) - p.eval(0.3 * s)).abs() < 1e-15);
        assert!((r.eval(s) - p.eval(0.3 + 0.7 * s)).abs() < 1e-15);
        assert!((q.eval(s) - p.eval(0.2 + 0.5 * s)).abs() < 1e-15);
    }
}

#[test]
fn elevation_and_sum_preserve_values() {
    let p = cubic();
    let e = p.elevate_to(7).unwrap();
    let s = p.add(&Bernstein::new(&[1.0, 2.0]).unwrap()).unwrap();
    for k in 0..=10 {
        let t = k as f64 / 10.0;
        assert!((e.eval(t) - p.eval(t)).abs() < 1e-15);
        assert!((s.eval(t) - (p.eval(t) + 1.0 + t)).abs() < 1e-14);
        assert!((p.add_constant(2.0).eval(t) - p.eval(t) - 2.0).abs() < 1e-15);
    }
    assert!(Bernstein::new(&[0.0; 17]).is_none());
    assert!(e.mul(&e.elevate().unwrap().elevate().unwrap()).is_none());
}

#[test]
fn convex_hull_bounds_the_values() {
    let p = Bernstein::new(&[0.3, -2.0, 5.0, 0.1, -0.7]).unwrap();
    let (lo, hi) = p
        .coeffs()
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &c| (l.min(c), h.max(c)));
    for k in 0..=1000 {
        let v = p.eval(k as f64 / 1000.0);
        assert!(v >= lo && v <= hi);
    }
}

/// The degree-6 pass in local variables gives the general pass's value and slope bit for bit.
#[test]
fn degree_six_in_locals_is_the_general_pass() {
    let mut x = 0.618_034f64;
    let mut next = || {
        x = (x * 3.987_654_321 + 0.314_159).fract();
        (x - 0.5) * 10f64.powi((x * 8.0) as i32 - 4)
    };
    for _ in 0..20_000 {
        let c: [f64; 7] = std::array::from_fn(|_| next());
        let p = Bernstein::new(&c).unwrap();
        let t = next().abs().fract();
        let (v, d) = p.eval_with_derivative(t);
        let (w, e) = casteljau::<7>(&p.c, t);
        assert_eq!(
            (v.to_bits(), d.to_bits()),
            (w.to_bits(), e.to_bits()),
            "{c:?} at {t}"
        );
    }
}
