//! Camera-path files: `{"frames": [{"origin": [x, y, z], "target": [x, y, z],
//! "up": [x, y, z], "fov": degrees}, …]}`, `up` and `fov` optional (the scene
//! camera's).

use std::path::Path;

use glam::Vec3;
use serde_json::Value;

use crate::scene::{Camera, CameraPath, CameraPose, SceneError};

/// Reads a camera path; a pose's missing `up` or `fov` is `camera`'s (its
/// cameras are checked by [`CameraPath::cameras`]). The error names the
/// file, the line of a JSON syntax error, or the frame and the field.
pub fn read_camera_path(path: &Path, camera: &Camera) -> Result<CameraPath, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let parse = |line: usize, message: String| SceneError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    let root: Value = serde_json::from_str(&text).map_err(|e| parse(e.line(), e.to_string()))?;
    let frames = root
        .get("frames")
        .and_then(Value::as_array)
        .ok_or_else(|| parse(0, "expected an object with a \"frames\" array".into()))?;
    let vector = |k: usize, frame: &Value, key: &str| -> Result<Option<Vec3>, SceneError> {
        let Some(v) = frame.get(key) else {
            return Ok(None);
        };
        let xyz: Option<Vec<f32>> = v
            .as_array()
            .filter(|a| a.len() == 3)
            .map(|a| a.iter().filter_map(|x| x.as_f64().map(|x| x as f32)).collect());
        match xyz {
            Some(xyz) if xyz.len() == 3 && xyz.iter().all(|x| x.is_finite()) => {
                Ok(Some(Vec3::from_slice(&xyz)))
            }
            _ => Err(parse(
                0,
                format!("frame {k}: \"{key}\" is {v}, expected [x, y, z] of finite numbers"),
            )),
        }
    };
    let frames = frames
        .iter()
        .enumerate()
        .map(|(k, frame)| {
            if !frame.is_object() {
                return Err(parse(0, format!("frame {k} is {frame}, expected an object")));
            }
            let required = |key: &str| {
                vector(k, frame, key)?.ok_or_else(|| parse(0, format!("frame {k} has no \"{key}\"")))
            };
            let fov_degrees = match frame.get("fov") {
                None => None,
                Some(v) => Some(
                    v.as_f64()
                        .map(|f| f as f32)
                        .filter(|f| *f > 0.0 && *f < 180.0)
                        .ok_or_else(|| {
                            parse(
                                0,
                                format!("frame {k}: \"fov\" is {v}, expected degrees in (0, 180)"),
                            )
                        })?,
                ),
            };
            Ok(CameraPose {
                origin: required("origin")?,
                target: required("target")?,
                up: vector(k, frame, "up")?.unwrap_or(camera.up),
                fov_degrees,
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(CameraPath { frames })
}
