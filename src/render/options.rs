//! Render settings.

use crate::cut::{CutOptions, SchemeChoice};

/// Render settings; the defaults render the Cornell box in about a second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// The cut's parameters: Ω, the hybrid threshold, the instruction-set path.
    pub cut: CutOptions,
    /// Traversal scheme.
    pub scheme: SchemeChoice,
    /// Microbuffer resolution N (an N×N octahedral grid over the hemisphere).
    pub microbuffer: usize,
    /// Indirect bounces: 0 direct only, 1 direct + one bounce (Mitsuba's `max_depth` 3), …
    pub bounces: u32,
    /// Camera samples per pixel (each a receiver).
    pub spp: u32,
    /// Light samples per receiver for direct light (`None`: `spp`, at most 16).
    pub direct_samples: Option<u32>,
    /// Ambient-occlusion mode: no radiance at all, `1 − AO` as a grey image.
    pub ao: bool,
    /// Surfels per unit area.
    pub density: f32,
    /// Area-light samples per surfel.
    pub surfel_light_samples: u32,
    /// Seed of every random choice.
    pub seed: u64,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            cut: CutOptions::default(),
            scheme: SchemeChoice::Auto,
            microbuffer: 12,
            bounces: 1,
            spp: 4,
            direct_samples: None,
            ao: false,
            density: 2000.0,
            surfel_light_samples: 16,
            seed: 1,
        }
    }
}
