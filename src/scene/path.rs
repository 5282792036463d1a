//! Camera paths: the poses of a shot's frames, rendered from one bake.
//!
//! A pose moves the scene's camera; its film (width, height) and field-of-view
//! axis stay the scene's, so every frame of a path has the same pixels and
//! shares the surfels, their light and the tree.

use glam::Vec3;

use super::{Camera, SceneError};

/// Where the camera of one frame is and where it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    /// Eye position.
    pub origin: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up hint.
    pub up: Vec3,
    /// Field of view in degrees on the scene camera's axis; `None` keeps the
    /// scene camera's.
    pub fov_degrees: Option<f32>,
}

impl CameraPose {
    /// The pose of `camera` itself.
    pub fn of(camera: &Camera) -> CameraPose {
        CameraPose {
            origin: camera.origin,
            target: camera.target,
            up: camera.up,
            fov_degrees: Some(camera.fov_degrees),
        }
    }

    /// `camera` moved to this pose: the film and the field-of-view axis stay.
    pub fn apply(&self, camera: &Camera) -> Camera {
        Camera {
            origin: self.origin,
            target: self.target,
            up: self.up,
            fov_degrees: self.fov_degrees.unwrap_or(camera.fov_degrees),
            ..*camera
        }
    }
}

/// The frames of a shot, in order (frame 0 first).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CameraPath {
    /// One pose per frame.
    pub frames: Vec<CameraPose>,
}

impl CameraPath {
    /// The cameras of the frames, each `camera` moved to its pose and
    /// checked; the error names the frame.
    pub fn cameras(&self, camera: &Camera) -> Result<Vec<Camera>, SceneError> {
        if self.frames.is_empty() {
            return Err(SceneError::Invalid {
                what: "the camera path has no frames".into(),
            });
        }
        self.frames
            .iter()
            .enumerate()
            .map(|(k, pose)| {
                let c = pose.apply(camera);
                c.validate().map(|()| c).map_err(|e| SceneError::Invalid {
                    what: format!("camera path frame {k}: {e}"),
                })
            })
            .collect()
    }
}
