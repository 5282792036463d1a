//! A record: the irradiance gathered at one point of a surface, and which
//! points it may serve (the screen lattice's one-surface test, in world
//! units).

use glam::Vec3;

use crate::microbuffer::Gradients;

/// Cosine between two normals of one surface (18°): a curved surface (the
/// nave's piers, a vault, the bunny) is one surface, a box's faces are not;
/// at 5.7° the lattice refined curved surfaces to single pixels.
pub(crate) const SAME_NORMAL: f32 = 0.95;

/// Distance off a record's plane, relative to the distance along it, that
/// a surface curving by 5.7° keeps; normals further apart allow their
/// angle's sine. A step is two surfaces.
pub(crate) const CURVATURE: f32 = 0.05;

/// Whether a point at `p` with normal `n` lies on the surface through
/// `position` with normal `normal` (both unit), `slack` the distance off
/// its plane that is rounding: normals within 18°, and off the plane by no
/// more than the slack and the bend the normals allow (a step is two
/// surfaces). The screen lattice's corners and the cache's records share it.
#[inline]
pub(crate) fn same_surface(position: Vec3, normal: Vec3, p: Vec3, n: Vec3, slack: f32) -> bool {
    let d = p - position;
    normal.dot(n) >= SAME_NORMAL && {
        let bend = normal.cross(n).length().max(CURVATURE);
        normal.dot(d).abs() <= slack + bend * d.length()
    }
}

/// A gathered point: where, which way it faces, and what its microbuffer
/// gave (irradiance, or occlusion in AO mode), with how that changes
/// about it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Position (a surfel's: on the surface).
    pub position: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// The gathered irradiance `E` (RGB), or occlusion in every channel.
    pub e: Vec3,
    /// How `e` changes as the point turns: the rotational gradient, the
    /// one a lookup applies (zero for occlusion). The translational one
    /// and the distance are not gathered for records yet (zero, infinite).
    pub gradients: Gradients,
}

impl Record {
    /// Whether a point at `p` with normal `n` lies on this record's
    /// surface, `slack` the distance off its plane that is rounding.
    #[inline]
    pub fn covers(&self, p: Vec3, n: Vec3, slack: f32) -> bool {
        same_surface(self.position, self.normal, p, n, slack)
    }

    /// The record's light turned to unit normal `n` by its rotational
    /// gradient (none of it negative). Not moved by its translational one:
    /// that made the Cornell box's cache at threshold 0.4 worse, 3.8 →
    /// 5.6 % (docs/lab/cache.md), so the record keeps it unapplied.
    #[inline]
    pub fn turned(&self, n: Vec3) -> Vec3 {
        let e = self.gradients.extrapolate(self.e, Vec3::ZERO, self.normal, n);
        // A NaN stays NaN (glam's `max` would return the zero): a record's
        // light and gradients are checked finite when it is made, so only
        // a defect upstream could bring one.
        if e.is_nan() { e } else { e.max(Vec3::ZERO) }
    }
}
