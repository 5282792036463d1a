//! Built-in scenes, no files needed.
//!
//! `cornell-box` is Mitsuba 3's `cornell_box()` exactly as exported to
//! `cbox.xml` + PLY (Mitsuba 3 is BSD-licensed): same geometry, reflectances,
//! light radiance and camera, 256×256. `cornell-box-glossy` is the same box
//! with a glossy floor, a bump-mapped back wall and a glossy tall block: the
//! high-frequency case where packets lose coherence. `nave` is the procedural
//! church interior of [`super::nave`], standing in for Sibenik.

use glam::Vec3;

use super::{Bump, Camera, FovAxis, Glossy, Material, Mesh, Scene, SceneError};

/// Names of the built-in scenes.
pub const NAMES: [&str; 3] = ["cornell-box", "cornell-box-glossy", "nave"];

const WHITE: usize = 0;
const GREEN: usize = 1;
const RED: usize = 2;
const LIGHT: Vec3 = Vec3::new(18.387, 13.9873, 6.75357);

type ShapeData = (
    &'static str,
    usize,
    Option<Vec3>,
    &'static [[f32; 3]],
    &'static [[u32; 3]],
);

#[rustfmt::skip]
const CORNELL: &[ShapeData] = &[
    ("light", WHITE, Some(LIGHT),
     &[[-0.22999999, 0.99, -0.17999999], [0.22999999, 0.99, -0.17999999], [0.22999999, 0.99, 0.2], [-0.22999999, 0.99, 0.2]],
     &[[0, 1, 2], [0, 2, 3]]),
    ("floor", WHITE, None,
     &[[-0.99999994, -0.99999994, 1.0], [0.99999994, -0.99999994, 1.0], [0.99999994, -1.0, -1.0], [-0.99999994, -1.0, -1.0]],
     &[[0, 1, 2], [0, 2, 3]]),
    ("ceiling", WHITE, None,
     &[[-0.99999994, 1.0, -1.0], [0.99999994, 1.0, -1.0], [0.99999994, 0.99999994, 1.0], [-0.99999994, 0.99999994, 1.0]],
     &[[0, 1, 2], [0, 2, 3]]),
    ("back", WHITE, None,
     &[[-1.0, -1.0, -1.0], [1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [-1.0, 1.0, -1.0]],
     &[[0, 1, 2], [0, 2, 3]]),
    ("green-wall", GREEN, None,
     &[[1.0, -0.99999994, -1.0], [0.99999994, -0.99999994, 1.0], [0.99999994, 0.99999994, 1.0], [1.0, 0.99999994, -1.0]],
     &[[0, 1, 2], [0, 2, 3]]),
    ("red-wall", RED, None,
     &[[-0.99999994, -0.99999994, 1.0], [-1.0, -0.99999994, -1.0], [-1.0, 0.99999994, -1.0], [-0.99999994, 0.99999994, 1.0]],
     &[[0, 1, 2], [0, 2, 3]]),
    ("small-box", WHITE, None,
     &[[0.709603, -1.0, 0.18082005], [0.53418, -1.0, 0.75460297], [-0.039602965, -1.0, 0.57917994], [0.13582006, -1.0, 0.005397022], [0.709603, -0.39999998, 0.18082005], [0.13582006, -0.39999998, 0.005397022], [-0.039602965, -0.39999998, 0.57917994], [0.53418, -0.39999998, 0.75460297], [0.709603, -1.0, 0.18082005], [0.709603, -0.39999998, 0.18082005], [0.53418, -0.39999998, 0.75460297], [0.53418, -1.0, 0.75460297], [0.53418, -1.0, 0.75460297], [0.53418, -0.39999998, 0.75460297], [-0.039602965, -0.39999998, 0.57917994], [-0.039602965, -1.0, 0.57917994], [-0.039602965, -1.0, 0.57917994], [-0.039602965, -0.39999998, 0.57917994], [0.13582006, -0.39999998, 0.005397022], [0.13582006, -1.0, 0.005397022], [0.709603, -0.39999998, 0.18082005], [0.709603, -1.0, 0.18082005], [0.13582006, -1.0, 0.005397022], [0.13582006, -0.39999998, 0.005397022]],
     &[[0, 1, 2], [3, 0, 2], [4, 5, 6], [7, 4, 6], [8, 9, 10], [11, 8, 10], [12, 13, 14], [15, 12, 14], [16, 17, 18], [19, 16, 18], [20, 21, 22], [23, 20, 22]]),
    ("large-box", WHITE, None,
     &[[-0.1390394, -1.01, -0.6588589], [0.04885888, -1.01, -0.089039385], [-0.5209606, -1.01, 0.09885889], [-0.7088589, -1.01, -0.47096062], [-0.1390394, 0.21000001, -0.6588589], [-0.7088589, 0.21000001, -0.47096062], [-0.5209606, 0.21000001, 0.09885889], [0.04885888, 0.21000001, -0.089039385], [-0.1390394, -1.01, -0.6588589], [-0.1390394, 0.21000001, -0.6588589], [0.04885888, 0.21000001, -0.089039385], [0.04885888, -1.01, -0.089039385], [0.04885888, -1.01, -0.089039385], [0.04885888, 0.21000001, -0.089039385], [-0.5209606, 0.21000001, 0.09885889], [-0.5209606, -1.01, 0.09885889], [-0.5209606, -1.01, 0.09885889], [-0.5209606, 0.21000001, 0.09885889], [-0.7088589, 0.21000001, -0.47096062], [-0.7088589, -1.01, -0.47096062], [-0.1390394, 0.21000001, -0.6588589], [-0.1390394, -1.01, -0.6588589], [-0.7088589, -1.01, -0.47096062], [-0.7088589, 0.21000001, -0.47096062]],
     &[[0, 1, 2], [3, 0, 2], [4, 5, 6], [7, 4, 6], [8, 9, 10], [11, 8, 10], [12, 13, 14], [15, 12, 14], [16, 17, 18], [19, 16, 18], [20, 21, 22], [23, 20, 22]]),
];

/// The built-in scene `name`.
pub fn scene(name: &str) -> Result<Scene, SceneError> {
    match name {
        "cornell-box" => Ok(cornell_box()),
        "cornell-box-glossy" => Ok(cornell_box_glossy()),
        "nave" => Ok(super::nave::nave()),
        _ => Err(SceneError::UnknownScene {
            name: name.to_string(),
            builtins: NAMES.to_vec(),
        }),
    }
}

/// Mitsuba 3's Cornell box.
pub fn cornell_box() -> Scene {
    let materials = vec![
        Material::diffuse("white", Vec3::new(0.885809, 0.698859, 0.666422)),
        Material::diffuse("green", Vec3::new(0.105421, 0.37798, 0.076425)),
        Material::diffuse("red", Vec3::new(0.570068, 0.0430135, 0.0443706)),
    ];
    let meshes = CORNELL
        .iter()
        .map(|&(name, material, emission, positions, triangles)| Mesh {
            name: name.to_string(),
            positions: positions.iter().map(|&p| Vec3::from_array(p)).collect(),
            triangles: triangles.to_vec(),
            normals: None,
            uvs: Vec::new(),
            material,
            emission,
        })
        .collect();
    Scene {
        name: "cornell-box".into(),
        meshes,
        materials,
        lights: Vec::new(),
        environment: None,
        camera: Camera {
            origin: Vec3::new(0.0, 0.0, 3.9),
            target: Vec3::new(0.0, 0.0, 2.9),
            up: Vec3::Y,
            fov_degrees: 39.3077,
            fov_axis: FovAxis::Smaller,
            width: 256,
            height: 256,
        },
        warnings: Vec::new(),
        file_settings: Default::default(),
    }
}

/// The Cornell box with a glossy floor, a bump-mapped back wall and a glossy
/// tall block.
pub fn cornell_box_glossy() -> Scene {
    let mut s = cornell_box();
    s.name = "cornell-box-glossy".into();
    let white = s.materials[WHITE].clone();
    let glossy_floor = Material {
        name: "glossy-floor".into(),
        glossy: Some(Glossy {
            specular: Vec3::splat(0.35),
            roughness: 0.15,
        }),
        albedo: white.albedo * 0.6,
        ..white.clone()
    };
    let bumpy_back = Material {
        name: "bumpy-back".into(),
        bump: Some(Bump {
            amplitude: 0.35,
            frequency: 6.0,
        }),
        ..white.clone()
    };
    let glossy_block = Material {
        name: "glossy-block".into(),
        glossy: Some(Glossy {
            specular: Vec3::splat(0.5),
            roughness: 0.08,
        }),
        albedo: white.albedo * 0.4,
        ..white
    };
    for (mesh, material) in [
        ("floor", glossy_floor),
        ("back", bumpy_back),
        ("large-box", glossy_block),
    ] {
        s.materials.push(material);
        let index = s.materials.len() - 1;
        if let Some(m) = s.meshes.iter_mut().find(|m| m.name == mesh) {
            m.material = index;
        }
    }
    s
}
