//! A denoiser's guides: each pixel's albedo and normal where its camera
//! samples first meet the scene, averaged over the pixel's samples as its
//! colour is. Neither carries light, so neither is noisy: a denoiser (Intel
//! OIDN's `RT` filter, `crate::render::denoise` with the `denoise`
//! feature) keeps the edges and textures they show.

use glam::Vec3;
use rayon::prelude::*;

use super::frame::Frame;
use super::image::Image;

/// The guide images of a frame's window.
#[derive(Clone, Debug, PartialEq)]
pub struct Guides {
    /// Reflectance at the first hit: the diffuse albedo (textured) plus a
    /// glossy lobe's specular colour, at most 1 per channel; black where a
    /// camera ray leaves the scene.
    pub albedo: Image,
    /// Shading normal at the first hit (with its bump or normal map),
    /// averaged over the pixel, so not of unit length at an edge; zero
    /// where a camera ray leaves the scene.
    pub normal: Image,
}

impl Frame<'_> {
    /// The guides of this frame's window, from the same camera samples the
    /// render takes (so a crop's are the full frame's, cut).
    pub fn guides(&self) -> Guides {
        let window = self.window();
        let (w, h) = (window.width(), window.height());
        let spp = self.opts.spp;
        let tiles: Vec<Vec<(u32, Vec3, Vec3)>> = (0..self.tiles())
            .into_par_iter()
            .with_max_len(1)
            .map(|tile| {
                let pixels = self.tile_pixels(tile);
                let mut sums = vec![(Vec3::ZERO, Vec3::ZERO); pixels.len()];
                for s in 0..spp {
                    for pp in self.packet(&pixels, s, None) {
                        let sp = &pp.point;
                        let m = &self.scene.materials[sp.material];
                        let specular = m.glossy.map_or(Vec3::ZERO, |g| g.specular);
                        let sum = &mut sums[pp.pixel];
                        sum.0 += (sp.albedo + specular).min(Vec3::ONE);
                        sum.1 += sp.normal;
                    }
                }
                pixels
                    .iter()
                    .zip(sums)
                    .map(|(&(x, y), (a, n))| {
                        (
                            (y - window.y0) * w + x - window.x0,
                            a / spp as f32,
                            n / spp as f32,
                        )
                    })
                    .collect()
            })
            .collect();
        let mut albedo = vec![Vec3::ZERO; (w * h) as usize];
        let mut normal = albedo.clone();
        for (i, a, n) in tiles.into_iter().flatten() {
            albedo[i as usize] = a;
            normal[i as usize] = n;
        }
        let image = |pixels| Image {
            width: w,
            height: h,
            pixels,
        };
        Guides {
            albedo: image(albedo),
            normal: image(normal),
        }
    }
}
