//! BSDFs. A material evaluated at a hit becomes a [`Bsdf`] (plain `Copy` data, no heap) in a
//! shading frame. Directions are world-space unit vectors pointing away from the surface.

mod bump;
#[cfg(test)]
mod check;
mod coated;
mod conductor;
mod dielectric;
mod diffuse;
pub mod eval;
mod glossy;
mod mirror;
mod rough_dielectric;
#[cfg(test)]
mod tests;
mod thin_dielectric;

use glam::{Vec2, Vec3A};

use crate::geometry::Frame;

/// Which quantity a path carries: camera paths carry radiance, photon paths importance
/// (pbrt's TransportMode). Refraction scales radiance by 1/eta^2 but not importance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

/// The lobes a BSDF has, in local (shading-frame) coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lobes {
    Diffuse {
        albedo: Vec3A,
    },
    Mirror {
        tint: Vec3A,
    },
    /// `eta`: inside over outside index of refraction; `alpha` below
    /// `rough_dielectric::MIN_ALPHA` is smooth glass (delta lobes), else frosted glass's
    /// GGX alpha (rough_dielectric.rs).
    Glass {
        eta: f32,
        tint: Vec3A,
        alpha: f32,
    },
    /// A thin pane of index `eta` (thin_dielectric.rs): reflects, or passes straight through.
    ThinGlass {
        eta: f32,
        tint: Vec3A,
    },
    Glossy {
        albedo: Vec3A,
        specular: Vec3A,
        alpha: f32,
    },
    /// A metal (conductor.rs): complex index `eta + i k` per channel; `alpha` 0 is smooth.
    Conductor {
        eta: Vec3A,
        k: Vec3A,
        alpha: f32,
    },
    /// A dielectric coat of index `eta` over a Lambertian base (plastic); `alpha` zero: a
    /// smooth coat (a delta reflection), else the coat's GGX alpha.
    Coated {
        albedo: Vec3A,
        eta: f32,
        alpha: f32,
    },
}

/// A BSDF at a surface point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bsdf {
    pub lobes: Lobes,
    /// Shading frame (normal = shading normal).
    pub frame: Frame,
    /// Geometric normal; decides reflection vs transmission.
    pub ng: Vec3A,
    /// A bump or normal map's perturbed normal, as a microsurface in the shading frame
    /// (bump.rs); `None` for a surface without one, which pays only this check.
    pub bump: Option<bump::Microsurface>,
}

/// A BSDF's value and both densities for one pair of directions ([`Bsdf::eval`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfEval {
    /// [`Bsdf::f_mode`]`(wo, wi, mode)`.
    pub f: Vec3A,
    /// [`Bsdf::pdf`]`(wo, wi)`: the density of sampling `wi` from `wo`.
    pub pdf: f32,
    /// [`Bsdf::pdf`]`(wi, wo)`: the density of the reverse choice.
    pub pdf_rev: f32,
}

/// Whether a pair's local cosines `co`, `ci` (shading frame) are nonzero and put it on the
/// same side as its geometric test did (`reflect`, the product of its cosines with `ng`).
#[inline]
fn shading_sides_agree(reflect: f32, co: f32, ci: f32) -> bool {
    let local = co * ci;
    local != 0.0 && (local > 0.0) == (reflect > 0.0)
}

/// A sampled direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3A,
    /// `f * |cos| / pdf`: what the path throughput is multiplied by.
    pub weight: Vec3A,
    /// Solid-angle density (meaningless for specular samples).
    pub pdf: f32,
    pub specular: bool,
}

impl Bsdf {
    pub fn new(lobes: Lobes, ns: Vec3A, dpdu: Vec3A, ng: Vec3A) -> Self {
        Self {
            lobes,
            frame: Frame::from_normal_tangent(ns, dpdu),
            ng,
            bump: None,
        }
    }

    /// A BSDF whose lobes sit on facets of normal `np` (world space, a bump or normal map's
    /// perturbed normal) of a microsurface around the normal of the shading frame `frame`
    /// (bump.rs). A normal that does not lean from the shading normal gives the plain BSDF.
    pub fn bumped(lobes: Lobes, frame: Frame, ng: Vec3A, np: Vec3A) -> Self {
        Self {
            lobes,
            frame,
            ng,
            bump: bump::Microsurface::new(frame.to_local(np)),
        }
    }

    /// The bump's perturbed normal in the shading frame, if the BSDF has a bump: with the
    /// lobes, the frame and `ng`, all [`Bsdf::from_parts`] needs to rebuild it (a compact
    /// copy to keep, where the microsurface's derived geometry would take room).
    pub fn bump_normal(&self) -> Option<Vec3A> {
        self.bump.as_ref().map(bump::Microsurface::normal)
    }

    /// The BSDF of these parts, `bump` a [`Bsdf::bump_normal`]: the BSDF it came from, bit
    /// for bit.
    pub fn from_parts(lobes: Lobes, frame: Frame, ng: Vec3A, bump: Option<Vec3A>) -> Self {
        Self {
            lobes,
            frame,
            ng,
            bump: bump.map(bump::Microsurface::from_normal),
        }
    }

    /// Purely specular (delta) BSDFs: camera paths pass through them, photons never deposit.
    pub fn is_specular(&self) -> bool {
        match self.lobes {
            Lobes::Mirror { .. } | Lobes::ThinGlass { .. } => true,
            Lobes::Glass { alpha, .. } => alpha < rough_dielectric::MIN_ALPHA,
            Lobes::Conductor { alpha, .. } => alpha == 0.0,
            Lobes::Diffuse { .. } | Lobes::Glossy { .. } | Lobes::Coated { .. } => false,
        }
    }

    /// Whether [`Bsdf::sample`] may return a delta (specular) sample: a delta BSDF, or a
    /// smooth coat's mirror reflection; bumped or not. Where this is false, no sample is
    /// specular.
    pub fn samples_delta(&self) -> bool {
        match self.lobes {
            Lobes::Coated { alpha, .. } => alpha == 0.0,
            _ => self.is_specular(),
        }
    }

    /// A glossy lobe sharp enough (GGX alpha below 0.3, roughness below about 0.55) that a
    /// density estimate of the light arriving on it is noisy: photon methods follow camera
    /// paths through it, by BSDF sampling, to the next surface (pbrt's SPPM does so for every
    /// glossy surface).
    ///
    /// A coated surface is never specular (photons deposit on its base), and glossy when its
    /// coat is sharp by the same measure or smooth: a smooth coat's mirror reflection is a
    /// delta lobe that `f` leaves out, so a density estimate there would miss it.
    ///
    /// Frosted glass is glossy by the same measure (its reflection and its refraction).
    pub fn is_glossy(&self) -> bool {
        matches!(self.lobes, Lobes::Glossy { alpha, .. } | Lobes::Coated { alpha, .. } if alpha < 0.3)
            || matches!(self.lobes, Lobes::Conductor { alpha, .. } if alpha > 0.0 && alpha < 0.3)
            || matches!(self.lobes, Lobes::Glass { alpha, .. }
                if (rough_dielectric::MIN_ALPHA..0.3).contains(&alpha))
    }

    /// Frosted glass: the one lobe with non-specular transmission.
    fn rough_glass(&self) -> Option<(f32, Vec3A, f32)> {
        self.lobes.rough_glass()
    }

    /// The local directions of a pair whose geometric side (reflection or transmission, by
    /// `ng`) agrees with the shading frame's, for a BSDF that transmits or not.
    #[inline]
    fn local_pair(&self, wo: Vec3A, wi: Vec3A, transmits: bool) -> Option<(Vec3A, Vec3A)> {
        let reflect = self.geometric_sides(wo, wi, transmits)?;
        let (o, i) = (self.frame.to_local(wo), self.frame.to_local(wi));
        shading_sides_agree(reflect, o.z, i.z).then_some((o, i))
    }

    /// [`Self::local_pair`]'s side tests alone: the pair's local cosines (the `z` of its
    /// local directions, bit for bit) where it passes them.
    #[inline]
    fn local_cosines(&self, wo: Vec3A, wi: Vec3A, transmits: bool) -> Option<(f32, f32)> {
        let reflect = self.geometric_sides(wo, wi, transmits)?;
        let (co, ci) = (wo.dot(self.frame.n), wi.dot(self.frame.n));
        shading_sides_agree(reflect, co, ci).then_some((co, ci))
    }

    /// The product of the pair's cosines with `ng` (its sign: reflection or transmission),
    /// where it is not zero and, for a BSDF that does not transmit, the pair is on one side.
    #[inline]
    fn geometric_sides(&self, wo: Vec3A, wi: Vec3A, transmits: bool) -> Option<f32> {
        let reflect = wo.dot(self.ng) * wi.dot(self.ng);
        (!(reflect == 0.0 || (!transmits && reflect < 0.0))).then_some(reflect)
    }

    /// BSDF value for light arriving from `wi` and leaving toward `wo` (radiance transport:
    /// `wo` toward the camera).
    pub fn f(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        self.f_mode(wo, wi, TransportMode::Radiance)
    }

    /// [`Bsdf::f`] for a path carrying `mode`: the two differ only across frosted glass, where
    /// the importance value is the adjoint `f(wi, wo)` (no `1/eta^2`).
    pub fn f_mode(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> Vec3A {
        if let Some(m) = &self.bump {
            let Some((o, i)) = self.local_pair(wo, wi, true) else {
                return Vec3A::ZERO;
            };
            return m.f(&self.lobes, o, i, mode);
        }
        if let Some((eta, tint, alpha)) = self.rough_glass() {
            let Some((o, i)) = self.local_pair(wo, wi, true) else {
                return Vec3A::ZERO;
            };
            return tint * rough_dielectric::eval(eta, alpha, o, i, mode).0;
        }
        // A Lambertian lobe needs the side tests alone.
        if let Lobes::Diffuse { albedo } = self.lobes {
            return match self.local_cosines(wo, wi, false) {
                Some(_) => diffuse::f(albedo),
                None => Vec3A::ZERO,
            };
        }
        let Some((o, i)) = self.local_pair(wo, wi, false) else {
            return Vec3A::ZERO;
        };
        self.lobes.f_reflect(o, i)
    }

    /// The value [`Bsdf::f`] gives for every pair of directions that passes its two side tests,
    /// if it does not depend on the directions (Lambertian reflection): lets a caller that
    /// evaluates one `wo` against many `wi` (SPPM's photon deposits) keep only the two normals
    /// and this value.
    pub fn constant_f(&self) -> Option<Vec3A> {
        if self.bump.is_some() {
            return None;
        }
        match self.lobes {
            Lobes::Diffuse { albedo } => Some(diffuse::f(albedo)),
            _ => None,
        }
    }

    /// Solid-angle density of [`Bsdf::sample`] choosing `wi`.
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if let Some(m) = &self.bump {
            let Some((o, i)) = self.local_pair(wo, wi, true) else {
                return 0.0;
            };
            return m.pdf(&self.lobes, o, i);
        }
        if let Some((eta, _, alpha)) = self.rough_glass() {
            let Some((o, i)) = self.local_pair(wo, wi, true) else {
                return 0.0;
            };
            return rough_dielectric::eval(eta, alpha, o, i, TransportMode::Radiance).1;
        }
        // A Lambertian lobe needs the local cosines alone.
        if let Lobes::Diffuse { .. } = self.lobes {
            return self
                .local_cosines(wo, wi, false)
                .map_or(0.0, |(_, ci)| diffuse::pdf_cos(ci));
        }
        let Some((o, i)) = self.local_pair(wo, wi, false) else {
            return 0.0;
        };
        self.lobes.pdf_reflect(o, i)
    }

    /// [`Bsdf::f_mode`], [`Bsdf::pdf`] and the reverse [`Bsdf::pdf`] of one pair at once, bit
    /// for bit the three calls' values, with one side test and one change to the local frame
    /// where the three take one each (the side tests and the local cosines of a pair are
    /// symmetric in its two directions). `None` where `f` is zero: a caller that needs the
    /// densities only with a nonzero value (a connection, a merge, next-event estimation) is
    /// spared them there.
    #[inline(always)]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> Option<BsdfEval> {
        // A Lambertian lobe needs the local cosines alone.
        if let (None, Lobes::Diffuse { albedo }) = (&self.bump, self.lobes) {
            let (co, ci) = self.local_cosines(wo, wi, false)?;
            let f = diffuse::f(albedo);
            return (f != Vec3A::ZERO).then(|| BsdfEval {
                f,
                pdf: diffuse::pdf_cos(ci),
                pdf_rev: diffuse::pdf_cos(co),
            });
        }
        self.eval_other(wo, wi, mode)
    }

    /// [`Bsdf::eval`] of every BSDF but a plain Lambertian one (a call: the Lambertian case,
    /// the most common, stays small enough to inline).
    #[inline(never)]
    fn eval_other(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> Option<BsdfEval> {
        let rough_glass = self.rough_glass();
        let transmits = self.bump.is_some() || rough_glass.is_some();
        let (o, i) = self.local_pair(wo, wi, transmits)?;
        let (f, pdf, pdf_rev) = if let Some(m) = &self.bump {
            m.eval(&self.lobes, o, i, mode)
        } else if let Some((eta, tint, alpha)) = rough_glass {
            // The density does not depend on the transport mode.
            let (f, pdf) = rough_dielectric::eval(eta, alpha, o, i, mode);
            let f = tint * f;
            if f == Vec3A::ZERO {
                return None;
            }
            let rev = rough_dielectric::eval(eta, alpha, i, o, TransportMode::Radiance).1;
            (f, pdf, rev)
        } else {
            let f = self.lobes.f_reflect(o, i);
            if f == Vec3A::ZERO {
                return None;
            }
            (
                f,
                self.lobes.pdf_reflect(o, i),
                self.lobes.pdf_reflect(i, o),
            )
        };
        // A bump's walk gives its value with a density: tested last.
        (f != Vec3A::ZERO).then_some(BsdfEval { f, pdf, pdf_rev })
    }

    /// Samples an incident direction for outgoing `wo`.
    #[inline]
    pub fn sample(&self, wo: Vec3A, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let o = self.frame.to_local(wo);
        if o.z == 0.0 {
            return None;
        }
        let s = match &self.bump {
            None => self.lobes.sample_local(o, uc, u, mode),
            Some(m) => m.sample(&self.lobes, o, uc, u, mode),
        }?;
        let wi = self.frame.to_world(s.wi);
        // Reject samples whose geometric side disagrees with the local decision (shading
        // normals): reflection must stay on wo's side, refraction must cross.
        let reflect = s.wi.z * o.z > 0.0;
        if (wo.dot(self.ng) * wi.dot(self.ng) > 0.0) != reflect {
            return None;
        }
        if !(s.weight.is_finite() && s.pdf.is_finite()) {
            return None;
        }
        Some(BsdfSample { wi, ..s })
    }
}

impl Lobes {
    /// Frosted glass's parameters: the one lobe with non-specular transmission.
    fn rough_glass(&self) -> Option<(f32, Vec3A, f32)> {
        match *self {
            Lobes::Glass { eta, tint, alpha } if alpha >= rough_dielectric::MIN_ALPHA => {
                Some((eta, tint, alpha))
            }
            _ => None,
        }
    }

    /// `f` in the local frame for a pair on one side (`o.z * i.z > 0`), for every lobe but
    /// frosted glass's.
    #[inline]
    fn f_reflect(&self, o: Vec3A, i: Vec3A) -> Vec3A {
        match *self {
            Lobes::Diffuse { albedo } => diffuse::f(albedo),
            Lobes::Glossy {
                albedo,
                specular,
                alpha,
            } => glossy::f(albedo, specular, alpha, o, i),
            Lobes::Conductor { eta, k, alpha } => conductor::f(eta, k, alpha, o, i),
            Lobes::Coated { albedo, eta, alpha } => coated::f(albedo, eta, alpha, o, i),
            Lobes::Mirror { .. } | Lobes::Glass { .. } | Lobes::ThinGlass { .. } => Vec3A::ZERO,
        }
    }

    /// [`Self::f_reflect`]'s density.
    #[inline]
    fn pdf_reflect(&self, o: Vec3A, i: Vec3A) -> f32 {
        match *self {
            Lobes::Diffuse { .. } => diffuse::pdf(i),
            Lobes::Glossy {
                albedo,
                specular,
                alpha,
            } => glossy::pdf(albedo, specular, alpha, o, i),
            Lobes::Conductor { alpha, .. } => conductor::pdf(alpha, o, i),
            Lobes::Coated { albedo, eta, alpha } => coated::pdf(albedo, eta, alpha, o, i),
            Lobes::Mirror { .. } | Lobes::Glass { .. } | Lobes::ThinGlass { .. } => 0.0,
        }
    }

    /// `f` and `pdf` in the local frame, the normal being the only geometry (a facet of a
    /// bumped microsurface): zero for a pair on two sides unless frosted glass.
    fn eval_local(&self, o: Vec3A, i: Vec3A, mode: TransportMode) -> (Vec3A, f32) {
        let local = o.z * i.z;
        if local == 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        if let Some((eta, tint, alpha)) = self.rough_glass() {
            let (f, pdf) = rough_dielectric::eval(eta, alpha, o, i, mode);
            return (tint * f, pdf);
        }
        if local < 0.0 {
            return (Vec3A::ZERO, 0.0);
        }
        (self.f_reflect(o, i), self.pdf_reflect(o, i))
    }

    /// Samples an incident direction in the local frame.
    #[inline]
    fn sample_local(&self, o: Vec3A, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        match *self {
            Lobes::Diffuse { albedo } => diffuse::sample(albedo, o, u),
            Lobes::Mirror { tint } => mirror::sample(tint, o),
            Lobes::Glass { eta, tint, alpha } if alpha < rough_dielectric::MIN_ALPHA => {
                dielectric::sample(eta, tint, o, uc, mode)
            }
            Lobes::Glass { eta, tint, alpha } => {
                rough_dielectric::sample(eta, tint, alpha, o, uc, u, mode)
            }
            Lobes::ThinGlass { eta, tint } => thin_dielectric::sample(eta, tint, o, uc),
            Lobes::Glossy {
                albedo,
                specular,
                alpha,
            } => glossy::sample(albedo, specular, alpha, o, uc, u),
            Lobes::Conductor { eta, k, alpha } => conductor::sample(eta, k, alpha, o, u),
            Lobes::Coated { albedo, eta, alpha } => coated::sample(albedo, eta, alpha, o, uc, u),
        }
    }
}
