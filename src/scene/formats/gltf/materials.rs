//! glTF materials: metallic-roughness factors and textures (base colour with
//! its alpha as a cut-out, normals; metallic-roughness and emissive by their
//! mean), each texture with its sampler's wrap modes, coordinate set and
//! `KHR_texture_transform`.

use std::path::PathBuf;
use std::sync::Arc;

use ::gltf::image::Source;
use ::gltf::material::AlphaMode;
use ::gltf::texture::WrappingMode;
use glam::{Vec2, Vec3};

use super::super::images::ImageSource;
use super::Gltf;
use super::buffers::{base64, percent_decode};
use crate::scene::texture::{Encoding, Relief, UvTransform, Wrap};
use crate::scene::{AlphaMap, Glossy, Material, NormalMap, Texture, TextureMap};

/// Where a texture is read from and how it is placed.
struct Placement {
    uv_set: u32,
    transform: UvTransform,
}

fn wrap(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::ClampToEdge => Wrap::Clamp,
        WrappingMode::MirroredRepeat => Wrap::Mirror,
        WrappingMode::Repeat => Wrap::Repeat,
    }
}

impl Gltf<'_> {
    /// The image of texture `t` under `encoding`; a warning and `None` when
    /// it cannot be read.
    fn image(&mut self, t: &::gltf::Texture, encoding: Encoding) -> Option<Arc<Texture>> {
        let image = t.source();
        let what = format!("texture {} (image {})", t.index(), image.index());
        let got = match image.source() {
            Source::View { view, .. } => match self.buffers.view(&view) {
                Some(bytes) => {
                    let name = format!("{} image {}", self.path.display(), image.index());
                    self.images.get(ImageSource::Bytes { name, bytes }, encoding)
                }
                None => Err(format!("{what}: buffer view {} out of range", view.index())),
            },
            Source::Uri { uri, .. } if uri.starts_with("data:") => {
                match uri.split_once(";base64,").map(|(_, p)| base64(p)) {
                    Some(Ok(bytes)) => {
                        let name = format!("{} image {}", self.path.display(), image.index());
                        self.images
                            .get(ImageSource::Bytes { name, bytes: &bytes }, encoding)
                    }
                    _ => Err(format!("{what}: a data URI that is not base64")),
                }
            }
            Source::Uri { uri, .. } if uri.contains("://") => Err(format!(
                "{what}: URI {uri:?} (only data URIs and files beside the scene)"
            )),
            Source::Uri { uri, .. } => {
                let file: PathBuf = self
                    .path
                    .parent()
                    .unwrap_or(std::path::Path::new("."))
                    .join(percent_decode(uri));
                self.images.get(ImageSource::File(&file), encoding)
            }
        };
        got.map_err(|e| self.warn(format!("{e}: left out"))).ok()
    }

    /// A texture placed on a material.
    fn texture_map(&mut self, t: &::gltf::Texture, at: Placement, encoding: Encoding) -> Option<TextureMap> {
        let texture = self.image(t, encoding)?;
        let sampler = t.sampler();
        Some(TextureMap {
            texture,
            uv_set: at.uv_set as usize,
            transform: at.transform,
            wrap: [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())],
        })
    }

    /// A texture reference's coordinate set and transform.
    fn placement(info: &::gltf::texture::Info) -> Placement {
        match info.texture_transform() {
            Some(x) => Placement {
                uv_set: x.tex_coord().unwrap_or(info.tex_coord()),
                transform: UvTransform::offset_rotation_scale(
                    Vec2::from(x.offset()),
                    x.rotation(),
                    Vec2::from(x.scale()),
                ),
            },
            None => Placement {
                uv_set: info.tex_coord(),
                transform: UvTransform::IDENTITY,
            },
        }
    }

    /// The scene material for a glTF one (made once) and its emission.
    ///
    /// Metallic-roughness as the Mitsuba `plastic`/`conductor` loaders do
    /// it: diffuse albedo `base·(1 − metallic)`, a glossy lobe of
    /// reflectance `0.04·(1 − metallic) + base·metallic` (F0) and roughness
    /// α = perceptual roughness². The base colour texture multiplies the
    /// albedo; its alpha cuts out (`MASK` at `alphaCutoff`, `BLEND` at ½).
    /// The lobe is one per material: a metallic-roughness texture enters by
    /// its mean, as does an emissive texture into the emission. A primitive
    /// with no material gets the two-sided grey of a bare mesh (the spec's
    /// default is a rough white metal, which renders nothing diffuse).
    pub(super) fn material(&mut self, m: &::gltf::Material) -> (usize, Option<Vec3>) {
        let mut emission = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
        if let Some(info) = m.emissive_texture()
            && emission.max_element() > 0.0
            && let Some(t) = self.image(&info.texture(), Encoding::Srgb)
        {
            self.warn(format!("{}: emissive texture taken by its mean colour", t.name));
            emission *= t.mean().truncate();
        }
        let emission = (emission.max_element() > 0.0).then_some(emission);
        if let Some(&k) = self.material_of.get(&m.index()) {
            return (k, emission);
        }
        let material = match m.index() {
            None => {
                self.warn("a primitive without a material gets a two-sided grey".into());
                Material {
                    two_sided: true,
                    ..Material::diffuse("default", Vec3::splat(0.5))
                }
            }
            Some(i) => self.pbr(m, i),
        };
        self.materials.push(material);
        let k = self.materials.len() - 1;
        self.material_of.insert(m.index(), k);
        (k, emission)
    }

    fn pbr(&mut self, m: &::gltf::Material, i: usize) -> Material {
        let name = m.name().map_or_else(|| format!("material {i}"), str::to_string);
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        let base = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
        let (mut metallic, mut roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
        if let Some(info) = pbr.metallic_roughness_texture()
            && let Some(t) = self.image(&info.texture(), Encoding::Linear)
        {
            self.warn(format!(
                "{name}: metallic-roughness texture taken by its mean (one lobe per material)"
            ));
            let mean = t.mean();
            (metallic, roughness) = (metallic * mean.z, roughness * mean.y);
        }
        let metallic = metallic.clamp(0.0, 1.0);
        let base_info = pbr.base_color_texture();
        let albedo_map = base_info
            .as_ref()
            .and_then(|info| self.texture_map(&info.texture(), Self::placement(info), Encoding::Srgb));
        let mut albedo = base * (1.0 - metallic);
        if albedo_map.is_none() {
            if albedo.max_element() >= 1.0 {
                self.warn(format!("{name}: base colour {base} clamped below 1"));
            }
            albedo = albedo.min(Vec3::splat(0.99));
        }
        let cutoff = match m.alpha_mode() {
            AlphaMode::Opaque => None,
            AlphaMode::Mask => Some(m.alpha_cutoff().unwrap_or(0.5)),
            AlphaMode::Blend => {
                self.warn(format!("{name}: alphaMode BLEND drawn as a cut-out at alpha 0.5"));
                Some(0.5)
            }
        };
        let alpha = match (cutoff, &albedo_map) {
            (Some(cutoff), Some(map)) if map.texture.has_alpha() => Some(AlphaMap {
                map: map.clone(),
                channel: 3,
                factor: alpha,
                cutoff,
            }),
            (Some(cutoff), _) if alpha < cutoff => {
                self.warn(format!(
                    "{name}: alpha {alpha} below the cutoff {cutoff} with no alpha texture: drawn opaque"
                ));
                None
            }
            _ => None,
        };
        let normal_map = m.normal_texture().and_then(|n| {
            let placement = Placement {
                uv_set: n.tex_coord(),
                transform: UvTransform::IDENTITY,
            };
            Some(NormalMap {
                map: self.texture_map(&n.texture(), placement, Encoding::Linear)?,
                relief: Relief::Normals,
                scale: n.scale(),
            })
        });
        if m.occlusion_texture().is_some() {
            self.warn(format!(
                "{name}: occlusion texture ignored (the renderer computes occlusion)"
            ));
        }
        let specular = Vec3::splat(0.04) * (1.0 - metallic) + base * metallic;
        Material {
            name,
            albedo,
            glossy: Some(Glossy {
                specular: specular.min(Vec3::splat(0.99)),
                roughness: roughness.powi(2).clamp(0.01, 1.0),
            }),
            two_sided: m.double_sided(),
            albedo_map,
            alpha,
            normal_map,
            ..Material::diffuse("", Vec3::ZERO)
        }
    }
}
