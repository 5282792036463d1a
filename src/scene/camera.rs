//! The pinhole camera: its pose, film and field of view, checked, and the
//! direction of the ray through each point of its film.

use glam::Vec3;

use super::{MAX_IMAGE_SIDE, SceneError};

/// Which image axis the field of view spans.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    /// Horizontal.
    X,
    /// Vertical.
    Y,
    /// The smaller of width and height.
    Smaller,
    /// The larger of width and height.
    Larger,
}

/// A pinhole perspective camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub origin: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up hint.
    pub up: Vec3,
    /// Field of view in degrees along `fov_axis`.
    pub fov_degrees: f32,
    /// The axis `fov_degrees` spans.
    pub fov_axis: FovAxis,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// Checks the film, the field of view and the pose; the error says which.
    pub fn validate(&self) -> Result<(), SceneError> {
        let c = self;
        let bad = |what: String| Err(SceneError::Invalid { what });
        if c.width == 0 || c.height == 0 || !(c.fov_degrees > 0.0 && c.fov_degrees < 180.0) {
            return bad(format!(
                "camera {}×{} fov {} is not usable",
                c.width, c.height, c.fov_degrees
            ));
        }
        if c.width > MAX_IMAGE_SIDE || c.height > MAX_IMAGE_SIDE {
            return bad(format!(
                "camera {}×{} is larger than {MAX_IMAGE_SIDE}×{MAX_IMAGE_SIDE}",
                c.width, c.height
            ));
        }
        if !(c.origin.is_finite() && c.target.is_finite() && c.up.is_finite()) {
            return bad(format!(
                "camera origin {} target {} up {} is not finite",
                c.origin, c.target, c.up
            ));
        }
        if (c.target - c.origin).length_squared() == 0.0
            || (c.target - c.origin).cross(c.up).length_squared() == 0.0
        {
            return bad("camera looks along its up vector or at its own origin".into());
        }
        Ok(())
    }

    /// Unit forward, right and up vectors (right-handed: image right is
    /// `forward × up`).
    pub fn frame(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.origin).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        (forward, right, up)
    }

    /// Tangents of the half field of view horizontally and vertically.
    pub fn tan_half_fov(&self) -> (f32, f32) {
        let (w, h) = (self.width as f32, self.height as f32);
        let t = (self.fov_degrees.to_radians() * 0.5).tan();
        let horizontal = match self.fov_axis {
            FovAxis::X => true,
            FovAxis::Y => false,
            FovAxis::Smaller => w <= h,
            FovAxis::Larger => w >= h,
        };
        if horizontal {
            (t, t * h / w)
        } else {
            (t * w / h, t)
        }
    }

    /// The angle (radians) one pixel subtends at the image's centre.
    pub fn pixel_spread(&self) -> f32 {
        let (_, ty) = self.tan_half_fov();
        2.0 * ty / self.height as f32
    }

    /// Direction (unit) of the ray through image position `(x, y)` in pixels,
    /// `(0, 0)` the top-left corner of the image.
    pub fn ray_direction(&self, x: f32, y: f32) -> Vec3 {
        self.rays().direction(x, y)
    }

    /// The frame and field of view [`ray_direction`](Self::ray_direction)
    /// works out, worked out once for many rays.
    pub fn rays(&self) -> CameraRays {
        let (forward, right, up) = self.frame();
        CameraRays {
            forward,
            right,
            up,
            tan_half_fov: self.tan_half_fov(),
            size: (self.width as f32, self.height as f32),
        }
    }
}

/// A camera's rays: its unit frame and half field of view, from
/// [`Camera::rays`] (a normalize, two cross products and a tangent less
/// per ray).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraRays {
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half_fov: (f32, f32),
    size: (f32, f32),
}

impl CameraRays {
    /// [`Camera::ray_direction`], bit for bit.
    #[inline]
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        let (tx, ty) = self.tan_half_fov;
        let u = (2.0 * x / self.size.0 - 1.0) * tx;
        let v = (1.0 - 2.0 * y / self.size.1) * ty;
        (self.forward + self.right * u + self.up * v).normalize()
    }
}
