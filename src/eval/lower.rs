//! Lowering into the [`Scene`]: objects become scene objects, declared materials and
//! textures get ids (once each), and images and meshes are loaded (once each).

use std::collections::HashMap;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::Arc;

use super::Evaluator;
use super::value::{
    ColorDef, MatKind, MaterialDef, NormalDef, NormalSource, ObjectDef, Part, PatternDef, ShapeDef,
    TextureDef,
};
use crate::diag::{Error, SourceResult};
use crate::scene::*;
use crate::span::Span;

/// Loaded assets and the ids given to declared materials and textures.
///
/// Materials and textures are keyed by address; the map holds the `Rc` too, so that an address
/// is not reused by another definition while its id is stored.
#[derive(Default)]
pub(crate) struct Assets {
    materials: HashMap<*const MaterialDef, (Rc<MaterialDef>, MaterialId)>,
    textures: HashMap<*const TextureDef, (Rc<TextureDef>, TextureId)>,
    images: HashMap<(PathBuf, bool), Arc<ImageData>>,
    meshes: HashMap<PathBuf, Arc<MeshData>>,
    /// Why each loaded mesh is not closed (`None`: it is), found once per mesh: a CSG may
    /// place one mesh of a million triangles many times.
    open_meshes: HashMap<PathBuf, Option<String>>,
    default_material: Option<MaterialId>,
    black_material: Option<MaterialId>,
}

pub(crate) fn empty_scene() -> Scene {
    Scene {
        settings: Settings::default(),
        camera: Camera::default(),
        objects: Vec::new(),
        lights: Vec::new(),
        materials: Vec::new(),
        textures: Vec::new(),
        background: Background::default(),
        backdrop: None,
    }
}

impl Evaluator {
    pub(crate) fn check_object_budget(&self, span: Span) -> SourceResult<()> {
        if self.scene.objects.len() >= self.options.max_objects {
            return Err(vec![
                Error::new(format!(
                    "the scene has more than {} objects",
                    self.options.max_objects
                ))
                .label("limit reached here")
                .help("is a recursion too deep?")
                .at(span),
            ]);
        }
        Ok(())
    }

    /// Counts `adding` parts copied into a container that holds `holding` already: one
    /// container may hold at most `max_objects` parts, and all containers together may copy at
    /// most twice that many in one load (a union copied into itself each iteration doubles).
    pub(crate) fn count_parts(
        &mut self,
        holding: usize,
        adding: usize,
        span: Span,
    ) -> SourceResult<()> {
        self.parts_copied = self.parts_copied.saturating_add(adding);
        let max = self.options.max_objects;
        if holding.saturating_add(adding) > max || self.parts_copied > max.saturating_mul(2) {
            return Err(vec![
                Error::new(if holding.saturating_add(adding) > max {
                    format!("a union or group would hold more than {max} parts")
                } else {
                    format!(
                        "unions and groups copied more than {} parts in all (twice the object \
                         limit)",
                        max.saturating_mul(2)
                    )
                })
                .label("limit reached here")
                .help("is a union copied into itself, or a recursion too deep?")
                .at(span),
            ]);
        }
        Ok(())
    }

    /// Adds an object's parts to the scene.
    pub(super) fn emit(&mut self, obj: &ObjectDef, span: Span) -> SourceResult<()> {
        for part in &obj.parts {
            self.check_object_budget(span)?;
            if let ShapeDef::Csg(c) = &part.shape {
                // The shapes of a CSG count against the copies of all containers.
                self.count_parts(0, c.leaves, span)?;
            }
            let object = self.lower_part(part, None)?;
            self.scene.objects.push(object);
        }
        Ok(())
    }

    /// A part as a scene object; `inherited`: the material of the nearest enclosing CSG node
    /// that has one (for the shapes of a CSG without their own).
    fn lower_part(
        &mut self,
        part: &Part,
        inherited: Option<&Rc<MaterialDef>>,
    ) -> SourceResult<Object> {
        let own = part.material.as_ref().or(inherited);
        let material = match (own, part.emission) {
            (Some(m), _) => self.material_id(m)?,
            (None, Some(_)) => self.black_material(),
            (None, None) => self.default_material(),
        };
        let shape = match &part.shape {
            ShapeDef::Ready(s) => s.clone(),
            ShapeDef::Mesh { path, span } => ShapeDecl::Mesh {
                mesh: self.mesh(path, *span)?,
            },
            ShapeDef::Csg(c) => {
                let mut children = Vec::with_capacity(c.children.len());
                for child in &c.children {
                    let object = self.lower_part(child, own)?;
                    // Meshes are known only now: is this one closed?
                    let why = match (&child.shape, &object.shape) {
                        (ShapeDef::Mesh { path, .. }, ShapeDecl::Mesh { mesh }) => self
                            .assets
                            .open_meshes
                            .entry(path.clone())
                            .or_insert_with(|| why_open(&ShapeDecl::Mesh { mesh: mesh.clone() }))
                            .clone(),
                        (_, shape) => why_open(shape),
                    };
                    if let Some(why) = why {
                        return Err(vec![
                            Error::new(format!(
                                "this {} has no inside, so it cannot be part of {}: {why}",
                                object.shape.kind(),
                                c.op.a_name()
                            ))
                            .label("not a closed shape")
                            .help(
                                "close the mesh in a modeller, or use `union`, which needs no \
                                 inside",
                            )
                            .at(object.span),
                        ]);
                    }
                    children.push(object);
                }
                ShapeDecl::Csg(Csg { op: c.op, children })
            }
        };
        Ok(Object {
            shape,
            transform: part.transform,
            material,
            emission: part.emission,
            span: part.span,
        })
    }

    fn push_material(&mut self, m: Material) -> MaterialId {
        self.scene.materials.push(m);
        MaterialId(self.scene.materials.len() as u32 - 1)
    }

    fn default_material(&mut self) -> MaterialId {
        if let Some(id) = self.assets.default_material {
            return id;
        }
        let id = self.push_material(Material::Diffuse {
            albedo: ColorParam::Const(Color::splat(0.5)),
        });
        self.assets.default_material = Some(id);
        id
    }

    fn black_material(&mut self) -> MaterialId {
        if let Some(id) = self.assets.black_material {
            return id;
        }
        let id = self.push_material(Material::Diffuse {
            albedo: ColorParam::Const(Color::ZERO),
        });
        self.assets.black_material = Some(id);
        id
    }

    fn material_id(&mut self, m: &Rc<MaterialDef>) -> SourceResult<MaterialId> {
        let key = Rc::as_ptr(m);
        if let Some((_, id)) = self.assets.materials.get(&key) {
            return Ok(*id);
        }
        let material = match &m.kind {
            MatKind::Diffuse(a) => Material::Diffuse {
                albedo: self.color_param(a)?,
            },
            MatKind::Mirror(t) => Material::Mirror {
                tint: self.color_param(t)?,
            },
            MatKind::Glass {
                ior, tint, thin, ..
            } if *thin => Material::ThinGlass {
                ior: *ior,
                tint: *tint,
            },
            MatKind::Glass {
                ior,
                absorb,
                tint,
                roughness,
                ..
            } => Material::Glass {
                ior: *ior,
                absorb: self.color_param(absorb)?,
                tint: *tint,
                roughness: match roughness {
                    None => ScalarParam::Const(0.0),
                    Some(r) => match self.color_param(r)? {
                        ColorParam::Const(c) => ScalarParam::Const(c.x),
                        ColorParam::Texture(t) => ScalarParam::Texture(t),
                    },
                },
            },
            MatKind::Glossy {
                albedo,
                specular,
                roughness,
            } => Material::Glossy {
                albedo: self.color_param(albedo)?,
                specular: self.color_param(specular)?,
                roughness: match self.color_param(roughness)? {
                    ColorParam::Const(c) => ScalarParam::Const(c.x),
                    ColorParam::Texture(t) => ScalarParam::Texture(t),
                },
            },
            MatKind::Conductor { eta, k, roughness } => Material::Conductor {
                eta: *eta,
                k: *k,
                roughness: *roughness,
            },
            // The parts are pushed first: a blend refers only to earlier materials.
            MatKind::Blend { a, b, weight, .. } => Material::Blend {
                a: self.material_id(a)?,
                b: self.material_id(b)?,
                weight: match self.color_param(weight)? {
                    ColorParam::Const(c) => ScalarParam::Const(c.x),
                    ColorParam::Texture(t) => ScalarParam::Texture(t),
                },
            },
            MatKind::Coated {
                albedo,
                ior,
                roughness,
            } => Material::Coated {
                albedo: self.color_param(albedo)?,
                ior: *ior,
                roughness: match roughness {
                    None => ScalarParam::Const(0.0),
                    Some(r) => match self.color_param(r)? {
                        ColorParam::Const(c) => ScalarParam::Const(c.x),
                        ColorParam::Texture(t) => ScalarParam::Texture(t),
                    },
                },
            },
        };
        // A bumped material wraps its plain self, pushed first.
        let material = match &m.normal {
            None => material,
            Some(n) => {
                let normal = self.normal(n)?;
                Material::Bumped {
                    base: self.push_material(material),
                    normal,
                }
            }
        };
        let id = self.push_material(material);
        self.assets.materials.insert(key, (m.clone(), id));
        Ok(id)
    }

    fn normal(&mut self, n: &NormalDef) -> SourceResult<Normal> {
        let kind = match &n.source {
            NormalSource::Pattern(k) => *k,
            NormalSource::Height(t) => NormalKind::Height(self.texture_id(t)?),
            NormalSource::Map(t) => NormalKind::Map(self.texture_id(t)?),
        };
        Ok(Normal {
            kind,
            amount: n.amount,
            transform: n.transform,
        })
    }

    fn color_param(&mut self, c: &ColorDef) -> SourceResult<ColorParam> {
        Ok(match c {
            ColorDef::Const(c) => ColorParam::Const(*c),
            ColorDef::Tex(t) => ColorParam::Texture(self.texture_id(t)?),
        })
    }

    pub(super) fn texture_id(&mut self, t: &Rc<TextureDef>) -> SourceResult<TextureId> {
        let key = Rc::as_ptr(t);
        if let Some((_, id)) = self.assets.textures.get(&key) {
            return Ok(*id);
        }
        let pattern = match &t.pattern {
            PatternDef::Ready(p) => p.clone(),
            PatternDef::Image {
                path,
                linear,
                wrap,
                bilinear,
                span,
            } => Pattern::Image {
                image: self.image(path, *linear, *span)?,
                wrap: *wrap,
                bilinear: *bilinear,
            },
        };
        self.scene.textures.push(Texture {
            pattern,
            mapping: t.mapping,
            transform: t.transform,
            span: t.span,
        });
        let id = TextureId(self.scene.textures.len() as u32 - 1);
        self.assets.textures.insert(key, (t.clone(), id));
        Ok(id)
    }

    pub(super) fn image(
        &mut self,
        path: &std::path::Path,
        linear: bool,
        span: Span,
    ) -> SourceResult<Arc<ImageData>> {
        let key = (path.to_path_buf(), linear);
        if let Some(img) = self.assets.images.get(&key) {
            return Ok(img.clone());
        }
        let space = if linear {
            ColorSpace::Linear
        } else {
            ColorSpace::Srgb
        };
        // Recorded before the read so that `watch` also waits for a file that is missing.
        self.dependencies.push(path.to_path_buf());
        let loaded: u64 = self
            .assets
            .images
            .values()
            .map(|i| i.width as u64 * i.height as u64)
            .sum();
        // Images count against the memory the whole load holds (`eval::memory`).
        let room = ImageRoom::after(loaded, self.held.total(), Some(self.memory_limit()));
        let img = load_image_within(&*self.options.world, path, space, room).map_err(|e| {
            vec![
                Error::new(e.message)
                    .label("cannot load this image")
                    .help(if let Some(help) = e.help {
                        help
                    } else if e.read {
                        format!(
                            "the file `{}` was found but is not an image that can be used: give \
                             a PNG, JPEG, EXR or Radiance HDR image",
                            path.display()
                        )
                    } else {
                        self.path_help(span)
                    })
                    .at(span),
            ]
        })?;
        self.held.images += img.width as u64 * img.height as u64 * IMAGE_BYTES_PER_PIXEL;
        let img = Arc::new(img);
        self.assets.images.insert(key, img.clone());
        Ok(img)
    }

    fn mesh(&mut self, path: &PathBuf, span: Span) -> SourceResult<Arc<MeshData>> {
        if let Some(m) = self.assets.meshes.get(path) {
            return Ok(m.clone());
        }
        self.dependencies.push(path.clone());
        let m = load_obj_in(&*self.options.world, path).map_err(|e| {
            vec![
                Error::new(e.message)
                    .label("cannot load this mesh")
                    .help(if e.read {
                        format!(
                            "the file `{}` was found but is not a mesh that can be read: a \
                             Wavefront OBJ with `v x y z` vertices and `f i j k` faces, whose \
                             indices count the `v` lines from 1 (or back from -1)",
                            path.display()
                        )
                    } else {
                        self.path_help(span)
                    })
                    .at(span),
            ]
        })?;
        let m = Arc::new(m);
        self.assets.meshes.insert(path.clone(), m.clone());
        Ok(m)
    }
}
