//! glTF 2.0: `.gltf` (JSON, buffers as base64 data URIs or `.bin` files
//! beside it) and `.glb` (the binary container). Read: the default scene's
//! node tree (else scene 0) with its transforms composed down the tree,
//! triangle meshes with their texture coordinates, PBR metallic-roughness
//! materials with their textures (`materials`),
//! emissive materials (area lights), the first perspective camera and
//! `KHR_lights_punctual` lights.
//!
//! Units: the project's radiometric quantities take glTF's photometric
//! ones one to one, as three.js and Babylon.js display them (candela →
//! W/sr, lux → irradiance, emissive × `KHR_materials_emissive_strength` →
//! radiance): a file is as bright here as in those viewers.

mod buffers;
mod materials;

use std::collections::HashMap;
use std::path::Path;

use ::gltf::camera::Projection;
use ::gltf::khr_lights_punctual::Kind;
use ::gltf::mesh::Mode;
use ::gltf::{Document, Semantic, json};
use glam::{Mat4, Quat, Vec3};

use super::common::{framing_camera, parse_err, regular_file, stem};
use super::images::Images;
use crate::scene::{Camera, FovAxis, Light, Material, Mesh, Scene, SceneError};
use buffers::{Buffers, load_buffers, split_glb};

/// Height of the image a glTF camera gets; its width follows the aspect ratio.
const IMAGE_HEIGHT: u32 = 256;

/// Reads a `.gltf` or `.glb` file (told apart by the GLB magic, not the
/// extension) into a scene. Anything read but not supported is named in
/// [`Scene::warnings`]; a malformed file is a [`SceneError`] naming the item.
///
/// ```
/// // One triangle, its vertices in a base64 data URI, under a node moved up by 2.
/// let json = r#"{"asset": {"version": "2.0"},
///   "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
///   "bufferViews": [{"buffer": 0, "byteLength": 36}],
///   "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
///   "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
///   "nodes": [{"mesh": 0, "translation": [0, 2, 0]}],
///   "scenes": [{"nodes": [0]}]}"#;
/// let path = std::env::temp_dir().join(format!("doc-{}.gltf", std::process::id()));
/// std::fs::write(&path, json).unwrap();
/// let scene = pbgi::scene::formats::read_gltf(&path).unwrap();
/// assert_eq!(scene.meshes[0].positions[2], glam::Vec3::new(0.0, 3.0, 0.0));
/// assert!(scene.warnings.iter().any(|w| w.contains("no perspective camera")));
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn read_gltf(path: &Path) -> Result<Scene, SceneError> {
    regular_file(path)?;
    let bytes = std::fs::read(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
        split_glb(path, &bytes)?
    } else {
        (&bytes[..], None)
    };
    let root: json::Root = json::deserialize::from_slice(json_bytes)
        .map_err(|e| parse_err(path, e.line(), format!("glTF JSON: {e}")))?;
    let mut warnings = Vec::new();
    let doc = validated(path, json_bytes, root, &mut warnings)?;
    let buffers = Buffers {
        path,
        data: load_buffers(path, &doc, blob)?,
    };
    let mut g = Gltf {
        path,
        doc: &doc,
        buffers,
        meshes: Vec::new(),
        materials: Vec::new(),
        material_of: HashMap::new(),
        images: Images::default(),
        lights: Vec::new(),
        camera: None,
        warnings,
    };
    g.walk()?;
    g.warn_unsupported();
    if g.meshes.iter().all(|m| m.triangles.is_empty()) {
        return Err(parse_err(path, 0, "no triangles in the scene's meshes"));
    }
    let camera = match g.camera {
        Some(c) => c,
        None => {
            g.warnings.push(format!(
                "{}: no perspective camera in the scene, a default camera looks at it from +z",
                path.display()
            ));
            framing_camera(&g.meshes)
        }
    };
    Ok(Scene {
        name: stem(path),
        meshes: g.meshes,
        materials: g.materials,
        lights: g.lights,
        environment: None,
        camera,
        warnings: g.warnings,
        file_settings: Default::default(),
    })
}

/// The document, checked by the `gltf` crate's validation. A POSITION
/// accessor without the `min` and `max` the spec asks for (some exporters
/// leave them out; nothing here reads them) is a warning; any other finding
/// an error naming the first three, each with its JSON path and the value
/// found there.
fn validated(
    path: &Path,
    json_bytes: &[u8],
    root: json::Root,
    warnings: &mut Vec<String>,
) -> Result<Document, SceneError> {
    use json::validation::{Checked, Error, Validate};
    // The crate's check of POSITION's min and max indexes the accessors
    // before checking the index (gltf-json 1.4.1 panics): checked here first.
    for (i, mesh) in root.meshes.iter().enumerate() {
        for (j, prim) in mesh.primitives.iter().enumerate() {
            if let Some(a) = prim.attributes.get(&Checked::Valid(Semantic::Positions))
                && a.value() >= root.accessors.len()
            {
                return Err(parse_err(
                    path,
                    0,
                    format!(
                        "glTF: meshes[{i}].primitives[{j}].attributes[\"POSITION\"]: Index out of bounds ({}): {} accessor(s)",
                        a.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(&root, json::Path::new, &mut |p, e| errors.push((p(), e)));
    let harmless = |(p, e): &(json::Path, Error)| {
        *e == Error::Missing
            && (p.as_str().ends_with("[\"POSITION\"].min") || p.as_str().ends_with("[\"POSITION\"].max"))
    };
    if errors.iter().any(harmless) {
        warnings.push(format!(
            "{}: a POSITION accessor without min and max (the spec asks for them; not needed here)",
            path.display()
        ));
    }
    errors.retain(|e| !harmless(e));
    if errors.is_empty() {
        return Ok(Document::from_json_without_validation(root));
    }
    let value: Option<json::Value> = json::deserialize::from_slice(json_bytes).ok();
    let items: Vec<String> = errors
        .iter()
        .take(3)
        .map(|(p, err)| {
            let pointer = format!(
                "/{}",
                p.as_str().replace('[', "/").replace(']', "").replace('.', "/")
            );
            match value.as_ref().and_then(|v| v.pointer(&pointer)) {
                Some(found) => format!("{p}: {err} ({found})"),
                None => format!("{p}: {err}"),
            }
        })
        .collect();
    let more = errors.len().saturating_sub(3);
    let tail = if more > 0 {
        format!(" (and {more} more)")
    } else {
        String::new()
    };
    Err(parse_err(path, 0, format!("glTF: {}{tail}", items.join("; "))))
}

struct Gltf<'a> {
    path: &'a Path,
    doc: &'a Document,
    buffers: Buffers<'a>,
    meshes: Vec<Mesh>,
    materials: Vec<Material>,
    /// glTF material index (`None`: the primitive names none) → index in `materials`.
    material_of: HashMap<Option<usize>, usize>,
    /// Texture images, each decoded once.
    images: Images,
    lights: Vec<Light>,
    camera: Option<Camera>,
    warnings: Vec<String>,
}

impl Gltf<'_> {
    fn err(&self, message: String) -> SceneError {
        parse_err(self.path, 0, message)
    }

    fn warn(&mut self, message: String) {
        let w = format!("{}: {message}", self.path.display());
        if !self.warnings.contains(&w) {
            self.warnings.push(w);
        }
    }

    /// The default scene (else scene 0, else every root node), depth first,
    /// each node's world transform its parent's times its own. A node reached
    /// twice (the graph is not a tree, or has a cycle) is drawn once.
    fn walk(&mut self) -> Result<(), SceneError> {
        let doc = self.doc;
        let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => s.nodes().map(|n| n.index()).collect(),
            None => {
                self.warn("no scene: every root node is drawn".into());
                let mut child = vec![false; doc.nodes().len()];
                for c in doc.nodes().flat_map(|n| n.children()) {
                    child[c.index()] = true;
                }
                (0..child.len()).filter(|&i| !child[i]).collect()
            }
        };
        let nodes: Vec<_> = doc.nodes().collect();
        let mut seen = vec![false; nodes.len()];
        let mut stack: Vec<(usize, Mat4)> = roots.into_iter().rev().map(|i| (i, Mat4::IDENTITY)).collect();
        while let Some((i, parent)) = stack.pop() {
            if std::mem::replace(&mut seen[i], true) {
                self.warn(format!("node {i} is reached twice (not a tree): drawn once"));
                continue;
            }
            let node = &nodes[i];
            let world = parent * self.local(node)?;
            if let Some(mesh) = node.mesh() {
                if node.skin().is_some() {
                    self.warn(format!(
                        "node {i}: skin ignored, the mesh is drawn in its rest pose"
                    ));
                }
                self.mesh(&mesh, world)?;
            }
            if let Some(camera) = node.camera() {
                self.camera(i, &camera, world)?;
            }
            if let Some(light) = node.light() {
                self.light(i, &light, world)?;
            }
            stack.extend(
                node.children()
                    .map(|c| (c.index(), world))
                    .collect::<Vec<_>>()
                    .into_iter()
                    .rev(),
            );
        }
        Ok(())
    }

    /// A node's own transform: its matrix, or translation × rotation × scale.
    fn local(&self, node: &::gltf::Node) -> Result<Mat4, SceneError> {
        let m = match node.transform() {
            ::gltf::scene::Transform::Matrix { matrix } => Mat4::from_cols_array_2d(&matrix),
            ::gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let q = Quat::from_array(rotation);
                if !(q.is_finite() && q.length_squared() > 0.0) {
                    return Err(self.err(format!(
                        "node {}: rotation {rotation:?} is not a quaternion",
                        node.index()
                    )));
                }
                Mat4::from_scale_rotation_translation(scale.into(), q.normalize(), translation.into())
            }
        };
        if !m.is_finite() {
            return Err(self.err(format!("node {}: transform is not finite", node.index())));
        }
        Ok(m)
    }

    /// One scene mesh per primitive, in world space.
    fn mesh(&mut self, mesh: &::gltf::Mesh, world: Mat4) -> Result<(), SceneError> {
        let flip = world.determinant() < 0.0;
        let normal_m = world.inverse().transpose();
        let name = mesh
            .name()
            .map_or_else(|| format!("mesh {}", mesh.index()), str::to_string);
        for prim in mesh.primitives() {
            let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
            let mode = prim.mode();
            if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                self.warn(format!("{what}: {mode:?} primitives are not triangles, skipped"));
                continue;
            }
            if prim.morph_targets().next().is_some() {
                self.warn(format!("{what}: morph targets ignored"));
            }
            let positions_acc = prim
                .get(&Semantic::Positions)
                .ok_or_else(|| self.err(format!("{what}: no POSITION attribute")))?;
            let positions = self.buffers.vec3(&format!("{what} POSITION"), &positions_acc)?;
            let n = positions.len();
            let corners: Vec<u32> = match prim.indices() {
                Some(a) => {
                    let idx = self.buffers.indices(&format!("{what} indices"), &a)?;
                    if let Some(k) = idx.iter().position(|&i| i as usize >= n) {
                        return Err(self.err(format!(
                            "{what}: index {k} (vertex {}) beyond the {n} vertices of accessor {}",
                            idx[k],
                            positions_acc.index()
                        )));
                    }
                    idx
                }
                None => (0..n as u32).collect(),
            };
            let triangles = triangles(mode, &corners);
            if mode == Mode::Triangles && !corners.len().is_multiple_of(3) {
                self.warn(format!(
                    "{what}: {} corners, not a multiple of 3: the rest left out",
                    corners.len()
                ));
            }
            let normals = match prim.get(&Semantic::Normals) {
                Some(a) => {
                    let ns = self.buffers.vec3(&format!("{what} NORMAL"), &a)?;
                    if ns.len() != n {
                        return Err(self.err(format!("{what}: {} normals for {n} positions", ns.len())));
                    }
                    Some(
                        ns.into_iter()
                            .map(|v| normal_m.transform_vector3(v).normalize_or(Vec3::Z))
                            .collect(),
                    )
                }
                None => None,
            };
            let mut uvs = Vec::new();
            while let Some(a) = prim.get(&Semantic::TexCoords(uvs.len() as u32)) {
                let set = self.buffers.vec2(&format!("{what} TEXCOORD_{}", uvs.len()), &a)?;
                if set.len() != n {
                    return Err(self.err(format!(
                        "{what}: {} texture coordinates for {n} positions",
                        set.len()
                    )));
                }
                uvs.push(set);
            }
            let (material, emission) = self.material(&prim.material());
            self.meshes.push(Mesh {
                name: format!("{name}/{}", prim.index()),
                positions: positions.into_iter().map(|p| world.transform_point3(p)).collect(),
                triangles: if flip {
                    triangles.into_iter().map(|[a, b, c]| [a, c, b]).collect()
                } else {
                    triangles
                },
                normals,
                uvs,
                material,
                emission,
            });
        }
        Ok(())
    }

    /// The first perspective camera: glTF cameras look down their −Z with +Y up.
    fn camera(&mut self, node: usize, camera: &::gltf::Camera, world: Mat4) -> Result<(), SceneError> {
        let Projection::Perspective(p) = camera.projection() else {
            self.warn(format!(
                "node {node}: orthographic camera {} not supported",
                camera.index()
            ));
            return Ok(());
        };
        if self.camera.is_some() {
            self.warn(format!(
                "node {node}: camera {} ignored, the first camera is used",
                camera.index()
            ));
            return Ok(());
        }
        let origin = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y);
        if forward == Vec3::ZERO || forward.cross(up).length_squared() == 0.0 {
            return Err(self.err(format!(
                "node {node}: camera {} has a degenerate transform",
                camera.index()
            )));
        }
        // No aspect ratio: the viewer's, here a square frame.
        let aspect = p.aspect_ratio().unwrap_or(1.0);
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(self.err(format!(
                "node {node}: camera {} has aspect ratio {aspect}",
                camera.index()
            )));
        }
        self.camera = Some(Camera {
            origin,
            target: origin + forward,
            up,
            fov_degrees: p.yfov().to_degrees(),
            fov_axis: FovAxis::Y,
            width: (IMAGE_HEIGHT as f32 * aspect)
                .round()
                .clamp(1.0, crate::scene::MAX_IMAGE_SIDE as f32) as u32,
            height: IMAGE_HEIGHT,
        });
        Ok(())
    }

    /// A `KHR_lights_punctual` light at its node: candela and lux taken as
    /// W/sr and irradiance (see the module's note on units).
    fn light(
        &mut self,
        node: usize,
        light: &::gltf::khr_lights_punctual::Light,
        world: Mat4,
    ) -> Result<(), SceneError> {
        let value = Vec3::from(light.color()) * light.intensity();
        if light.range().is_some() {
            self.warn(format!(
                "light {}: range ignored (inverse-square falloff to any distance)",
                light.index()
            ));
        }
        match light.kind() {
            Kind::Directional => {
                let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
                if direction == Vec3::ZERO {
                    return Err(self.err(format!("node {node}: light {} has no direction", light.index())));
                }
                self.lights.push(Light::Directional {
                    direction,
                    irradiance: value,
                });
            }
            kind => {
                if matches!(kind, Kind::Spot { .. }) {
                    self.warn(format!(
                        "light {}: spot light taken as a point light (no cone)",
                        light.index()
                    ));
                }
                self.lights.push(Light::Point {
                    position: world.transform_point3(Vec3::ZERO),
                    intensity: value,
                });
            }
        }
        Ok(())
    }

    /// Warnings for what the file holds that is read past, once each.
    fn warn_unsupported(&mut self) {
        if self.doc.animations().next().is_some() {
            self.warn("animations ignored: the scene is drawn in its static pose".into());
        }
        let used: Vec<String> = self
            .doc
            .extensions_used()
            .filter(|e| {
                !matches!(
                    *e,
                    "KHR_lights_punctual" | "KHR_materials_emissive_strength" | "KHR_texture_transform"
                )
            })
            .map(str::to_string)
            .collect();
        if !used.is_empty() {
            self.warn(format!("extensions ignored: {}", used.join(", ")));
        }
    }
}

/// Triangles from a primitive's corners (strips and fans unrolled, their
/// odd triangles kept counter-clockwise).
fn triangles(mode: Mode, c: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..c.len().saturating_sub(2))
            .map(|i| {
                if i % 2 == 0 {
                    [c[i], c[i + 1], c[i + 2]]
                } else {
                    [c[i + 1], c[i], c[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..c.len().saturating_sub(1))
            .map(|i| [c[0], c[i], c[i + 1]])
            .collect(),
        _ => c.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}
