//! Rendering a scene with point-based global illumination: camera rays give
//! the receivers (4×4 pixel tiles make the packets), the kernels give their
//! cuts, the microbuffer splats and convolves them, direct light comes from
//! shadow rays. Stages a scene does not need are left out, and said so.
//!
//! Data enters as a [`Scene`](crate::scene::Scene) and [`RenderOptions`];
//! it leaves as a [`RenderOutput`] (image, Table-1 times, counters, stages).
//! The files, in data-flow order: `options`, `resolve` (the settings a
//! render takes, flags over the scene file over the defaults); `trace` (ray queries), `light`
//! (direct light), `surfels` (surfels with their direct light), `bounces`
//! (extra bounces at the surfels, through [`Gather`](crate::gather::Gather));
//! `bake` (the surfels and tree a render needs, built or read from a tree
//! file, [`bake_tree`]);
//! `shading` (shading points), `frame` (the frame, tile by tile, each packet
//! through a [`Gatherer`](crate::gather::Gatherer)), `sparse` (the lattice of
//! sparse gathers), `cached` (the frame's records of the world-space
//! cache, `crate::cache`), `share` (which samples it does not serve share a
//! gather), `tile` (one tile's camera samples);
//! `image` and `output` (what comes out); `guides` (a denoiser's albedo
//! and normal images) and `denoise` (Intel OIDN on the image, the
//! `denoise` feature); `reference` (the path tracer the report measures
//! against).

mod bake;
mod bounces;
mod cached;
mod camera_samples;
#[cfg(feature = "denoise")]
mod denoise;
mod edged;
mod frame;
mod guides;
mod image;
mod light;
mod near_rays;
mod options;
mod output;
pub mod reference;
mod resolve;
mod shading;
mod share;
mod sparse;
mod spherical;
mod stitch;
mod surfel_groups;
mod surfels;
mod tile;
mod trace;

pub use bake::{bake_record, bake_tree, bake_tree_with_progress, scene_hash};
#[cfg(feature = "denoise")]
pub use denoise::{DenoiseError, denoise};
#[cfg(feature = "lab")]
pub(crate) use frame::PacketPoint;
pub use frame::{Frame, render};
pub use guides::Guides;
pub use image::Image;
pub use light::{ANALYTIC_TRIANGLES, Brdf, LightSamples, Lights};
pub use near_rays::NearRays;
pub use options::{
    Component, Crop, CropError, DEFAULT_LIGHT_SAMPLES, DEFAULT_SURFEL_BUDGET, Direct, Gathers, RenderOptions,
};
pub use output::{PreTimings, Progress, RenderError, RenderOutput, Stage, Timings};
pub use reference::{ReferenceOptions, ReferenceOutput, render_reference};
pub use resolve::{Flags, Resolved, UNLIMITED_BOUNCES, file_bounces, file_spp};
#[cfg(feature = "lab")]
pub(crate) use shading::shading_point;
pub use stitch::{TileError, Tiles};
pub use surfels::{BakeOptions, Baked, bake};
pub use trace::{Hit, Tracer};
