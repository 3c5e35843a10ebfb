//! Lights: point, spot, area lights (one per emissive shape) and the environment. Each can be sampled for
//! direct lighting at a point (`sample_li`) and for photon emission (`sample_photon`).

mod area;
mod environment;
mod ground;
mod point;
mod spot;

pub use area::{AreaLight, LightSampling};
pub use environment::{EnvironmentLight, Sky};
pub use ground::GroundPhotons;
pub use point::PointLight;
pub use spot::SpotLight;

use glam::{Vec2, Vec3A};

/// Incident light sampled at a receiving point.
#[derive(Debug, Clone, Copy)]
pub struct LightSample {
    /// Unit direction from the receiver toward the light.
    pub wi: Vec3A,
    /// Incident radiance (area lights) or intensity / distance^2 (delta lights).
    pub li: Vec3A,
    /// Solid-angle density; 1 for delta lights.
    pub pdf: f32,
    /// The sampled point on the light and its normal (zero normal for point/spot lights).
    pub p: Vec3A,
    pub n: Vec3A,
    pub delta: bool,
}

/// A photon leaving a light: origin, normal of the emitting surface (zero for delta lights),
/// direction and flux weight `Le |cos| / pdf`.
#[derive(Debug, Clone, Copy)]
pub struct PhotonSample {
    pub p: Vec3A,
    pub n: Vec3A,
    pub dir: Vec3A,
    pub beta: Vec3A,
}

pub enum Light {
    Point(PointLight),
    Spot(SpotLight),
    Area(AreaLight),
    Environment(EnvironmentLight),
}

impl Light {
    /// Emitted power (average over channels), for choosing lights in proportion to power.
    pub fn power(&self) -> f64 {
        let p = match self {
            Light::Point(l) => l.power(),
            Light::Spot(l) => l.power(),
            Light::Area(l) => l.power(),
            Light::Environment(l) => l.power(),
        };
        ((p.x + p.y + p.z) / 3.0) as f64
    }

    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        self.sample_li_from(p, u, false)
    }

    /// [`Light::sample_li`] for a receiver that may lie on this light's own surface
    /// (`on_light`; see [`AreaLight::sample_li_from`]).
    pub fn sample_li_from(&self, p: Vec3A, u: Vec2, on_light: bool) -> Option<LightSample> {
        match self {
            Light::Point(l) => l.sample_li(p),
            Light::Spot(l) => l.sample_li(p),
            Light::Area(l) => l.sample_li_from(p, u, on_light),
            Light::Environment(l) => l.sample_li(p, u),
        }
    }

    /// A constant background colour (pbrt's uniform infinite light).
    pub fn is_uniform_sky(&self) -> bool {
        matches!(
            self,
            Light::Environment(EnvironmentLight {
                sky: Sky::Uniform(_),
                ..
            })
        )
    }

    /// The densities of [`Light::sample_photon`] choosing a photon that leaves the point with
    /// normal `n` (zero for point and spot lights) in unit direction `dir`: per area of the
    /// light (1 for the single point of a delta light) and per solid angle. For the
    /// environment, whose photons start on a disk outside the scene, `p` is a point the photon
    /// passes ([`EnvironmentLight::emission_pdf`]); the other lights ignore it.
    pub fn emission_pdf(&self, p: Vec3A, n: Vec3A, dir: Vec3A) -> (f32, f32) {
        use std::f32::consts::{FRAC_1_PI, PI};
        match self {
            Light::Point(_) => (1.0, 0.25 * FRAC_1_PI),
            Light::Spot(l) => {
                let inside = dir.dot(l.frame.n) >= l.cos_total;
                let pdf = crate::sampling::uniform_cone_pdf(l.cos_total);
                (1.0, if inside { pdf } else { 0.0 })
            }
            Light::Area(l) => {
                let cos = n.dot(dir);
                let dir_pdf = if l.two_sided {
                    cos.abs() / (2.0 * PI)
                } else {
                    cos.max(0.0) / PI
                };
                (1.0 / l.area, dir_pdf)
            }
            Light::Environment(l) => l.emission_pdf(p, dir),
        }
    }

    /// Point and spot lights: a single point, which no ray can hit.
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_))
    }

    pub fn sample_photon(&self, u1: Vec2, u2: Vec2) -> Option<PhotonSample> {
        match self {
            Light::Point(l) => l.sample_photon(u1),
            Light::Spot(l) => l.sample_photon(u1),
            Light::Area(l) => l.sample_photon(u1, u2),
            Light::Environment(l) => l.sample_photon(u1, u2),
        }
    }
}
