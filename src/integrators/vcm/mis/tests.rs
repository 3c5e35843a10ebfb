//! The recursive weights against brute force: for random paths of every length from 2 to 8
//! segments (random distances, cosines and densities), every technique's density is computed
//! from the whole path (Veach's products of per-vertex densities, merges counting `pi r^2 N`
//! and light tracing `N`), and each weight the renderer's functions give from the subpaths'
//! recursive quantities must equal that technique's power-heuristic weight, and all of them
//! must sum to one, for VCM and for BPT, for paths from a light's surface and from the sky
//! (whose first vertex is a direction), and with the final gather (the merge at the camera
//! path's second vertex counting `pi R^2 N`).

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

    /// The same techniques' weights from the recursive quantities.
    fn recursive_weights(&self, f: &Factors) -> Vec<f64> {
        let n = self.n;
        let emission = self.pos * self.dir;
        // Light subpath: quantities at x_1 .. x_{n-1}.
        let mut light = vec![Quantities::default(); n];
        let (cos_light, d0) = if self.env {
            (1.0, None)
        } else {
            (self.cos_next[0], Some(self.d[0] * self.d[0]))
        };
        let mut q = Quantities::light(f, self.nee_area(), emission, cos_light);
        q.arrive(d0, self.cos_prev[1]);
        light[1] = q;
        for i in 1..n - 1 {
            q.scatter(f, self.cos_next[i], self.a[i], self.b[i], false);
            q.arrive(Some(self.d[i] * self.d[i]), self.cos_prev[i + 1]);
            light[i + 1] = q;
        }
        // Camera subpath: quantities at x_{n-1} .. x_0. Camera vertex t is x_{n-t}; its second,
        // x_{n-2}, is the final gather's (every vertex here scatters non-specularly). With the
        // gather off its factors are the plain merge's, so the flag changes nothing there.
        let mut camera = vec![Quantities::default(); n];
        let mut q = Quantities::camera(f, self.cam);
        q.arrive(Some(self.d[n - 1] * self.d[n - 1]), self.cos_next[n - 1]);
        camera[n - 1] = q;
        for i in (0..n - 1).rev() {
            let gather = i + 1 + 2 == n;
            q.scatter(
                f,
                self.cos_prev[i + 1],
                self.b[i + 1],
                self.a[i + 1],
                gather,
            );
            // A path escaping to the sky arrives nowhere.
            if !(i == 0 && self.env) {
                q.arrive(Some(self.d[i] * self.d[i]), self.cos_next[i]);
            }
            camera[i] = q;
        }
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
        for s in 2..n {
            let d2 = self.d[s - 1] * self.d[s - 1];
            // The camera part is x_s .. x_{n-1}: n - s vertices.
            let gather = match n - s {
                2 => GatherAt::Camera,
                1 => GatherAt::Light,
                _ => GatherAt::Neither,
            };
            w.push(connect(
                f,
                &camera[s],
                &light[s - 1],
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
        let last = light[n - 1].gathered(f);
        w.push(to_camera(f, &last, camera_pdf_a, self.b[n - 1]));
        if f.vm_weight > 0.0 {
            for i in 1..n {
                // At the camera's first vertex the light vertex's predecessor is its second.
                let l = if i + 1 == n {
                    light[i].gathered(f)
                } else {
                    light[i]
                };
                w.push(merge(f, &camera[i], &l, self.b[i], self.a[i], i + 2 == n));
            }
        }
        w
    }
}

/// Whether the recursive weights of `path` with factors `f` equal the power-heuristic weights
/// of the brute-force densities `p` and sum to one; the first mismatch otherwise.
fn check(path: &Path, f: &Factors, p: &[f64]) -> Result<(), String> {
    let total: f64 = p.iter().map(|x| mis(*x)).sum();
    let w = path.recursive_weights(f);
    if w.len() != p.len() {
        return Err(format!("technique count {} vs {}", w.len(), p.len()));
    }
    let sum: f64 = w.iter().sum();
    if (sum - 1.0).abs() >= 1e-9 {
        return Err(format!("sum {sum}"));
    }
    for (k, (wk, pk)) in w.iter().zip(p).enumerate() {
        let expected = mis(*pk) / total;
        if (wk - expected).abs() >= 1e-9 * (1.0 + expected) {
            return Err(format!("technique {k}: {wk} vs {expected}"));
        }
    }
    Ok(())
}

#[test]
fn recursive_weights_equal_brute_force_and_sum_to_one() {
    let mut rng = Rng::new(2024);
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
                let radius = 0.01 + 0.5 * f64::from(rng.f32());
                let factor = 1.5 + 5.0 * f64::from(rng.f32());
                let mut f = Factors::new(radius, n_paths, true, use_vm);
                if gather {
                    f = f.with_gather(factor);
                }
                let r_gather = (gather && use_vm).then_some(factor * radius);
                let p = path.densities(n_paths, radius, use_vm, r_gather);
                if let Err(e) = check(&path, &f, &p) {
                    panic!("{name}, {n} segments: {e}");
                }
            }
        }
    }
}

/// The comparison sees the final gather's factor: with the recursion's gather radius other
/// than the brute force's (or none), the weights of every path long enough to have a camera
/// vertex 2 fail it, and those of a path of 2 segments (no such vertex) do not.
#[test]
fn a_wrong_gather_factor_fails_the_comparison() {
    let mut rng = Rng::new(77);
    for env in [false, true] {
        for n in 2..=8 {
            for _ in 0..50 {
                let mut path = random_path(n, &mut rng);
                path.env = env;
                let n_paths = 10.0 + 1000.0 * f64::from(rng.f32());
                let radius = 0.01 + 0.5 * f64::from(rng.f32());
                let p = path.densities(n_paths, radius, true, Some(4.0 * radius));
                let plain = Factors::new(radius, n_paths, true, true);
                for f in [plain, plain.with_gather(3.0), plain.with_gather(5.0)] {
                    let got = check(&path, &f, &p);
                    assert_eq!(got.is_ok(), n == 2, "{n} segments, env {env}: {got:?}");
                }
                assert!(check(&path, &plain.with_gather(4.0), &p).is_ok());
            }
        }
    }
}
