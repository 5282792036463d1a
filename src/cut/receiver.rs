//! Receivers: the points being shaded, checked on entry.

use glam::Vec3;

use super::classify::ReceiverLanes;
use crate::error::{Error, Invalid};
use crate::points::check_normal;

/// A point being shaded: position and unit normal of its tangent plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    position: Vec3,
    normal: Vec3,
}

impl Receiver {
    /// A receiver at `position` facing `normal` (unit length, see
    /// [`NORMAL_TOLERANCE`](crate::error::NORMAL_TOLERANCE)).
    pub fn new(position: Vec3, normal: Vec3) -> Result<Self, Error> {
        let fail = |reason| Err(Error::InvalidReceiver { index: 0, reason });
        if !position.is_finite() {
            return fail(Invalid::NonFinite { field: "position" });
        }
        if let Err(reason) = check_normal(normal) {
            return fail(reason);
        }
        Ok(Self { position, normal })
    }

    /// Builds many receivers, naming the first invalid one by its index.
    pub fn from_pairs(pairs: impl IntoIterator<Item = (Vec3, Vec3)>) -> Result<Vec<Self>, Error> {
        pairs
            .into_iter()
            .enumerate()
            .map(|(index, (p, n))| {
                Self::new(p, n).map_err(|e| match e {
                    Error::InvalidReceiver { reason, .. } => Error::InvalidReceiver { index, reason },
                    other => other,
                })
            })
            .collect()
    }

    /// Position.
    #[inline(always)]
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// Unit normal.
    #[inline(always)]
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    #[inline(always)]
    pub(crate) fn lanes(&self) -> ReceiverLanes<f32> {
        ReceiverLanes {
            px: self.position.x,
            py: self.position.y,
            pz: self.position.z,
            nx: self.normal.x,
            ny: self.normal.y,
            nz: self.normal.z,
        }
    }
}
