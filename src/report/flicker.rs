//! How steady the frames of a shot are: each frame-to-frame change against
//! the true change.
//!
//! For frames `F` and their references `R`, pair `k` compares
//! `ΔF = F[k+1] − F[k]` with `ΔR = R[k+1] − R[k]`:
//! `sqrt(Σ‖ΔF − ΔR‖² / Σ‖R[k+1]‖²)` over the pixels that see no emitter in
//! either frame ([`emitter_mask`](super::emitter_mask)), the same relative
//! RMSE as a frame's error but of its change. An error that stays put on
//! the surfaces cancels in it; noise drawn anew each frame counts about
//! `√2` times its per-frame error. The flicker of the shot is the RMS over
//! its pairs.

use crate::render::{Image, RenderError};

use super::compare::{Comparison, compare};

/// A shot's per-frame errors and flicker.
#[derive(Clone, Debug, PartialEq)]
pub struct Flicker {
    /// Each frame against its reference.
    pub frames: Vec<Comparison>,
    /// Each pair of consecutive frames: its change against the true change.
    pub pairs: Vec<f64>,
    /// RMS of [`pairs`](Self::pairs).
    pub flicker: f64,
}

impl Flicker {
    /// RMS of the frames' relative RMSE.
    pub fn frame_error(&self) -> f64 {
        (self.frames.iter().map(|c| c.rel_rmse * c.rel_rmse).sum::<f64>() / self.frames.len() as f64).sqrt()
    }
}

/// The flicker of `frames` against `references`, `masks[k]` frame `k`'s
/// emitter mask (`true`: left out). Errors: counts or sizes that differ, or
/// fewer than two frames.
pub fn flicker(frames: &[Image], references: &[Image], masks: &[Vec<bool>]) -> Result<Flicker, RenderError> {
    if frames.len() != references.len() || frames.len() != masks.len() || frames.len() < 2 {
        return Err(RenderError::Check(format!(
            "flicker needs two frames or more, each with a reference and a mask: {} frames, {} references, {} masks",
            frames.len(),
            references.len(),
            masks.len()
        )));
    }
    let per_frame = frames
        .iter()
        .zip(references)
        .zip(masks)
        .map(|((f, r), m)| compare(f, r, m))
        .collect::<Result<Vec<_>, _>>()?;
    let pairs = (0..frames.len() - 1)
        .map(|k| {
            let (mut err, mut norm) = (0.0f64, 0.0f64);
            let pixels = frames[k]
                .pixels
                .iter()
                .zip(&frames[k + 1].pixels)
                .zip(references[k].pixels.iter().zip(&references[k + 1].pixels))
                .zip(masks[k].iter().zip(&masks[k + 1]));
            for (((f0, f1), (r0, r1)), (&m0, &m1)) in pixels {
                if m0 || m1 {
                    continue;
                }
                let (f0, f1, r0, r1) = (f0.as_dvec3(), f1.as_dvec3(), r0.as_dvec3(), r1.as_dvec3());
                err += ((f1 - f0) - (r1 - r0)).length_squared();
                norm += r1.length_squared();
            }
            if norm > 0.0 && err.is_finite() {
                Ok((err / norm).sqrt())
            } else {
                Err(RenderError::Check(format!(
                    "frames {k} and {}: the reference is black or the frames not finite where compared",
                    k + 1
                )))
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    let flicker = (pairs.iter().map(|p| p * p).sum::<f64>() / pairs.len() as f64).sqrt();
    Ok(Flicker {
        frames: per_frame,
        pairs,
        flicker,
    })
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::compare::tests::image;
    use super::*;
    use crate::rng::Rng;

    /// Four references of a moving gradient, and noise fields.
    fn shot() -> (Vec<Image>, Vec<Vec<bool>>) {
        let refs = (0..4)
            .map(|k| {
                image(
                    (0..256)
                        .map(|i| Vec3::splat(1.0 + ((i + 7 * k) % 50) as f32 / 25.0))
                        .collect(),
                )
            })
            .collect();
        (refs, vec![vec![false; 256]; 4])
    }

    fn noise(seed: u64) -> Vec<Vec3> {
        let mut rng = Rng::new(seed);
        (0..256).map(|_| Vec3::splat(0.2 * (rng.f32() - 0.5))).collect()
    }

    #[test]
    fn noise_that_stays_put_does_not_flicker_and_new_noise_does() {
        let (refs, masks) = shot();
        let fixed = noise(1);
        let steady: Vec<Image> = refs
            .iter()
            .map(|r| image(r.pixels.iter().zip(&fixed).map(|(a, n)| *a + *n).collect()))
            .collect();
        let s = flicker(&steady, &refs, &masks).unwrap();
        assert!(s.frame_error() > 0.02, "{}", s.frame_error());
        assert!(s.flicker < 1e-6, "fixed noise cancels: {}", s.flicker);
        let moving: Vec<Image> = refs
            .iter()
            .enumerate()
            .map(|(k, r)| {
                image(
                    r.pixels
                        .iter()
                        .zip(&noise(10 + k as u64))
                        .map(|(a, n)| *a + *n)
                        .collect(),
                )
            })
            .collect();
        let m = flicker(&moving, &refs, &masks).unwrap();
        // New noise each frame: the change carries two frames' noise.
        let ratio = m.flicker / m.frame_error();
        assert!((ratio - 2f64.sqrt()).abs() < 0.2, "{ratio}");
        // A masked pixel in either frame is left out of the pair.
        let mut masks = masks;
        masks[1][..128].fill(true);
        let half = flicker(&moving, &refs, &masks).unwrap();
        assert_ne!(half.pairs[0], m.pairs[0]);
        assert_eq!(half.pairs[2], m.pairs[2]);
        assert!(flicker(&moving[..1], &refs[..1], &masks[..1]).is_err());
    }
}
