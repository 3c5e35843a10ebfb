//! A material evaluated at a hit: its lobes, with each textured parameter looked up at the
//! hit's texture coordinates (computed only when a parameter is a texture).

use glam::{DVec3, Vec3A};

use super::Lobes;
use crate::scene::{ColorParam, Material, Normal, ScalarParam, Scene};
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
    // A blend's parts may read textures (and its choice reads the point): counted as one.
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
        // The part a blend shows changes from point to point, and a bump's normal.
        Material::Blend { .. } | Material::Bumped { .. } => false,
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

/// The material a hit shows: `m` itself, or for a blend the part chosen at this point
/// (following nested blends), as pbrt-v4's `MixMaterial` chooses: part `b` when a hash of the
/// hit point falls below the weight. The choice is fixed for a point, so a camera path, a
/// photon and a visible point that meet it see the same single material, whose `f`, `pdf` and
/// `sample` agree as any material's do; averaged over the points a pixel or a gather radius
/// covers, the blend reflects `(1 - w) A + w B`.
///
/// Each step goes to an earlier material (the scene's validation checks it), so this ends;
/// the bound is a second guard for a scene that was not validated.
pub fn choose<'a>(m: &'a Material, scene: &'a Scene, tc: impl Fn() -> TexCoord) -> &'a Material {
    choose_bumped(m, None, scene, tc).0
}

/// [`choose`], and the normal of the outermost bump met on the way (a bumped material's
/// base is a step like a blend's part), with the index of the bumped material that carries
/// it (`None` if that is `m` and the caller gave no `id` for it).
pub fn choose_bumped<'a>(
    m: &'a Material,
    id: Option<usize>,
    scene: &'a Scene,
    tc: impl Fn() -> TexCoord,
) -> (&'a Material, Option<(&'a Normal, Option<usize>)>) {
    let mut m = m;
    let mut id = id;
    let mut key = None;
    let mut bump = None;
    for level in 0..=crate::scene::MAX_BLEND_DEPTH {
        if let Material::Bumped { base, normal } = m {
            bump = bump.or(Some((normal, id)));
            id = Some(base.0 as usize);
            match scene.materials.get(base.0 as usize) {
                Some(n) => m = n,
                None => break,
            }
            continue;
        }
        let Material::Blend { a, b, weight } = m else {
            return (m, bump);
        };
        let tc_key = *key.get_or_insert_with(|| point_key(&tc()));
        let w = scalar(weight, scene, &tc);
        let u =
            unit_hash(tc_key ^ (u64::from(level) << 58) ^ (u64::from(a.0) << 32) ^ u64::from(b.0));
        let next = if u < w { b } else { a };
        id = Some(next.0 as usize);
        match scene.materials.get(next.0 as usize) {
            Some(n) => m = n,
            None => break,
        }
    }
    // Only an unvalidated scene gets here (a cycle, or an id past the end).
    (&BLACK, None)
}

static BLACK: Material = Material::Diffuse {
    albedo: ColorParam::Const(DVec3::ZERO),
};

/// A 64-bit key of a hit point (its object-space position's bits).
fn point_key(tc: &TexCoord) -> u64 {
    let [x, y, z] = tc.p.to_array().map(|c| u64::from(c.to_bits()));
    mix64(x ^ mix64(y ^ mix64(z)))
}

/// A number in [0, 1) from a key (SplitMix64's finalizer: every input bit reaches every
/// output bit).
fn unit_hash(k: u64) -> f32 {
    (mix64(k) >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// One splitmix64 output from `z` (its increment, then its finaliser).
fn mix64(z: u64) -> u64 {
    crate::sampling::splitmix64(z).1
}

/// For each of the scene's materials, whether some point of it may scatter other than
/// specularly (a blend: either part may), in one pass: a blend's parts come before it.
pub fn non_specular_parts(scene: &Scene) -> Vec<bool> {
    let mut rough = Vec::with_capacity(scene.materials.len());
    for (i, m) in scene.materials.iter().enumerate() {
        let r = match m {
            Material::Mirror { .. } | Material::ThinGlass { .. } => false,
            // Frosted glass (any roughness but a constant zero) scatters non-specularly.
            Material::Glass { roughness, .. } => {
                !matches!(roughness, ScalarParam::Const(r) if *r == 0.0)
            }
            Material::Conductor { roughness, .. } => *roughness > 0.0,
            Material::Diffuse { .. } | Material::Glossy { .. } | Material::Coated { .. } => true,
            Material::Blend { a, b, .. } => [a, b]
                .iter()
                .any(|id| (id.0 as usize) < i && rough[id.0 as usize]),
            Material::Bumped { base, .. } => (base.0 as usize) < i && rough[base.0 as usize],
        };
        rough.push(r);
    }
    rough
}

/// For each of the scene's materials, whether it is a glass or blends one (at any depth), in
/// one pass: a blend's parts come before it.
pub fn glass_parts(scene: &Scene) -> Vec<bool> {
    let mut glass = Vec::with_capacity(scene.materials.len());
    for (i, m) in scene.materials.iter().enumerate() {
        let g = match m {
            Material::Glass { .. } => true,
            Material::Blend { a, b, .. } => [a, b]
                .iter()
                .any(|id| (id.0 as usize) < i && glass[id.0 as usize]),
            Material::Bumped { base, .. } => (base.0 as usize) < i && glass[base.0 as usize],
            _ => false,
        };
        glass.push(g);
    }
    glass
}

/// The lobes of material `m` at a hit (texture lookups where the material has them; a blend's
/// chosen part, see [`choose`]).
pub fn lobes(m: &Material, scene: &Scene, tc: impl Fn() -> TexCoord) -> Lobes {
    lobes_of(choose(m, scene, &tc), scene, tc)
}

/// [`lobes`], and the normal of the bump on the material (or the blend's part) shown at the
/// hit, if any, with the index of the bumped material carrying it; `id` is `m`'s index.
pub fn bumped_lobes<'a>(
    m: &'a Material,
    id: usize,
    scene: &'a Scene,
    tc: impl Fn() -> TexCoord,
) -> (Lobes, Option<(&'a Normal, Option<usize>)>) {
    let (m, normal) = choose_bumped(m, Some(id), scene, &tc);
    (lobes_of(m, scene, tc), normal)
}

/// The lobes of a material that is neither a blend nor bumped (what [`choose`] gives).
fn lobes_of(m: &Material, scene: &Scene, tc: impl Fn() -> TexCoord) -> Lobes {
    let clamp01 = |c: Vec3A| c.clamp(Vec3A::ZERO, Vec3A::ONE);
    match m {
        Material::Blend { .. } | Material::Bumped { .. } => Lobes::Diffuse {
            albedo: Vec3A::ZERO,
        },
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

#[cfg(test)]
mod tests {
    use glam::{DAffine3, Vec2};

    use super::*;
    use crate::sampling::Rng;
    use crate::scene::{Mapping, MaterialId, Pattern, Texture, TextureId};
    use crate::span::Span;

    fn at(p: Vec3A) -> TexCoord {
        TexCoord {
            p,
            n: Vec3A::Z,
            uv: Vec2::ZERO,
        }
    }

    fn random_point(rng: &mut Rng) -> Vec3A {
        Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 20.0 - 10.0
    }

    /// A scene whose materials are `ms`, in order.
    fn scene_with(ms: Vec<Material>) -> Scene {
        Scene {
            settings: Default::default(),
            camera: Default::default(),
            objects: Vec::new(),
            lights: Vec::new(),
            materials: ms,
            textures: Vec::new(),
            background: Default::default(),
            backdrop: None,
        }
    }

    fn gray(v: f64) -> Material {
        Material::Diffuse {
            albedo: ColorParam::Const(DVec3::splat(v)),
        }
    }

    /// How often each of the scene's first materials is chosen for material `top` over `n`
    /// random points.
    fn shares(scene: &Scene, top: usize, n: usize) -> Vec<f64> {
        let mut counts = vec![0usize; scene.materials.len()];
        let mut rng = Rng::new(7);
        for _ in 0..n {
            let p = random_point(&mut rng);
            let chosen = choose(&scene.materials[top], scene, || at(p));
            let i = scene
                .materials
                .iter()
                .position(|m| std::ptr::eq(m, chosen))
                .expect("a scene material");
            counts[i] += 1;
        }
        counts.iter().map(|&c| c as f64 / n as f64).collect()
    }

    /// Within five standard deviations of a binomial share `p` over `n` draws.
    fn near(share: f64, p: f64, n: usize) -> bool {
        (share - p).abs() <= 5.0 * (p * (1.0 - p) / n as f64).sqrt() + 1e-12
    }

    /// A blend shows its second part at the fraction `weight` of points (so it reflects the
    /// weighted mean in expectation), never a blend itself, and the same part at a point
    /// every time it is asked.
    #[test]
    fn blend_chooses_its_parts_in_proportion_to_the_weight() {
        let n = 200_000;
        for w in [0.0, 0.3, 0.5, 0.9, 1.0] {
            let scene = scene_with(vec![
                gray(0.8),
                Material::Mirror {
                    tint: ColorParam::Const(DVec3::ONE),
                },
                Material::Blend {
                    a: MaterialId(0),
                    b: MaterialId(1),
                    weight: ScalarParam::Const(w),
                },
            ]);
            let s = shares(&scene, 2, n);
            assert_eq!(s[2], 0.0);
            assert!(near(s[1], w, n), "weight {w}: mirror share {}", s[1]);
            let p = Vec3A::new(0.25, -1.5, 3.0);
            let first = choose(&scene.materials[2], &scene, || at(p));
            for _ in 0..10 {
                assert!(std::ptr::eq(
                    first,
                    choose(&scene.materials[2], &scene, || at(p))
                ));
            }
        }
    }

    /// Nested blends multiply their weights: blend(blend(A, B, 1/2), C, 1/4) shows A and B
    /// at 3/8 of the points each and C at 1/4 (the levels' choices are independent).
    #[test]
    fn nested_blends_multiply_their_weights() {
        let n = 200_000;
        let scene = scene_with(vec![
            gray(0.1),
            gray(0.5),
            gray(0.9),
            Material::Blend {
                a: MaterialId(0),
                b: MaterialId(1),
                weight: ScalarParam::Const(0.5),
            },
            Material::Blend {
                a: MaterialId(3),
                b: MaterialId(2),
                weight: ScalarParam::Const(0.25),
            },
        ]);
        let s = shares(&scene, 4, n);
        for (i, p) in [(0, 0.375), (1, 0.375), (2, 0.25)] {
            assert!(near(s[i], p, n), "part {i}: share {} not {p}", s[i]);
        }
        assert_eq!(
            scene.blend_depths(),
            vec![Some(0), Some(0), Some(0), Some(1), Some(2)]
        );
        assert!(scene.validate().is_ok());
    }

    /// A textured weight is read at the point: under a black and white checker, the points
    /// in white cells show the second part and those in black cells the first, every one.
    #[test]
    fn a_textured_weight_is_read_at_each_point() {
        let mut scene = scene_with(vec![
            gray(0.2),
            gray(0.7),
            Material::Blend {
                a: MaterialId(0),
                b: MaterialId(1),
                weight: ScalarParam::Texture(TextureId(0)),
            },
        ]);
        scene.textures.push(Texture {
            pattern: Pattern::Checker {
                a: DVec3::ZERO,
                b: DVec3::ONE,
            },
            mapping: Mapping::Solid,
            transform: DAffine3::IDENTITY,
            span: Span::detached(),
        });
        let mut rng = Rng::new(3);
        let (mut white, mut black) = (0, 0);
        for _ in 0..10_000 {
            let p = random_point(&mut rng);
            let w = scalar(&ScalarParam::Texture(TextureId(0)), &scene, || at(p));
            let chosen = choose(&scene.materials[2], &scene, || at(p));
            let want = if w > 0.5 { 1 } else { 0 };
            if want == 1 {
                white += 1
            } else {
                black += 1
            }
            assert!(
                std::ptr::eq(chosen, &scene.materials[want]),
                "at {p}, weight {w}"
            );
        }
        assert!(white > 1000 && black > 1000, "{white} white, {black} black");
    }

    /// A blend that refers to itself or to a later material (only a scene built by hand can)
    /// is refused by validation, and choosing on it still ends (black); nesting deeper than
    /// `MAX_BLEND_DEPTH` is refused.
    #[test]
    fn blend_cycles_and_deep_nesting_are_refused_and_cannot_hang() {
        let cyclic = scene_with(vec![
            gray(0.5),
            Material::Blend {
                a: MaterialId(1),
                b: MaterialId(1),
                weight: ScalarParam::Const(0.5),
            },
        ]);
        assert!(cyclic.validate().is_err());
        let m = choose(&cyclic.materials[1], &cyclic, || at(Vec3A::ONE));
        assert!(matches!(m, Material::Diffuse { .. }));
        let d = 1 + crate::scene::MAX_BLEND_DEPTH as usize;
        let mut ms = vec![gray(0.5)];
        for i in 0..d {
            ms.push(Material::Blend {
                a: MaterialId(i as u32),
                b: MaterialId(0),
                weight: ScalarParam::Const(0.0),
            });
        }
        let deep = scene_with(ms.clone());
        assert!(deep.validate().is_err());
        ms.pop();
        assert!(scene_with(ms).validate().is_ok());
    }
}
