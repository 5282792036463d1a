//! # pbgi — point-based global illumination kernels
//!
//! Light gathered from surfels: give it the lit surfaces as disks
//! ([`Surfel`]), build a [`Tree`], and ask a [`Gather`] for the irradiance,
//! occlusion or glossy radiance at any points.
//!
//! ```
//! use pbgi::glam::Vec3;
//! use pbgi::{Gather, GatherOptions, PointCloud, Surfel, Tree};
//!
//! // A glowing 1 × 1 ceiling at height 1, facing down: 32 × 32 disks.
//! let radius = 1.0 / 32.0 / std::f32::consts::PI.sqrt(); // a disk the area of its cell
//! let surfels = (0..1024).map(|i| {
//!     let position = Vec3::new((i % 32) as f32 / 32.0, 1.0, (i / 32) as f32 / 32.0);
//!     Surfel { position, normal: -Vec3::Y, radius, radiance: Vec3::ONE }
//! });
//! let tree = Tree::build(&PointCloud::new(surfels.collect())?);
//! let gather = Gather::new(&tree, &GatherOptions::default())?;
//! let e = gather.irradiance(&[(Vec3::new(0.5, 0.0, 0.5), Vec3::Y)])?; // (position, normal)
//! assert!(e[0].x > 0.0 && e[0].x < std::f32::consts::PI);
//! # Ok::<(), pbgi::Error>(())
//! ```
//!
//! [`gather`] says how to choose Ω and N and what error to expect;
//! `render` (feature `render`, on by default) is a whole renderer built on
//! it, and `docs/guide.md` in the repository the rest.
//!
//! # Underneath: the cut
//!
//! A bounding-sphere hierarchy ([`Tree`]) clusters the surfels; for each
//! receiver a top-down traversal picks a *cut* of the tree ([`Traversal`]),
//! whose nodes are splatted into a small z-buffered raster, the
//! microbuffer, and convolved with the BRDF.
//!
//! The traversal is written once on `std::simd` with 16 lanes and comes in
//! four schemes ([`Scheme`]): the scalar reference, *single* (16 nodes of one
//! receiver), *packet* (16 receivers, one node) and *hybrid*. Each is compiled
//! for AVX-512, AVX2, NEON and portable code and chosen at run time ([`Isa`]).
//! All give the identical cut, bit for bit, on every path.
//!
//! ```
//! use pbgi::{CutOptions, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};
//! use pbgi::glam::Vec3;
//!
//! // Your surfels: here a 32 × 32 glowing ceiling facing down.
//! let surfels: Vec<Surfel> = (0..1024)
//!     .map(|i| Surfel {
//!         position: Vec3::new((i % 32) as f32 / 32.0, 1.0, (i / 32) as f32 / 32.0),
//!         normal: -Vec3::Y,
//!         radius: 0.5 / 32.0 * std::f32::consts::SQRT_2,
//!         radiance: Vec3::splat(2.0),
//!     })
//!     .collect();
//! let tree = Tree::build(&PointCloud::new(surfels)?);
//!
//! // Receivers on the floor, facing up.
//! let receivers = Receiver::from_pairs((0..16).map(|i| {
//!     (Vec3::new(0.25 + 0.03 * i as f32, 0.0, 0.5), Vec3::Y)
//! }))?;
//!
//! let traversal = Traversal::new(&tree, CutOptions { max_solid_angle: 0.02, ..Default::default() })?;
//! let cuts = traversal.cuts(Scheme::Hybrid, &receivers);
//! assert_eq!(cuts, traversal.cuts(Scheme::Scalar, &receivers));
//! for cut in &cuts {
//!     cut.check(&tree).unwrap(); // splats and discards partition the leaves
//! }
//! # Ok::<(), pbgi::Error>(())
//! ```
//!
//! # Numerical range and stability
//!
//! Checked in `tests/stability.rs`, which lists every case:
//!
//! * **Inputs**: finite; positions and radii within
//!   [`MAX_COORDINATE`](points::MAX_COORDINATE) (10³⁷), radiance within
//!   [`MAX_RADIANCE`](points::MAX_RADIANCE) (10³⁰), unit normals; anything
//!   else is an [`Error`] naming the surfel or receiver. Within that range no
//!   NaN or infinity leaves the library (node areas saturate at `f32::MAX`),
//!   irradiance is at most `π · max L` per channel and ambient occlusion in
//!   `[0, 1]`. The tree aggregates area-weighted radiance in `f64`, so one
//!   scene may span 10⁻³⁰ … 10³⁰. Subnormal values are accepted.
//! * **Scale**: scaling surfels and receivers by `2^k` (k within ±40 for a
//!   unit-sized scene) gives the identical cut and the identical irradiance,
//!   bit for bit.
//! * **Far from the origin**: positions are `f32`, so at distance `T` the
//!   input itself is rounded to half an ulp of `T`. The node test and the
//!   microbuffer subtract nearby `f32` values exactly; with Ω = 0 a translated
//!   scene shades bit for bit like the same rounded scene at the origin, and
//!   with Ω > 0 only the inner nodes' stored centres add rounding, less than
//!   the input's own (on a unit box: 0.005 % RMS at 10⁴, 0.8 % at 10⁶, 2.5 %
//!   at 10⁷, while the input's rounding alone costs 0.06 %, 1 % and tens of
//!   %). Keep a scene's coordinates small relative to its detail, or centre it.
//! * **Depth**: the median split gives depth ⌈log₂ n⌉ whatever the positions;
//!   splits by orientation (a hollow solid's two sides) may add up to
//!   [`EXTRA_DEPTH`](tree::EXTRA_DEPTH) = 4 levels, never past
//!   [`MAX_DEPTH`](tree::MAX_DEPTH) = 30; the traversal stacks are sized for it.
//! * **Ω**: any finite Ω ≥ 0 is accepted; from Ω ≥ π on, the node test
//!   `π R² < Ω d²` may splat a node whose sphere contains the receiver, and
//!   the estimate degrades (bounded, not accurate).
#![feature(portable_simd)]
// Feature-gated items say which feature they need, in the API docs.
#![cfg_attr(doc, feature(doc_cfg))]
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]
// Every `unsafe` block says why it is sound (a `SAFETY:` comment).
#![deny(clippy::undocumented_unsafe_blocks)]

// Modules in data-flow order: the SIMD vocabulary and dispatch, the kernel
// layer's data (errors, surfels, tree), cuts, the microbuffer, the gather in
// one call, the world-space cache; random numbers (the renderer's sampling);
// behind the `render` feature, scenes and the renderer. Last the lab, for the
// tool, tests, benchmarks and examples alone (feature `lab`, which `cli`
// turns on): synthetic clouds, the closed-form references and the report.
// The lab is hidden from the API docs; `cargo doc` with
// `RUSTDOCFLAGS="-Z unstable-options --document-hidden-items"` shows it.
pub mod simd;

pub mod error;
pub mod points;
pub mod tree;

pub mod cut;

pub mod brdf;
pub mod environment;
pub mod microbuffer;
mod polygon;

pub mod gather;

pub mod cache;

#[cfg(feature = "lab")]
#[doc(hidden)]
pub mod rng;
#[cfg(all(not(feature = "lab"), any(test, feature = "render")))]
mod rng;

#[cfg(feature = "render")]
pub mod scene;

#[cfg(feature = "render")]
pub mod render;

#[cfg(any(test, feature = "lab"))]
#[doc(hidden)]
pub mod synthetic;

#[cfg(feature = "lab")]
#[doc(hidden)]
pub mod exact;

#[cfg(feature = "lab")]
#[doc(hidden)]
pub mod report;

pub use cut::{
    AUTO_SINGLE_BELOW, Cut, CutOptions, CutRecorder, CutSink, Outcome, Receiver, Scheme, SchemeChoice,
    SplatCounter, Traversal, TraversalStats, auto_scheme,
};
pub use error::{Error, Invalid};
pub use gather::{Gather, GatherOptions, GlossyReceiver, ReceiverOrder};
/// The vector types of every signature, so a user needs no version of
/// their own in step with this crate's.
pub use glam;
pub use points::{PointCloud, Surfel};
pub use simd::{Isa, IsaError, LANES};
pub use tree::{NodeId, NodeView, Tree, TreeFile, TreeFileError};
