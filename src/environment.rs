//! Light from infinitely far away: a uniform sky or a lat-long radiance map.
//! What a receiver's cut leaves uncovered sees it (the microbuffer's open
//! pixels, as in Christensen 2008), and the path tracer's escaping paths
//! see the same.

use glam::Vec3;

use crate::error::{Error, Invalid};

/// Radiance arriving from every direction not blocked by the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// The same radiance (RGB) from every direction.
    Uniform(Vec3),
    /// A latitude-longitude map.
    LatLong(LatLong),
}

/// A radiance map over the sphere of directions (an equirectangular
/// image, as HDR environment maps are stored): rows from +Y (up) down to −Y,
/// columns by azimuth; direction `d` reads the texel at
/// `u = ½ + atan2(d.x, −d.z)/2π`, `v = acos(d.y)/π` (nearest texel).
#[derive(Clone, Debug, PartialEq)]
pub struct LatLong {
    width: usize,
    height: usize,
    pixels: Vec<Vec3>,
    max: Vec3,
}

impl LatLong {
    /// A map of `width × height` texels, row by row. Errors: a size that
    /// does not match, or a texel not finite and ≥ 0 (named by its index).
    pub fn new(width: usize, height: usize, pixels: Vec<Vec3>) -> Result<Self, Error> {
        if width == 0 || height == 0 || width.checked_mul(height) != Some(pixels.len()) {
            return Err(Error::InvalidParameter {
                name: "environment map",
                value: format!("{width} × {height} with {} texels", pixels.len()),
                expected: "width × height texels, both at least 1",
            });
        }
        let mut max = Vec3::ZERO;
        for (index, p) in pixels.iter().enumerate() {
            if !p.is_finite() {
                return Err(Error::InvalidEnvironment {
                    index,
                    reason: Invalid::NonFinite { field: "radiance" },
                });
            }
            if p.min_element() < 0.0 {
                return Err(Error::InvalidEnvironment {
                    index,
                    reason: Invalid::NegativeRadiance,
                });
            }
            max = max.max(*p);
        }
        Ok(LatLong {
            width,
            height,
            pixels,
            max,
        })
    }

    /// The texel `d` (unit) falls in.
    #[inline(always)]
    fn lookup(&self, d: Vec3) -> Vec3 {
        let u = 0.5 + d.x.atan2(-d.z) * (0.5 * std::f32::consts::FRAC_1_PI);
        let v = d.y.clamp(-1.0, 1.0).acos() * std::f32::consts::FRAC_1_PI;
        // `as usize` saturates (NaN to 0): always a texel.
        let x = ((u * self.width as f32) as usize).min(self.width - 1);
        let y = ((v * self.height as f32) as usize).min(self.height - 1);
        self.pixels[y * self.width + x]
    }
}

impl Environment {
    /// A uniform sky. Errors: radiance not finite and ≥ 0.
    pub fn uniform(radiance: Vec3) -> Result<Self, Error> {
        if !radiance.is_finite() || radiance.min_element() < 0.0 {
            return Err(Error::InvalidEnvironment {
                index: 0,
                reason: if radiance.is_finite() {
                    Invalid::NegativeRadiance
                } else {
                    Invalid::NonFinite { field: "radiance" }
                },
            });
        }
        Ok(Environment::Uniform(radiance))
    }

    /// Radiance arriving from direction `d` (unit, pointing away from the
    /// scene). Inlined: the shading kernels' clones call it.
    #[inline(always)]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        match self {
            Environment::Uniform(l) => *l,
            Environment::LatLong(m) => m.lookup(d),
        }
    }

    /// The map's size and texels, row by row (a uniform sky: 1 × 1).
    pub fn texels(&self) -> (usize, usize, &[Vec3]) {
        match self {
            Environment::Uniform(l) => (1, 1, std::slice::from_ref(l)),
            Environment::LatLong(m) => (m.width, m.height, &m.pixels),
        }
    }

    /// The largest radiance per channel.
    #[inline(always)]
    pub fn max_radiance(&self) -> Vec3 {
        match self {
            Environment::Uniform(l) => *l,
            Environment::LatLong(m) => m.max,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lat_long_rows_run_from_up_to_down_and_columns_by_azimuth() {
        // 4 × 2: top row 1..4, bottom row 5..8 (red channel).
        let m = LatLong::new(4, 2, (1..=8).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect()).unwrap();
        let env = Environment::LatLong(m);
        assert_eq!(env.radiance(Vec3::new(0.0, 0.9, -0.43)).x, 3.0); // up, looking −z: u ½
        assert_eq!(env.radiance(Vec3::new(0.0, -0.9, -0.43)).x, 7.0);
        assert_eq!(env.radiance(Vec3::new(-0.9, 0.3, 0.0)).x, 2.0); // −x: u ¼
        assert_eq!(env.max_radiance(), Vec3::new(8.0, 0.0, 0.0));
        assert!(LatLong::new(2, 2, vec![Vec3::ONE; 3]).is_err());
        let nan = LatLong::new(1, 2, vec![Vec3::ONE, Vec3::NAN]).unwrap_err();
        assert!(matches!(nan, Error::InvalidEnvironment { index: 1, .. }), "{nan}");
        assert!(Environment::uniform(Vec3::new(1.0, -1.0, 0.0)).is_err());
    }
}
