//! Surfels: the oriented disks that carry the scene's outgoing radiance.

use glam::Vec3;

use crate::error::{Error, Invalid, NORMAL_TOLERANCE};

/// Largest accepted radiance component. The shading sums stay far from `f32`
/// overflow below it: irradiance is at most `π · max L`, and a sharp glossy
/// lobe (whose peak is a few 10⁵ at the smallest roughness) times the
/// microbuffer's solid angles at most about 10⁶ · max L.
pub const MAX_RADIANCE: f32 = 1e30;

/// Largest accepted position component and radius. Every bounding sphere of
/// the tree then has a finite centre and radius (at most about 5·10³⁷); node
/// areas, sums of `π r²`, saturate at `f32::MAX` instead of overflowing.
pub const MAX_COORDINATE: f32 = 1e37;

/// The axis of `v`'s largest magnitude, the first among equals: the cache
/// files a record by it (its facing), and a compact leaf's normal keeps it.
#[inline]
pub(crate) fn dominant_axis(v: Vec3) -> usize {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    }
}

/// One surfel: a disk at `position` facing `normal`, of `radius`, emitting
/// `radiance` (outgoing diffuse radiance, RGB) from its front side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surfel {
    /// Centre of the disk, each component within `±MAX_COORDINATE`.
    pub position: Vec3,
    /// Unit normal; the disk emits on this side only.
    pub normal: Vec3,
    /// Disk radius, in `(0, MAX_COORDINATE]`.
    pub radius: f32,
    /// Outgoing radiance, RGB, each component in `[0, MAX_RADIANCE]`.
    pub radiance: Vec3,
}

impl Surfel {
    /// Checks one surfel; `index` only labels the error.
    pub fn validate(&self, index: usize) -> Result<(), Error> {
        let fail = |reason| Err(Error::InvalidSurfel { index, reason });
        let too_large = |field, value, max| fail(Invalid::TooLarge { field, value, max });
        if !self.position.is_finite() {
            return fail(Invalid::NonFinite { field: "position" });
        }
        let far = self.position.abs().max_element();
        if far > MAX_COORDINATE {
            return too_large("position", far, MAX_COORDINATE);
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
        if self.radius > MAX_COORDINATE {
            return too_large("radius", self.radius, MAX_COORDINATE);
        }
        if !self.radiance.is_finite() {
            return fail(Invalid::NonFinite { field: "radiance" });
        }
        if self.radiance.min_element() < 0.0 {
            return fail(Invalid::NegativeRadiance);
        }
        if self.radiance.max_element() > MAX_RADIANCE {
            return too_large("radiance", self.radiance.max_element(), MAX_RADIANCE);
        }
        Ok(())
    }

    /// Area of the disk, `π r²` (saturating at `f32::MAX` for radii beyond about 10¹⁹).
    pub fn area(&self) -> f32 {
        (std::f32::consts::PI * self.radius * self.radius).min(f32::MAX)
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
