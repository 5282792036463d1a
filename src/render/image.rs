//! The rendered image.

use glam::Vec3;

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
