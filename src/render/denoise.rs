//! Intel Open Image Denoise on a rendered image, guided by its albedo and
//! normal ([`Guides`]); the `denoise` feature, through the `oidn` crate.
//!
//! OIDN is not part of pbgi's bit-for-bit guarantee: its output may differ
//! between its versions and devices. The image it is given keeps that
//! guarantee.
//!
//! ```no_run
//! use pbgi::render::{Frame, RenderOptions, denoise};
//!
//! let scene = pbgi::scene::builtin::cornell_box();
//! let frame = Frame::prepare(&scene, &RenderOptions::default())?;
//! let image = frame.render(&|_, _| {})?.image;
//! let clean = denoise(&image, &frame.guides())?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use glam::Vec3;

use super::guides::Guides;
use super::image::Image;

/// Why the denoiser gave no image.
#[derive(Debug)]
pub enum DenoiseError {
    /// The image and its guides differ in size.
    Size {
        /// The image's width and height.
        image: (u32, u32),
        /// The guides' width and height.
        guides: (u32, u32),
    },
    /// OIDN itself failed: its message (no CPU device, a bad library).
    Oidn(String),
    /// OIDN gave a value that is not finite, at this pixel.
    NonFinite {
        /// The pixel's column and row.
        pixel: (u32, u32),
    },
}

impl std::fmt::Display for DenoiseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Size { image, guides } => write!(
                f,
                "the image is {}×{} but its guides {}×{}",
                image.0, image.1, guides.0, guides.1
            ),
            Self::Oidn(m) => write!(f, "Intel Open Image Denoise: {m}"),
            Self::NonFinite { pixel } => {
                write!(
                    f,
                    "the denoiser gave a non-finite value at pixel ({}, {})",
                    pixel.0, pixel.1
                )
            }
        }
    }
}

impl std::error::Error for DenoiseError {}

/// `image` (linear radiance) through OIDN's `RT` filter on the CPU, at
/// high quality, with `guides`' albedo and normal.
pub fn denoise(image: &Image, guides: &Guides) -> Result<Image, DenoiseError> {
    let size = |i: &Image| (i.width, i.height);
    for g in [&guides.albedo, &guides.normal] {
        if size(g) != size(image) {
            return Err(DenoiseError::Size {
                image: size(image),
                guides: size(g),
            });
        }
    }
    let flat = |i: &Image| -> Vec<f32> { i.pixels.iter().flat_map(|p| p.to_array()).collect() };
    let (color, albedo, normal) = (flat(image), flat(&guides.albedo), flat(&guides.normal));
    let mut out = vec![0.0; color.len()];
    let oidn = |e: oidn::Error| DenoiseError::Oidn(e.to_string());
    let device = oidn::Device::cpu().map_err(oidn)?;
    oidn::RayTracing::try_new(&device)
        .map_err(oidn)?
        .hdr(true)
        .filter_quality(oidn::Quality::High)
        .albedo_normal(&albedo, &normal)
        .image_dimensions(image.width as usize, image.height as usize)
        .filter(&color, &mut out)
        .map_err(oidn)?;
    device.get_error().map_err(oidn)?;
    let pixels: Vec<Vec3> = out.chunks_exact(3).map(Vec3::from_slice).collect();
    if let Some(i) = pixels.iter().position(|p| !p.is_finite()) {
        let w = image.width as usize;
        return Err(DenoiseError::NonFinite {
            pixel: ((i % w) as u32, (i / w) as u32),
        });
    }
    Ok(Image {
        width: image.width,
        height: image.height,
        pixels,
    })
}
