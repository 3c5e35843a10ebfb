//! Value macros, as in POV-Ray: a macro whose body ends in one value is used wherever that
//! value stands (a declaration, a vector, a property, an object's place), its `#local`s stay
//! private, and it may recurse; a macro called as a statement still puts its objects where the
//! call stands.

use crate::common;
use common::{debug, load};
use glam::DVec3;
use sppm_lang::EvalOptions;
use sppm_lang::internals::eval::load_source;
use sppm_lang::internals::scene::*;

/// Each sphere's centre (in the world) and radius, in scene order.
fn spheres(objects: &[Object]) -> Vec<(DVec3, f64)> {
    objects
        .iter()
        .map(|o| match o.shape {
            ShapeDecl::Sphere { center, radius } => (o.transform.transform_point3(center), radius),
            _ => panic!("not a sphere: {:?}", o.shape),
        })
        .collect()
}

const MACROS: &str = "
#macro Radius(N) N * 0.1 #end
#macro Lerp(A, B, T) #local D = B - A; (A + D * T) #end
#macro Ball(R) sphere { <0, 0, 0>, R } #end
";

#[test]
fn a_value_macro_stands_in_a_declaration_a_vector_and_a_property() {
    let l = load(&format!(
        "{MACROS}
         #declare R = Radius(3);
         sphere {{ <Lerp(0, 10, 0.25), Radius(20), 0>, R }}
         sphere {{ <0, 0, 0>, Radius(5) }}
         sphere {{ <0, 0, 0>, 1 translate <Lerp(-2, 2, 0.75), 0, 0> }}
         #debug str(Lerp(1, 3, 0.5) * 2)"
    ));
    let s = spheres(&l.scene.as_ref().unwrap().objects);
    assert_eq!(s.len(), 3);
    assert!(
        (s[0].0 - DVec3::new(2.5, 2.0, 0.0)).length() < 1e-12,
        "{s:?}"
    );
    assert!((s[0].1 - 0.3).abs() < 1e-12, "{s:?}");
    assert!((s[1].1 - 0.5).abs() < 1e-12, "{s:?}");
    assert!((s[2].0.x - 1.0).abs() < 1e-12, "{s:?}");
    assert_eq!(debug(&l), ["4"]);
}

#[test]
fn a_macro_yielding_an_object_stands_in_object_union_and_declarations() {
    let l = load(&format!(
        "{MACROS}
         object {{ Ball(2) translate <5, 0, 0> }}
         union {{ Ball(1) Ball(Radius(4)) translate <0, 3, 0> }}
         #declare B = Ball(0.5);
         object {{ B translate <0, 0, -1> }}
         difference {{ Ball(1) object {{ Ball(0.5) translate <0.9, 0, 0> }} }}"
    ));
    let scene = l.scene.unwrap();
    let s = spheres(&scene.objects[..4]);
    assert_eq!(scene.objects.len(), 5);
    assert_eq!(s[0], (DVec3::new(5.0, 0.0, 0.0), 2.0));
    assert_eq!(s[1], (DVec3::new(0.0, 3.0, 0.0), 1.0));
    assert!((s[2].1 - 0.4).abs() < 1e-12 && s[2].0 == DVec3::new(0.0, 3.0, 0.0));
    assert_eq!(s[3], (DVec3::new(0.0, 0.0, -1.0), 0.5));
    assert!(
        matches!(scene.objects[4].shape, ShapeDecl::Csg(_)),
        "{:?}",
        scene.objects[4].shape
    );
}

/// The `#local`s of a value macro are its own: gone after the call, a global of the same name
/// untouched; its parameters likewise.
#[test]
fn locals_of_a_value_macro_stay_private() {
    let l = load(&format!(
        "{MACROS}
         #declare D = 100;
         #declare V = Lerp(0, 4, 0.5);
         #debug str(V) + \" \" + str(D)
         #ifdef (T) #error \"the parameter leaked\" #end
         sphere {{ <0, 0, 0>, 1 }}"
    ));
    assert_eq!(debug(&l), ["2 100"]);
}

#[test]
fn value_macros_recurse() {
    let l = load(
        "#macro Fact(N) #if (N <= 1) 1 #else N * Fact(N - 1) #end #end
         #macro Fib(N) (N < 2 ? N : Fib(N - 1) + Fib(N - 2)) #end
         #macro Double(X) X * 2 #end
         #macro Quad(X) Double(Double(X)) #end
         #macro Inner() Double(3) #end
         #debug str(Fact(10))
         #debug str(Fib(15))
         #debug str(Quad(1.5)) + \" \" + str(Inner())
         sphere { <0, 0, 0>, Fact(3) }",
    );
    assert_eq!(debug(&l), ["3628800", "610", "6 6"]);
    // A value macro as a property's value.
    let l = load(
        "#macro Fact(N) #if (N <= 1) 1 #else N * Fact(N - 1) #end #end
         sphere { <0, 0, 0>, Fact(10) }",
    );
    assert_eq!(
        spheres(&l.scene.as_ref().unwrap().objects)[0].1,
        3_628_800.0
    );
}

/// A macro called as a statement still puts its objects where it stands, and a value its body
/// yields goes to the block around the call (POV-Ray's textual substitution).
#[test]
fn statement_calls_keep_their_meaning() {
    let l = load(&format!(
        "{MACROS}
         #macro Row(N) #for (I, 1, N) sphere {{ <I, 0, 0>, 0.25 }} #end #end
         Row(3)
         union {{ Row(2) translate <0, 1, 0> }}
         sphere {{ <0, 0, 0>, Radius(7) }}
         Ball(2)"
    ));
    let s = spheres(&l.scene.as_ref().unwrap().objects);
    let xs: Vec<f64> = s.iter().map(|(c, _)| c.x).collect();
    assert_eq!(xs, [1.0, 2.0, 3.0, 1.0, 2.0, 0.0, 0.0]);
    assert!((s[5].1 - 0.7).abs() < 1e-12);
    assert_eq!(s[6].1, 2.0);
}

/// Runaway recursion of a value macro ends with the depth diagnostic at a span, not a crash;
/// a deep but finite one (200 levels, under the default 256) is fine.
#[test]
fn runaway_value_recursion_is_the_depth_error() {
    let l = load_source(
        "t.scn",
        "#macro Down(N) Down(N - 1) + 1 #end\n#declare T = Down(3);\n",
        &EvalOptions::default(),
    );
    assert!(l.has_errors());
    let d = &l.diagnostics[0];
    assert!(
        d.message.contains("macro calls nested deeper than 256"),
        "{}",
        d.message
    );
    assert!(!d.span.is_detached());
    let l = load(
        "#macro Sum(N) #if (N <= 0) 0 #else N + Sum(N - 1) #end #end
         #debug str(Sum(200))
         sphere { <0, 0, 0>, 1 }",
    );
    assert_eq!(debug(&l), ["20100"]);
}
