//! Baking a scene object into world-space shapes: shapes whose transform is a similarity
//! (translate, rotate, uniform scale) are transformed exactly into their own kind; any other
//! transform wraps the object-space shape in a [`Transformed`].

use std::sync::Arc;

use glam::{DMat3, DVec3, Vec3A};
use rayon::prelude::*;

use crate::scene;
use crate::shapes::Shape;
use crate::shapes::blob::Blob;
use crate::shapes::cone::Cone;
use crate::shapes::cuboid::cuboid_faces;
use crate::shapes::cylinder::Cylinder;
use crate::shapes::disk::Disk;
use crate::shapes::height_field::HeightField;
use crate::shapes::isosurface::Isosurface;
use crate::shapes::mesh::TriangleMesh;
use crate::shapes::patch::BezierPatch;
use crate::shapes::plane::Plane;
use crate::shapes::primitive::AnyShape;
use crate::shapes::prism::Prism;
use crate::shapes::quad::Quad;
use crate::shapes::revolve::Revolve;
use crate::shapes::sphere::Sphere;
use crate::shapes::sphere_sweep::SphereSweep;
use crate::shapes::superellipsoid::Superellipsoid;
use crate::shapes::torus::Torus;
use crate::shapes::transformed::Transformed;
use crate::shapes::triangle::Triangle;

/// Uniform scale, rotation (possibly mirrored) and translation: returns the scale.
fn similarity_scale(m: &DMat3) -> Option<f64> {
    let (a, b, c) = (m.x_axis, m.y_axis, m.z_axis);
    let s = a.length();
    let tol = 1e-9 * s.max(1e-300);
    let ok = (b.length() - s).abs() <= tol * 10.0
        && (c.length() - s).abs() <= tol * 10.0
        && a.dot(b).abs() <= tol * s * 10.0
        && a.dot(c).abs() <= tol * s * 10.0
        && b.dot(c).abs() <= tol * s * 10.0;
    (ok && s > 0.0 && s.is_finite()).then_some(s)
}

pub(super) fn v(p: DVec3) -> Vec3A {
    p.as_vec3a()
}

/// The determinant of the object's transform, when it is not singular.
fn determinant(obj: &scene::Object) -> Result<f64, String> {
    let det = obj.transform.matrix3.determinant();
    if !(det.is_finite() && det.abs() > 1e-300) {
        return Err("the object's transform is singular (a zero scale?)".into());
    }
    Ok(det)
}

/// The world-space mesh of a mesh object, its triangles rewound if `reverse`.
pub(super) fn build_mesh(
    obj: &scene::Object,
    mesh: &scene::MeshData,
    reverse: bool,
) -> Result<TriangleMesh, String> {
    determinant(obj)?;
    let m = TriangleMesh::with_winding(mesh, &obj.transform, reverse)?;
    if m.is_empty() {
        return Err(format!("mesh `{}` has no triangles", mesh.path.display()));
    }
    Ok(m)
}

/// An object-space shape under the object's transform. A concrete `S` (a revolve's part, a
/// patch's piece) is called directly by its [`Transformed`], without a second dynamic call.
fn placed<S: Shape + ?Sized + 'static>(s: Arc<S>, obj: &scene::Object) -> Result<AnyShape, String> {
    Ok(AnyShape::Other(Box::new(Transformed::new(
        s,
        obj.transform.as_affine3a(),
    )?)))
}

/// The isosurfaces a prepared scene holds, with their objects' spans: their counts of rays
/// given up ([`Isosurface::exhausted`]) are reported when a render ends.
pub(super) type Isosurfaces = Vec<(Arc<Isosurface>, crate::span::Span)>;

/// World-space shapes of one object; its isosurface, if it is one, also goes into `isos`.
pub(super) fn build_shapes(
    obj: &scene::Object,
    isos: &mut Isosurfaces,
) -> Result<Vec<AnyShape>, String> {
    let xf = &obj.transform;
    let m = xf.matrix3;
    let det = determinant(obj)?;
    let nmat = m.inverse().transpose();
    let mirrored = det < 0.0;
    let sim = similarity_scale(&m);
    let wrap = |s: Arc<dyn Shape>| placed(s, obj);
    let quad = |o: DVec3, u: DVec3, w: DVec3| -> Result<AnyShape, String> {
        let (u, w) = if mirrored { (w, u) } else { (u, w) };
        let o2 = xf.transform_point3(o);
        Ok(AnyShape::Quad(Quad::new(
            v(o2),
            v(xf.transform_vector3(u)),
            v(xf.transform_vector3(w)),
        )?))
    };
    // A cylinder's or cone's side (radii at base and cap) and its end caps, a cap of radius 0
    // (a cone's point) left out.
    let axial = |base: DVec3,
                 cap: DVec3,
                 (r0, r1): (f64, f64),
                 open: bool,
                 cone: bool|
     -> Result<Vec<AnyShape>, String> {
        let axis = cap - base;
        let caps: Vec<(DVec3, DVec3, f64)> = if open {
            vec![]
        } else {
            [(base, -axis, r0), (cap, axis, r1)]
                .into_iter()
                .filter(|c| c.2 > 0.0)
                .collect()
        };
        let mut out = Vec::new();
        match sim {
            Some(s) => {
                let (b, c) = (xf.transform_point3(base), xf.transform_point3(cap));
                out.push(if cone {
                    AnyShape::Other(Box::new(Cone::new(b, c, r0 * s, r1 * s)?))
                } else {
                    AnyShape::Cylinder(Cylinder::new(v(b), v(c), (r0 * s) as f32)?)
                });
                for (p, n, r) in caps {
                    out.push(AnyShape::Disk(Disk::new(
                        v(xf.transform_point3(p)),
                        v(nmat * n),
                        (r * s) as f32,
                    )?));
                }
            }
            None => {
                out.push(if cone {
                    wrap(Arc::new(Cone::new(base, cap, r0, r1)?))?
                } else {
                    wrap(Arc::new(Cylinder::new(v(base), v(cap), r0 as f32)?))?
                });
                for (p, n, r) in caps {
                    out.push(wrap(Arc::new(Disk::new(v(p), v(n), r as f32)?))?);
                }
            }
        }
        Ok(out)
    };
    Ok(match &obj.shape {
        scene::ShapeDecl::Sphere { center, radius } => match sim {
            Some(s) => vec![AnyShape::Sphere(Sphere::with_frame(
                v(xf.transform_point3(*center)),
                (radius * s) as f32,
                glam::Mat3A::from(((m / s).transpose()).as_mat3()),
            )?)],
            None => vec![wrap(Arc::new(Sphere::new(v(*center), *radius as f32)?))?],
        },
        scene::ShapeDecl::Plane { normal, offset } => {
            let p0 = xf.transform_point3(*normal * *offset / normal.length_squared().max(1e-300));
            let n = (nmat * *normal).normalize_or_zero();
            vec![AnyShape::Plane(Plane::new(v(n), n.dot(p0) as f32)?)]
        }
        scene::ShapeDecl::Quad {
            origin,
            edge_u,
            edge_v,
        } => vec![quad(*origin, *edge_u, *edge_v)?],
        scene::ShapeDecl::Box { min, max } => {
            let to_world = |p: Vec3A| v(xf.transform_point3(p.as_dvec3()));
            cuboid_faces(v(*min), v(*max), to_world, mirrored)?
                .into_iter()
                .map(AnyShape::Quad)
                .collect()
        }
        scene::ShapeDecl::Disk {
            center,
            normal,
            radius,
        } => match sim {
            Some(s) => vec![AnyShape::Disk(Disk::new(
                v(xf.transform_point3(*center)),
                v(nmat * *normal),
                (radius * s) as f32,
            )?)],
            None => vec![wrap(Arc::new(Disk::new(
                v(*center),
                v(*normal),
                *radius as f32,
            )?))?],
        },
        scene::ShapeDecl::Cylinder {
            base,
            cap,
            radius,
            open,
        } => axial(*base, *cap, (*radius, *radius), *open, false)?,
        scene::ShapeDecl::Cone {
            base,
            base_radius,
            cap,
            cap_radius,
            open,
        } => axial(*base, *cap, (*base_radius, *cap_radius), *open, true)?,
        scene::ShapeDecl::Torus { major, minor } => {
            vec![wrap(Arc::new(Torus::new(*major, *minor)?))?]
        }
        scene::ShapeDecl::Triangle { vertices } => {
            let mut p = vertices.map(|q| v(xf.transform_point3(q)));
            if mirrored {
                p.swap(1, 2);
            }
            vec![AnyShape::Triangle(Triangle::new(p, None, None)?)]
        }
        scene::ShapeDecl::Mesh { mesh } => build_mesh(obj, mesh, false)?
            .triangles()
            .into_par_iter()
            .map(AnyShape::Triangle)
            .collect(),
        scene::ShapeDecl::Revolve {
            profile,
            sweep,
            method,
        } => Revolve::new(profile, *sweep, *method)?
            .split()
            .into_iter()
            .map(|part| placed(Arc::new(part), obj))
            .collect::<Result<_, _>>()?,
        scene::ShapeDecl::BezierPatch { points, method } => BezierPatch::new(points, *method)?
            .split()
            .into_iter()
            .map(|piece| placed(Arc::new(piece), obj))
            .collect::<Result<_, _>>()?,
        scene::ShapeDecl::Prism(p) => vec![wrap(Arc::new(Prism::new(p)?))?],
        scene::ShapeDecl::Superellipsoid { e, n } => {
            vec![wrap(Arc::new(Superellipsoid::new(*e, *n)?))?]
        }
        scene::ShapeDecl::Blob(b) => vec![wrap(Arc::new(Blob::new(b)?))?],
        scene::ShapeDecl::Isosurface(i) => {
            let iso = Arc::new(Isosurface::new(i)?);
            isos.push((iso.clone(), obj.span));
            vec![wrap(iso)?]
        }
        scene::ShapeDecl::HeightField(h) => vec![wrap(Arc::new(HeightField::new(h)?))?],
        scene::ShapeDecl::SphereSweep(s) => vec![wrap(Arc::new(SphereSweep::new(s)?))?],
        // Built whole by `csg::build_csg`, which gives its parts their own ids.
        scene::ShapeDecl::Csg(_) => return Err("a CSG object is not one of a CSG's shapes".into()),
    })
}
