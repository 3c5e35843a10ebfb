//! Photon-pass energy conservation and the SPPM radius / N / tau update.

use crate::common;

use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

use glam::DVec3;
use sppm_lang::Span;
use sppm_lang::internals::integrators::sppm::{photon_flux, render_with_state};
use sppm_lang::internals::render::{PreparedScene, RenderOptions, effective_settings};
use sppm_lang::internals::scene::{LightDecl, ShapeDecl};

/// A closed box with diffuse walls of albedo a and a point light inside: the flux reaching the
/// walls over all bounces is Phi / (1 - a), Phi a / (1 - a) from the second hit on, and all of
/// Phi is absorbed.
#[test]
fn photon_pass_conserves_energy_in_a_closed_box() {
    let a = 0.5;
    let mut s = common::empty_scene((4, 4));
    let m = common::diffuse(&mut s, a);
    common::add_object(
        &mut s,
        ShapeDecl::Box {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        },
        m,
        None,
    );
    s.lights.push(LightDecl::Point {
        position: DVec3::new(0.2, -0.1, 0.3),
        intensity: DVec3::ONE,
        span: Span::detached(),
    });
    let prepared = PreparedScene::new(&s).unwrap();
    let phi = 4.0 * PI;
    let [all, later, absorbed] = photon_flux(&prepared, 200_000, 1024, 5, a);
    println!(
        "closed box: incident {all:.4} (expected {:.4}), from 2nd hit {later:.4} (expected {:.4}), absorbed {absorbed:.4} (expected {phi:.4})",
        phi / (1.0 - a),
        phi * a / (1.0 - a)
    );
    assert!((all / (phi / (1.0 - a)) - 1.0).abs() < 0.01);
    assert!((later / (phi * a / (1.0 - a)) - 1.0).abs() < 0.01);
    assert!((absorbed / phi - 1.0).abs() < 0.01);
}

/// With M_k photons in pass k, N_{k+1} = N_k + alpha M and r_{k+1}^2 = r_k^2 (N_k + alpha M) /
/// (N_k + M). Rendering 16 and 64 iterations with the same seed (the first 16 are identical),
/// the ratio r_64^2 / r_16^2 matches that recursion with M_k proportional to r_k^2 (a uniformly
/// lit surface), its constant fitted to each pixel's N_64.
#[test]
fn radius_shrinks_as_theory_says() {
    let mut s = common::furnace_point(8);
    s.settings.radius = Some(0.25);
    let alpha = 2.0 / 3.0;
    s.settings.alpha = alpha;
    let prepared = PreparedScene::new(&s).unwrap();
    let state = |iters: u32| {
        let o = RenderOptions {
            iterations: Some(iters),
            photons: Some(20_000),
            seed: Some(9),
            ..Default::default()
        };
        let set = effective_settings(&s, &o).unwrap();
        render_with_state(&prepared, &set, &AtomicBool::new(false), &mut |_| {}).1
    };
    let (a, b) = (state(16), state(64));
    let mut ratio_sum = 0.0;
    let mut theory_sum = 0.0;
    for (p16, p64) in a.iter().zip(&b) {
        assert!(p64.n.is_finite() && p64.tau.iter().all(|t| t.is_finite()));
        assert!(p64.radius > 0.0 && p64.radius < p16.radius && p16.radius < 0.25);
        // Expected photons per pass are proportional to the disc area: M_k = lambda r_k^2.
        // Fit lambda so that the recursion reproduces this pixel's N_64, then predict the radii.
        let run = |lambda: f64| {
            let (mut n, mut r2, mut r2_16) = (0.0f64, 0.25f64 * 0.25, 0.0);
            for k in 1..=64 {
                let m = lambda * r2;
                r2 *= (n + alpha * m) / (n + m);
                n += alpha * m;
                if k == 16 {
                    r2_16 = r2;
                }
            }
            (n, r2 / r2_16)
        };
        let (mut lo, mut hi) = (1e-3f64, 1e12f64);
        for _ in 0..200 {
            let mid = (lo * hi).sqrt();
            if run(mid).0 < p64.n {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (_, r2) = run(lo);
        let r2_16 = 1.0;
        ratio_sum += (p64.radius / p16.radius).powi(2);
        theory_sum += r2 / r2_16;
    }
    let n = a.len() as f64;
    let (ratio, theory) = (ratio_sum / n, theory_sum / n);
    println!("radius: mean r64^2/r16^2 = {ratio:.4}, theory {theory:.4}");
    assert!((ratio / theory - 1.0).abs() < 0.03);
}
