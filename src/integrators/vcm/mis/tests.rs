//! The recursive weights against brute force: for random paths of every length from 2 to 8
//! segments (random distances, cosines and densities), every technique's density is computed
//! from the whole path (Veach's products of per-vertex densities, merges counting `pi r^2 N`
//! and light tracing `N`), and each weight the renderer's functions give from the subpaths'
//! recursive quantities must equal that technique's power-heuristic weight, and all of them
//! must sum to one, for VCM and for BPT, for paths from a light's surface and from the sky
//! (whose first vertex is a direction), without and with the final gather (the merge at the
//! camera path's second vertex counting `pi R^2 N`, `R` a factor times that camera path's
//! `r`). The light subpath's quantities are computed once, with no radius, and meet two camera
//! paths of different radii (as a stored light vertex meets every pixel's): the weights hold
//! for each with its own radius and gather, and fail with the other's radius or a wrong gather
//! factor.

use super::*;
use crate::sampling::Rng;

/// A path x_0 (on the light) .. x_n (the eye), all of whose surface vertices scatter
/// non-specularly.
struct Path {
    n: usize,
    /// d[i]: distance from x_i to x_{i+1}.
    d: Vec<f64>,
    /// cos_next[i], cos_prev[i]: cosine at x_i toward x_{i+1} and toward x_{i-1}.
    cos_next: Vec<f64>,
    cos_prev: Vec<f64>,
    /// a[i]: BSDF density at x_i of x_{i+1}'s direction given x_{i-1}'s; b[i] the reverse.
    a: Vec<f64>,
    b: Vec<f64>,
    /// Emission: light choice and area density, direction density; next-event estimation's
    /// solid-angle density (with the light choice) from x_1; the camera's direction density.
    pos: f64,
    dir: f64,
    nee: f64,
    cam: f64,
    /// x_0 is a direction of the environment light (densities per solid angle, no distance
    /// or cosine at it): emission picks the direction (`dir`) then a point of the disk
    /// (`pos`, per area across the direction).
    env: bool,
}

fn random_path(n: usize, rng: &mut Rng) -> Path {
    let mut u = |lo: f64, hi: f64| lo + (hi - lo) * f64::from(rng.f32());
    Path {
        n,
        d: (0..n).map(|_| u(0.2, 3.0)).collect(),
        cos_next: (0..=n).map(|_| u(0.05, 1.0)).collect(),
        cos_prev: (0..=n).map(|_| u(0.05, 1.0)).collect(),
        a: (0..=n).map(|_| u(0.05, 3.0)).collect(),
        b: (0..=n).map(|_| u(0.05, 3.0)).collect(),
        pos: u(0.1, 4.0),
        dir: u(0.05, 1.0),
        nee: u(0.05, 5.0),
        cam: u(0.5, 50.0),
        env: false,
    }
}

impl Path {
    /// Density per area of x_i sampled from the light side (i < n).
    fn fwd(&self, i: usize) -> f64 {
        match i {
            0 if self.env => self.dir,
            1 if self.env => self.pos * self.cos_prev[1],
            0 => self.pos,
            1 => self.dir * self.cos_prev[1] / (self.d[0] * self.d[0]),
            _ => self.a[i - 1] * self.cos_prev[i] / (self.d[i - 1] * self.d[i - 1]),
        }
    }

    /// Density per area of x_i sampled from the camera side (i < n).
    fn bwd(&self, i: usize) -> f64 {
        let d2 = self.d[i] * self.d[i];
        if i == 0 && self.env {
            // The camera side reaches the sky by the direction alone.
            self.b[1]
        } else if i == self.n - 1 {
            self.cam * self.cos_next[i] / d2
        } else {
            self.b[i + 1] * self.cos_next[i] / d2
        }
    }

    fn nee_area(&self) -> f64 {
        if self.env {
            return self.nee;
        }
        self.nee * self.cos_next[0] / (self.d[0] * self.d[0])
    }

    /// Every technique's density, by brute force: connections with s light vertices (0..n-1),
    /// light tracing (s = n), then merges at x_1 .. x_{n-1}; the one at x_{n-2}, the camera
    /// path's second vertex, with radius `gather` where given (the final gather).
    fn densities(&self, n_paths: f64, radius: f64, vm: bool, gather: Option<f64>) -> Vec<f64> {
        let n = self.n;
        let mut out = Vec::new();
        for s in 0..=n {
            let mut p = if s == n { n_paths } else { 1.0 };
            for i in 0..s {
                p *= if i == 0 && s == 1 {
                    self.nee_area()
                } else {
                    self.fwd(i)
                };
            }
            for i in s..n {
                p *= self.bwd(i);
            }
            out.push(p);
        }
        if vm {
            for i in 1..n {
                let r = match gather {
                    Some(r_gather) if i + 2 == n => r_gather,
                    _ => radius,
                };
                let mut p = n_paths * std::f64::consts::PI * r * r;
                for j in 0..=i {
                    p *= self.fwd(j);
                }
                for j in i..n {
                    p *= self.bwd(j);
                }
                out.push(p);
            }
        }
        out
    }

    /// The same techniques' weights from the recursive quantities, for a camera path of
    /// factors `f` (its radius and, if on, its gather); the light subpath's quantities are
    /// evaluated with `f_light` (`f` itself in the renderer).
    fn recursive_weights(&self, f: &Factors, f_light: &Factors) -> Vec<f64> {
        let n = self.n;
        let emission = self.pos * self.dir;
        // Light subpath: quantities at x_1 .. x_{n-1}.
        let mut light = vec![Parts::default(); n];
        let (cos_light, d0) = if self.env {
            (1.0, None)
        } else {
            (self.cos_next[0], Some(self.d[0] * self.d[0]))
        };
        let mut q = Parts::light(self.nee_area(), emission, cos_light);
        q.arrive(d0, self.cos_prev[1]);
        light[1] = q;
        for i in 1..n - 1 {
            q.scatter(self.cos_next[i], self.a[i], self.b[i], 1.0);
            q.arrive(Some(self.d[i] * self.d[i]), self.cos_prev[i + 1]);
            light[i + 1] = q;
        }
        // The light vertex x_i met by a camera path whose gather vertex is x_{i+1} (light
        // tracing from x_{n-1}, a merge at x_{n-1}) takes its last merge term as the gather's.
        let light_at = |i: usize| {
            if i + 1 == n {
                light[i].gathered(f_light)
            } else {
                light[i].at(f_light)
            }
        };
        // Camera subpath: quantities at x_{n-1} .. x_0. Camera vertex t is x_{n-t}; its second,
        // x_{n-2}, is the final gather's (every vertex here scatters non-specularly). With the
        // gather off its ratio is 1, so the flag changes nothing there.
        let mut camera = vec![Parts::default(); n];
        let mut q = Parts::camera(f.light_paths, self.cam);
        q.arrive(Some(self.d[n - 1] * self.d[n - 1]), self.cos_next[n - 1]);
        camera[n - 1] = q;
        for i in (0..n - 1).rev() {
            let ratio = f.merge_ratio(i + 1 + 2 == n);
            q.scatter(self.cos_prev[i + 1], self.b[i + 1], self.a[i + 1], ratio);
            // A path escaping to the sky arrives nowhere.
            if !(i == 0 && self.env) {
                q.arrive(Some(self.d[i] * self.d[i]), self.cos_next[i]);
            }
            camera[i] = q;
        }
        let camera: Vec<Quantities> = camera.iter().map(|q| q.at(f)).collect();
        let mut w = Vec::new();
        // s = 0: the camera path hits the light.
        w.push(hit_light(&camera[0], self.nee_area(), emission));
        // s = 1: next-event estimation at x_1.
        if n >= 2 {
            w.push(direct(
                f,
                &camera[1],
                n == 3,
                self.b[1],
                self.a[1],
                self.nee,
                emission,
                self.cos_prev[1],
                cos_light,
            ));
        }
        // 2 <= s <= n-1: light vertex x_{s-1} to camera vertex x_s.
        for (s, cam) in camera.iter().enumerate().skip(2) {
            let d2 = self.d[s - 1] * self.d[s - 1];
            // The camera part is x_s .. x_{n-1}: n - s vertices.
            let gather = match n - s {
                2 => GatherAt::Camera,
                1 => GatherAt::Light,
                _ => GatherAt::Neither,
            };
            w.push(connect(
                f,
                cam,
                &light_at(s - 1),
                self.b[s] * self.cos_next[s - 1] / d2,
                self.a[s - 1] * self.cos_prev[s] / d2,
                self.a[s],
                self.b[s - 1],
                gather,
            ));
        }
        // s = n: light tracing from x_{n-1}.
        let d2 = self.d[n - 1] * self.d[n - 1];
        let camera_pdf_a = self.cam * self.cos_next[n - 1] / d2;
        w.push(to_camera(f, &light_at(n - 1), camera_pdf_a, self.b[n - 1]));
        if f.vm_weight > 0.0 {
            for (i, cam) in camera.iter().enumerate().skip(1) {
                let gather = i + 2 == n;
                w.push(merge(f, cam, &light_at(i), self.b[i], self.a[i], gather));
            }
        }
        w
    }
}

/// Whether weights `w` are the power heuristic's for densities `p` (to 1e-9), and sum to one.
fn exact(w: &[f64], p: &[f64]) -> bool {
    let total: f64 = p.iter().map(|x| mis(*x)).sum();
    let sum: f64 = w.iter().sum();
    w.len() == p.len()
        && (sum - 1.0).abs() < 1e-9
        && w.iter().zip(p).all(|(wk, pk)| {
            let expected = mis(*pk) / total;
            (wk - expected).abs() < 1e-9 * (1.0 + expected)
        })
}

#[test]
fn recursive_weights_equal_brute_force_and_sum_to_one() {
    let mut rng = Rng::new(2024);
    // VCM paths where merging has a share of at least 1e-3, and those whose weights, with the
    // light quantities evaluated with the other camera path's radius, still passed the check
    // (without and with the final gather).
    let (mut wrong_tried, mut wrong_passed) = ([0; 2], [0; 2]);
    for (use_vm, env, gather, name) in [
        (true, false, false, "vcm"),
        (false, false, false, "bpt"),
        (true, true, false, "vcm from the sky"),
        (false, true, false, "bpt from the sky"),
        (true, false, true, "vcm with the final gather"),
        (true, true, true, "vcm from the sky with the final gather"),
        (
            false,
            false,
            true,
            "bpt, the final gather asked (no merges: no change)",
        ),
    ] {
        for n in 2..=8 {
            for _ in 0..200 {
                let mut path = random_path(n, &mut rng);
                path.env = env;
                let n_paths = 10.0 + 1000.0 * f64::from(rng.f32());
                // Two camera paths meeting the same light subpath, each with its own radius
                // and, with the final gather, a gather radius `factor` times its own.
                let radii = [0.0; 2].map(|_| 0.01 + 0.5 * f64::from(rng.f32()));
                // (Drawn only with it: the cases without it see the same paths as before.)
                let factor = if gather {
                    1.5 + 5.0 * f64::from(rng.f32())
                } else {
                    1.0
                };
                let factors = radii.map(|r| {
                    let f = Factors::new(r, n_paths, true, use_vm);
                    if gather { f.with_gather(factor) } else { f }
                });
                let densities = |r: f64| {
                    let r_gather = (gather && use_vm).then_some(factor * r);
                    path.densities(n_paths, r, use_vm, r_gather)
                };
                for (&radius, f) in radii.iter().zip(&factors) {
                    let p = densities(radius);
                    let w = path.recursive_weights(f, f);
                    let sum: f64 = w.iter().sum();
                    assert!(
                        exact(&w, &p),
                        "{name}, {n} segments: {w:?} (sum {sum}) for {p:?}"
                    );
                }
                // The light quantities evaluated with the other camera path's radius (and its
                // gather): where merges weigh at all, the check above fails. From 3 segments:
                // with 2 the light side's radius only weighs the camera path hitting the light
                // against the merge (a share near 1e-7, below the check's 1e-9 resolution).
                let ratio = radii[0].max(radii[1]) / radii[0].min(radii[1]);
                let p = densities(radii[0]);
                let total: f64 = p.iter().map(|x| mis(*x)).sum();
                let merges: f64 = p[n + 1..].iter().map(|x| mis(*x)).sum();
                if use_vm && n >= 3 && ratio > 1.5 && merges > 1e-3 * total {
                    let w = path.recursive_weights(&factors[0], &factors[1]);
                    wrong_tried[usize::from(gather)] += 1;
                    wrong_passed[usize::from(gather)] += usize::from(exact(&w, &p));
                }
            }
        }
    }
    println!("the other radius: {wrong_passed:?} of {wrong_tried:?} paths passed");
    assert!(wrong_tried.iter().all(|&t| t > 500) && wrong_passed == [0, 0]);
}

/// The comparison sees the final gather's factor, per camera path: with the recursion's gather
/// radius other than the brute force's (or none), the weights of every path long enough to
/// have a camera vertex 2 fail it, and those of a path of 2 segments (no such vertex) do not;
/// the light subpath's parts evaluated with each of two camera paths' radii and the right
/// factor pass it.
#[test]
fn a_wrong_gather_factor_fails_the_comparison() {
    let mut rng = Rng::new(77);
    for env in [false, true] {
        for n in 2..=8 {
            for _ in 0..50 {
                let mut path = random_path(n, &mut rng);
                path.env = env;
                let n_paths = 10.0 + 1000.0 * f64::from(rng.f32());
                for _ in 0..2 {
                    let radius = 0.01 + 0.5 * f64::from(rng.f32());
                    let p = path.densities(n_paths, radius, true, Some(4.0 * radius));
                    let plain = Factors::new(radius, n_paths, true, true);
                    for f in [plain, plain.with_gather(3.0), plain.with_gather(5.0)] {
                        let ok = exact(&path.recursive_weights(&f, &f), &p);
                        assert_eq!(ok, n == 2, "{n} segments, env {env}, radius {radius}");
                    }
                    let f = plain.with_gather(4.0);
                    assert!(exact(&path.recursive_weights(&f, &f), &p));
                }
            }
        }
    }
}
