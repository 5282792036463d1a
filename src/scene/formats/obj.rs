//! OBJ meshes with their MTL materials (through tobj), checked before tobj
//! sees them.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::common::{parse_err, read_text};
use crate::scene::{Material, Mesh, SceneError};

/// Reads an OBJ with its MTL: one mesh per object, with its texture
/// coordinates; the materials as `mtl` makes them (`Kd` and `map_Kd` the
/// albedo, `Ks`/`Ns` a glossy lobe, `Ke` emission, `map_d` a cut-out,
/// `bump`/`norm` a normal map).
pub fn read_obj(path: &Path) -> Result<ObjFile, SceneError> {
    // tobj reports no line numbers: check the common faults first, with lines.
    let text = read_text(path)?;
    // Counts of v, vt and vn lines so far: every face index must refer to one
    // (tobj's own checks miss some and then index out of bounds).
    let mut counts = [0i64; 3];
    // Lines (0-based) of faces with fewer than three vertices.
    let mut degenerate: Vec<usize> = Vec::new();
    // Material names in order of first use, for an OBJ whose MTL is missing.
    let mut used_materials: Vec<String> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("usemtl") => {
                let name = line.trim_start()["usemtl".len()..].trim();
                if !name.is_empty() && !used_materials.iter().any(|m| m == name) {
                    used_materials.push(name.to_string());
                }
            }
            Some(key @ ("v" | "vn" | "vt")) => {
                let n = if key == "vt" { 2 } else { 3 };
                let nums: Vec<_> = w.collect();
                if nums.len() < n
                    || nums
                        .iter()
                        .take(n)
                        .any(|t| t.parse::<f32>().map_or(true, |x| !x.is_finite()))
                {
                    return Err(parse_err(path, i + 1, format!("bad {key} line {line:?}")));
                }
                counts[["v", "vt", "vn"].iter().position(|k| *k == key).unwrap_or(0)] += 1;
            }
            Some("f") => {
                let idx: Vec<_> = w.collect();
                if idx.len() < 3 {
                    // Lines and points written as faces (real exports have
                    // them): no area to light, left out with a warning.
                    degenerate.push(i);
                    continue;
                }
                for t in idx {
                    for (slot, part) in t.split('/').enumerate() {
                        let (what, count) = match slot {
                            0 => ("vertex", counts[0]),
                            1 => ("texture coordinate", counts[1]),
                            2 => ("normal", counts[2]),
                            _ => {
                                return Err(parse_err(
                                    path,
                                    i + 1,
                                    format!("face index {t:?} has too many parts"),
                                ));
                            }
                        };
                        if slot > 0 && part.is_empty() {
                            continue; // `v//vn` or `v/vt/`
                        }
                        match part.parse::<i64>() {
                            Ok(k) if (k > 0 && k <= count) || (k < 0 && -k <= count) => {}
                            _ => {
                                return Err(parse_err(
                                    path,
                                    i + 1,
                                    format!("face index {t:?}: {what} out of range ({count} so far)"),
                                ));
                            }
                        }
                    }
                }
            }
            _ => {}
        }
    }
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    // The text already read; material libraries relative to the file,
    // regular files only, and refused when tobj would panic on them. A
    // missing, unreadable or refused MTL is not an error: the materials
    // `usemtl` names get the default grey (and keep their names, so meshes
    // stay apart by material).
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mtl_problems = std::cell::RefCell::new(Vec::<String>::new());
    let load_mtl = |p: &Path| -> tobj::MTLLoadResult {
        let file = dir.join(p);
        let problem = match read_text(&file) {
            Ok(text) if mtl_is_well_formed(&text) => return tobj::load_mtl_buf(&mut text.as_bytes()),
            Ok(_) => format!("{}: a colour with fewer than three numbers", file.display()),
            Err(e) => e.to_string(),
        };
        let mut problems = mtl_problems.borrow_mut();
        let first = problems.is_empty();
        problems.push(problem);
        let names = if first { &used_materials[..] } else { &[] };
        let stand_ins = names
            .iter()
            .map(|name| tobj::Material {
                name: name.clone(),
                diffuse: Some([MISSING_MTL_GREY; 3]),
                ..Default::default()
            })
            .collect();
        let map = names.iter().enumerate().map(|(k, n)| (n.clone(), k)).collect();
        Ok((stand_ins, map))
    };
    // The text tobj reads: degenerate faces commented out (lines keep their numbers).
    let text = if degenerate.is_empty() {
        text
    } else {
        let mut skip = degenerate.iter().peekable();
        text.lines()
            .enumerate()
            .map(|(i, line)| {
                if skip.next_if_eq(&&i).is_some() {
                    format!("# {line}\n")
                } else {
                    format!("{line}\n")
                }
            })
            .collect()
    };
    let (models, mtl) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, load_mtl)
        .map_err(|e| parse_err(path, 0, e.to_string()))?;
    let mut warnings: Vec<String> = mtl_problems
        .into_inner()
        .into_iter()
        .map(|problem| {
            format!(
                "{}: material library not read ({problem}): the {} material(s) named by usemtl get the default grey {MISSING_MTL_GREY}",
                path.display(),
                used_materials.len()
            )
        })
        .collect();
    if let Some(first) = degenerate.first() {
        warnings.push(format!(
            "{}: {} face(s) with fewer than three vertices left out (the first at line {})",
            path.display(),
            degenerate.len(),
            first + 1
        ));
    }
    let mtl = mtl.unwrap_or_else(|e| {
        warnings.push(format!(
            "{}: materials not read ({e}), default grey used",
            path.display()
        ));
        Vec::new()
    });
    let (mut materials, emission) = super::mtl::materials(&dir, &mtl, &mut warnings);
    // Faces with no material: the grey of a bare PLY or OFF mesh, two-sided
    // as it is (an OBJ cube without its .mtl rendered black from behind).
    materials.push(Material {
        two_sided: true,
        ..Material::diffuse("default", Vec3::splat(0.5))
    });
    let default = materials.len() - 1;
    let meshes = models
        .into_iter()
        .map(|m| {
            let mesh = m.mesh;
            let positions: Vec<Vec3> = mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect();
            let normals =
                (mesh.normals.len() == mesh.positions.len() && !mesh.normals.is_empty()).then(|| {
                    mesh.normals
                        .chunks_exact(3)
                        .map(|n| Vec3::new(n[0], n[1], n[2]).normalize_or(Vec3::Z))
                        .collect()
                });
            let material = mesh.material_id.filter(|&i| i < default).unwrap_or(default);
            // OBJ's v grows up the image; the scene's grows down.
            let uvs = (mesh.texcoords.len() / 2 == positions.len() && !positions.is_empty())
                .then(|| {
                    mesh.texcoords
                        .chunks_exact(2)
                        .map(|t| Vec2::new(t[0], 1.0 - t[1]))
                        .collect()
                })
                .into_iter()
                .collect();
            Mesh {
                name: m.name,
                positions,
                triangles: mesh.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
                normals,
                uvs,
                material,
                emission: emission.get(material).copied().flatten(),
            }
        })
        .collect::<Vec<Mesh>>();
    super::mtl::scale_heights(&mut materials, &meshes);
    Ok(ObjFile {
        meshes,
        materials,
        warnings,
    })
}

/// tobj 4.0.5 panics on a colour line with fewer than three numbers
/// (`Ks 0.5 0.5`); such a library is refused before it gets there.
fn mtl_is_well_formed(text: &str) -> bool {
    text.lines().all(|line| {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("Ka" | "Kd" | "Ks" | "Ke") => w.take(3).filter(|t| t.parse::<f32>().is_ok()).count() == 3,
            _ => true,
        }
    })
}

/// Albedo of the materials an OBJ names by `usemtl` when its MTL file is missing.
pub const MISSING_MTL_GREY: f32 = 0.5;

/// What an OBJ file holds.
pub struct ObjFile {
    /// One mesh per object.
    pub meshes: Vec<Mesh>,
    /// Its materials, and a default grey last.
    pub materials: Vec<Material>,
    /// What was read but changed or not supported.
    pub warnings: Vec<String>,
}
