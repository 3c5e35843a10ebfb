//! A material evaluated at a hit: its lobes, with each textured parameter looked up at the
//! hit's texture coordinates (computed only when a parameter is a texture).

use glam::{DVec3, Vec3A};

use super::Lobes;
use crate::scene::{ColorParam, Material, ScalarParam, Scene};
use crate::textures::{self, TexCoord};

/// Whether any parameter of a material is a texture: its lobes' (see [`is_constant`]) or a
/// glass's absorption, which is looked up at every hit from inside.
pub fn has_texture(m: &Material) -> bool {
    let absorb_textured = matches!(
        m,
        Material::Glass {
            absorb: ColorParam::Texture(_),
            ..
        }
    );
    absorb_textured || !is_constant(m)
}

/// Whether a material's lobes have no textured parameter (a glass's absorption is not part
/// of its lobes).
pub fn is_constant(m: &Material) -> bool {
    let c = |p: &ColorParam| matches!(p, ColorParam::Const(_));
    match m {
        Material::Diffuse { albedo } => c(albedo),
        Material::Mirror { tint } => c(tint),
        Material::Glass { roughness, .. } => matches!(roughness, ScalarParam::Const(_)),
        Material::ThinGlass { .. } => true,
        Material::Glossy {
            albedo,
            specular,
            roughness,
        } => c(albedo) && c(specular) && matches!(roughness, ScalarParam::Const(_)),
        Material::Conductor { .. } => true,
        Material::Coated {
            albedo, roughness, ..
        } => c(albedo) && matches!(roughness, ScalarParam::Const(_)),
    }
}

/// A glass's index as the lobes use it (1, no interface, for an index a caller's scene got
/// wrong).
fn glass_eta(ior: f64) -> f32 {
    if ior.is_finite() && ior > 0.0 {
        ior as f32
    } else {
        1.0
    }
}

fn color3(c: DVec3) -> Vec3A {
    c.as_vec3a()
}

/// A color parameter at a hit; `tc` gives the hit's texture coordinates.
pub fn color(p: &ColorParam, scene: &Scene, tc: impl Fn() -> TexCoord) -> Vec3A {
    match p {
        ColorParam::Const(c) => color3(*c),
        ColorParam::Texture(t) => textures::evaluate(scene.texture(*t), &tc()),
    }
}

/// A scalar parameter at a hit (a texture's luminance).
pub fn scalar(p: &ScalarParam, scene: &Scene, tc: impl Fn() -> TexCoord) -> f32 {
    match p {
        ScalarParam::Const(c) => *c as f32,
        ScalarParam::Texture(t) => {
            let c = textures::evaluate(scene.texture(*t), &tc());
            0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
        }
    }
}

/// The lobes of material `m` at a hit (texture lookups where the material has them).
pub fn lobes(m: &Material, scene: &Scene, tc: impl Fn() -> TexCoord) -> Lobes {
    let clamp01 = |c: Vec3A| c.clamp(Vec3A::ZERO, Vec3A::ONE);
    match m {
        Material::Diffuse { albedo } => Lobes::Diffuse {
            albedo: clamp01(color(albedo, scene, &tc)),
        },
        Material::Mirror { tint } => Lobes::Mirror {
            tint: clamp01(color(tint, scene, &tc)),
        },
        Material::Glass {
            ior,
            tint,
            roughness,
            ..
        } => {
            // Below the rough lobe's floor (roughness 0.0316) glass is smooth.
            let r = scalar(roughness, scene, &tc).clamp(0.0, 1.0);
            let alpha = r * r;
            Lobes::Glass {
                eta: glass_eta(*ior),
                tint: clamp01(color3(*tint)),
                alpha: if alpha >= super::rough_dielectric::MIN_ALPHA {
                    alpha
                } else {
                    0.0
                },
            }
        }
        Material::ThinGlass { ior, tint } => Lobes::ThinGlass {
            eta: glass_eta(*ior),
            tint: clamp01(color3(*tint)),
        },
        Material::Glossy {
            albedo,
            specular,
            roughness,
        } => {
            let r = scalar(roughness, scene, &tc).clamp(0.0, 1.0);
            Lobes::Glossy {
                albedo: clamp01(color(albedo, scene, &tc)),
                specular: clamp01(color(specular, scene, &tc)),
                alpha: (r * r).max(1e-3),
            }
        }
        Material::Conductor { eta, k, roughness } => {
            let r = if roughness.is_finite() {
                roughness.clamp(0.0, 1.0) as f32
            } else {
                0.0
            };
            let nonneg = |c: Vec3A| c.max(Vec3A::ZERO);
            Lobes::Conductor {
                eta: nonneg(color3(*eta)),
                k: nonneg(color3(*k)),
                alpha: r * r,
            }
        }
        Material::Coated {
            albedo,
            ior,
            roughness,
        } => {
            // Roughness zero (none given, or a texture's black) is a smooth coat.
            let r = scalar(roughness, scene, &tc).clamp(0.0, 1.0);
            Lobes::Coated {
                albedo: clamp01(color(albedo, scene, &tc)),
                eta: (*ior as f32).clamp(1.0, super::coated::MAX_ETA),
                alpha: r * r,
            }
        }
    }
}
