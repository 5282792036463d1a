//! A subset of Mitsuba 3 XML large enough for real scenes: shapes (obj, ply,
//! rectangle, cube, sphere), bsdfs, emitters, the perspective sensor,
//! `<default>` parameters. Anything read but not supported is a warning.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

use super::common::{parse_err, read_text, single_file, smooth_normals, stem};
use super::images::Images;
use super::obj::read_obj;
use super::ply::read_ply;
use crate::scene::shapes::{cube_mesh, quad_mesh, sphere_mesh};
use crate::scene::{Camera, FileSettings, FovAxis, Light, Material, Mesh, Scene, SceneError};

/// Emitters: lights, and the environment (`constant`, `envmap`).
mod bsdfs;
mod emitters;

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
    environment: Option<crate::environment::Environment>,
    camera: Option<Camera>,
    /// The integrator's `max_depth` and the sampler's `sample_count`.
    file_settings: FileSettings,
    /// Texture images, each decoded once.
    images: Images,
}

type Node<'a, 'b> = roxmltree::Node<'a, 'b>;

pub(super) fn mitsuba(path: &Path, overrides: &HashMap<String, String>) -> Result<Scene, SceneError> {
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
        environment: None,
        ignored: Vec::new(),
        bsdfs: HashMap::new(),
        materials: Vec::new(),
        meshes: Vec::new(),
        lights: Vec::new(),
        camera: None,
        file_settings: FileSettings::default(),
        images: Images::default(),
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
            // Read where a bsdf refers to it (`<ref name=… id=…>`).
            "texture" if child.attribute("id").is_some() => {}
            "shape" => m.shape(child)?,
            "emitter" => m.emitter(child)?,
            "sensor" => m.sensor(child)?,
            "integrator" => {
                let depth = m.integer(child, "max_depth")?;
                m.file_settings.max_depth = depth.map(|d| d.clamp(-1, i64::from(i32::MAX)) as i32);
                m.ignore_rest("integrator", child, &["max_depth"]);
            }
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
        environment: m.environment,
        camera,
        warnings: m.warnings,
        file_settings: m.file_settings,
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

    /// The integer property `key` of `node` (`$name` substituted), if it has one.
    fn integer(&self, node: Node, key: &str) -> Result<Option<i64>, SceneError> {
        let Some(p) = self.prop(node, key) else {
            return Ok(None);
        };
        let v = self.attr(p, "value")?;
        let n = v.trim().parse::<i64>();
        n.map(Some)
            .map_err(|_| self.err(p, format!("{key} {v:?} is not a whole number")))
    }

    /// Names what `node` (an integrator, a sampler) sets beyond `used` as
    /// ignored; a path integrator or a sampler with nothing else is not.
    fn ignore_rest(&mut self, what: &str, node: Node, used: &[&str]) {
        let rest = self.describe(node, used);
        let ty = node.attribute("type").unwrap_or("?");
        if !rest.ends_with("()")
            || !matches!(
                ty,
                "path" | "independent" | "stratified" | "multijitter" | "ldsampler"
            )
        {
            self.ignored.push(format!("{what} {rest}"));
        }
    }

    fn describe(&self, node: Node, used: &[&str]) -> String {
        let props: Vec<String> = node
            .children()
            .filter(Node::is_element)
            .filter(|c| !c.attribute("name").is_some_and(|n| used.contains(&n)))
            .filter_map(|c| {
                // With `$name` parameters substituted where they resolve.
                let value = match c.attribute("value") {
                    Some(raw) => self.attr(c, "value").unwrap_or_else(|_| raw.to_string()),
                    None => "…".to_string(),
                };
                Some(format!("{}={value}", c.attribute("name")?))
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
        // Mitsuba's own form of a `<vector>` or `<point>`: `x=`, `y=`,
        // `z=`, each 0 where left out.
        let xyz = ["x", "y", "z"];
        if attr == "value"
            && node.attribute("value").is_none()
            && xyz.iter().any(|a| node.attribute(*a).is_some())
        {
            let mut v = [0.0f32; 3];
            for (c, a) in v.iter_mut().zip(xyz) {
                if node.attribute(a).is_some() {
                    *c = self.float(node, a)?;
                }
            }
            return Ok(Vec3::from_array(v));
        }
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
            } else if mesh.normals.is_none() && (ty == "obj" || ty == "ply") {
                // As Mitsuba does for a mesh file without normals unless
                // the shape asks for face normals.
                Some(smooth_normals(&mesh))
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
                "sampler" => {
                    let count = self.integer(c, "sample_count")?;
                    self.file_settings.sample_count = count.map(|n| n.clamp(1, i64::from(u32::MAX)) as u32);
                    self.ignore_rest("sampler", c, &["sample_count"]);
                }
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
