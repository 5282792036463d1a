//! An image against a reference: the relative RMSE and bias over the pixels
//! that see no emitter, and the signed error as a picture.

use crate::render::{Image, RenderError, Tracer, shading_point};
use crate::scene::Scene;

/// Pixels that see an emitter's front, even in part (true: left out of the
/// error): those whose centre ray hits an emitter and their 8 neighbours, so
/// the light's edge pixels, whose value is mostly antialiasing noise, are
/// left out with it.
pub fn emitter_mask(scene: &Scene) -> Vec<bool> {
    let tracer = Tracer::new(scene);
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut hits = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let dir = cam.ray_direction(x as f32 + 0.5, y as f32 + 0.5);
            hits.push(
                tracer
                    .closest(cam.origin, dir, f32::INFINITY)
                    .and_then(|hit| shading_point(scene, &tracer, cam.origin, dir, &hit, 0.0))
                    .is_some_and(|sp| sp.emitted.max_element() > 0.0),
            );
        }
    }
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            (y.saturating_sub(1)..(y + 2).min(h))
                .any(|yy| (x.saturating_sub(1)..(x + 2).min(w)).any(|xx| hits[yy * w + xx]))
        })
        .collect()
}

/// An image measured against a reference over the pixels that see no emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// `sqrt(Σ‖I − R‖² / Σ‖R‖²)`.
    pub rel_rmse: f64,
    /// `Σ(I − R) / ΣR` over the channels: the mean's relative error.
    pub bias: f64,
    /// The part of `rel_rmse` that the mean offset alone makes,
    /// `|Σ(I − R)| / sqrt(n·Σ‖R‖²)` over the `n` channel values: the error
    /// splits into the mean offset's share and the rest, so a renderer
    /// whose offset is systematic (a bias, not noise) never gets below it,
    /// however many samples it takes.
    pub floor: f64,
    /// Mean of the image over the pixels and channels compared.
    pub mean: f64,
    /// Mean of the reference over the same.
    pub reference_mean: f64,
    /// Pixels compared.
    pub pixels: usize,
}

/// Whether `mask` has one entry per pixel of `image` (a mask of another
/// scene's camera would not).
fn mask_fits(mask: &[bool], image: &Image) -> Result<(), RenderError> {
    if mask.len() == image.pixels.len() {
        return Ok(());
    }
    Err(RenderError::Check(format!(
        "an emitter mask of {} pixels for images of {}×{} (a mask of another scene?)",
        mask.len(),
        image.width,
        image.height
    )))
}

/// `image` against `reference` over the pixels not in `mask`, in f64.
pub fn compare(image: &Image, reference: &Image, mask: &[bool]) -> Result<Comparison, RenderError> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(RenderError::Check(format!(
            "image {}×{} against reference {}×{}",
            image.width, image.height, reference.width, reference.height
        )));
    }
    mask_fits(mask, image)?;
    let (mut err, mut norm, mut sum, mut sum_ref, mut pixels) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize);
    for ((a, b), &skip) in image.pixels.iter().zip(&reference.pixels).zip(mask) {
        if skip {
            continue;
        }
        let (a, b) = (a.as_dvec3(), b.as_dvec3());
        err += (a - b).length_squared();
        norm += b.length_squared();
        sum += a.element_sum();
        sum_ref += b.element_sum();
        pixels += 1;
    }
    if norm > 0.0 && sum_ref != 0.0 {
        let n = 3.0 * pixels as f64;
        Ok(Comparison {
            rel_rmse: (err / norm).sqrt(),
            bias: (sum - sum_ref) / sum_ref,
            floor: (sum - sum_ref).abs() / (n * norm).sqrt(),
            mean: sum / n,
            reference_mean: sum_ref / n,
            pixels,
        })
    } else {
        Err(RenderError::Check(
            "the reference is black outside the emitters".into(),
        ))
    }
}

/// Relative RMSE of `image` against `reference` over the pixels not in
/// `mask`: `sqrt(Σ‖I − R‖² / Σ‖R‖²)`, in f64.
pub fn relative_rmse(image: &Image, reference: &Image, mask: &[bool]) -> Result<f64, RenderError> {
    Ok(compare(image, reference, mask)?.rel_rmse)
}

/// The mean of `image`'s channels over the pixels not in `mask`, if positive.
fn unmasked_mean(image: &Image, mask: &[bool]) -> Option<f64> {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (p, &skip) in image.pixels.iter().zip(mask) {
        if !skip {
            sum += f64::from(p.element_sum()) / 3.0;
            n += 1;
        }
    }
    (n > 0 && sum > 0.0).then(|| sum / n as f64)
}

/// The signed error `I − R` (luminance-like mean of the channels) as 8-bit
/// RGB: red where the image is too bright, blue where too dark, saturated at
/// ±25 % of the reference's mean; pixels in `mask` grey. Same sizes as
/// [`compare`] checks.
pub fn error_image(image: &Image, reference: &Image, mask: &[bool]) -> Vec<u8> {
    let scale = unmasked_mean(reference, mask).map_or(1.0, |m| 0.25 * m);
    let mut out = Vec::with_capacity(image.pixels.len() * 3);
    for ((a, b), &skip) in image.pixels.iter().zip(&reference.pixels).zip(mask) {
        if skip {
            out.extend([96, 96, 96]);
            continue;
        }
        let e = (f64::from((*a - *b).element_sum()) / 3.0 / scale).clamp(-1.0, 1.0);
        let v = (255.0 * (1.0 - e.abs())) as u8;
        out.extend(if e >= 0.0 { [255, v, v] } else { [v, v, 255] });
    }
    out
}

/// The mean of several references of one scene (path-traced with different
/// seeds), and its own noise: the relative RMSE the mean is expected to have
/// against the converged image, `sqrt(Σ s² / k / Σ‖R̄‖²)` over the pixels not
/// in `mask`, `s²` each pixel's unbiased sample variance over the `k`
/// references. An image's error against the mean is about
/// `sqrt(e² + noise²)`, `e` its error against the converged image, so a
/// reference's noise need not hide an image's error below it. `noise` is
/// `None` for one reference.
pub fn mean_reference(references: &[Image], mask: &[bool]) -> Result<(Image, Option<f64>), RenderError> {
    let Some(first) = references.first() else {
        return Err(RenderError::Check("no reference".into()));
    };
    if let Some(bad) = references
        .iter()
        .find(|r| (r.width, r.height) != (first.width, first.height))
    {
        return Err(RenderError::Check(format!(
            "references of {}×{} and {}×{} pixels",
            first.width, first.height, bad.width, bad.height
        )));
    }
    mask_fits(mask, first)?;
    let k = references.len() as f64;
    let (mut pixels, mut var, mut norm) = (Vec::with_capacity(mask.len()), 0.0f64, 0.0f64);
    for (i, &skip) in mask.iter().enumerate() {
        let mean = references
            .iter()
            .map(|r| r.pixels[i].as_dvec3())
            .sum::<glam::DVec3>()
            / k;
        pixels.push(mean.as_vec3());
        if !skip {
            norm += mean.length_squared();
            var += references
                .iter()
                .map(|r| (r.pixels[i].as_dvec3() - mean).length_squared())
                .sum::<f64>()
                / (k - 1.0).max(1.0);
        }
    }
    let noise = (references.len() > 1 && norm > 0.0).then(|| (var / k / norm).sqrt());
    Ok((
        Image {
            width: first.width,
            height: first.height,
            pixels,
        },
        noise,
    ))
}

/// `image`, `reference` and their signed error ([`error_image`]) side by
/// side as one 8-bit RGB picture `3·width × height`: the two images exposed
/// alike, the reference's mean over the pixels not in `mask` at 0.4 before
/// the sRGB curve (an indirect-only image is far darker than a frame).
/// Same sizes as [`compare`] checks.
pub fn side_by_side(image: &Image, reference: &Image, mask: &[bool]) -> (Vec<u8>, u32, u32) {
    let scale = unmasked_mean(reference, mask).map_or(1.0, |m| (0.4 / m) as f32);
    let exposed = |img: &Image| {
        Image {
            width: img.width,
            height: img.height,
            pixels: img.pixels.iter().map(|p| *p * scale).collect(),
        }
        .to_srgb8()
    };
    let panels = [
        exposed(image),
        exposed(reference),
        error_image(image, reference, mask),
    ];
    let (w, h) = (image.width as usize, image.height as usize);
    let mut out = Vec::with_capacity(panels.len() * w * h * 3);
    for y in 0..h {
        for panel in &panels {
            out.extend_from_slice(&panel[y * w * 3..(y + 1) * w * 3]);
        }
    }
    (out, 3 * image.width, image.height)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use glam::Vec3;

    /// An image one pixel high (the tests of this module and of the flicker).
    pub(in crate::report) fn image(pixels: Vec<Vec3>) -> Image {
        Image {
            width: pixels.len() as u32,
            height: 1,
            pixels,
        }
    }

    /// The floor is the mean offset's share of the relative RMSE: all of
    /// it for an image 10 % too bright everywhere, none of it for noise
    /// that averages out, and between the two for both at once.
    #[test]
    fn the_floor_is_the_mean_offsets_share_of_the_error() {
        let reference = image(vec![Vec3::ONE; 4]);
        let mask = [false; 4];
        let biased = compare(&image(vec![Vec3::splat(1.1); 4]), &reference, &mask).unwrap();
        assert!((biased.floor - 0.1).abs() < 1e-6 && (biased.rel_rmse - 0.1).abs() < 1e-6);
        let noisy = image([1.1, 0.9, 1.1, 0.9].map(Vec3::splat).to_vec());
        let noisy = compare(&noisy, &reference, &mask).unwrap();
        assert!(noisy.floor < 1e-6 && (noisy.rel_rmse - 0.1).abs() < 1e-6);
        // Offset 0.1 and noise 0.1: RMSE √0.02, floor 0.1.
        let both = image([1.2, 1.0, 1.2, 1.0].map(Vec3::splat).to_vec());
        let both = compare(&both, &reference, &mask).unwrap();
        assert!((both.floor - 0.1).abs() < 1e-6 && (both.rel_rmse - 0.02f64.sqrt()).abs() < 1e-6);
    }

    /// Two references `1 ± 0.1` per channel: mean 1, sample variance
    /// `2·0.1²` per channel, so noise `sqrt(3·0.02 / 2 / 3) = 0.1`; the masked
    /// pixel (wildly off) counts in neither.
    #[test]
    fn two_references_average_and_estimate_their_noise() {
        let a = image(vec![Vec3::splat(1.1), Vec3::splat(0.9), Vec3::splat(50.0)]);
        let b = image(vec![Vec3::splat(0.9), Vec3::splat(1.1), Vec3::splat(-50.0)]);
        let mask = [false, false, true];
        let (mean, noise) = mean_reference(&[a.clone(), b], &mask).unwrap();
        assert_eq!(mean.pixels[..2], [Vec3::ONE, Vec3::ONE]);
        let noise = noise.expect("two references");
        assert!((noise - 0.1).abs() < 1e-6, "noise {noise}");
        assert_eq!(mean_reference(&[a], &mask).unwrap().1, None);
    }
}
