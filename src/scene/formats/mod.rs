//! Scene files: a subset of Mitsuba 3 XML (large enough for real scenes), OBJ +
//! MTL, PLY, OFF and glTF 2.0 (`.gltf`, `.glb`). Anything read but not supported is named in
//! [`Scene::warnings`]; malformed input is a [`SceneError`] with file and line.
//!
//! Data enters as a path; it leaves as a validated [`Scene`]. One file per
//! format (`mitsuba`, `obj`, `ply`, `off`, `gltf`), and `common` for what they share.

mod common;
mod gltf;
mod images;
mod mitsuba;
mod mtl;
mod obj;
mod off;
mod path;
mod ply;

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

pub use self::gltf::read_gltf;
pub use common::read_lat_long;
use common::single_file;
use mitsuba::mitsuba;
pub use obj::{MISSING_MTL_GREY, ObjFile, read_obj};
pub use off::read_off;
pub use path::read_camera_path;
pub use ply::read_ply;

use super::{Material, Scene, SceneError};

/// Loads a scene file, choosing the format by extension (`.xml`, `.obj`, `.ply`, `.off`,
/// `.gltf`, `.glb`).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, &HashMap::new())
}

/// As [`load`], with Mitsuba `$name` parameters overriding the file's `<default>`s.
pub fn load_with(path: &Path, params: &HashMap<String, String>) -> Result<Scene, SceneError> {
    if path.is_dir() {
        return Err(SceneError::Io {
            path: path.to_path_buf(),
            message:
                "a folder, not a regular file (a scene is an .xml, .obj, .ply, .off, .gltf or .glb file)"
                    .into(),
        });
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let scene = match ext.as_str() {
        "xml" => mitsuba(path, params)?,
        "obj" => {
            let obj = read_obj(path)?;
            let mut s = single_file(path, (obj.meshes, obj.materials))?;
            s.warnings.extend(obj.warnings);
            s
        }
        "ply" => bare_mesh(path, read_ply(path)?, Vec::new())?,
        "off" => {
            let (mesh, warnings) = read_off(path)?;
            bare_mesh(path, mesh, warnings)?
        }
        "gltf" | "glb" => read_gltf(path)?,
        _ => {
            return Err(SceneError::Unsupported {
                path: path.to_path_buf(),
                line: 0,
                what: format!("file type {ext:?} (expected .xml, .obj, .ply, .off, .gltf or .glb)"),
            });
        }
    };
    let mut scene = scene;
    warn_missing_coordinates(&mut scene);
    scene.light_if_unlit();
    scene.validate()?;
    Ok(scene)
}

/// A mesh whose material has a texture on a coordinate set the mesh lacks
/// (a PLY, a Mitsuba `cube`, an OBJ without `vt`) is warned of: its
/// textures are taken by their mean, a normal map left out.
fn warn_missing_coordinates(scene: &mut Scene) {
    // Per material: the first such mesh, and how many.
    let mut lacking: Vec<Option<(&str, usize, usize)>> = vec![None; scene.materials.len()];
    for mesh in &scene.meshes {
        let m = &scene.materials[mesh.material];
        let sets = [
            m.albedo_map.as_ref().map(|t| t.uv_set),
            m.alpha.as_ref().map(|a| a.map.uv_set),
            m.normal_map.as_ref().map(|n| n.map.uv_set),
        ];
        if let Some(set) = sets.into_iter().flatten().find(|&s| s >= mesh.uvs.len()) {
            let entry = lacking[mesh.material].get_or_insert((mesh.name.as_str(), set, 0));
            entry.2 += 1;
        }
    }
    let warnings: Vec<String> = lacking
        .iter()
        .zip(&scene.materials)
        .filter_map(|(l, m)| {
            let (first, set, count) = (*l)?;
            Some(format!(
                "material {}: {count} mesh(es), the first {first}, have no texture coordinate set {set}: \
                 their textures are taken by their mean, a normal map left out",
                m.name
            ))
        })
        .collect();
    scene.warnings.extend(warnings);
}

/// A scene around a mesh file that names no material, camera or light: a
/// two-sided grey, a camera looking at it, and (through `load`) the default
/// sky and sun when it has no light.
fn bare_mesh(path: &Path, mesh: super::Mesh, mut warnings: Vec<String>) -> Result<Scene, SceneError> {
    if mesh.emission.is_none() {
        warnings.insert(
            0,
            format!("{}: a bare mesh: default material and camera", path.display()),
        );
    }
    // A bare mesh's winding is anyone's guess: both sides reflect.
    let material = Material {
        two_sided: true,
        ..Material::diffuse("default", Vec3::splat(0.5))
    };
    let mut s = single_file(path, (vec![mesh], vec![material]))?;
    s.warnings.append(&mut warnings);
    Ok(s)
}
