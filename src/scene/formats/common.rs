//! What every format reader shares: errors naming file and line, reading
//! regular files only, and a scene around a single mesh file.

use std::path::Path;

use glam::Vec3;

use crate::environment::LatLong;
use crate::scene::{Camera, FovAxis, Material, Mesh, Scene, SceneError};

pub(super) fn parse_err(path: &Path, line: usize, message: impl Into<String>) -> SceneError {
    SceneError::Parse {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

/// Only regular files are read: a device (`/dev/zero`, a FIFO) named by a
/// scene or linked to would be read forever.
pub(super) fn regular_file(path: &Path) -> Result<(), SceneError> {
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

pub(super) fn read_text(path: &Path) -> Result<String, SceneError> {
    regular_file(path)?;
    std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// A scene of meshes from one file with a camera looking at them from +z.
pub(super) fn single_file(
    path: &Path,
    (meshes, materials): (Vec<Mesh>, Vec<Material>),
) -> Result<Scene, SceneError> {
    if meshes.iter().all(|m| m.triangles.is_empty()) {
        return Err(parse_err(path, 0, "no triangles"));
    }
    Ok(Scene {
        name: stem(path),
        camera: framing_camera(&meshes),
        meshes,
        materials,
        lights: Vec::new(),
        environment: None,
        warnings: vec![format!(
            "{}: no camera in the file, a default camera looks at it from +z",
            path.display()
        )],
        file_settings: Default::default(),
    })
}

/// A 256×256 camera looking at the meshes' bounding box from +z.
pub(super) fn framing_camera(meshes: &[Mesh]) -> Camera {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for p in meshes.iter().flat_map(|m| &m.positions) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let center = (lo + hi) * 0.5;
    let size = (hi - lo).max_element().max(1e-6);
    Camera {
        origin: center + Vec3::Z * (1.8 * size),
        target: center,
        up: Vec3::Y,
        fov_degrees: 40.0,
        fov_axis: FovAxis::Smaller,
        width: 256,
        height: 256,
    }
}

pub(super) fn stem(path: &Path) -> String {
    path.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string()
}

/// An equirectangular HDR environment map (OpenEXR, RGB) times `scale`.
pub fn read_lat_long(path: &Path, scale: f32) -> Result<LatLong, SceneError> {
    use exr::prelude::*;
    regular_file(path)?;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
        },
    )
    .map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        message: format!("environment map: {e}"),
    })?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    let pixels = pixels.into_iter().map(|p| p * scale).collect();
    LatLong::new(size.width(), size.height(), pixels).map_err(|e| SceneError::Invalid {
        what: format!("{}: {e}", path.display()),
    })
}

/// Area-weighted vertex normals of `mesh` (world space); a vertex whose
/// faces cancel takes its first face's normal.
pub(super) fn smooth_normals(mesh: &Mesh) -> Vec<Vec3> {
    let mut sum = vec![Vec3::ZERO; mesh.positions.len()];
    let mut first = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            sum[i as usize] += n;
            if first[i as usize] == Vec3::ZERO {
                first[i as usize] = n;
            }
        }
    }
    sum.iter()
        .zip(&first)
        .map(|(s, f)| s.try_normalize().or_else(|| f.try_normalize()).unwrap_or(Vec3::Z))
        .collect()
}
