//! Mitsuba BSDFs: `diffuse`, `plastic`, `conductor` (and their rough
//! forms), `twosided`, and the wrappers `normalmap`, `bumpmap` and `mask`
//! (a cut-out); any
//! reflectance may be a `bitmap` texture (with `raw`, `wrap_mode` and
//! `to_uv`), nested or a `<ref>` to one at the top level.

use glam::{Vec2, Vec3};
use roxmltree::Node;

use super::super::images::ImageSource;
use super::Mitsuba;
use crate::scene::texture::{Encoding, Relief, UvTransform, Wrap};
use crate::scene::{AlphaMap, Glossy, Material, NormalMap, SceneError, TextureMap};

/// The `<bsdf>` a wrapper holds.
fn nested<'a, 'i>(node: Node<'a, 'i>) -> Option<Node<'a, 'i>> {
    node.children().find(|c| c.has_tag_name("bsdf"))
}

impl Mitsuba<'_> {
    pub(super) fn bsdf(&mut self, node: Node) -> Result<Material, SceneError> {
        let ty = self.attr(node, "type")?;
        let name = node.attribute("id").unwrap_or(&ty).to_string();
        let mut m = Material::diffuse(name.clone(), Vec3::splat(0.5));
        match ty.as_str() {
            "diffuse" => {
                (m.albedo, m.albedo_map) = self.reflectance(node, "reflectance", Vec3::splat(0.5))?
            }
            "twosided" => {
                let inner = nested(node).ok_or_else(|| self.err(node, "twosided without a nested <bsdf>"))?;
                m = self.bsdf(inner)?;
                m.name = name;
                m.two_sided = true;
            }
            "normalmap" | "bumpmap" => {
                let inner =
                    nested(node).ok_or_else(|| self.err(node, format!("{ty} without a nested <bsdf>")))?;
                let texture = node
                    .children()
                    .find(|c| c.has_tag_name("texture"))
                    .ok_or_else(|| self.err(node, format!("{ty} without a <texture>")))?;
                m = self.bsdf(inner)?;
                m.name = name;
                let (relief, scale) = if ty == "normalmap" {
                    (Relief::Normals, 1.0)
                } else {
                    (Relief::Heights, self.scalar_prop(node, "scale", 1.0)?)
                };
                m.normal_map = self.bitmap(texture)?.map(|map| NormalMap { map, relief, scale });
            }
            "mask" => {
                // Mitsuba blends by opacity; a cut-out at ½ is the same for a
                // binary mask, the form cut-outs take.
                let inner = nested(node).ok_or_else(|| self.err(node, "mask without a nested <bsdf>"))?;
                let opacity = self
                    .prop(node, "opacity")
                    .filter(|p| p.has_tag_name("texture"))
                    .ok_or_else(|| self.err(node, "mask without an opacity <texture>"))?;
                m = self.bsdf(inner)?;
                m.name = name;
                m.alpha = self.bitmap(opacity)?.map(|map| AlphaMap {
                    channel: if map.texture.has_alpha() { 3 } else { 0 },
                    map,
                    factor: 1.0,
                    cutoff: 0.5,
                });
            }
            "plastic" | "roughplastic" => {
                (m.albedo, m.albedo_map) = self.reflectance(node, "diffuse_reflectance", Vec3::splat(0.5))?;
                let alpha = self.scalar_prop(node, "alpha", if ty == "plastic" { 0.02 } else { 0.1 })?;
                let spec = self.color(node, "specular_reflectance", Vec3::ONE)? * 0.04;
                m.glossy = Some(Glossy {
                    specular: spec,
                    roughness: alpha.clamp(0.01, 1.0),
                });
            }
            "conductor" | "roughconductor" => {
                m.albedo = Vec3::ZERO;
                let alpha = self.scalar_prop(node, "alpha", if ty == "conductor" { 0.01 } else { 0.1 })?;
                let spec = self.color(node, "specular_reflectance", Vec3::splat(0.9))?;
                m.glossy = Some(Glossy {
                    specular: spec.min(Vec3::splat(0.99)),
                    roughness: alpha.clamp(0.01, 1.0),
                });
            }
            other => {
                self.warnings.push(format!(
                    "{}:{}: bsdf {other:?} not supported, grey diffuse used",
                    self.path.display(),
                    self.line(node)
                ));
            }
        }
        if m.albedo_map.is_none() && m.albedo.max_element() >= 1.0 {
            self.warnings.push(format!(
                "{}:{}: reflectance {} clamped below 1",
                self.path.display(),
                self.line(node),
                m.albedo
            ));
            m.albedo = m.albedo.min(Vec3::splat(0.99));
        }
        Ok(m)
    }

    /// A reflectance: a colour, or a `bitmap` texture (factor 1), nested or
    /// a `<ref>` to a top-level `<texture id=…>`.
    fn reflectance(
        &mut self,
        node: Node,
        name: &str,
        default: Vec3,
    ) -> Result<(Vec3, Option<TextureMap>), SceneError> {
        let texture = match self.prop(node, name) {
            Some(p) if p.has_tag_name("texture") => Some(p),
            Some(p) if p.has_tag_name("ref") => {
                let id = self.attr(p, "id")?;
                let found = p
                    .document()
                    .descendants()
                    .find(|n| n.has_tag_name("texture") && n.attribute("id") == Some(id.as_str()));
                Some(found.ok_or_else(|| self.err(p, format!("no texture with id {id:?}")))?)
            }
            _ => None,
        };
        match texture {
            Some(t) => match self.bitmap(t)? {
                Some(map) => Ok((Vec3::ONE, Some(map))),
                None => Ok((Vec3::splat(0.5), None)),
            },
            None => Ok((self.color(node, name, default)?, None)),
        }
    }

    /// A `bitmap` texture; a warning and `None` for another type or an image
    /// that cannot be read.
    fn bitmap(&mut self, t: Node) -> Result<Option<TextureMap>, SceneError> {
        let ty = self.attr(t, "type")?;
        if ty != "bitmap" {
            self.warnings.push(format!(
                "{}:{}: texture {ty:?} not supported, 0.5 grey used",
                self.path.display(),
                self.line(t)
            ));
            return Ok(None);
        }
        let file = self
            .prop(t, "filename")
            .ok_or_else(|| self.err(t, "bitmap without filename"))?;
        let file = self.dir.join(self.attr(file, "value")?);
        let raw = self.prop(t, "raw").and_then(|p| p.attribute("value")) == Some("true");
        let encoding = if raw { Encoding::Linear } else { Encoding::Srgb };
        let texture = match self.images.get(ImageSource::File(&file), encoding) {
            Ok(texture) => texture,
            Err(e) => {
                self.warnings.push(format!(
                    "{}:{}: {e}: 0.5 grey used",
                    self.path.display(),
                    self.line(t)
                ));
                return Ok(None);
            }
        };
        let wrap = match self.prop(t, "wrap_mode").and_then(|p| p.attribute("value")) {
            Some("clamp") => Wrap::Clamp,
            Some("mirror") => Wrap::Mirror,
            _ => Wrap::Repeat,
        };
        let transform = match t
            .children()
            .find(|c| c.has_tag_name("transform") && c.attribute("name") == Some("to_uv"))
        {
            Some(x) => {
                let m = self.transform(x)?;
                UvTransform {
                    columns: [m.x_axis.truncate().truncate(), m.y_axis.truncate().truncate()],
                    offset: Vec2::new(m.w_axis.x, m.w_axis.y),
                }
            }
            None => UvTransform::IDENTITY,
        };
        Ok(Some(TextureMap {
            texture,
            uv_set: 0,
            transform,
            wrap: [wrap; 2],
        }))
    }
}
