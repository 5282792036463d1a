//! What can go wrong in a report: the renders, the reference, the CSV, the plot.

use std::fmt;
use std::path::PathBuf;

use crate::render::RenderError;

/// An error of the report layer, naming the offending input.
#[derive(Debug)]
pub enum ReportError {
    /// A render (point-based or path-traced) failed.
    Render(RenderError),
    /// The reference image is not the size the scene's camera renders.
    ReferenceSize {
        /// The reference's width and height.
        reference: (u32, u32),
        /// The camera's width and height.
        camera: (u32, u32),
    },
    /// A curve with a point of 0 samples per pixel.
    NoSamples {
        /// The curve's label.
        curve: String,
    },
    /// A line of an error sweep's CSV that cannot be read.
    Csv {
        /// Line number, from 1.
        line: usize,
        /// What is wrong with it.
        what: &'static str,
        /// The line.
        text: String,
    },
    /// A denoised curve, in a build without the `denoise` feature.
    NoDenoiser,
    /// The denoiser failed.
    #[cfg(feature = "denoise")]
    Denoise(crate::render::DenoiseError),
    /// A plot could not be drawn or written.
    Plot {
        /// The file being written.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

impl fmt::Display for ReportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReportError::Render(e) => e.fmt(f),
            ReportError::ReferenceSize { reference, camera } => write!(
                f,
                "the reference is {}×{} pixels, the scene's camera renders {}×{}",
                reference.0, reference.1, camera.0, camera.1
            ),
            ReportError::NoSamples { curve } => write!(f, "{curve}: a point of 0 samples per pixel"),
            ReportError::Csv { line, what, text } => write!(f, "line {line}: {what}: {text}"),
            ReportError::Plot { path, message } => write!(f, "{}: {message}", path.display()),
            ReportError::NoDenoiser => write!(
                f,
                "a denoised curve needs a pbgi built with the denoise feature (docs/options.md, \"Denoising\")"
            ),
            #[cfg(feature = "denoise")]
            ReportError::Denoise(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for ReportError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ReportError::Render(e) => Some(e),
            #[cfg(feature = "denoise")]
            ReportError::Denoise(e) => Some(e),
            _ => None,
        }
    }
}

impl From<RenderError> for ReportError {
    fn from(e: RenderError) -> Self {
        ReportError::Render(e)
    }
}
