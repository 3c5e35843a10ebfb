//! Building the lights of a prepared scene that are not emissive shapes: point and spot
//! lights, validated, and the environment light of a non-black background; and the boxes
//! around the emissive shapes ([`LightBounds`]). And the prepared scene's light queries: the
//! area light of a primitive, a light's photons, the environment light and the background.

use glam::Vec3A;

use super::shapes::v;
use super::{NO_LIGHT, PreparedScene};
use crate::accel::Bvh;
use crate::diag::Diagnostic;
use crate::geometry::{Aabb, Ray};
use crate::lights::{
    AreaLight, EnvironmentLight, GroundPhotons, Light, PhotonSample, PointLight, Sky, SpotLight,
};
use crate::scene::{self, Scene};
use crate::shapes::Shape;
use crate::textures;

/// Boxes around the primitives of the area lights, padded: a ray that misses them all cannot
/// end on an area light. Direct lighting's BSDF sample adds light only where its ray ends on
/// one (or, with an environment light, escapes), so it skips the closest-hit search for the
/// others: in the Cornell box most of them (that search was a third of a camera path's cost).
#[derive(Debug, Clone, Default)]
pub(super) struct LightBounds {
    boxes: Vec<Aabb>,
}

/// The most boxes kept apart; more lights share one box around them all.
const LIGHT_BOXES: usize = 8;

impl LightBounds {
    /// The boxes of the emissive primitives' `bounds` (one per primitive).
    pub(super) fn new(bounds: Vec<Aabb>) -> Self {
        let mut boxes = bounds;
        if boxes.len() > LIGHT_BOXES {
            let all = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
            boxes = vec![all];
        }
        // Padded well beyond rounding (a shape's hit point, the slab test's arithmetic): the
        // test must never miss a box the closest hit lies in. A box that is not finite keeps
        // every ray (a NaN or infinite bound compares false below).
        for b in &mut boxes {
            let reach = b.min.abs().max(b.max.abs()).max_element();
            let pad = 1e-3 * b.diagonal().max_element() + 1e-5 * reach + 1e-6;
            *b = Aabb::new(b.min - Vec3A::splat(pad), b.max + Vec3A::splat(pad));
        }
        LightBounds { boxes }
    }

    /// Whether `ray` (from its origin on, without end) may meet a box.
    #[inline]
    pub(super) fn may_reach(&self, ray: &Ray) -> bool {
        let inv = ray.d.recip();
        self.boxes.iter().any(|b| {
            let t0 = (b.min - ray.o) * inv;
            let t1 = (b.max - ray.o) * inv;
            let near = t0.min(t1).max_element().max(0.0);
            let far = t0.max(t1).min_element();
            // Not `near <= far`: a NaN (a zero direction component with the origin on a
            // slab's plane) compares as nothing and keeps the ray.
            near.partial_cmp(&(far * 1.000_01 + 1e-30)) != Some(std::cmp::Ordering::Greater)
        })
    }
}

/// Appends the scene's point and spot lights to `lights`.
pub(super) fn push_scene_lights(scene: &Scene, lights: &mut Vec<Light>) -> Result<(), Diagnostic> {
    let color3 = |c: glam::DVec3| c.as_vec3a();
    for l in &scene.lights {
        match l {
            scene::LightDecl::Point {
                position,
                intensity,
                span,
            } => {
                if !(position.is_finite()
                    && intensity.is_finite()
                    && intensity.min_element() >= 0.0)
                {
                    return Err(Diagnostic::error(
                        *span,
                        "point light: position and intensity must be finite, intensity non-negative",
                    )
                    .with_help(
                        "give a finite position and an intensity of finite numbers of at least 0",
                    ));
                }
                lights.push(Light::Point(PointLight {
                    position: v(*position),
                    intensity: color3(*intensity),
                }))
            }
            scene::LightDecl::Spot {
                position,
                direction,
                intensity,
                cone_angle,
                falloff_angle,
                span,
            } => {
                // Normalised in f64 first: a direction of length 1e-50 is a direction, though
                // it is zero in f32 (and its squared length underflows).
                let unit = crate::scene::scaled_unit(*direction);
                let direction = &unit.unwrap_or(glam::DVec3::ZERO);
                if !(position.is_finite()
                    && intensity.is_finite()
                    && intensity.min_element() >= 0.0
                    && unit.is_some()
                    && *cone_angle > 0.0
                    && *cone_angle <= 90.0
                    && (0.0..=*cone_angle).contains(falloff_angle))
                {
                    return Err(Diagnostic::error(
                        *span,
                        "spot light: invalid position, direction, intensity or angle",
                    )
                    .with_help(
                        "give a finite position, a non-zero direction, an intensity of at least \
                         0, a cone angle in (0, 90] degrees and a falloff from 0 to it (as the \
                         language does)",
                    ));
                }
                lights.push(Light::Spot(SpotLight::new(
                    v(*position),
                    v(*direction),
                    color3(*intensity),
                    *cone_angle as f32,
                    *falloff_angle as f32,
                )))
            }
        }
    }
    Ok(())
}

/// Appends the environment light of a non-black background (a map, a texture over directions
/// baked into one, or a constant colour:
/// pbrt's uniform infinite light, so photons carry the light a path tracer gets from the
/// background); returns its index.
pub(super) fn push_environment(scene: &Scene, bvh: &Bvh, lights: &mut Vec<Light>) -> Option<usize> {
    let sky = match &scene.background {
        scene::Background::Environment {
            image,
            intensity,
            transform,
        } => {
            let map = textures::EnvironmentMap::new(image, *intensity, *transform);
            (!map.is_black()).then(|| Sky::Map(Box::new(map)))
        }
        // A texture over directions is baked into a map: sampled like a loaded image.
        scene::Background::Texture(id) => {
            let texture = scene.textures.get(id.0 as usize)?;
            let image = textures::sky::bake(texture);
            let map = textures::EnvironmentMap::new(&image, 1.0, glam::DAffine3::IDENTITY);
            (!map.is_black()).then(|| Sky::Map(Box::new(map)))
        }
        scene::Background::Color(c) => {
            let c = c.as_vec3a();
            (c.is_finite() && c.min_element() >= 0.0 && c.max_element() > 0.0)
                .then_some(Sky::Uniform(c))
        }
    }?;
    // Bounding sphere of the finite shapes (planes excluded), as pbrt's infinite lights use
    // for photon emission.
    let b = bvh.bounds();
    let (center, radius) = if b.is_empty() {
        (Vec3A::ZERO, 1.0)
    } else {
        (b.centroid(), 0.5 * b.diagonal().length())
    };
    lights.push(Light::Environment(EnvironmentLight::new(
        sky, center, radius,
    )));
    Some(lights.len() - 1)
}

/// The far-part photon emitters ([`GroundPhotons`]) of the scene's infinite planes under the
/// environment light `environment` (none without one). `prim_object` maps primitive ids to
/// objects; planes inside CSG objects are not among the scene's objects and get none.
pub(super) fn ground_photons(
    scene: &Scene,
    prim_object: &[u32],
    lights: &[Light],
    environment: Option<usize>,
) -> Vec<GroundPhotons> {
    let Some(Light::Environment(env)) = environment.and_then(|i| lights.get(i)) else {
        return Vec::new();
    };
    let env_index = environment.unwrap_or(0);
    prim_object
        .iter()
        .enumerate()
        .filter_map(|(prim, &oi)| {
            let o = scene.objects.get(oi as usize)?;
            let scene::ShapeDecl::Plane { normal, offset } = o.shape else {
                return None;
            };
            let n = (o.transform.matrix3.inverse().transpose() * normal).normalize();
            let point = o.transform.transform_point3(normal * offset);
            GroundPhotons::new(
                env_index,
                prim as u32,
                v(n),
                v(point),
                env.center,
                env.radius,
            )
        })
        .collect()
}

/// Warnings for the one-sided flat area lights (quads, disks, triangles) with nothing on their
/// emitting side: all finite geometry lies behind or in the light's plane, and so does every
/// infinite plane (parallel to it). Such a light lights nothing; its normal was most likely
/// meant the other way. A light of several pieces (an emissive mesh) is named once, when none
/// of its pieces faces anything. The test uses the scene's bounding box, so it never warns
/// about a light that lights something; a tilted light beside a scene of scattered objects
/// may go unnamed.
pub(super) fn facing_away(prepared: &PreparedScene) -> Vec<Diagnostic> {
    let scene = prepared.scene;
    let b = prepared.bvh.bounds();
    // Infinite planes, as (unit normal, a point), in world space; an unbounded shape that is
    // not a plane object (a CSG part) could be anywhere: then no warning at all.
    let mut planes = Vec::new();
    for o in &scene.objects {
        if let scene::ShapeDecl::Plane { normal, offset } = o.shape {
            let n = (o.transform.matrix3.inverse().transpose() * normal).normalize();
            planes.push((n, o.transform.transform_point3(normal * offset)));
        }
    }
    if planes.len() != prepared.bvh.unbounded_len() {
        return Vec::new();
    }
    let corners: Vec<glam::DVec3> = if b.is_empty() {
        Vec::new()
    } else {
        (0..8)
            .map(|k| {
                let pick = |bit: usize, lo: f32, hi: f32| if k & bit == 0 { lo } else { hi };
                glam::DVec3::new(
                    pick(1, b.min.x, b.max.x) as f64,
                    pick(2, b.min.y, b.max.y) as f64,
                    pick(4, b.min.z, b.max.z) as f64,
                )
            })
            .collect()
    };
    let extent = corners
        .iter()
        .chain(planes.iter().map(|p| &p.1))
        .fold(1.0f64, |m, c| m.max(c.abs().max_element()));
    let tol = 1e-5 * extent;
    // Per object: whether one of its pieces faces something, and whether any was tested.
    let mut verdict: Vec<Option<bool>> = vec![None; scene.objects.len()];
    for (prim, &li) in prepared.prim_light.iter().enumerate() {
        let Some(Light::Area(light)) = prepared.lights.get(li as usize) else {
            continue;
        };
        let oi = prepared.prim_object[prim] as usize;
        if light.two_sided || verdict.get(oi).copied().flatten() == Some(true) {
            continue;
        }
        let samples: Vec<_> = [[0.2, 0.3], [0.7, 0.2], [0.4, 0.8]]
            .iter()
            .filter_map(|u| light.shape.sample(glam::Vec2::from(*u)))
            .collect();
        let Some(first) = samples.first() else {
            continue;
        };
        let n = first.n.as_dvec3();
        let flat = samples.len() == 3
            && samples.iter().all(|s| {
                s.n.as_dvec3().dot(n) > 1.0 - 1e-6 && (s.p - first.p).as_dvec3().dot(n).abs() <= tol
            });
        let p = first.p.as_dvec3();
        // The camera counts: a sign that faces the viewer is seen, whatever it lights.
        let faces_something = !flat
            || corners
                .iter()
                .chain([&scene.camera.location])
                .any(|c| n.dot(*c - p) > tol)
            || planes
                .iter()
                .any(|(pn, pp)| pn.dot(n).abs() < 1.0 - 1e-9 || n.dot(*pp - p) > tol);
        if let Some(v) = verdict.get_mut(oi) {
            *v = Some(faces_something);
        }
    }
    verdict
        .iter()
        .enumerate()
        .filter(|(_, v)| **v == Some(false))
        .map(|(oi, _)| {
            Diagnostic::warning(
                scene.objects[oi].span,
                "this area light faces away from everything: it emits only on the side its \
                 normal points to, and nothing is there",
            )
            .with_label("lights nothing")
            .with_help(
                "turn it around (swap a quad's two edges or a triangle's last two points; negate \
                 a disk's normal) or add `two_sided`",
            )
        })
        .collect()
}

impl PreparedScene<'_> {
    /// The area light a primitive belongs to.
    #[inline]
    pub fn area_light(&self, prim: u32) -> Option<(usize, &AreaLight)> {
        let l = *self.prim_light.get(prim as usize)?;
        if l == NO_LIGHT {
            return None;
        }
        match &self.lights[l as usize] {
            Light::Area(a) => Some((l as usize, a)),
            _ => None,
        }
    }

    /// A photon from light `li` ([`Light::sample_photon`]), for `u1` and `u2` in [0,1)^2.
    /// A rectangle's photons come from its [`super::emitters::QuadEmitter`] (the same photons).
    #[inline]
    pub fn sample_photon(&self, li: usize, u1: glam::Vec2, u2: glam::Vec2) -> Option<PhotonSample> {
        match self.quad_emitters.get(li) {
            Some(Some(e)) => e.sample_photon(u1, u2),
            _ => self.lights.get(li)?.sample_photon(u1, u2),
        }
    }

    /// The radiance a ray leaving the scene in direction `dir` sees: the environment light's (a
    /// map or a background colour), or black.
    #[inline]
    pub fn background_radiance(&self, dir: Vec3A) -> Vec3A {
        match self.environment_light() {
            Some((_, env)) => env.le(dir),
            None => Vec3A::ZERO,
        }
    }

    /// The environment light and its index in `lights`.
    #[inline]
    pub fn environment_light(&self) -> Option<(usize, &EnvironmentLight)> {
        let i = self.environment?;
        match &self.lights[i] {
            Light::Environment(e) => Some((i, e)),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{EvalOptions, load_source};

    /// How many "faces away" warnings a scene gets.
    fn facing_away_count(text: &str) -> usize {
        let l = load_source("t.scn", text, &EvalOptions::default());
        let scene = l.scene.unwrap_or_else(|| panic!("{:?}", l.diagnostics));
        let prepared = PreparedScene::new(&scene).expect("prepares");
        let warnings = prepared.warnings();
        warnings
            .iter()
            .filter(|w| w.message.contains("faces away"))
            .inspect(|w| assert!(w.is_placed(), "{}", w.message))
            .count()
    }

    /// A flat light with nothing on its emitting side is named, whatever its shape and
    /// transform; one that lights something (directly, through an infinite plane in front of it
    /// or tilted against it, or on its other side when two-sided) is not.
    #[test]
    fn a_light_facing_away_from_everything_is_named() {
        let room = "camera { location <0, 1, -4> look_at <0, 0.5, 0> }\n\
                    sphere { <0, 0.5, 0>, 0.5 material { diffuse rgb 0.5 } }\n";
        let floor = "plane { y, 0 material { diffuse rgb 0.8 } }\n";
        let cases = [
            // Quads 3 units up: normal up (edges z then x) faces away; x then z faces down.
            (
                "area_light { quad { <-0.5, 3, -0.5>, <0, 0, 1>, <1, 0, 0> } radiance rgb 10 }",
                true,
                1,
            ),
            (
                "area_light { quad { <-0.5, 3, -0.5>, <1, 0, 0>, <0, 0, 1> } radiance rgb 10 }",
                true,
                0,
            ),
            (
                "area_light { quad { <-0.5, 3, -0.5>, <0, 0, 1>, <1, 0, 0> } radiance rgb 10 two_sided }",
                true,
                0,
            ),
            (
                "area_light { quad { <-0.5, 3, -0.5>, <0, 0, 1>, <1, 0, 0> } radiance rgb 10 }",
                false,
                1,
            ),
            // The same quad turned over by a rotation, and moved below the floor facing up.
            (
                "area_light { quad { <-0.5, 0, -0.5>, <0, 0, 1>, <1, 0, 0> } radiance rgb 10 rotate <180, 0, 0> translate <0, 3, 0> }",
                true,
                0,
            ),
            (
                "area_light { quad { <-0.5, -1, -0.5>, <0, 0, 1>, <1, 0, 0> } radiance rgb 10 }",
                true,
                0,
            ),
            (
                "area_light { quad { <-0.5, -1, -0.5>, <0, 0, 1>, <1, 0, 0> } radiance rgb 10 }",
                false,
                0,
            ),
            // Disks and triangles.
            (
                "area_light { disk { <0, 3, 0>, <0, 1, 0>, 0.5 } radiance rgb 10 }",
                true,
                1,
            ),
            (
                "area_light { disk { <0, 3, 0>, <0, -1, 0>, 0.5 } radiance rgb 10 }",
                true,
                0,
            ),
            (
                "area_light { triangle { <0, 3, 0>, <0, 3, 1>, <1, 3, 0> } radiance rgb 10 }",
                true,
                1,
            ),
            (
                "area_light { triangle { <0, 3, 0>, <1, 3, 0>, <0, 3, 1> } radiance rgb 10 }",
                true,
                0,
            ),
            // Beside the scene, facing out to the left; facing in.
            (
                "area_light { quad { <-3, 0, -1>, <0, 0, 2>, <0, 2, 0> } radiance rgb 10 }",
                false,
                1,
            ),
            (
                "area_light { quad { <-3, 0, -1>, <0, 2, 0>, <0, 0, 2> } radiance rgb 10 }",
                false,
                0,
            ),
            // A sphere light is never named (it is not flat).
            (
                "area_light { sphere { <0, 3, 0>, 0.2 } radiance rgb 10 }",
                true,
                0,
            ),
        ];
        for (light, with_floor, want) in cases {
            let text = format!("{room}{}{light}\n", if with_floor { floor } else { "" });
            assert_eq!(facing_away_count(&text), want, "{text}");
        }
        // A tilted floor crosses the light's side: lit.
        let tilted = format!(
            "{room}plane {{ <0.2, 1, 0>, 0 }}\n\
             area_light {{ quad {{ <-0.5, 3, -0.5>, <0, 0, 1>, <1, 0, 0> }} radiance rgb 10 }}\n"
        );
        assert_eq!(facing_away_count(&tilted), 0);
        // A sign in front of a wall, facing the camera and nothing else: it is seen, so it is
        // not named; turned to the wall, it is.
        let sign = |edges: &str| {
            format!(
                "camera {{ location <0, 0, -5> look_at <0, 0, 0> }}
                 box {{ <-3, -3, 1>, <3, 3, 1.2> }}
                 area_light {{ quad {{ <-1, -0.5, 0>, {edges} }} radiance rgb 4 }}
"
            )
        };
        assert_eq!(facing_away_count(&sign("<0, 1, 0>, <2, 0, 0>")), 0);
        assert_eq!(facing_away_count(&sign("<2, 0, 0>, <0, 1, 0>")), 0);
        let behind = sign("<2, 0, 0>, <0, 1, 0>").replace("<0, 0, -5>", "<0, 0, 5>");
        assert_eq!(facing_away_count(&behind), 0);
        let unseen = sign("<0, 1, 0>, <2, 0, 0>").replace("<0, 0, -5>", "<0, 0, 5>");
        assert_eq!(facing_away_count(&unseen), 1);
    }
}
