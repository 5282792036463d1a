//! What the speed costs in accuracy: Table-1 timings per scheme ([`bench()`])
//! and the point-based renderer against the path tracer at equal error
//! ([`error_sweep`], [`equal_error()`]).
//!
//! The point-based side is a set of curves ([`Curve`]): each holds its
//! settings (a label and [`RenderOptions`](crate::render::RenderOptions))
//! while the camera samples per pixel rise, since the error falls with them;
//! the path tracer's curve raises its paths per pixel. Each image's error is
//! the relative RMSE over the pixels that see no emitter directly, not even
//! in part ([`emitter_mask`]): `sqrt(Σ‖I − R‖² / Σ‖R‖²)` over those pixels
//! and the three channels, `R` the reference. Emitters seen directly are left
//! out because both renderers show them exactly and their radiance would
//! dominate the sums. Along each curve, the time to reach an error is read
//! off log(time) against log(error) ([`time_for`]).

pub mod bench;
pub mod compare;
mod csv;
mod equal_error;
mod error;
mod eta;
mod flicker;
mod markdown;
#[cfg(feature = "plots")]
pub mod plot;
pub mod scale;
mod sweep;

pub use bench::{BenchOptions, BenchReceivers, BenchRow, bench};
pub use compare::{
    Comparison, compare, emitter_mask, error_image, mean_reference, relative_rmse, side_by_side,
};
pub use csv::{External, external_points, from_csv, to_csv};
pub use equal_error::{
    EqualError, Reach, Series, equal_error, fitted_floor, series, time_above_floor, time_for,
};
pub use error::ReportError;
pub use flicker::{Flicker, flicker};
pub use markdown::{OIDN_SUFFIX, equal_error_markdown, summary_header, summary_row, to_markdown};
pub use scale::{
    GROWTH_FROM, Growth, ScaleRow, copies, growth, growth_markdown, scale_csv, scale_markdown, scale_row,
    stage_peaks_markdown,
};
pub use sweep::{
    Curve, DEFAULT_PATH_TRACER_SPP, DEFAULT_SPP, DEFAULT_TARGETS, ErrorPoint, Grid, Method, PATH_TRACER,
    SweepOptions, SweepProgress, Variant, check_reference, default_curves, describe, error_sweep,
};
