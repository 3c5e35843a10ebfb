//! Random streams: `seed(n)` and `rand(S)`, with the `rand.inc` helpers built in. A stream is
//! deterministic per seed: the same numbers on every load and for any render thread count.

use std::sync::atomic::AtomicBool;

use crate::common;
use common::{debug, load};
use glam::DVec3;
use sppm_lang::internals::render::{RenderOptions, render};
use sppm_lang::internals::scene::*;

/// Each sphere's centre, in scene order.
fn centres(s: &Scene) -> Vec<DVec3> {
    s.objects
        .iter()
        .map(|o| match o.shape {
            ShapeDecl::Sphere { center, .. } => o.transform.transform_point3(center),
            _ => panic!("not a sphere: {:?}", o.shape),
        })
        .collect()
}

/// Twenty small spheres placed with `rand` (and `VRand`) from stream `seed`, lit, framed.
fn placed(seed: u32) -> String {
    format!(
        "settings {{ resolution <24, 24> iterations 2 photons 4000 }}
         camera {{ location <0.5, 0.5, -3> look_at <0.5, 0.5, 0.5> fov 45 }}
         light {{ <0.5, 3, -2> intensity rgb <20, 20, 20> }}
         #declare S = seed({seed});
         #for (I, 1, 20)
           sphere {{ <rand(S), rand(S), RRand(0, 1, S)>, 0.05 + 0.05 * rand(S) }}
         #end
         sphere {{ VRand(S), 0.1 material {{ mirror rgb 0.9 }} }}"
    )
}

#[test]
fn a_stream_is_the_same_on_every_load_and_differs_by_seed() {
    let a = centres(&load(&placed(42)).scene.unwrap());
    let b = centres(&load(&placed(42)).scene.unwrap());
    let c = centres(&load(&placed(43)).scene.unwrap());
    assert_eq!(a.len(), 21);
    let bits = |v: &[DVec3]| -> Vec<[u64; 3]> {
        v.iter().map(|p| p.to_array().map(f64::to_bits)).collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_ne!(bits(&a), bits(&c));
    // Drawn from [0, 1) and not all alike.
    assert!(
        a.iter()
            .all(|p| p.cmpge(DVec3::ZERO).all() && p.cmplt(DVec3::ONE).all())
    );
    assert!(a.windows(2).all(|w| w[0] != w[1]));
}

/// A scene placed by `rand` renders to the same pixels with 1 and 2 threads: the stream is
/// drawn once, by the evaluation, before the render starts.
#[test]
fn a_scene_placed_by_rand_renders_alike_on_one_and_two_threads() {
    let mut images = Vec::new();
    for threads in [1, 2] {
        let scene = load(&placed(7)).scene.unwrap();
        let opts = RenderOptions {
            seed: Some(1),
            threads: Some(threads),
            ..Default::default()
        };
        let out = render(&scene, &opts, &AtomicBool::new(false), &mut |_| {}).unwrap();
        images.push(out.image);
    }
    let bits = |i: usize| -> Vec<[u64; 3]> {
        images[i]
            .pixels
            .iter()
            .map(|p| p.map(f64::to_bits))
            .collect()
    };
    assert_eq!(bits(0), bits(1));
    assert!(images[0].mean().iter().any(|c| *c > 0.0), "a black image");
}

/// `rand` advances the stream the variable holds: a copy of the variable and a macro's
/// parameter share it (as POV-Ray's stream handles), so a macro drawing from its parameter
/// advances the caller's stream.
#[test]
fn rand_advances_the_stream_every_holder_shares() {
    let l = load(
        "#declare S = seed(5);
         #declare T = seed(5);
         #declare S2 = S;
         #macro Draw(St) rand(St) #end
         #declare A = rand(S);
         #declare B = rand(S2);
         #declare C = Draw(S);
         #declare D = Draw(S);
         #debug A == rand(T) & B == rand(T) & C == rand(T) & D == rand(T)
         #debug A != B & B != C & C != D
         sphere { <0, 0, 0>, 1 }",
    );
    assert_eq!(debug(&l), ["true", "true"]);
}

/// `RRand` stays in its bounds (10 000 draws, reaching close to both ends) and equal bounds
/// give that number; `VRand_In_Sphere` stays inside the unit sphere over 10 000 draws and fills
/// it (the mean length of a uniform point in the ball is 3/4); `VRand_On_Sphere` is unit
/// length; `VRand`'s components are in [0, 1); `Rand_Normal` has the mean and spread asked
/// for.
#[test]
fn the_rand_inc_helpers_keep_their_ranges() {
    let l = load(
        "#declare S = seed(2024);
         #declare Lo = 10; #declare Hi = -10;
         #declare Inside = 0; #declare MaxLen = 0; #declare SumLen = 0;
         #declare OnErr = 0; #declare CubeOk = true;
         #declare NSum = 0; #declare NSq = 0;
         #for (I, 1, 10000)
           #local R = RRand(-2, 3, S);
           #declare Lo = min(Lo, R); #declare Hi = max(Hi, R);
           #local V = VRand_In_Sphere(S);
           #declare Inside = Inside + (vlength(V) < 1 ? 1 : 0);
           #declare MaxLen = max(MaxLen, vlength(V));
           #declare SumLen = SumLen + vlength(V);
           #declare OnErr = max(OnErr, abs(vlength(VRand_On_Sphere(S)) - 1));
           #local C = VRand(S);
           #declare CubeOk = CubeOk & min(C.x, C.y, C.z) >= 0 & max(C.x, C.y, C.z) < 1;
           #local N = Rand_Normal(5, 2, S);
           #declare NSum = NSum + N; #declare NSq = NSq + N * N;
         #end
         #debug str(Lo)
         #debug str(Hi)
         #debug str(Inside)
         #debug str(MaxLen)
         #debug str(SumLen / 10000)
         #debug str(OnErr)
         #debug CubeOk
         #debug str(NSum / 10000)
         #debug str(sqrt(NSq / 10000 - pow(NSum / 10000, 2)))
         #debug str(RRand(1.5, 1.5, S))
         sphere { <0, 0, 0>, 1 }",
    );
    let d = debug(&l);
    let num = |i: usize| d[i].parse::<f64>().unwrap_or_else(|_| panic!("{}", d[i]));
    assert!((-2.0..-1.99).contains(&num(0)), "{d:?}");
    // (`str` shows 6 digits: a draw just below 3 may read as 3.)
    assert!(num(1) > 2.99 && num(1) <= 3.0, "{d:?}");
    assert_eq!(num(2), 10_000.0, "{d:?}");
    assert!(num(3) > 0.99 && num(3) <= 1.0, "{d:?}");
    // Standard error of the mean length: 0.19 / 100; bound at about 5.
    assert!((num(4) - 0.75).abs() < 0.01, "{d:?}");
    assert!(num(5) < 1e-12, "{d:?}");
    assert_eq!(d[6], "true");
    // Standard errors: 0.02 for the mean, about 0.014 for the deviation; bounds at about 5.
    assert!((num(7) - 5.0).abs() < 0.1, "{d:?}");
    assert!((num(8) - 2.0).abs() < 0.07, "{d:?}");
    assert_eq!(num(9), 1.5);
}
