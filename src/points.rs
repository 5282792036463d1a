//! Surfels: the oriented disks that carry the scene's outgoing radiance.

#[cfg(feature = "render")]
pub mod bake;

use glam::Vec3;

use crate::error::{Error, Invalid, NORMAL_TOLERANCE};

/// One surfel: a disk at `position` facing `normal`, of `radius`, emitting
/// `radiance` (outgoing diffuse radiance, RGB) from its front side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surfel {
    /// Centre of the disk.
    pub position: Vec3,
    /// Unit normal; the disk emits on this side only.
    pub normal: Vec3,
    /// Disk radius (> 0).
    pub radius: f32,
    /// Outgoing radiance, RGB, each component ≥ 0.
    pub radiance: Vec3,
}

impl Surfel {
    /// Checks one surfel; `index` only labels the error.
    pub fn validate(&self, index: usize) -> Result<(), Error> {
        let fail = |reason| Err(Error::InvalidSurfel { index, reason });
        if !self.position.is_finite() {
            return fail(Invalid::NonFinite { field: "position" });
        }
        if let Err(reason) = check_normal(self.normal) {
            return fail(reason);
        }
        if !self.radius.is_finite() {
            return fail(Invalid::NonFinite { field: "radius" });
        }
        if self.radius <= 0.0 {
            return fail(Invalid::NonPositiveRadius(self.radius));
        }
        if !self.radiance.is_finite() {
            return fail(Invalid::NonFinite { field: "radiance" });
        }
        if self.radiance.min_element() < 0.0 {
            return fail(Invalid::NegativeRadiance);
        }
        Ok(())
    }

    /// Area of the disk, `π r²`.
    pub fn area(&self) -> f32 {
        std::f32::consts::PI * self.radius * self.radius
    }
}

/// Finite, non-zero, unit length within [`NORMAL_TOLERANCE`].
pub(crate) fn check_normal(n: Vec3) -> Result<(), Invalid> {
    if !n.is_finite() {
        return Err(Invalid::NonFinite { field: "normal" });
    }
    let len2 = n.length_squared();
    if len2 == 0.0 {
        return Err(Invalid::ZeroNormal);
    }
    if (len2 - 1.0).abs() > NORMAL_TOLERANCE {
        return Err(Invalid::NonUnitNormal { length: len2.sqrt() });
    }
    Ok(())
}

/// A validated set of surfels, kept exactly as the caller gave them.
///
/// ```
/// use pbgi::{PointCloud, Surfel};
/// use glam::Vec3;
///
/// let s = Surfel { position: Vec3::ZERO, normal: Vec3::Z, radius: 0.1, radiance: Vec3::ONE };
/// let cloud = PointCloud::new(vec![s])?;
/// assert_eq!(cloud.len(), 1);
///
/// let bad = Surfel { radius: -1.0, ..s };
/// let err = PointCloud::new(vec![s, bad]).unwrap_err();
/// assert_eq!(err.to_string(), "surfel 1: radius -1 is not positive");
/// # Ok::<(), pbgi::Error>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    surfels: Vec<Surfel>,
}

impl PointCloud {
    /// The most surfels a cloud may hold: node indices are 31-bit.
    pub const MAX_SURFELS: usize = 1 << 30;

    /// Validates every surfel; the first invalid one is reported by index.
    pub fn new(surfels: Vec<Surfel>) -> Result<Self, Error> {
        if surfels.len() > Self::MAX_SURFELS {
            return Err(Error::TooManySurfels {
                count: surfels.len(),
                max: Self::MAX_SURFELS,
            });
        }
        for (i, s) in surfels.iter().enumerate() {
            s.validate(i)?;
        }
        Ok(Self { surfels })
    }

    /// The surfels, in the caller's order.
    pub fn surfels(&self) -> &[Surfel] {
        &self.surfels
    }

    /// Number of surfels.
    pub fn len(&self) -> usize {
        self.surfels.len()
    }

    /// True when the cloud holds no surfel.
    pub fn is_empty(&self) -> bool {
        self.surfels.is_empty()
    }

    /// Gives the surfels back.
    pub fn into_surfels(self) -> Vec<Surfel> {
        self.surfels
    }
}
