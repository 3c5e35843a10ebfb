//! Every closed shape knows its inside: a `merge` or `intersection` of a shape with itself has
//! the shape's hits (same distance; normals out of the solid, so reversed where the shape's own
//! normals point in: a mesh wound inward, a revolve profile run clockwise), for rays from
//! outside and from inside. A wrong inside makes the copies hide each other's hits.

use glam::Vec3A;
use sppm_lang::EvalOptions;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::render::PreparedScene;
use sppm_lang::internals::scene::Scene;

const CUBE: &str = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";

/// The same cube as a modeller exports it flat-shaded: quads whose corners carry a normal and a
/// texture coordinate per face, so `tobj` gives every face its own four vertices. Its surface is
/// still closed (the edges meet by position).
const FLAT_CUBE: &str = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 -1\nvn 0 0 1\nvn 0 -1 0\nvn 0 1 0\nvn -1 0 0\nvn 1 0 0\n\
f 1/1/1 4/2/1 3/3/1 2/4/1\nf 5/1/2 6/2/2 7/3/2 8/4/2\nf 1/1/3 2/2/3 6/3/3 5/4/3\n\
f 4/1/4 8/2/4 7/3/4 3/4/4\nf 1/1/5 5/2/5 8/3/5 4/4/5\nf -7/1/-1 -6/2/-1 -2/3/-1 -3/4/-1\n";

fn load(dir: &std::path::Path, objects: &str) -> Scene {
    let path = dir.join("s.scn");
    std::fs::write(&path, objects).unwrap();
    let l = sppm_lang::internals::eval::load_file(&path, &EvalOptions::default()).unwrap();
    assert!(!l.has_errors(), "{objects}: {:?}", l.diagnostics);
    l.scene.unwrap()
}

#[test]
fn a_shape_merged_or_intersected_with_itself_is_the_shape() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cube.obj"), CUBE).unwrap();
    // The same cube wound the other way: every face reversed.
    let inward: String = CUBE
        .lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(f) => format!("f {}\n", f.split(' ').rev().collect::<Vec<_>>().join(" ")),
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::write(dir.path().join("inward.obj"), inward).unwrap();
    std::fs::write(dir.path().join("flat.obj"), FLAT_CUBE).unwrap();
    // (shape, whether its own normals point into it)
    let shapes = [
        ("cylinder { <0, -0.8, 0>, <0.3, 0.8, 0.2>, 0.6 }", false),
        ("cone { <0, -0.8, 0>, 0.7, <0.2, 0.8, 0.1>, 0.2 }", false),
        ("torus { 0.8, 0.4 rotate <30, 0, 10> }", false),
        ("torus { 0.7, 0.35 scale <1, 2, 1> }", false),
        (
            "cone { <0, 0.8, 0>, 0, <0, -0.8, 0>, 0.9 scale <1, 0.8, 1.3> }",
            false,
        ),
        (
            "box { <-0.7, -0.5, -0.6>, <0.8, 0.6, 0.5> scale <1, 2, 0.5> rotate <20, 30, 0> }",
            false,
        ),
        ("sphere { <0, 0, 0>, 0.8 scale <1, 0.5, 1.2> }", false),
        ("plane { <0.2, 1, 0.1>, 0.3 }", false),
        ("mesh { \"cube.obj\" scale 0.7 }", false),
        ("mesh { \"inward.obj\" scale 0.7 }", true),
        ("mesh { \"flat.obj\" scale 0.7 }", false),
        (
            "revolve { profile bezier { <0, -0.6>, <0.9, -0.6>, <0.9, 0.6>, <0, 0.6> } }",
            false,
        ),
        (
            "revolve { profile bezier { <0, 0.6>, <0.9, 0.6>, <0.9, -0.6>, <0, -0.6> } }",
            true,
        ),
        // A frame: a square with a square hole (even-odd), run clockwise and anticlockwise.
        (
            "prism { -0.6, 0.7, 10, <-0.9, -0.9>, <0.9, -0.9>, <0.9, 0.9>, <-0.9, 0.9>, \
             <-0.9, -0.9>, <-0.4, -0.4>, <-0.4, 0.4>, <0.4, 0.4>, <0.4, -0.4>, <-0.4, -0.4> \
             rotate <20, 0, 10> }",
            false,
        ),
        (
            "prism { cubic_spline conic_sweep 0.3, 1.2, 8, <0, 0>, <1, 0>, <0, 1>, \
             <-1, 0>, <0, -1>, <1, 0>, <0, 1>, <0, 0> translate <0, -0.6, 0> }",
            false,
        ),
        (
            "prism { bezier_spline -0.5, 0.5, 8, <0, -0.8>, <1.2, -0.8>, <1.2, 0.8>, <0, 0.8>, \
             <0, 0.8>, <-0.3, 0.8>, <-0.3, -0.8>, <0, -0.8> scale <1, 1.5, 1> }",
            false,
        ),
        (
            "superellipsoid { <0.01, 0.05> scale 0.8 rotate <10, 20, 0> }",
            false,
        ),
        ("superellipsoid { <0.3, 2.5> scale 1.2 }", false),
        // A glyph with a hole (its outer and inner contours), from the system's DejaVu Sans.
        (
            "text { ttf \"DejaVuSans.ttf\" \"O\" 0.6, 0 translate <-0.4, -0.36, -0.3> scale 2 }",
            false,
        ),
        // A terrain cut at its water level, and one whose heights reach 0 (holes there).
        (
            "height_field { function 23, 17 { 0.5 + 0.4 * sin(9 * x) * cos(7 * y) } \
             water_level 0.2 translate <-0.5, -0.5, -0.5> scale <2.4, 2, 2.4> rotate <10, 20, 0> }",
            false,
        ),
        (
            "height_field { function 12, 9 { max(0, sin(5 * x + 3 * y)) } smooth \
             translate <-0.5, -0.5, -0.5> scale <2.4, 2.2, 2.4> }",
            false,
        ),
        (
            "blob { threshold 0.5 sphere { <-0.4, 0, 0>, 1, strength 1 } \
             sphere { <0.4, 0.1, 0>, 1, strength 1 } \
             cylinder { <0, -0.6, 0>, <0, 0.6, 0.2>, 0.7, strength 1 } \
             sphere { <0, 0.7, 0>, 0.5, strength -2 } rotate <10, 20, 0> }",
            false,
        ),
        (
            "isosurface { function { x*x + 2*y*y + z*z + 0.2*sin(4*x) } threshold 1 \
             contained_by { box { <-1.4, -1.4, -1.4>, <1.4, 1.4, 1.4> } } }",
            false,
        ),
        // Cut by its container: the walls close it.
        (
            "isosurface { function { x*x + y*y + z*z } threshold 1.2 \
             contained_by { box { <-0.9, -0.9, -0.9>, <0.9, 0.9, 0.9> } } rotate <0, 30, 0> }",
            false,
        ),
        (
            "sphere_sweep { linear_spline 3, <-0.8, -0.5, 0>, 0.5, <0, 0.3, 0.2>, 0.7, \
             <0.9, 0, -0.3>, 0.3 }",
            false,
        ),
    ];
    for (shape, inward) in shapes {
        let alone = load(dir.path(), shape);
        let pa = PreparedScene::new(&alone).unwrap();
        for op in ["merge", "intersection"] {
            let both = load(dir.path(), &format!("{op} {{ {shape} {shape} }}"));
            let pb = PreparedScene::new(&both).unwrap();
            let mut rng = sppm_lang::internals::sampling::Rng::new(7);
            let mut f = || rng.f32() * 2.0 - 1.0;
            let (mut hits, mut inside) = (0, 0);
            for _ in 0..3000 {
                let o = Vec3A::new(f(), f(), f()) * 1.5;
                let d = Vec3A::new(f(), f(), f()).normalize_or(Vec3A::X);
                let ray = Ray::new(o, d);
                let a = pa.intersect(&ray, f32::INFINITY);
                let b = pb.intersect(&ray, f32::INFINITY);
                let (Some(a), Some(b)) = (a, b) else {
                    assert!(a.is_none() && b.is_none(), "{op} of {shape}: {ray:?}");
                    continue;
                };
                hits += 1;
                assert!(
                    (a.hit.t - b.hit.t).abs() <= 1e-5 * a.hit.t.max(1.0),
                    "{op} of {shape}: {ray:?}: {} vs {}",
                    a.hit.t,
                    b.hit.t
                );
                let want = if inward { -a.hit.n } else { a.hit.n };
                assert!(
                    want.dot(b.hit.n) > 0.9999,
                    "{op} of {shape}: {ray:?}: normal {} vs {}",
                    want,
                    b.hit.n
                );
                // Leaving the solid: the ray started inside.
                inside += usize::from(b.hit.n.dot(d) > 0.0);
            }
            assert!(
                hits > 300 && inside > 100,
                "{op} of {shape}: {hits} hits, {inside} from inside"
            );
        }
    }
}

/// Coincident faces read as the scene means them: a cutter flush with the top opens its hole, a
/// cutter as tall as the solid leaves a tunnel, boxes merged along a shared face show no face
/// between them, and a solid minus itself is empty. (Hits at the same distance: every leaf
/// counts a hair larger, a subtracted one larger still.)
#[test]
fn coincident_faces_read_as_meant() {
    let dir = tempfile::tempdir().unwrap();
    let first_hit = |objects: &str, o: Vec3A, d: Vec3A| {
        let s = load(dir.path(), objects);
        let p = PreparedScene::new(&s).unwrap();
        p.intersect(&Ray::new(o, d), f32::INFINITY).map(|h| h.hit.t)
    };
    let (down, up) = (Vec3A::new(0.0, -1.0, 0.0), Vec3A::Y);
    let above = Vec3A::new(0.1, 3.0, 0.2);
    let below = Vec3A::new(0.1, -3.0, 0.2);
    let solid = "box { <-1, 0, -1>, <1, 1, 1> }";
    let pit = format!("difference {{ {solid} box {{ <-0.5, 0.5, -0.5>, <0.5, 1, 0.5> }} }}");
    let t = first_hit(&pit, above, down).expect("the pit's floor");
    assert!(
        (t - 2.5).abs() < 1e-5,
        "hit at y = {}, not the pit's floor",
        3.0 - t
    );
    let tunnel = format!("difference {{ {solid} box {{ <-0.5, 0, -0.5>, <0.5, 1, 0.5> }} }}");
    assert_eq!(first_hit(&tunnel, above, down), None);
    assert_eq!(first_hit(&tunnel, below, up), None);
    let pair = "merge { box { <0, 0, 0>, <1, 1, 1> } box { <1, 0, 0>, <2, 1, 1> } }";
    let t = first_hit(pair, Vec3A::splat(0.5), Vec3A::X).expect("the far face");
    assert!(
        (t - 1.5).abs() < 1e-5,
        "hit at x = {}, not the far face",
        0.5 + t
    );
    let nothing = "difference { sphere { <0, 0, 0>, 1 } sphere { <0, 0, 0>, 1 } }";
    assert_eq!(
        first_hit(nothing, Vec3A::new(0.0, 0.0, -3.0), Vec3A::Z),
        None
    );
}
