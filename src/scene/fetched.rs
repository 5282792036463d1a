//! Scenes built on the classic test models, which `scripts/fetch-scenes.sh`
//! fetches from package registries into the scene folder (never committed):
//!
//! | name | file | from |
//! | --- | --- | --- |
//! | `bunny`, `bunny-glossy` | `bunny/bunny.obj` | Debian `glmark2-data` (Stanford bunny) |
//! | `sponza`, `sponza-bump` | `sponza/sponza.obj` | crate `bvh` 0.13.0 (Dabrovic Sponza) |
//! | `cornell-box-embree` | `cornell-box-embree/cornell_box.{obj,mtl}` | Debian `python3-tinyobjloader` (Embree's box) |
//!
//! Which files they need and where they are looked for: [`catalogue`](super::catalogue).

use std::path::Path;

use glam::Vec3;

use super::formats::read_obj;
use super::{Bump, Camera, FovAxis, Glossy, Light, Material, Mesh, Scene, SceneError, builtin};

/// Sponza's scale: its 35 × 16.5 × 15.6 model units become 3.5 × 1.65 × 1.56,
/// so the default surfel density (2000 per unit area) gives about 200,000
/// surfels rather than 15 million.
pub const SPONZA_SCALE: f32 = 0.1;

/// All meshes of an OBJ merged into one (keeping the first's material).
fn merged(meshes: Vec<Mesh>, name: &str) -> Mesh {
    let mut out = Mesh {
        name: name.to_string(),
        ..Mesh::default()
    };
    let mut normals = Some(Vec::new());
    for m in meshes {
        let base = out.positions.len() as u32;
        out.triangles
            .extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
        out.positions.extend_from_slice(&m.positions);
        normals = match (normals, m.normals) {
            (Some(mut all), Some(n)) => {
                all.extend(n);
                Some(all)
            }
            _ => None,
        };
    }
    out.normals = normals.filter(|n| !n.is_empty());
    out
}

/// Six times the signed volume a mesh encloses (positive: faces point outward).
fn signed_volume6(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            a.dot(b.cross(c))
        })
        .sum()
}

/// Area-weighted vertex normals (unit; a vertex of only degenerate faces gets +y).
fn smooth_normals(mesh: &Mesh) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let f = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += f;
        }
    }
    n.into_iter().map(|v| v.normalize_or(Vec3::Y)).collect()
}

/// The paper's "Bunny": the Stanford bunny on the floor of the built-in
/// Cornell box (its blocks taken out), diffuse white, or glossy on a glossy floor.
pub(super) fn bunny(dir: &Path, glossy: bool) -> Result<Scene, SceneError> {
    let path = dir.join("bunny/bunny.obj");
    let obj = read_obj(&path)?;
    let mut mesh = merged(obj.meshes, "bunny");
    if mesh.triangles.is_empty() {
        return Err(SceneError::Invalid {
            what: format!("{}: no triangles", path.display()),
        });
    }
    if signed_volume6(&mesh) < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    // Stand it on the floor (y = −1), 1.1 tall, centred, turned a little towards the camera.
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for p in &mesh.positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let scale = 1.1 / (hi.y - lo.y).max(1e-6);
    let centre = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    let turn = glam::Quat::from_rotation_y(25f32.to_radians());
    let place = Vec3::new(0.0, -1.0, -0.1);
    for p in &mut mesh.positions {
        *p = turn * ((*p - centre) * scale) + place;
    }
    mesh.normals = Some(smooth_normals(&mesh));

    let mut s = builtin::cornell_box();
    s.meshes
        .retain(|m| m.name != "small-box" && m.name != "large-box");
    s.materials.push(if glossy {
        Material {
            glossy: Some(Glossy {
                specular: Vec3::splat(0.5),
                roughness: 0.1,
            }),
            ..Material::diffuse("glossy-bunny", Vec3::splat(0.35))
        }
    } else {
        Material::diffuse("bunny", Vec3::splat(0.8))
    });
    mesh.material = s.materials.len() - 1;
    s.meshes.push(mesh);
    if glossy {
        let white = s.materials[0].clone();
        s.materials.push(Material {
            name: "glossy-floor".into(),
            glossy: Some(Glossy {
                specular: Vec3::splat(0.35),
                roughness: 0.15,
            }),
            albedo: white.albedo * 0.6,
            ..white
        });
        let floor = s.materials.len() - 1;
        if let Some(m) = s.meshes.iter_mut().find(|m| m.name == "floor") {
            m.material = floor;
        }
    }
    s.name = if glossy { "bunny-glossy" } else { "bunny" }.into();
    s.warnings = obj.warnings;
    Ok(s)
}

/// Sandstone colours for Sponza's material groups (it ships no .mtl): by the
/// Croatian names' stems (pod floor, zid wall, stup/stub column, luk arch,
/// svod vault, prozor window, vrata door, kapitel capital, vijenac cornice).
fn sponza_albedo(name: &str) -> Vec3 {
    let rgb = |r, g, b| Vec3::new(r, g, b);
    if name.contains("pod") {
        rgb(0.46, 0.42, 0.37)
    } else if name.contains("zid_vani") {
        rgb(0.58, 0.52, 0.44)
    } else if name.contains("zid") {
        rgb(0.66, 0.6, 0.5)
    } else if name.contains("svod") || name.contains("kapitel") {
        rgb(0.72, 0.68, 0.6)
    } else if name.contains("stup") || name.contains("stub") {
        rgb(0.62, 0.58, 0.52)
    } else if name.contains("luk") || name.contains("vijenac") || name.contains("reljef") {
        rgb(0.68, 0.63, 0.55)
    } else if name.contains("prozor") || name.contains("vrata") {
        rgb(0.35, 0.25, 0.18)
    } else {
        rgb(0.6, 0.6, 0.6)
    }
}

/// Dabrovic Sponza scaled by [`SPONZA_SCALE`]: a sun from above the open
/// atrium, warm point lights in the arcades, a camera at the west end of the
/// atrium looking along it. `bump`: procedural bump on walls and floor and a
/// glossy floor.
pub(super) fn sponza(dir: &Path, bump: bool) -> Result<Scene, SceneError> {
    let path = dir.join("sponza/sponza.obj");
    let obj = read_obj(&path)?;
    let mut materials = obj.materials;
    for m in &mut materials {
        m.albedo = sponza_albedo(&m.name);
        m.two_sided = true;
        if bump && (m.name.contains("zid") || m.name.contains("pod")) {
            m.bump = Some(Bump {
                amplitude: 0.25,
                frequency: 12.0,
            });
        }
        if bump && m.name.contains("pod") {
            m.glossy = Some(Glossy {
                specular: Vec3::splat(0.3),
                roughness: 0.12,
            });
            m.albedo *= 0.7;
        }
    }
    let mut meshes = obj.meshes;
    for m in &mut meshes {
        for p in &mut m.positions {
            *p *= SPONZA_SCALE;
        }
    }
    let mut warnings: Vec<String> = obj
        .warnings
        .into_iter()
        .map(|w| {
            if w.contains("material library") {
                format!("{w}; pbgi gives them sandstone colours by group name instead")
            } else {
                w
            }
        })
        .collect();
    warnings.retain(|w| !w.is_empty());
    let k = SPONZA_SCALE;
    let mut lights = vec![Light::Directional {
        direction: Vec3::new(0.2, -1.0, 0.15).normalize(),
        irradiance: Vec3::new(6.0, 5.6, 4.8),
    }];
    // Warm lanterns along both ground-floor arcades and a cooler pair in the galleries.
    for x in [-9.0f32, -3.0, 3.0, 9.0] {
        for z in [-4.5f32, 4.0] {
            lights.push(Light::Point {
                position: Vec3::new(x, 2.5, z) * k,
                intensity: Vec3::new(0.036, 0.027, 0.018),
            });
        }
    }
    Ok(Scene {
        name: if bump { "sponza-bump" } else { "sponza" }.into(),
        meshes,
        materials,
        lights,
        environment: None,
        camera: Camera {
            origin: Vec3::new(-12.5, 2.0, -0.4) * k,
            target: Vec3::new(0.0, 4.2, 0.2) * k,
            up: Vec3::Y,
            fov_degrees: 70.0,
            fov_axis: FovAxis::X,
            width: 320,
            height: 240,
        },
        warnings,
        file_settings: Default::default(),
    })
}

/// Embree's Cornell box (the classic measured data, millimetres) scaled to
/// about 2 units, seen by the classic camera; the light is its `Ka 20`.
pub(super) fn cornell_box_embree(dir: &Path) -> Result<Scene, SceneError> {
    let path = dir.join("cornell-box-embree/cornell_box.obj");
    let obj = read_obj(&path)?;
    let (centre, k) = (Vec3::new(278.0, 274.4, 279.6), 2.0 / 556.0);
    let mut meshes = obj.meshes;
    for m in &mut meshes {
        for p in &mut m.positions {
            *p = (*p - centre) * k;
        }
    }
    let origin = (Vec3::new(278.0, 273.0, -800.0) - centre) * k;
    Ok(Scene {
        name: "cornell-box-embree".into(),
        meshes,
        materials: obj.materials,
        lights: Vec::new(),
        environment: None,
        camera: Camera {
            origin,
            target: origin + Vec3::Z,
            up: Vec3::Y,
            fov_degrees: 39.3077,
            fov_axis: FovAxis::Smaller,
            width: 256,
            height: 256,
        },
        warnings: obj.warnings,
        file_settings: Default::default(),
    })
}
