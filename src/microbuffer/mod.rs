//! The microbuffer: a small z-buffered raster per receiver into which the cut
//! is splatted, then convolved with the BRDF using exact per-pixel solid
//! angles.
//!
//! **Parametrization.** The hemisphere above the receiver is one N×N grid
//! through the octahedral map: a local direction `(x, y, z)` goes to
//! `p = (x, y)/(|x| + |y| + z)` in the diamond `|px| + |py| ≤ 1`, turned by
//! 45° into the square `(u, v) = (px + py, px − py) ∈ [−1, 1]²`. The square's
//! edge is the horizon, so the grid has no seams: every footprint is a box of
//! pixels around its centre, and locating a direction costs an absolute value,
//! two additions and two divisions (no branch, no face choice). Pixels near
//! the horizon are about 3× larger in solid angle than near the normal, where
//! the cosine weight is largest.
//!
//! **Composition** (docs/design.md §3): a splat leaves a fragment (depth,
//! node, coverage) in each pixel it touches; `compose` spreads each
//! fragment over the pixel's 4×4 sub-samples (`samples`), keeps at each the
//! front layer (the fragments reaching the nearest one's depth interval)
//! over what lies behind it, and convolves. Fragments are taken in node
//! order, so the shading depends on the set of splats only, not on the
//! order a traversal scheme reports them in, and both pipelines share one
//! composition.
//!
//! Data enters as a receiver (position, normal: [`MicroBuffer::reset`]) and
//! its cut (node ids of a [`Tree`](crate::Tree)); it leaves as irradiance,
//! occlusion or glossy radiance. The files, in data-flow order: `table`
//! (the map and its per-pixel tables), `locate` (where a node falls),
//! `fragments` (what a splat leaves in a pixel), `buffer` (a receiver's
//! fragments and the convolutions' entry points), `near` and `open` (what
//! rays from the receiver meet: the near field, the sky), `samples` (a fragment at
//! the pixel's sub-samples), `compose`
//! (fragments to pixels, pixels to irradiance, occlusion or glossy),
//! `gradients` (how the irradiance changes as the receiver moves), `plan`
//! (a splat's class and footprint), `draw` (the scalar draw), `tiles` (the
//! 16-lane draw), `shade` (the two shading pipelines: [`shade_cuts`] and
//! [`shade_packet`]).

mod buffer;
mod compose;
mod draw;
mod fragments;
mod gradients;
mod incident;
mod locate;
mod near;
mod open;
mod plan;
mod samples;
mod shade;
mod table;
mod tiles;

pub use buffer::{MicroBuffer, MicroBufferSink};
pub use gradients::Gradients;
pub(crate) use incident::{reflect, tilted};
pub use near::{NEAR_RADII, Near, NearField, Sight};
pub use shade::{Convolution, PacketCut, shade_cuts, shade_packet};
pub(crate) use shade::{shade_cuts_near, shade_packet_near};
pub(crate) use table::Table;

#[cfg(test)]
mod tests;
