//! A record: the irradiance gathered at one point of a surface, and which
//! points it may serve (the screen lattice's one-surface test, in world
//! units).

use glam::Vec3;

/// Cosine between two normals of one surface (18°): a curved surface's
/// records still serve each other, a box's faces never.
pub(crate) const SAME_NORMAL: f32 = 0.95;

/// Distance off a record's plane, relative to the distance along it, that
/// a surface curving by 5.7° keeps; normals further apart allow their
/// angle's sine. A step is two surfaces.
pub(crate) const CURVATURE: f32 = 0.05;

/// A gathered point: where, which way it faces, and what its microbuffer
/// gave (irradiance, or occlusion in AO mode).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Position (a surfel's: on the surface).
    pub position: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// The gathered irradiance `E` (RGB), or occlusion in every channel.
    pub e: Vec3,
}

impl Record {
    /// Whether a point at `p` with normal `n` lies on this record's
    /// surface, `slack` the distance off its plane that is rounding.
    #[inline]
    pub fn covers(&self, p: Vec3, n: Vec3, slack: f32) -> bool {
        let d = p - self.position;
        self.normal.dot(n) >= SAME_NORMAL && {
            let bend = self.normal.cross(n).length().max(CURVATURE);
            self.normal.dot(d).abs() <= slack + bend * d.length()
        }
    }

    /// The record's light in one number (the sum of its channels).
    #[inline]
    pub fn luminance(&self) -> f32 {
        self.e.x + self.e.y + self.e.z
    }
}
