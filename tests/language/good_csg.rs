//! Good CSG scenes: the evaluated `Scene` holds the tree the text describes, with POV-Ray's
//! material rules (a shape keeps its own material; a material on an operation goes to the
//! shapes below it that have none, the nearest operation's first).

use glam::{DAffine3, DVec3};
use sppm_lang::EvalOptions;
use sppm_lang::internals::eval::load_source;
use sppm_lang::internals::scene::*;

fn scene(text: &str) -> Scene {
    let l = load_source("csg.scn", text, &EvalOptions::default());
    assert!(
        l.diagnostics.is_empty(),
        "{}",
        sppm_lang::render_plain(&l.sources, &l.diagnostics, 100)
    );
    l.scene.expect("scene")
}

fn csg(o: &Object) -> &Csg {
    match &o.shape {
        ShapeDecl::Csg(c) => c,
        s => panic!("expected a CSG, found a {}", s.kind()),
    }
}

fn albedo(s: &Scene, id: MaterialId) -> f64 {
    match s.material(id) {
        Material::Diffuse {
            albedo: ColorParam::Const(c),
        } => c.x,
        m => panic!("{m:?}"),
    }
}

#[test]
fn merge_keeps_own_materials_and_gives_its_own_to_the_rest() {
    let s = scene(
        "merge {
            sphere { <0, 0, 0>, 1  material { diffuse 0.1 } }
            sphere { <1, 0, 0>, 1 }
            material { diffuse 0.2 }
            translate <0, 2, 0>
        }",
    );
    assert_eq!(s.objects.len(), 1);
    let c = csg(&s.objects[0]);
    assert_eq!(c.op, CsgOp::Merge);
    assert_eq!(c.children.len(), 2);
    assert_eq!(albedo(&s, c.children[0].material), 0.1);
    assert_eq!(albedo(&s, c.children[1].material), 0.2);
    // The transform is the operation's; its children keep their own (none here).
    assert_eq!(
        s.objects[0].transform,
        DAffine3::from_translation(DVec3::new(0.0, 2.0, 0.0))
    );
    assert!(c.children.iter().all(|k| k.transform == DAffine3::IDENTITY));
    assert!(matches!(c.children[1].shape, ShapeDecl::Sphere { center, .. } if center == DVec3::X));
}

#[test]
fn intersection_of_two_spheres_is_a_lens() {
    let s = scene(
        "intersection {
            sphere { <0, 0, -0.8>, 1 }
            sphere { <0, 0, 0.8>, 1 }
            material { glass ior 1.5 }
        }",
    );
    let c = csg(&s.objects[0]);
    assert_eq!(c.op, CsgOp::Intersection);
    assert_eq!(c.children.len(), 2);
    for k in &c.children {
        assert!(matches!(s.material(k.material), Material::Glass { ior, .. } if *ior == 1.5));
    }
}

#[test]
fn difference_keeps_order_and_a_child_union_is_one_operand() {
    let s = scene(
        "difference {
            box { <-1, -1, -1>, <1, 1, 1> }
            union { sphere { <0, 1, 0>, 0.5 } sphere { <0, -1, 0>, 0.5 } }
            cylinder { <0, -2, 0>, <0, 2, 0>, 0.2  scale 2 }
        }",
    );
    assert_eq!(s.objects.len(), 1);
    let c = csg(&s.objects[0]);
    assert_eq!(c.op, CsgOp::Difference);
    assert_eq!(c.children.len(), 3);
    assert_eq!(c.children[0].shape.kind(), "box");
    let u = csg(&c.children[1]);
    assert_eq!(u.op, CsgOp::Union);
    assert_eq!(u.children.len(), 2);
    assert_eq!(c.children[2].shape.kind(), "cylinder");
    assert_eq!(
        c.children[2].transform,
        DAffine3::from_scale(DVec3::splat(2.0))
    );
}

#[test]
fn inverse_wraps_a_shape_or_an_operation() {
    let s = scene(
        "sphere { <0, 0, 0>, 1 inverse }
         merge { sphere { <0, 0, 0>, 1 } sphere { <1, 0, 0>, 1 } inverse translate <0, 1, 0> }",
    );
    assert_eq!(s.objects.len(), 2);
    let a = csg(&s.objects[0]);
    assert_eq!(a.op, CsgOp::Inverse);
    assert_eq!(a.children.len(), 1);
    assert_eq!(a.children[0].shape.kind(), "sphere");
    let b = csg(&s.objects[1]);
    assert_eq!(b.op, CsgOp::Inverse);
    assert_eq!(csg(&b.children[0]).op, CsgOp::Merge);
    // The transform goes on the outermost node, once.
    assert_eq!(s.objects[1].transform, DAffine3::from_translation(DVec3::Y));
    assert_eq!(b.children[0].transform, DAffine3::IDENTITY);
}

#[test]
fn nested_materials_come_from_the_nearest_operation() {
    let s = scene(
        "#declare A = material { diffuse 0.3 }
         merge {
            difference { sphere { <0, 0, 0>, 1 } sphere { <0, 0, 0>, 0.5 } material { A } }
            box { <0, 0, 0>, <1, 1, 1> }
            box { <1, 0, 0>, <2, 1, 1> material { diffuse 0.7 } }
            material { diffuse 0.4 }
         }",
    );
    let c = csg(&s.objects[0]);
    let d = csg(&c.children[0]);
    assert_eq!(albedo(&s, d.children[0].material), 0.3);
    assert_eq!(albedo(&s, d.children[1].material), 0.3);
    assert_eq!(albedo(&s, c.children[1].material), 0.4);
    assert_eq!(albedo(&s, c.children[2].material), 0.7);
}

#[test]
fn declared_csg_objects_are_reused_and_top_level_unions_stay_flat() {
    let s = scene(
        "#declare Lens = intersection { sphere { <0, 0, -0.8>, 1 } sphere { <0, 0, 0.8>, 1 } }
         object { Lens translate <-2, 0, 0> }
         object { Lens translate <2, 0, 0> }
         union { sphere { <0, 0, 0>, 1 } sphere { <1, 0, 0>, 1 } }",
    );
    assert_eq!(s.objects.len(), 4);
    assert_eq!(csg(&s.objects[0]).op, CsgOp::Intersection);
    assert_eq!(csg(&s.objects[1]).op, CsgOp::Intersection);
    assert_eq!(
        s.objects[1].transform.translation,
        DVec3::new(2.0, 0.0, 0.0)
    );
    assert_eq!(s.objects[2].shape.kind(), "sphere");
    assert_eq!(s.objects[3].shape.kind(), "sphere");
}

#[test]
fn closed_shapes_are_accepted() {
    // A capped cylinder, a revolve closed on the axis, a plane's half-space, a box.
    let s = scene(
        "difference {
            plane { <0, 1, 0>, 1 }
            cylinder { <0, 0, 0>, <0, 1, 0>, 0.5 }
            revolve { profile bezier { <0, 0>, <0.35, 0>, <0.4, 0.3>, <0, 0.6> } }
            box { <-1, -1, -1>, <0, 0, 0> }
        }",
    );
    assert_eq!(csg(&s.objects[0]).children.len(), 4);
    sppm_lang::internals::prepare::PreparedScene::new(&s).expect("prepares");
}
