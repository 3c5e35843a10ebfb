//! What shading reads from a prepared scene at a hit: the material, its BSDF (constant
//! lobes computed once, textures and bumps at the hit), the texture coordinates in the
//! object's space, and a glass's absorption.

use glam::Vec3A;

use super::{PreparedScene, SurfaceHit, color3};
use crate::geometry::Frame;
use crate::materials::{Bsdf, Lobes, eval};
use crate::scene::{ColorParam, Material};
use crate::textures::{self, TexCoord};

/// A material's part in [`PreparedScene::glass_absorption`], decided once per material.
pub(super) enum GlassAbsorption {
    NotGlass,
    /// A constant absorption (zero for clear glass), as [`PreparedScene::absorption`] gives it.
    Constant(Vec3A),
    /// An absorption from a texture: evaluated at each hit.
    Textured,
    /// A blend with a glass among its parts: the part chosen at each hit decides.
    Blended,
}

impl GlassAbsorption {
    pub(super) fn of(m: &Material, has_glass: bool) -> Self {
        match m {
            Material::Blend { .. } | Material::Bumped { .. } if has_glass => Self::Blended,
            Material::Glass {
                absorb: ColorParam::Const(c),
                ..
            } => {
                let a = color3(*c).max(Vec3A::ZERO);
                Self::Constant(if a.is_finite() { a } else { Vec3A::ZERO })
            }
            Material::Glass { .. } => Self::Textured,
            _ => Self::NotGlass,
        }
    }
}

impl PreparedScene<'_> {
    /// The material of primitive `prim` (`None` for a number no primitive has).
    #[inline]
    pub fn material(&self, prim: u32) -> Option<&Material> {
        let m = *self.prim_material.get(prim as usize)?;
        self.scene.materials.get(m as usize)
    }

    fn tex_coord(&self, sh: &SurfaceHit) -> TexCoord {
        let object = self
            .prim_object
            .get(sh.prim as usize)
            .and_then(|&o| self.objects.get(o as usize));
        match object {
            Some(o) => TexCoord {
                p: o.to_object.transform_point3a(sh.hit.p),
                n: (o.normal_to_object * sh.hit.ns).normalize_or_zero(),
                uv: sh.hit.uv,
            },
            // A hit made up by the caller, on no primitive: world space.
            None => TexCoord {
                p: sh.hit.p,
                n: sh.hit.ns,
                uv: sh.hit.uv,
            },
        }
    }

    /// The BSDF at a hit (black for a `SurfaceHit` whose `prim` no primitive has, which only
    /// a caller making one up can give).
    #[inline(always)]
    pub fn bsdf(&self, sh: &SurfaceHit) -> Bsdf {
        let m = self
            .prim_material
            .get(sh.prim as usize)
            .map_or(usize::MAX, |&m| m as usize);
        // A constant material (most of them) inline; textures and bumps are a call.
        if let Some(Some(l)) = self.const_lobes.get(m) {
            return Bsdf::new(*l, sh.hit.ns, sh.hit.dpdu, sh.hit.n);
        }
        self.varying_bsdf(sh, m)
    }

    /// [`Self::bsdf`] of material `m` when it is not constant.
    #[inline(never)]
    fn varying_bsdf(&self, sh: &SurfaceHit, m: usize) -> Bsdf {
        let Some(material) = self.scene.materials.get(m) else {
            let black = Lobes::Diffuse {
                albedo: Vec3A::ZERO,
            };
            return Bsdf::new(black, sh.hit.ns, sh.hit.dpdu, sh.hit.n);
        };
        // The texture coordinates, looked up once for the lobes and the bump alike.
        let cell = std::cell::OnceCell::new();
        let tc = || *cell.get_or_init(|| self.tex_coord(sh));
        let (lobes, normal) = eval::bumped_lobes(material, m, self.scene, tc);
        match normal {
            None => Bsdf::new(lobes, sh.hit.ns, sh.hit.dpdu, sh.hit.n),
            Some((normal, id)) => {
                let frame = Frame::from_normal_tangent(sh.hit.ns, sh.hit.dpdu);
                let scale = match id.and_then(|i| self.bump_scale.get(i)) {
                    Some(&s) => s,
                    None => textures::bump::pattern_scale(normal, &self.scene.textures),
                };
                let np = self.perturbed_normal(normal, scale, sh, &frame, &tc());
                Bsdf::bumped(lobes, frame, sh.hit.n, np)
            }
        }
    }

    /// The lobes of material `m` at a hit (texture lookups where the material has them).
    pub(super) fn lobes(&self, m: &Material, sh: &SurfaceHit) -> Lobes {
        eval::lobes(m, self.scene, || self.tex_coord(sh))
    }

    /// Whether the hit is on a blend with a part that scatters other than specularly: photon
    /// mapping stores a photon arriving there even where the point shows a specular part, so
    /// that the density around a point showing the rough part counts all the light reaching
    /// the surface (SPPM deposits at every surface alike).
    #[inline]
    pub fn blend_stores_photons(&self, sh: &SurfaceHit) -> bool {
        let m = self
            .prim_material
            .get(sh.prim as usize)
            .map_or(usize::MAX, |&m| m as usize);
        matches!(self.scene.materials.get(m), Some(Material::Blend { .. }))
            && self.rough_parts.get(m) == Some(&true)
    }

    /// Whether some material may absorb light inside it (a glass with an absorption that is
    /// not a constant zero). Where this is false, a path's medium is zero everywhere: no
    /// absorption to track or apply.
    #[inline]
    pub fn absorbs(&self) -> bool {
        self.absorbs
    }

    /// For a hit on glass, its absorption coefficient (zero for clear glass); `None` for any
    /// other material.
    #[inline]
    pub fn glass_absorption(&self, sh: &SurfaceHit) -> Option<Vec3A> {
        self.glass_absorption_varying(sh).map(|(sigma, _)| sigma)
    }

    /// [`Self::glass_absorption`], and whether it comes from a texture (so that it differs
    /// from point to point of the glass): one material lookup for both.
    #[inline]
    pub fn glass_absorption_varying(&self, sh: &SurfaceHit) -> Option<(Vec3A, bool)> {
        let m = *self.prim_material.get(sh.prim as usize)?;
        match self.glass.get(m as usize)? {
            GlassAbsorption::NotGlass => None,
            GlassAbsorption::Constant(sigma) => Some((*sigma, false)),
            GlassAbsorption::Textured => Some((self.absorption(sh).unwrap_or(Vec3A::ZERO), true)),
            GlassAbsorption::Blended => {
                let m = eval::choose(self.material(sh.prim)?, self.scene, || self.tex_coord(sh));
                matches!(m, Material::Glass { .. })
                    .then(|| (self.absorption(sh).unwrap_or(Vec3A::ZERO), true))
            }
        }
    }

    /// Beer–Lambert absorption coefficient inside the material at this hit, if any.
    pub fn absorption(&self, sh: &SurfaceHit) -> Option<Vec3A> {
        let m = self.material(sh.prim)?;
        match eval::choose(m, self.scene, || self.tex_coord(sh)) {
            Material::Glass { absorb, .. } => {
                let a = eval::color(absorb, self.scene, || self.tex_coord(sh)).max(Vec3A::ZERO);
                (a != Vec3A::ZERO && a.is_finite()).then_some(a)
            }
            _ => None,
        }
    }
}
