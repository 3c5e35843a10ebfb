//! Building the lights of a prepared scene that are not emissive shapes: point and spot
//! lights, validated, and the environment light of a non-black background.

use glam::Vec3A;

use super::RenderError;
use super::shapes::v;
use crate::accel::Bvh;
use crate::lights::{EnvironmentLight, Light, PointLight, Sky, SpotLight};
use crate::scene::{self, Scene};
use crate::textures;

/// Appends the scene's point and spot lights to `lights`.
pub(super) fn push_scene_lights(scene: &Scene, lights: &mut Vec<Light>) -> Result<(), RenderError> {
    let color3 = |c: glam::DVec3| c.as_vec3a();
    for l in &scene.lights {
        match l {
            scene::Light::Point {
                position,
                intensity,
                span,
            } => {
                if !(position.is_finite()
                    && intensity.is_finite()
                    && intensity.min_element() >= 0.0)
                {
                    return Err(RenderError {
                        message: "point light: position and intensity must be finite, intensity non-negative".into(),
                        span: Some(*span),
                        label: String::new(),
                        help: Some("give a finite position and an intensity of finite numbers of at least 0".into()),
                    });
                }
                lights.push(Light::Point(PointLight {
                    position: v(*position),
                    intensity: color3(*intensity),
                }))
            }
            scene::Light::Spot {
                position,
                direction,
                intensity,
                cone_angle,
                falloff_angle,
                span,
            } => {
                if !(position.is_finite()
                    && intensity.is_finite()
                    && intensity.min_element() >= 0.0
                    && direction.is_finite()
                    && direction.length() > 0.0
                    && *cone_angle > 0.0
                    && *cone_angle <= 90.0
                    && (0.0..=*cone_angle).contains(falloff_angle))
                {
                    return Err(RenderError {
                        message: "spot light: invalid position, direction, intensity or angle"
                            .into(),
                        span: Some(*span),
                        label: String::new(),
                        help: Some(
                            "give a finite position, a non-zero direction, an intensity of at \
                             least 0, a cone angle in (0, 90] degrees and a falloff from 0 to it \
                             (as the language does)"
                                .into(),
                        ),
                    });
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

/// Appends the environment light of a non-black background (a map, or a constant colour:
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
