//! Scene files: a subset of Mitsuba 3 XML (large enough for real scenes), OBJ +
//! MTL and PLY. Anything read but not supported is named in
//! [`Scene::warnings`]; malformed input is a [`SceneError`] with file and line.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

use super::{Camera, FovAxis, Glossy, Light, Material, Mesh, Scene, SceneError, builtin, fetched};

/// Loads a scene file, choosing the format by extension (`.xml`, `.obj`, `.ply`).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, &HashMap::new())
}

/// As [`load`], with Mitsuba `$name` parameters overriding the file's `<default>`s.
pub fn load_with(path: &Path, params: &HashMap<String, String>) -> Result<Scene, SceneError> {
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
        "ply" => {
            let mesh = read_ply(path)?;
            let mut warnings = vec![format!(
                "{}: a bare mesh: default material and camera",
                path.display()
            )];
            if mesh.emission.is_some() {
                warnings.clear();
            }
            let mut s = single_file(
                path,
                (vec![mesh], vec![Material::diffuse("default", Vec3::splat(0.5))]),
            )?;
            s.warnings.append(&mut warnings);
            s
        }
        _ => {
            return Err(SceneError::Unsupported {
                path: path.to_path_buf(),
                line: 0,
                what: format!("file type {ext:?} (expected .xml, .obj or .ply)"),
            });
        }
    };
    scene.validate()?;
    Ok(scene)
}

/// A built-in scene by name, else a fetched scene by name (from the scene
/// folder, [`fetched::scene_dir`]), else a file by path.
pub fn resolve(name_or_path: &str) -> Result<Scene, SceneError> {
    resolve_in(name_or_path, &fetched::scene_dir())
}

/// As [`resolve`], with fetched scenes read from `scene_dir`. A fetched
/// scene's name with its file missing is [`SceneError::MissingSceneData`].
pub fn resolve_in(name_or_path: &str, scene_dir: &Path) -> Result<Scene, SceneError> {
    if builtin::NAMES.contains(&name_or_path) {
        return builtin::scene(name_or_path);
    }
    if fetched::files(name_or_path).is_some() {
        return fetched::scene_in(name_or_path, scene_dir);
    }
    let p = Path::new(name_or_path);
    if p.exists() {
        load(p)
    } else {
        Err(SceneError::UnknownScene {
            name: name_or_path.to_string(),
            builtins: builtin::NAMES
                .iter()
                .chain(fetched::NAMES.iter())
                .copied()
                .collect(),
        })
    }
}

fn parse_err(path: &Path, line: usize, message: impl Into<String>) -> SceneError {
    SceneError::Parse {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

/// Only regular files are read: a device (`/dev/zero`, a FIFO) named by a
/// scene or linked to would be read forever.
fn regular_file(path: &Path) -> Result<(), SceneError> {
    let io = |message: String| SceneError::Io {
        path: path.to_path_buf(),
        message,
    };
    let meta = std::fs::metadata(path).map_err(|e| io(e.to_string()))?;
    if meta.is_file() {
        Ok(())
    } else {
        Err(io("not a regular file".into()))
    }
}

fn read_text(path: &Path) -> Result<String, SceneError> {
    regular_file(path)?;
    std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// A scene of meshes from one file with a camera looking at them from +z.
fn single_file(path: &Path, (meshes, materials): (Vec<Mesh>, Vec<Material>)) -> Result<Scene, SceneError> {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for p in meshes.iter().flat_map(|m| &m.positions) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    if meshes.iter().all(|m| m.triangles.is_empty()) {
        return Err(parse_err(path, 0, "no triangles"));
    }
    let center = (lo + hi) * 0.5;
    let size = (hi - lo).max_element().max(1e-6);
    Ok(Scene {
        name: stem(path),
        meshes,
        materials,
        lights: Vec::new(),
        camera: Camera {
            origin: center + Vec3::Z * (1.8 * size),
            target: center,
            up: Vec3::Y,
            fov_degrees: 40.0,
            fov_axis: FovAxis::Smaller,
            width: 256,
            height: 256,
        },
        warnings: vec![format!(
            "{}: no camera in the file, a default camera looks at it from +z",
            path.display()
        )],
    })
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string()
}

// ---------------------------------------------------------------- PLY

#[derive(Clone, Copy, PartialEq)]
enum PlyFormat {
    Ascii,
    Little,
    Big,
}

fn ply_size(t: &str) -> Option<usize> {
    Some(match t {
        "char" | "uchar" | "int8" | "uint8" => 1,
        "short" | "ushort" | "int16" | "uint16" => 2,
        "int" | "uint" | "float" | "int32" | "uint32" | "float32" => 4,
        "double" | "float64" => 8,
        _ => return None,
    })
}

struct PlyProp {
    name: String,
    ty: String,
    list: Option<String>,
}

struct PlyElement {
    name: String,
    count: usize,
    props: Vec<PlyProp>,
}

/// Reads a PLY mesh: vertices x, y, z (and nx, ny, nz), faces as index lists
/// (fan-triangulated); other properties and elements are skipped.
pub fn read_ply(path: &Path) -> Result<Mesh, SceneError> {
    regular_file(path)?;
    let bytes = std::fs::read(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| parse_err(path, 1, "no end_header"))?;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| parse_err(path, 1, "header is not text"))?;
    let mut body = end + 10;
    while body < bytes.len() && (bytes[body] == b'\r' || bytes[body] == b'\n') {
        body += 1;
        if bytes[body - 1] == b'\n' {
            break;
        }
    }
    let header_lines = header.lines().count() + 1;
    let mut format = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    for (i, line) in header.lines().enumerate() {
        let w: Vec<&str> = line.split_whitespace().collect();
        let bad = |m: &str| parse_err(path, i + 1, m.to_string());
        match w.first().copied() {
            Some("ply") | Some("comment") | Some("obj_info") | None => {}
            Some("format") => {
                format = Some(match w.get(1).copied() {
                    Some("ascii") => PlyFormat::Ascii,
                    Some("binary_little_endian") => PlyFormat::Little,
                    Some("binary_big_endian") => PlyFormat::Big,
                    _ => return Err(bad("unknown format")),
                })
            }
            Some("element") => {
                let count = w
                    .get(2)
                    .and_then(|c| c.parse::<usize>().ok())
                    .ok_or_else(|| bad("bad element count"))?;
                // Each element takes at least one byte: a count beyond the file is corrupt.
                if count > bytes.len() {
                    return Err(bad(&format!("element count {count} exceeds the file size")));
                }
                elements.push(PlyElement {
                    name: w.get(1).unwrap_or(&"").to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?;
                let p = if w.get(1) == Some(&"list") {
                    if w.len() < 5 || ply_size(w[2]).is_none() || ply_size(w[3]).is_none() {
                        return Err(bad("bad list property"));
                    }
                    PlyProp {
                        name: w[4].to_string(),
                        ty: w[3].to_string(),
                        list: Some(w[2].to_string()),
                    }
                } else {
                    if w.len() < 3 || ply_size(w[1]).is_none() {
                        return Err(bad("bad property"));
                    }
                    PlyProp {
                        name: w[2].to_string(),
                        ty: w[1].to_string(),
                        list: None,
                    }
                };
                e.props.push(p);
            }
            Some(other) => return Err(bad(&format!("unknown header keyword {other:?}"))),
        }
    }
    let format = format.ok_or_else(|| parse_err(path, 1, "no format line"))?;
    let mut reader = PlyReader {
        bytes: &bytes,
        pos: body,
        format,
        path,
        line: header_lines,
        tokens: Vec::new(),
    };
    let mut mesh = Mesh {
        name: stem(path),
        ..Mesh::default()
    };
    let mut normals = Vec::new();
    for e in &elements {
        for _ in 0..e.count {
            reader.start_row()?;
            let mut v = [0f64; 6];
            let mut has_normal = false;
            for p in &e.props {
                match &p.list {
                    Some(count_ty) => {
                        let n = reader.scalar(count_ty)?;
                        if !(0.0..=1e6).contains(&n) || n.fract() != 0.0 {
                            return Err(reader.error(&format!("bad list length {n}")));
                        }
                        let idx = (0..n as usize)
                            .map(|_| reader.scalar(&p.ty))
                            .collect::<Result<Vec<_>, _>>()?;
                        if e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index") {
                            let line = reader.line;
                            for k in 1..idx.len().saturating_sub(1) {
                                let t = [idx[0], idx[k], idx[k + 1]];
                                if t.iter().any(|&i| i < 0.0 || i.fract() != 0.0) {
                                    return Err(parse_err(path, line, "negative or fractional vertex index"));
                                }
                                mesh.triangles.push(t.map(|i| i as u32));
                            }
                        }
                    }
                    None => {
                        let x = reader.scalar(&p.ty)?;
                        if e.name == "vertex" {
                            let slot = ["x", "y", "z", "nx", "ny", "nz"]
                                .iter()
                                .position(|n| *n == p.name);
                            if let Some(s) = slot {
                                v[s] = x;
                                has_normal |= s >= 3;
                            }
                        }
                    }
                }
            }
            reader.end_row()?;
            if e.name == "vertex" {
                mesh.positions
                    .push(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32));
                if has_normal {
                    normals.push(Vec3::new(v[3] as f32, v[4] as f32, v[5] as f32).normalize_or(Vec3::Z));
                }
            }
        }
    }
    let n = mesh.positions.len() as u32;
    if let Some(t) = mesh.triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(parse_err(
            path,
            0,
            format!("face {t} refers to a vertex beyond the {n} given"),
        ));
    }
    if normals.len() == mesh.positions.len() && !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    Ok(mesh)
}

struct PlyReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: PlyFormat,
    path: &'a Path,
    line: usize,
    tokens: Vec<f64>,
}

impl PlyReader<'_> {
    fn error(&self, m: &str) -> SceneError {
        match self.format {
            PlyFormat::Ascii => parse_err(self.path, self.line, m.to_string()),
            _ => parse_err(self.path, self.line, format!("{m} (byte {})", self.pos)),
        }
    }

    fn start_row(&mut self) -> Result<(), SceneError> {
        if self.format != PlyFormat::Ascii {
            return Ok(());
        }
        loop {
            if self.pos >= self.bytes.len() {
                return Err(self.error("file ends early"));
            }
            let end = self.bytes[self.pos..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(self.bytes.len(), |i| self.pos + i);
            let text = String::from_utf8_lossy(&self.bytes[self.pos..end]).to_string();
            self.pos = end + 1;
            self.line += 1;
            if text.trim().is_empty() {
                continue;
            }
            let mut tokens = Vec::new();
            for t in text.split_whitespace().rev() {
                tokens.push(
                    t.parse::<f64>()
                        .map_err(|_| self.error(&format!("{t:?} is not a number")))?,
                );
            }
            self.tokens = tokens;
            return Ok(());
        }
    }

    fn end_row(&mut self) -> Result<(), SceneError> {
        Ok(())
    }

    fn scalar(&mut self, ty: &str) -> Result<f64, SceneError> {
        if self.format == PlyFormat::Ascii {
            return self
                .tokens
                .pop()
                .ok_or_else(|| self.error("too few values on the line"));
        }
        let size = ply_size(ty).ok_or_else(|| self.error("bad type"))?;
        if self.pos + size > self.bytes.len() {
            return Err(self.error("file ends early"));
        }
        let mut b = [0u8; 8];
        b[..size].copy_from_slice(&self.bytes[self.pos..self.pos + size]);
        if self.format == PlyFormat::Big {
            b[..size].reverse();
        }
        self.pos += size;
        Ok(match ty {
            "char" | "int8" => b[0] as i8 as f64,
            "uchar" | "uint8" => b[0] as f64,
            "short" | "int16" => i16::from_le_bytes([b[0], b[1]]) as f64,
            "ushort" | "uint16" => u16::from_le_bytes([b[0], b[1]]) as f64,
            "int" | "int32" => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            "uint" | "uint32" => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            "float" | "float32" => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            _ => f64::from_le_bytes(b),
        })
    }
}

// ---------------------------------------------------------------- OBJ

/// Reads an OBJ with its MTL: one mesh per object; `Kd` is the albedo
/// (clamped below 1, with a warning), `Ks`/`Ns` a glossy lobe, `Ke` emission.
/// Files from the wild that write a light as `Ka` > 1 get that as emission (warned).
pub fn read_obj(path: &Path) -> Result<ObjFile, SceneError> {
    // tobj reports no line numbers: check the common faults first, with lines.
    let text = read_text(path)?;
    // Counts of v, vt and vn lines so far: every face index must refer to one
    // (tobj's own checks miss some and then index out of bounds).
    let mut counts = [0i64; 3];
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
                    return Err(parse_err(path, i + 1, "a face needs three vertices"));
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
    let mtl = mtl.unwrap_or_else(|e| {
        warnings.push(format!(
            "{}: materials not read ({e}), default grey used",
            path.display()
        ));
        Vec::new()
    });
    let mut materials: Vec<Material> = Vec::new();
    let mut emission = Vec::new();
    for m in &mtl {
        let kd = Vec3::from(m.diffuse.unwrap_or([0.5; 3]));
        let mut albedo = kd;
        if kd.max_element() >= 1.0 {
            albedo = kd.min(Vec3::splat(0.99));
            warnings.push(format!("material {}: Kd {kd} clamped below 1", m.name));
        }
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
            bump: None,
            two_sided: false,
        });
    }
    materials.push(Material::diffuse("default", Vec3::splat(0.5)));
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
            Mesh {
                name: m.name,
                positions,
                triangles: mesh.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
                normals,
                material,
                emission: emission.get(material).copied().flatten(),
            }
        })
        .collect();
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

fn parse_vec3(s: &str) -> Option<Vec3> {
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

// ---------------------------------------------------------------- Mitsuba 3 XML

struct Mitsuba<'a> {
    path: &'a Path,
    dir: PathBuf,
    text: &'a str,
    params: HashMap<String, String>,
    warnings: Vec<String>,
    ignored: Vec<String>,
    bsdfs: HashMap<String, usize>,
    materials: Vec<Material>,
    meshes: Vec<Mesh>,
    lights: Vec<Light>,
    camera: Option<Camera>,
}

type Node<'a, 'b> = roxmltree::Node<'a, 'b>;

fn mitsuba(path: &Path, overrides: &HashMap<String, String>) -> Result<Scene, SceneError> {
    let text = read_text(path)?;
    let doc = roxmltree::Document::parse(&text)
        .map_err(|e| parse_err(path, e.pos().row as usize, e.to_string()))?;
    let root = doc.root_element();
    let mut m = Mitsuba {
        path,
        dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        text: &text,
        params: overrides.clone(),
        warnings: Vec::new(),
        ignored: Vec::new(),
        bsdfs: HashMap::new(),
        materials: Vec::new(),
        meshes: Vec::new(),
        lights: Vec::new(),
        camera: None,
    };
    if root.tag_name().name() != "scene" {
        return Err(parse_err(
            path,
            m.line(root),
            format!("root element is <{}>, expected <scene>", root.tag_name().name()),
        ));
    }
    for child in root.children().filter(Node::is_element) {
        match child.tag_name().name() {
            "default" => {
                let name = m.attr(child, "name")?;
                let value = child.attribute("value").unwrap_or("").to_string();
                m.params.entry(name).or_insert(value);
            }
            "bsdf" => {
                let material = m.bsdf(child)?;
                let id = child
                    .attribute("id")
                    .map(str::to_string)
                    .unwrap_or_else(|| material.name.clone());
                m.materials.push(Material {
                    name: id.clone(),
                    ..material
                });
                m.bsdfs.insert(id, m.materials.len() - 1);
            }
            "shape" => m.shape(child)?,
            "emitter" => m.emitter(child)?,
            "sensor" => m.sensor(child)?,
            "integrator" => m.ignored.push(format!("integrator {}", m.describe(child))),
            other => m.warnings.push(format!(
                "{}:{}: <{other}> not supported, skipped",
                path.display(),
                m.line(child)
            )),
        }
    }
    if !m.ignored.is_empty() {
        m.warnings.push(format!(
            "{}: rendering settings ignored: {}",
            path.display(),
            m.ignored.join("; ")
        ));
    }
    let camera = match m.camera {
        Some(c) => c,
        None => {
            m.warnings
                .push(format!("{}: no sensor, a default camera is used", path.display()));
            let s = single_file(path, (m.meshes.clone(), m.materials.clone()))?;
            s.camera
        }
    };
    if m.materials.is_empty() {
        m.materials.push(Material::diffuse("default", Vec3::splat(0.5)));
    }
    Ok(Scene {
        name: stem(path),
        meshes: m.meshes,
        materials: m.materials,
        lights: m.lights,
        camera,
        warnings: m.warnings,
    })
}

impl Mitsuba<'_> {
    fn line(&self, node: Node) -> usize {
        self.text[..node.range().start]
            .bytes()
            .filter(|&b| b == b'\n')
            .count()
            + 1
    }

    fn err(&self, node: Node, message: impl Into<String>) -> SceneError {
        parse_err(self.path, self.line(node), message)
    }

    fn describe(&self, node: Node) -> String {
        let props: Vec<String> = node
            .children()
            .filter(Node::is_element)
            .filter_map(|c| {
                Some(format!(
                    "{}={}",
                    c.attribute("name")?,
                    c.attribute("value").unwrap_or("…")
                ))
            })
            .collect();
        format!("{}({})", node.attribute("type").unwrap_or("?"), props.join(", "))
    }

    /// An attribute with `$name` parameters substituted.
    fn attr(&self, node: Node, name: &str) -> Result<String, SceneError> {
        let raw = node
            .attribute(name)
            .ok_or_else(|| self.err(node, format!("<{}> lacks {name}=", node.tag_name().name())))?;
        let mut out = String::new();
        let mut rest = raw;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let tail = &rest[i + 1..];
            let end = tail
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(tail.len());
            let key = &tail[..end];
            let v = self
                .params
                .get(key)
                .ok_or_else(|| self.err(node, format!("unknown parameter ${key}")))?;
            out.push_str(v);
            rest = &tail[end..];
        }
        out.push_str(rest);
        Ok(out)
    }

    fn float(&self, node: Node, name: &str) -> Result<f32, SceneError> {
        let v = self.attr(node, name)?;
        v.trim()
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| self.err(node, format!("{name}={v:?} is not a number")))
    }

    fn vec3(&self, node: Node, attr: &str) -> Result<Vec3, SceneError> {
        let v = self.attr(node, attr)?;
        let nums: Option<Vec<f32>> = v
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|t| !t.is_empty())
            .map(|t| t.parse().ok())
            .collect();
        match nums.as_deref() {
            Some([x]) if x.is_finite() => Ok(Vec3::splat(*x)),
            Some([x, y, z]) if [x, y, z].iter().all(|v| v.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(self.err(node, format!("{attr}={v:?} is not one or three numbers"))),
        }
    }

    /// A named property among `node`'s children.
    fn prop<'n>(&self, node: Node<'n, 'n>, name: &str) -> Option<Node<'n, 'n>> {
        node.children()
            .filter(Node::is_element)
            .find(|c| c.attribute("name") == Some(name))
    }

    fn color(&self, node: Node, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
        let Some(p) = self.prop(node, name) else {
            return Ok(default);
        };
        match p.tag_name().name() {
            "rgb" | "spectrum" | "float" => self.vec3(p, "value"),
            other => {
                let line = self.line(p);
                let _ = other;
                Err(SceneError::Unsupported {
                    path: self.path.to_path_buf(),
                    line,
                    what: format!("<{}> for {name}", p.tag_name().name()),
                })
            }
        }
    }

    fn scalar_prop(&self, node: Node, name: &str, default: f32) -> Result<f32, SceneError> {
        match self.prop(node, name) {
            Some(p) => self.float(p, "value"),
            None => Ok(default),
        }
    }

    fn bsdf(&mut self, node: Node) -> Result<Material, SceneError> {
        let ty = self.attr(node, "type")?;
        let name = node.attribute("id").unwrap_or(&ty).to_string();
        let mut m = Material::diffuse(name.clone(), Vec3::splat(0.5));
        match ty.as_str() {
            "diffuse" => m.albedo = self.texture_or_color(node, "reflectance", Vec3::splat(0.5))?,
            "twosided" => {
                let inner = node
                    .children()
                    .find(|c| c.has_tag_name("bsdf"))
                    .ok_or_else(|| self.err(node, "twosided without a nested <bsdf>"))?;
                m = self.bsdf(inner)?;
                m.name = name;
                m.two_sided = true;
            }
            "plastic" | "roughplastic" => {
                m.albedo = self.texture_or_color(node, "diffuse_reflectance", Vec3::splat(0.5))?;
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
        if m.albedo.max_element() >= 1.0 {
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

    fn texture_or_color(&mut self, node: Node, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
        if let Some(p) = self.prop(node, name)
            && p.tag_name().name() == "texture"
        {
            self.warnings.push(format!(
                "{}:{}: texture for {name} not supported, 0.5 used",
                self.path.display(),
                self.line(p)
            ));
            return Ok(Vec3::splat(0.5));
        }
        self.color(node, name, default)
    }

    fn transform(&self, node: Node) -> Result<Mat4, SceneError> {
        let mut m = Mat4::IDENTITY;
        for t in node.children().filter(Node::is_element) {
            let step = match t.tag_name().name() {
                "translate" => Mat4::from_translation(self.xyz(t, 0.0)?),
                "scale" => Mat4::from_scale(if t.attribute("value").is_some() {
                    self.vec3(t, "value")?
                } else {
                    self.xyz(t, 1.0)?
                }),
                "rotate" => {
                    let axis = self.xyz(t, 0.0)?;
                    if axis.length_squared() == 0.0 {
                        return Err(self.err(t, "rotation axis is zero"));
                    }
                    Mat4::from_axis_angle(axis.normalize(), self.float(t, "angle")?.to_radians())
                }
                "matrix" => {
                    let v = self.attr(t, "value")?;
                    let nums: Option<Vec<f32>> = v.split_whitespace().map(|x| x.parse().ok()).collect();
                    match nums {
                        Some(n) if n.len() == 16 && n.iter().all(|x| x.is_finite()) => {
                            Mat4::from_cols_array(&n.try_into().unwrap()).transpose()
                        }
                        _ => return Err(self.err(t, "matrix needs 16 numbers")),
                    }
                }
                "lookat" => {
                    let (o, target, up) = (
                        self.vec3(t, "origin")?,
                        self.vec3(t, "target")?,
                        self.vec3(t, "up")?,
                    );
                    let dir = (target - o).normalize_or_zero();
                    let left = up.cross(dir).normalize_or_zero();
                    if left == Vec3::ZERO {
                        return Err(self.err(t, "lookat: up is parallel to the view direction"));
                    }
                    let up = dir.cross(left);
                    Mat4::from_cols(left.extend(0.0), up.extend(0.0), dir.extend(0.0), o.extend(1.0))
                }
                other => {
                    return Err(SceneError::Unsupported {
                        path: self.path.to_path_buf(),
                        line: self.line(t),
                        what: format!("<{other}> in a transform"),
                    });
                }
            };
            m = step * m;
        }
        Ok(m)
    }

    fn xyz(&self, node: Node, default: f32) -> Result<Vec3, SceneError> {
        if node.attribute("value").is_some() {
            return self.vec3(node, "value");
        }
        let c = |a: &str| -> Result<f32, SceneError> {
            if node.attribute(a).is_some() {
                self.float(node, a)
            } else {
                Ok(default)
            }
        };
        Ok(Vec3::new(c("x")?, c("y")?, c("z")?))
    }

    fn to_world(&self, node: Node) -> Result<Mat4, SceneError> {
        match node.children().find(|c| c.has_tag_name("transform")) {
            Some(t) => self.transform(t),
            None => Ok(Mat4::IDENTITY),
        }
    }

    fn shape(&mut self, node: Node) -> Result<(), SceneError> {
        let ty = self.attr(node, "type")?;
        let id = node.attribute("id").unwrap_or(&ty).to_string();
        let m = self.to_world(node)?;
        let mut meshes = match ty.as_str() {
            "ply" | "obj" => {
                let file = self
                    .prop(node, "filename")
                    .ok_or_else(|| self.err(node, "shape without filename"))?;
                let rel = self.attr(file, "value")?;
                let p = self.dir.join(&rel);
                if !p.exists() {
                    return Err(SceneError::Io {
                        path: p,
                        message: format!(
                            "mesh file not found (referenced at {}:{})",
                            self.path.display(),
                            self.line(file)
                        ),
                    });
                }
                if ty == "ply" {
                    vec![read_ply(&p)?]
                } else {
                    let obj = read_obj(&p)?;
                    self.warnings.extend(obj.warnings);
                    obj.meshes
                }
            }
            "rectangle" => vec![quad_mesh()],
            "cube" => vec![cube_mesh()],
            "sphere" => {
                let center = match self.prop(node, "center") {
                    Some(c) => self.xyz(c, 0.0)?,
                    None => Vec3::ZERO,
                };
                let radius = self.scalar_prop(node, "radius", 1.0)?;
                vec![sphere_mesh(center, radius)]
            }
            other => {
                self.warnings.push(format!(
                    "{}:{}: shape {other:?} not supported, skipped",
                    self.path.display(),
                    self.line(node)
                ));
                return Ok(());
            }
        };
        let face_normals = matches!(
            self.prop(node, "face_normals").and_then(|p| p.attribute("value")),
            Some("true")
        );
        // Material: a <ref>, or a nested <bsdf>, else a default grey.
        let material = if let Some(r) = node.children().find(|c| c.has_tag_name("ref")) {
            let id = self.attr(r, "id")?;
            *self
                .bsdfs
                .get(&id)
                .ok_or_else(|| self.err(r, format!("no bsdf with id {id:?}")))?
        } else if let Some(b) = node.children().find(|c| c.has_tag_name("bsdf")) {
            let mat = self.bsdf(b)?;
            self.materials.push(mat);
            self.materials.len() - 1
        } else {
            self.materials
                .push(Material::diffuse(format!("{id}-default"), Vec3::splat(0.5)));
            self.materials.len() - 1
        };
        let emission = match node.children().find(|c| c.has_tag_name("emitter")) {
            Some(e) if self.attr(e, "type")? == "area" => Some(self.color(e, "radiance", Vec3::ONE)?),
            Some(e) => {
                self.warnings.push(format!(
                    "{}:{}: emitter {:?} on a shape not supported",
                    self.path.display(),
                    self.line(e),
                    e.attribute("type")
                ));
                None
            }
            None => None,
        };
        let flip = m.determinant() < 0.0;
        let normal_m = m.inverse().transpose();
        let count = meshes.len();
        for (i, mut mesh) in meshes.drain(..).enumerate() {
            for p in &mut mesh.positions {
                *p = m.transform_point3(*p);
            }
            if flip {
                for t in &mut mesh.triangles {
                    t.swap(1, 2);
                }
            }
            mesh.normals = if face_normals {
                None
            } else {
                mesh.normals.map(|ns| {
                    ns.into_iter()
                        .map(|n| normal_m.transform_vector3(n).normalize_or(Vec3::Z))
                        .collect()
                })
            };
            mesh.name = if count == 1 {
                id.clone()
            } else {
                format!("{id}/{i}")
            };
            mesh.material = material;
            mesh.emission = emission;
            self.meshes.push(mesh);
        }
        Ok(())
    }

    fn emitter(&mut self, node: Node) -> Result<(), SceneError> {
        let ty = self.attr(node, "type")?;
        let m = self.to_world(node)?;
        match ty.as_str() {
            "point" => {
                let position = match self.prop(node, "position") {
                    Some(p) => self.vec3(p, "value")?,
                    None => m.transform_point3(Vec3::ZERO),
                };
                self.lights.push(Light::Point {
                    position,
                    intensity: self.color(node, "intensity", Vec3::ONE)?,
                });
            }
            "directional" => {
                let direction = match self.prop(node, "direction") {
                    Some(p) => self.vec3(p, "value")?,
                    None => m.transform_vector3(Vec3::Z),
                };
                if direction.length_squared() == 0.0 {
                    return Err(self.err(node, "directional light with zero direction"));
                }
                self.lights.push(Light::Directional {
                    direction: direction.normalize(),
                    irradiance: self.color(node, "irradiance", Vec3::ONE)?,
                });
            }
            other => self.warnings.push(format!(
                "{}:{}: emitter {other:?} not supported, skipped",
                self.path.display(),
                self.line(node)
            )),
        }
        Ok(())
    }

    fn sensor(&mut self, node: Node) -> Result<(), SceneError> {
        let ty = self.attr(node, "type")?;
        if ty != "perspective" && ty != "thinlens" {
            return Err(SceneError::Unsupported {
                path: self.path.to_path_buf(),
                line: self.line(node),
                what: format!("sensor {ty:?}"),
            });
        }
        let fov = self.scalar_prop(node, "fov", 39.3077)?;
        let fov_axis = match self
            .prop(node, "fov_axis")
            .map(|p| self.attr(p, "value"))
            .transpose()?
            .as_deref()
        {
            None | Some("x") => FovAxis::X,
            Some("y") => FovAxis::Y,
            Some("smaller") => FovAxis::Smaller,
            Some("larger") => FovAxis::Larger,
            Some(other) => return Err(self.err(node, format!("fov_axis {other:?}"))),
        };
        let m = self.to_world(node)?;
        let origin = m.transform_point3(Vec3::ZERO);
        let forward = m.transform_vector3(Vec3::Z);
        let up = m.transform_vector3(Vec3::Y);
        let (mut width, mut height) = (768u32, 576u32);
        for c in node.children().filter(Node::is_element) {
            match c.tag_name().name() {
                "film" => {
                    for p in c.children().filter(Node::is_element) {
                        match p.attribute("name") {
                            Some("width") => width = self.float(p, "value")? as u32,
                            Some("height") => height = self.float(p, "value")? as u32,
                            _ => self.ignored.push(format!("film {}", self.describe_one(p)?)),
                        }
                    }
                }
                "sampler" => self.ignored.push(format!("sampler {}", self.describe(c))),
                "transform" | "float" | "string" => {
                    if let Some(n) = c.attribute("name")
                        && !matches!(n, "fov" | "fov_axis" | "to_world")
                    {
                        self.ignored.push(format!("sensor {}", self.describe_one(c)?));
                    }
                }
                other => self.ignored.push(format!("sensor <{other}>")),
            }
        }
        self.camera = Some(Camera {
            origin,
            target: origin + forward,
            up,
            fov_degrees: fov,
            fov_axis,
            width,
            height,
        });
        Ok(())
    }

    fn describe_one(&self, p: Node) -> Result<String, SceneError> {
        if p.attribute("name").is_none() {
            return Ok(format!(
                "<{} type={}>",
                p.tag_name().name(),
                self.attr(p, "type").unwrap_or_else(|_| "?".into())
            ));
        }
        Ok(format!(
            "{}={}",
            p.attribute("name").unwrap_or("?"),
            if p.attribute("value").is_some() {
                self.attr(p, "value")?
            } else {
                "…".into()
            }
        ))
    }
}

/// Mitsuba's `rectangle`: [−1, 1]² in z = 0, facing +z.
fn quad_mesh() -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..Mesh::default()
    }
}

/// Mitsuba's `cube`: [−1, 1]³, faces outward.
fn cube_mesh() -> Mesh {
    let mut mesh = Mesh::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push(n + u * a + v * b);
            }
            // Counter-clockwise seen from outside.
            if sign > 0.0 {
                mesh.triangles
                    .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
            } else {
                mesh.triangles
                    .extend([[base, base + 2, base + 1], [base, base + 3, base + 2]]);
            }
        }
    }
    mesh
}

/// A UV sphere, outward, with smooth normals.
fn sphere_mesh(center: Vec3, radius: f32) -> Mesh {
    let (nu, nv) = (64u32, 32u32);
    let mut mesh = Mesh::default();
    let mut normals = Vec::new();
    for j in 0..=nv {
        let theta = std::f32::consts::PI * j as f32 / nv as f32;
        for i in 0..=nu {
            let phi = std::f32::consts::TAU * i as f32 / nu as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            mesh.positions.push(center + n * radius);
            normals.push(n);
        }
    }
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (
                j * row + i,
                j * row + i + 1,
                (j + 1) * row + i,
                (j + 1) * row + i + 1,
            );
            if j > 0 {
                mesh.triangles.push([a, c, b]);
            }
            if j + 1 < nv {
                mesh.triangles.push([b, c, d]);
            }
        }
    }
    mesh.normals = Some(normals);
    mesh
}
