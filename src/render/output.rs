//! What a render reports: the image, the paper's Table 1 times, counters,
//! and which stages ran; and its errors.

use super::image::Image;
use super::options::CropError;
use crate::cache::CacheFileError;
use crate::cut::{Scheme, SchemeChoice, TraversalStats};
use crate::error::Error;
use crate::scene::SceneError;
use crate::simd::Isa;

/// Where a render is, for a progress bar: `(stage, done, total)`, called
/// with 0 done as a stage starts and `total` done as it ends (`total` 1 for
/// a stage that counts nothing on the way), from any thread. A stage whose
/// count is not known when it starts reports `(0, 0)` first, then `(0,
/// total)` once it is.
pub type Progress<'a> = dyn Fn(&'static str, usize, usize) + Sync + 'a;

/// Wall-clock seconds of the parts of `pre.`: what grows with the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PreTimings {
    /// The ray tracer's BVH over the triangles and the lights' tables.
    pub tracer: f64,
    /// Surfel placement and the direct light at the surfels.
    pub surfels: f64,
    /// Gathers at the surfels: the environment's light, extra bounces.
    pub gathers: f64,
    /// The trees over the surfels (none for a render from a tree file).
    pub tree: f64,
}

/// Seconds per stage, summed over threads (the paper's Table 1 columns).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Point cloud (surfels + their direct light + extra bounces) and tree.
    pub pre: f64,
    /// The parts of `pre`.
    pub pre_parts: PreTimings,
    /// Cut traversal.
    pub trav: f64,
    /// Splatting and convolution.
    pub shading: f64,
    /// Camera rays and direct light at the receivers.
    pub direct: f64,
    /// Wall-clock seconds of the whole render.
    pub total_wall: f64,
}

/// One pipeline stage and whether it ran.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stage {
    /// What it is.
    pub name: &'static str,
    /// `None` if it ran, else why it was left out.
    pub skipped: Option<String>,
}

/// What a render produced.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The image.
    pub image: Image,
    /// Stage times.
    pub timings: Timings,
    /// Traversal counters over all receivers.
    pub stats: TraversalStats,
    /// The scheme that ran (on full packets, under `auto`).
    pub scheme: Scheme,
    /// The choice it came from.
    pub choice: SchemeChoice,
    /// The instruction-set path that ran.
    pub isa: Isa,
    /// Surfels in the cloud (0 when none was needed).
    pub surfels: usize,
    /// Bytes the tree holds per surfel ([`Tree::bytes_per_surfel`](crate::Tree::bytes_per_surfel)).
    pub tree_bytes_per_surfel: f64,
    /// Receivers shaded.
    pub receivers: usize,
    /// Of them, records of the world-space cache gathered for this frame
    /// (`Gathers::Cache`; 0 otherwise, and in a later frame that found
    /// every record it needed).
    pub records: usize,
    /// Records the caches hold after this frame (the irradiance cache and
    /// those that keep their incident light).
    pub cached: usize,
    /// Every stage, run or left out.
    pub stages: Vec<Stage>,
}

/// Errors of a render.
#[derive(Debug)]
#[non_exhaustive]
pub enum RenderError {
    /// The scene is unusable.
    Scene(SceneError),
    /// A kernel-layer error (options, ISA, invalid surfels).
    Kernel(Error),
    /// A self-check failed (a scheme's cuts differ from the reference's, or
    /// an image does not match its reference's size).
    Check(String),
    /// A value that is not finite arose: a defect, never masked, reported
    /// where it first appeared.
    NonFinite {
        /// The stage that made it ("direct light at receivers", "gather", …).
        stage: &'static str,
        /// Where: the pixel and camera sample, or the surfel.
        place: String,
        /// The value (r, g, b).
        value: [f32; 3],
    },
    /// The crop window does not fit the frame.
    Crop(CropError),
    /// A loaded tree was baked from another scene, or with settings that
    /// contradict the render's.
    TreeMismatch {
        /// The setting (`"scene"`, `"density"`, `"bounces"`, …).
        setting: &'static str,
        /// Its value in the tree file.
        baked: String,
        /// Its value in this render.
        render: String,
    },
    /// A cache file could not be read or written, or belongs to another
    /// tree or other settings.
    CacheFile(CacheFileError),
}

impl std::fmt::Display for RenderError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RenderError::Scene(e) => e.fmt(f),
            RenderError::Kernel(e) => e.fmt(f),
            RenderError::Check(m) => f.write_str(m),
            RenderError::NonFinite { stage, place, value } => {
                write!(f, "{stage}: a value that is not finite ({value:?}) at {place}")
            }
            RenderError::Crop(e) => e.fmt(f),
            RenderError::CacheFile(e) => e.fmt(f),
            RenderError::TreeMismatch {
                setting,
                baked,
                render,
            } => write!(
                f,
                "the tree was baked with {setting} {baked}, this render has {render}: \
                 bake it again with the render's settings, or render with the tree's"
            ),
        }
    }
}

impl std::error::Error for RenderError {}

impl From<Error> for RenderError {
    fn from(e: Error) -> Self {
        RenderError::Kernel(e)
    }
}

impl From<CacheFileError> for RenderError {
    fn from(e: CacheFileError) -> Self {
        RenderError::CacheFile(e)
    }
}

impl From<CropError> for RenderError {
    fn from(e: CropError) -> Self {
        RenderError::Crop(e)
    }
}

impl From<SceneError> for RenderError {
    fn from(e: SceneError) -> Self {
        RenderError::Scene(e)
    }
}
