//! MTL materials (as tobj read them) made scene materials: colours, a
//! glossy lobe, emission, and the texture statements `map_Kd` (albedo),
//! `map_d` (cut-out), `bump`/`map_bump` (heights, or normals when the image
//! is one) and `norm` (normals), with their `-s`, `-o`, `-bm` and `-clamp`
//! options.

use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::images::{ImageSource, Images};
use crate::scene::texture::{Encoding, Relief, UvTransform, Wrap};
use crate::scene::{AlphaMap, Glossy, Material, Mesh, NormalMap, Texture, TextureMap};

/// A texture statement: the file and the options read.
#[derive(Clone, Debug, PartialEq)]
struct MapSpec {
    file: String,
    scale: Vec2,
    offset: Vec2,
    bump: f32,
    clamp: bool,
}

/// Parses `[options] file` (the file may hold spaces: it is the rest).
fn map_spec(s: &str) -> MapSpec {
    let mut spec = MapSpec {
        file: String::new(),
        scale: Vec2::ONE,
        offset: Vec2::ZERO,
        bump: 1.0,
        clamp: false,
    };
    let mut rest = s.trim();
    while rest.starts_with('-') {
        let mut words = rest.split_whitespace();
        let option = words.next().unwrap_or_default();
        let mut taken = 1;
        // Numbers an option takes (up to three for -o -s -t).
        let numbers: Vec<f32> = words
            .clone()
            .take(match option {
                "-o" | "-s" | "-t" => 3,
                "-mm" => 2,
                "-bm" | "-boost" => 1,
                _ => 0,
            })
            .map_while(|w| w.parse().ok())
            .collect();
        taken += numbers.len();
        let at = |i: usize, default: f32| numbers.get(i).copied().unwrap_or(default);
        match option {
            "-s" => spec.scale = Vec2::new(at(0, 1.0), at(1, 1.0)),
            "-o" => spec.offset = Vec2::new(at(0, 0.0), at(1, 0.0)),
            "-bm" => spec.bump = at(0, 1.0),
            "-clamp" => {
                spec.clamp = words.next() == Some("on");
                taken += 1;
            }
            "-blendu" | "-blendv" | "-cc" | "-imfchan" | "-texres" | "-type" => taken += 1,
            _ => {}
        }
        // Drop `taken` words from the front, keeping the rest's own spacing.
        for _ in 0..taken {
            rest = rest.trim_start();
            rest = rest.find(char::is_whitespace).map_or("", |i| &rest[i..]);
        }
        rest = rest.trim_start();
    }
    spec.file = rest.trim().to_string();
    spec
}

impl MapSpec {
    /// The options as a transform of flipped coordinates (`v` down): OBJ's
    /// `v' = v·s + o` with `v` up is `v' = v·s + (1 − s − o)` with `v` down.
    fn transform(&self) -> UvTransform {
        UvTransform {
            columns: [Vec2::new(self.scale.x, 0.0), Vec2::new(0.0, self.scale.y)],
            offset: Vec2::new(self.offset.x, 1.0 - self.scale.y - self.offset.y),
        }
    }

    fn map(&self, texture: Arc<Texture>) -> TextureMap {
        let mut map = TextureMap::new(texture);
        map.transform = self.transform();
        if self.clamp {
            map.wrap = [Wrap::Clamp; 2];
        }
        map
    }
}

/// The materials of an MTL: a scene material and the emission of each.
pub(super) fn materials(
    dir: &Path,
    mtl: &[tobj::Material],
    warnings: &mut Vec<String>,
) -> (Vec<Material>, Vec<Option<Vec3>>) {
    let mut images = Images::default();
    let mut materials = Vec::new();
    let mut emission = Vec::new();
    for m in mtl {
        let mut load = |statement: &str, encoding: Encoding, warnings: &mut Vec<String>| {
            let spec = map_spec(statement);
            let file = dir.join(spec.file.replace('\\', "/"));
            match images.get(ImageSource::File(&file), encoding) {
                Ok(t) => Some((spec, t)),
                Err(e) => {
                    warnings.push(format!("material {}: {e}: left out", m.name));
                    None
                }
            }
        };
        let albedo_map = m
            .diffuse_texture
            .as_deref()
            .and_then(|s| load(s, Encoding::Srgb, warnings))
            .map(|(spec, t)| spec.map(t));
        let kd = Vec3::from(
            m.diffuse
                .unwrap_or([if albedo_map.is_some() { 1.0 } else { 0.5 }; 3]),
        );
        // A texture's factor may be 1 (its lookups are capped); a colour's is kept below.
        let mut albedo = kd.max(Vec3::ZERO);
        if albedo_map.is_none() && kd.max_element() >= 1.0 {
            albedo = kd.min(Vec3::splat(0.99));
            warnings.push(format!("material {}: Kd {kd} clamped below 1", m.name));
        } else if kd.max_element() > 1.0 {
            albedo = kd.min(Vec3::ONE);
            warnings.push(format!("material {}: Kd {kd} clamped to 1", m.name));
        }
        let alpha = m.dissolve_texture.as_deref().and_then(|s| {
            // The alpha channel if the image has one (often map_Kd's own
            // file, decoded once), else its grey value.
            let (spec, t) = load(s, Encoding::Srgb, warnings)?;
            let (spec, t, channel) = if t.has_alpha() {
                (spec, t, 3)
            } else {
                let (spec, t) = load(s, Encoding::Linear, warnings)?;
                (spec, t, 0)
            };
            Some(AlphaMap {
                map: spec.map(t),
                channel,
                factor: 1.0,
                cutoff: 0.5,
            })
        });
        let norm = m.unknown_param.get("norm").map(|s| (s.as_str(), true));
        let bump = m.normal_texture.as_deref().map(|s| (s, false));
        let normal_map = norm.or(bump).and_then(|(s, normals)| {
            let (spec, t) = load(s, Encoding::Linear, warnings)?;
            // `bump` names a height map, but exporters write normal maps
            // there too: a bluish image of mean normal about +z is one.
            let mean = t.mean();
            let looks_normal = (mean.x - 0.5).abs() < 0.15 && (mean.y - 0.5).abs() < 0.15 && mean.z > 0.75;
            let relief = if normals || looks_normal {
                Relief::Normals
            } else {
                Relief::Heights
            };
            Some(NormalMap {
                map: spec.map(t),
                relief,
                // Heights get their scale once the meshes are known (`scale_heights`).
                scale: spec.bump,
            })
        });
        let ks = Vec3::from(m.specular.unwrap_or([0.0; 3]));
        let glossy = (ks.max_element() > 0.0).then(|| Glossy {
            specular: ks.min(Vec3::splat(0.99)),
            roughness: (2.0 / (m.shininess.unwrap_or(10.0).max(0.0) + 2.0)).sqrt(),
        });
        let ke = m.unknown_param.get("Ke").and_then(|s| parse_vec3(s));
        let ka = Vec3::from(m.ambient.unwrap_or([0.0; 3]));
        let e = match ke {
            Some(e) if e.max_element() > 0.0 => Some(e),
            _ if ka.max_element() > 1.0 => {
                warnings.push(format!(
                    "material {}: Ka {ka} > 1 taken as emitted radiance",
                    m.name
                ));
                Some(ka)
            }
            _ => None,
        };
        emission.push(e);
        materials.push(Material {
            name: m.name.clone(),
            albedo,
            glossy,
            albedo_map,
            alpha,
            normal_map,
            ..Material::diffuse("", Vec3::ZERO)
        });
    }
    (materials, emission)
}

/// An OBJ height map's `-bm` is in texels: its heights (0 to 1) times
/// `-bm` span that many texels of the surface, so the bump looks the same
/// whatever the model's units. Here each becomes scene units, by the mean
/// texel size over the material's triangles.
pub(super) fn scale_heights(materials: &mut [Material], meshes: &[Mesh]) {
    for (k, material) in materials.iter_mut().enumerate() {
        let Some(map) = material
            .normal_map
            .as_mut()
            .filter(|m| m.relief == Relief::Heights)
        else {
            continue;
        };
        let (w, h) = map.map.texture.size();
        let (mut area, mut uv_area) = (0.0f64, 0.0f64);
        for mesh in meshes.iter().filter(|m| m.material == k) {
            let Some(uvs) = mesh.uvs.first() else { continue };
            for t in &mesh.triangles {
                let [p, q, r] = t.map(|i| mesh.positions[i as usize]);
                let [a, b, c] = t.map(|i| map.map.transform.apply(uvs[i as usize]));
                area += (q - p).cross(r - p).length() as f64;
                uv_area += (b - a).perp_dot(c - a).abs() as f64;
            }
        }
        let texel = if uv_area > 0.0 {
            (area / (uv_area * w as f64 * h as f64)).sqrt() as f32
        } else {
            0.0
        };
        map.scale *= texel;
    }
}

pub(super) fn parse_vec3(s: &str) -> Option<Vec3> {
    let v: Vec<f32> = s
        .split_whitespace()
        .map(|t| t.parse().ok())
        .collect::<Option<_>>()?;
    match v.as_slice() {
        [x] => Some(Vec3::splat(*x)),
        [x, y, z] => Some(Vec3::new(*x, *y, *z)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_statements_with_options() {
        let s = map_spec("-s 2 3 1 -o 0.5 0.25 -bm 0.3 -clamp on textures/my wall.png");
        assert_eq!(s.file, "textures/my wall.png");
        assert_eq!(
            (s.scale, s.offset, s.bump, s.clamp),
            (Vec2::new(2.0, 3.0), Vec2::new(0.5, 0.25), 0.3, true)
        );
        assert_eq!(map_spec("  plain.jpg ").file, "plain.jpg");
        assert_eq!(map_spec("-imfchan r -bm 2 h.png").file, "h.png");
        // OBJ's v' = v·s + o, v up, seen with v down.
        let t = map_spec("-s 2 3 -o 0.5 0.25 x.png").transform();
        let (u, v) = (0.3f32, 0.6f32);
        let want = Vec2::new(u * 2.0 + 0.5, 1.0 - ((1.0 - v) * 3.0 + 0.25));
        assert!((t.apply(Vec2::new(u, v)) - want).length() < 1e-6);
    }
}
