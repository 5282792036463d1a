//! The gather in one call: for any slice of receivers (position, normal),
//! the irradiance, the occlusion or the glossy radiance from a [`Tree`] of
//! surfels. [`Gather`] forms the packets (Morton order, or the caller's
//! when it says its receivers are coherent), runs them on rayon's threads (in
//! the caller's pool, when called inside one) and takes the fastest path this
//! CPU runs ([`Gather::path`] says which).
//!
//! ```
//! use glam::Vec3;
//! use pbgi::gather::{Gather, GatherOptions};
//! use pbgi::{PointCloud, Surfel, Tree};
//!
//! // A glowing 2 × 2 ceiling at height 1: 64 × 64 surfels of radiance 1,
//! // each a disk of its cell's area.
//! let surfels: Vec<Surfel> = (0..4096)
//!     .map(|i| Surfel {
//!         position: Vec3::new((i % 64) as f32 / 32.0 - 1.0, 1.0, (i / 64) as f32 / 32.0 - 1.0),
//!         normal: -Vec3::Y,
//!         radius: 1.0 / 32.0 / std::f32::consts::PI.sqrt(),
//!         radiance: Vec3::ONE,
//!     })
//!     .collect();
//! let tree = Tree::build(&PointCloud::new(surfels)?);
//! let gather = Gather::new(&tree, &GatherOptions::default())?;
//!
//! // Receivers on the floor below, facing up, in any order.
//! let receivers: Vec<(Vec3, Vec3)> = (0..100)
//!     .map(|i| (Vec3::new((i % 10) as f32 * 0.05, 0.0, (i / 10) as f32 * 0.05), Vec3::Y))
//!     .collect();
//! let e = gather.irradiance(&receivers)?;
//! // Under the middle of the square, E = π·F·L with the square's form
//! // factor F = (2/π)·√2·atan(1/√2) ≈ 0.554.
//! assert!((e[0].x / std::f32::consts::PI - 0.55).abs() < 0.05, "{}", e[0]);
//! println!("path: {}", gather.path());
//! # Ok::<(), pbgi::Error>(())
//! ```
//!
//! **Units.** Irradiance is `E = ∫ L cosθ dω` over the hemisphere of the
//! normal (not `E/π`): a diffuse surface of albedo ρ reflects `ρ·E/π`.
//! Occlusion is the covered fraction of the cosine-weighted hemisphere, in
//! [0, 1]. Glossy radiance is `∫ L f_s cosθ dω` for the given lobe.
//!
//! **Choosing Ω and N.** Measured against closed-form answers in convex
//! rooms (`cargo run --release --example exact`; docs/lab/BENCHMARKS.md, ~10⁵
//! surfels, one thread), the relative RMSE of receivers mid-surface:
//!
//! | Ω (`cut.max_solid_angle`) | N (`microbuffer`) | irradiance | glossy (α 0.3) | µs per receiver |
//! | --- | --- | --- | --- | --- |
//! | 0.2 (near the renderer's 0.15) | 14 | 0.6–1 % | 21 % | 60–100 |
//! | 0.05 (default) | 24 (default) | 0.2–0.3 % | 0.7–4 % | 220–300 |
//! | 0.05, `cut.light_offset` 4 (the renderer's glossy) | 24 | 0.1–0.2 % | 0.8–1.9 % | 230–350 |
//! | 0.01 | 32 | 0.1 % | 0.5–1.3 % | 550–1000 |
//!
//! A glossy lobe reads where each cluster's light is drawn, not only its
//! sum: `cut.light_offset` refines a cluster whose light lies off its
//! centre (a small bright light in a dark ceiling) until it lies where its
//! surface does ([`CutOptions::light_offset`]).
//!
//! Ω sets the error of the far field; N matters for glossy lobes (N 8
//! gives 7 % there, whatever Ω) and little for irradiance from 16 on. Near
//! edges and in corners the error is set by the surfel density, not by Ω or
//! N: 5–7 % at 2–4 surfels across a receiver's distance to the edge, 2.5–3.5
//! % at 8. Irradiance costs the same as occlusion; glossy adds a
//! convolution of N² pixels per receiver.
//!
//! A renderer forming its own packets (screen tiles) uses a [`Gatherer`]
//! per thread instead: one packet at a time, the microbuffers kept for
//! convolutions of its own.

mod order;
#[cfg(feature = "render")]
pub(crate) use order::morton_codes;
mod packets;

use std::fmt;
use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;

pub use packets::Gatherer;

use crate::brdf::GlossyLobe;
use crate::cut::{CutOptions, Receiver, Scheme, SchemeChoice, Traversal};
use crate::environment::Environment;
use crate::error::{Error, Invalid};
use crate::microbuffer::{Convolution, Gradients, MicroBuffer, NearField};
use crate::simd::{Isa, LANES};
use crate::tree::Tree;

/// How far a receiver's normal may be from unit length: such normals are
/// normalised; others are an error naming the receiver.
pub const NORMAL_SLACK: f32 = 1e-2;

/// The most worker threads [`GatherOptions::threads`] takes.
pub const MAX_THREADS: usize = 4096;

/// How the receivers given are grouped into packets of 16.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ReceiverOrder {
    /// In any order: the gather sorts them by Morton order of their
    /// positions (neighbours share a packet) and returns results in the
    /// order given.
    #[default]
    Unordered,
    /// Already coherent (screen tiles, a surface's grid): 16 at a time as given.
    Coherent,
}

/// Settings of a [`Gather`]. The defaults (Ω 0.05, N 24) are finer than
/// the renderer's irradiance gathers (Ω 0.15, N 14): a library call has no
/// image to hide its error in (the table above).
#[derive(Clone, Debug, PartialEq)]
pub struct GatherOptions {
    /// The cut's parameters: Ω, the hybrid threshold, the instruction-set path.
    pub cut: CutOptions,
    /// Microbuffer resolution N (an N×N octahedral grid over the hemisphere).
    pub microbuffer: usize,
    /// Traversal scheme; [`SchemeChoice::Auto`] picks per packet. The scalar
    /// scheme shades through the scalar pipeline, every other through the
    /// 16-lane one: both give the same bits.
    pub scheme: SchemeChoice,
    /// How the receivers are grouped into packets.
    pub order: ReceiverOrder,
    /// What a receiver sees where its hemisphere is open: the pixels whose
    /// rays leave the scene, where the near field tells
    /// ([`NearField::escapes`]),
    /// else the microbuffer's uncovered part; `None`: black.
    pub environment: Option<Arc<Environment>>,
    /// Worker threads of the gather's own pool; `None`: rayon's pool the
    /// call runs in (the global one, or the caller's `install`). The
    /// results are the same bits for any count.
    pub threads: Option<usize>,
}

impl Default for GatherOptions {
    fn default() -> Self {
        GatherOptions {
            cut: CutOptions::default(),
            microbuffer: 24,
            scheme: SchemeChoice::Auto,
            order: ReceiverOrder::Unordered,
            environment: None,
            threads: None,
        }
    }
}

/// The shading pipelines: the scalar reference splats each receiver's cut
/// one node at a time; the 16-lane one each node for the packet's receivers
/// at once. The same bits, in the pipeline's own time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pipeline {
    /// One node and one pixel at a time.
    Scalar,
    /// 16 receivers at a time.
    Lanes,
}

/// The path a [`Gather`] takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GatherPath {
    /// The instruction-set path of the kernels.
    pub isa: Isa,
    /// The scheme of a full packet (a smaller one may take single under `Auto`).
    pub scheme: Scheme,
    /// The shading pipeline.
    pub pipeline: Pipeline,
    /// How receivers are grouped into packets.
    pub order: ReceiverOrder,
}

impl fmt::Display for GatherPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let pipeline = match self.pipeline {
            Pipeline::Scalar => "scalar",
            Pipeline::Lanes => "16-lane",
        };
        let order = match self.order {
            ReceiverOrder::Unordered => "Morton order",
            ReceiverOrder::Coherent => "the caller's order",
        };
        write!(
            f,
            "{} traversal on {}, {pipeline} shading, packets of 16 in {order}",
            self.scheme, self.isa
        )
    }
}

/// A receiver for the glossy convolution: where, which way it faces, the
/// outgoing direction (unit, away from the surface) and the lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlossyReceiver {
    /// Position.
    pub position: Vec3,
    /// Normal (unit within [`NORMAL_SLACK`]).
    pub normal: Vec3,
    /// Outgoing direction (unit within [`NORMAL_SLACK`]).
    pub wo: Vec3,
    /// The glossy lobe.
    pub lobe: GlossyLobe,
}

/// Gathers at receivers from one tree: built once, used for any number of
/// slices, from any number of threads.
pub struct Gather<'t> {
    traversal: Traversal<'t>,
    proto: MicroBuffer,
    opts: GatherOptions,
    path: GatherPath,
    /// The scene along short rays, where leaves are too near to stand for it.
    near: Option<&'t dyn NearField>,
    /// The pool of [`GatherOptions::threads`].
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl<'t> Gather<'t> {
    /// A gather over `tree`. Errors: an Ω out of range, an instruction-set
    /// path this CPU does not run, a microbuffer resolution or a thread
    /// count out of range.
    pub fn new(tree: &'t Tree, opts: &GatherOptions) -> Result<Self, Error> {
        let pool = match opts.threads {
            None => None,
            Some(n @ 1..=MAX_THREADS) => Some(Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|_| Error::InvalidParameter {
                        name: "threads",
                        value: n.to_string(),
                        expected: "a count the system can start",
                    })?,
            )),
            Some(n) => {
                return Err(Error::InvalidParameter {
                    name: "threads",
                    value: n.to_string(),
                    expected: "1 to 4096",
                });
            }
        };
        let traversal = Traversal::new(tree, opts.cut)?;
        let proto = MicroBuffer::new(opts.microbuffer)?.with_environment(opts.environment.clone());
        let scheme = opts.scheme.resolve(LANES);
        let pipeline = match opts.scheme {
            SchemeChoice::Fixed(Scheme::Scalar) => Pipeline::Scalar,
            _ => Pipeline::Lanes,
        };
        let path = GatherPath {
            isa: traversal.isa(),
            scheme,
            pipeline,
            order: opts.order,
        };
        Ok(Gather {
            traversal,
            proto,
            opts: opts.clone(),
            path,
            near: None,
            pool,
        })
    }

    /// This gather, drawing what lies within a few surfel radii of a
    /// receiver by rays into `field` ([`microbuffer::NearField`](crate::microbuffer::NearField)):
    /// where a receiver's cut holds a leaf of another surface that near,
    /// those leaves give way to one ray per pixel; and, with an
    /// environment, where `field` tells which rays escape, the sky shows
    /// through the pixels whose rays do (`microbuffer::open`).
    pub fn with_near_field(mut self, field: &'t dyn NearField) -> Self {
        self.near = Some(field);
        self
    }

    /// The path this gather takes.
    pub fn path(&self) -> GatherPath {
        self.path
    }

    /// The tree.
    pub fn tree(&self) -> &'t Tree {
        self.traversal.tree()
    }

    /// The options.
    pub fn options(&self) -> &GatherOptions {
        &self.opts
    }

    /// A packet-at-a-time gatherer for one thread.
    pub fn gatherer(&self) -> Gatherer<'_, 't> {
        Gatherer::new(self)
    }

    /// Irradiance `E` (RGB, not `E/π`) at each receiver `(position, normal)`.
    pub fn irradiance(&self, receivers: &[(Vec3, Vec3)]) -> Result<Vec<Vec3>, Error> {
        let r = checked(receivers.iter().map(|&(p, n)| (p, n, Vec3::Y)))?;
        self.run(&r, Convolution::Irradiance, |_, e, _| e)
    }

    /// [`irradiance`](Self::irradiance) and its [`Gradients`] at each
    /// receiver: how it changes as the receiver moves and turns, and the
    /// harmonic mean distance of what it sees (an irradiance cache's
    /// records).
    pub fn irradiance_gradients(&self, receivers: &[(Vec3, Vec3)]) -> Result<Vec<(Vec3, Gradients)>, Error> {
        let r = checked(receivers.iter().map(|&(p, n)| (p, n, Vec3::Y)))?;
        let tree = self.tree();
        self.run(&r, Convolution::Irradiance, |_, e, mb| (e, mb.gradients(tree)))
    }

    /// Ambient occlusion in [0, 1] at each receiver `(position, normal)`.
    pub fn occlusion(&self, receivers: &[(Vec3, Vec3)]) -> Result<Vec<f32>, Error> {
        let r = checked(receivers.iter().map(|&(p, n)| (p, n, Vec3::Y)))?;
        self.run(&r, Convolution::Occlusion, |_, ao, _| ao.x)
    }

    /// Glossy radiance `∫ L f_s cosθ dω` toward each receiver's `wo`.
    pub fn glossy(&self, receivers: &[GlossyReceiver]) -> Result<Vec<Vec3>, Error> {
        let r = checked(receivers.iter().map(|g| (g.position, g.normal, g.wo)))?;
        let tree = self.tree();
        self.run(&r, Convolution::Irradiance, |i, _, mb| {
            mb.glossy(tree, r.wo[i], &receivers[i].lobe)
        })
    }

    /// Runs the packets of `r` and maps each receiver's result (its index
    /// in the input, the convolution, its buffer) with `finish`.
    fn run<T: Send + Copy + Default>(
        &self,
        r: &Checked,
        what: Convolution,
        finish: impl Fn(usize, Vec3, &MicroBuffer) -> T + Sync,
    ) -> Result<Vec<T>, Error> {
        match &self.pool {
            Some(pool) => pool.install(|| self.run_here(r, what, &finish)),
            None => self.run_here(r, what, &finish),
        }
    }

    /// [`run`](Self::run) on the current rayon pool.
    fn run_here<T: Send + Copy + Default>(
        &self,
        r: &Checked,
        what: Convolution,
        finish: &(impl Fn(usize, Vec3, &MicroBuffer) -> T + Sync),
    ) -> Result<Vec<T>, Error> {
        let order: Vec<u32> = match self.opts.order {
            ReceiverOrder::Unordered => order::morton(r.receivers.iter().map(|x| x.position())),
            ReceiverOrder::Coherent => (0..r.receivers.len() as u32).collect(),
        };
        let packets: Vec<Vec<(u32, T)>> = order
            .par_chunks(LANES)
            .map_init(
                || (self.gatherer(), Vec::with_capacity(LANES)),
                |(g, packet), idx| {
                    packet.clear();
                    packet.extend(idx.iter().map(|&i| r.receivers[i as usize]));
                    g.cut(packet)?;
                    let out = g.shade(what);
                    Ok(idx
                        .iter()
                        .zip(out)
                        .zip(g.buffers())
                        .map(|((&i, v), mb)| (i, finish(i as usize, v, mb)))
                        .collect())
                },
            )
            .collect::<Result<_, Error>>()?;
        let mut out = vec![T::default(); r.receivers.len()];
        for (i, v) in packets.into_iter().flatten() {
            out[i as usize] = v;
        }
        Ok(out)
    }
}

/// Receivers checked and normalised, with their outgoing directions.
struct Checked {
    receivers: Vec<Receiver>,
    wo: Vec<Vec3>,
}

/// `v` as given if unit within the kernels' own tolerance
/// ([`NORMAL_TOLERANCE`](crate::error::NORMAL_TOLERANCE): the bits the caller
/// gave, as every other entry point keeps them), else normalised if within
/// [`NORMAL_SLACK`] of unit length.
fn unit(v: Vec3, field: &'static str) -> Result<Vec3, Invalid> {
    if !v.is_finite() {
        return Err(Invalid::NonFinite { field });
    }
    if (v.length_squared() - 1.0).abs() <= crate::error::NORMAL_TOLERANCE {
        return Ok(v);
    }
    let length = v.length();
    if (length - 1.0).abs() > NORMAL_SLACK {
        return Err(match field {
            "normal" if length == 0.0 => Invalid::ZeroNormal,
            "normal" => Invalid::NonUnitNormal { length },
            _ => Invalid::NonUnitDirection { field, length },
        });
    }
    Ok(v / length)
}

/// Checks and normalises `(position, normal, wo)` triples.
fn checked(items: impl ExactSizeIterator<Item = (Vec3, Vec3, Vec3)>) -> Result<Checked, Error> {
    let mut out = Checked {
        receivers: Vec::with_capacity(items.len()),
        wo: Vec::with_capacity(items.len()),
    };
    for (index, (p, n, wo)) in items.enumerate() {
        let fail = |reason| Error::InvalidReceiver { index, reason };
        let n = unit(n, "normal").map_err(fail)?;
        let wo = unit(wo, "outgoing direction").map_err(fail)?;
        let r = Receiver::new(p, n).map_err(|e| match e {
            Error::InvalidReceiver { reason, .. } => fail(reason),
            other => other,
        })?;
        out.receivers.push(r);
        out.wo.push(wo);
    }
    Ok(out)
}

impl fmt::Display for ReceiverOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ReceiverOrder::Unordered => "unordered",
            ReceiverOrder::Coherent => "coherent",
        })
    }
}
