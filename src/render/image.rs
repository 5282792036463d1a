//! The rendered image.

use glam::Vec3;

use crate::rng::mix;

/// A linear RGB image, row-major from the top-left corner.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear radiance per pixel.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// A 64-bit digest of the size and every pixel's bits: two renders gave
    /// the same image, bit for bit, when their digests agree (every scheme,
    /// instruction set and thread count gives the same one).
    pub fn digest(&self) -> u64 {
        let mut h = mix(u64::from(self.width) << 32 | u64::from(self.height));
        for p in &self.pixels {
            for c in p.to_array() {
                h = mix(h ^ u64::from(c.to_bits()));
            }
        }
        h
    }

    /// 8-bit sRGB, clamped (no other tone mapping).
    pub fn to_srgb8(&self) -> Vec<u8> {
        let encode = |x: f32| {
            let x = x.clamp(0.0, 1.0);
            let s = if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0 + 0.5) as u8
        };
        self.pixels
            .iter()
            .flat_map(|p| [encode(p.x), encode(p.y), encode(p.z)])
            .collect()
    }
}
