//! Tree cuts: for each receiver, the nodes whose disks are splatted.
//!
//! Data enters as a [`Tree`] with [`CutOptions`] (a [`Traversal`]) and a slice
//! of [`Receiver`]s; it leaves as splats (and discards) reported to a
//! [`CutSink`]. One node test ([`classify`]) and four traversals over it, one
//! file each: [`scalar`] (the reference), [`single`] (16 nodes of one
//! receiver in the lanes), [`packet`] (16 receivers in the lanes, one node at
//! a time) and [`hybrid`] (packet, then single once few lanes of an entry
//! stay active). `run` is the kernel the one dispatch point
//! (`simd::dispatch`) compiles for each instruction set.
//!
//! The cut is a function of (tree, receiver, Ω) alone: every scheme visits the
//! same (receiver, node) pairs and reports the same splats and discards, in
//! its own order (docs/design.md, "2. The node test and the cut").

pub mod classify;
pub mod hybrid;
mod nodes;
mod options;
pub mod packet;
mod receiver;
mod run;
pub mod scalar;
pub mod single;
mod sink;

use rayon::prelude::*;

pub use classify::Outcome;
pub use options::{AUTO_SINGLE_BELOW, CutOptions, Scheme, SchemeChoice, auto_scheme};
pub use receiver::Receiver;
pub use sink::{Cut, CutRecorder, CutSink, SplatCounter};

use crate::error::Error;
use crate::simd::dispatch::dispatch;
use crate::simd::{Isa, LANES};
use crate::tree::Tree;

/// Counters of one traversal run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Receivers traversed.
    pub receivers: u64,
    /// (receiver, node) pairs tested: the same for every scheme.
    pub node_tests: u64,
    /// Lane slots of the vector steps (16 per step); 0 for scalar.
    pub lane_slots: u64,
    /// Active lanes over those slots.
    pub active_lanes: u64,
    /// Hybrid: entries handed from packet to single.
    pub switches: u64,
}

impl TraversalStats {
    /// Active lanes / lane slots, `None` for the scalar scheme.
    pub fn lane_utilization(&self) -> Option<f64> {
        (self.lane_slots > 0).then(|| self.active_lanes as f64 / self.lane_slots as f64)
    }

    /// Node tests per receiver.
    pub fn nodes_per_receiver(&self) -> f64 {
        self.node_tests as f64 / self.receivers.max(1) as f64
    }

    /// Adds another run's counters.
    pub fn merge(&mut self, o: &TraversalStats) {
        self.receivers += o.receivers;
        self.node_tests += o.node_tests;
        self.lane_slots += o.lane_slots;
        self.active_lanes += o.active_lanes;
        self.switches += o.switches;
    }
}

/// A tree ready to be cut with fixed options and a resolved instruction set.
///
/// ```
/// use pbgi::{CutOptions, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};
/// use glam::Vec3;
///
/// // A floor of surfels facing up, and a receiver above it looking down.
/// let surfels: Vec<_> = (0..64)
///     .map(|i| Surfel {
///         position: Vec3::new((i % 8) as f32, 0.0, (i / 8) as f32),
///         normal: Vec3::Y,
///         radius: 0.6,
///         radiance: Vec3::splat(1.0),
///     })
///     .collect();
/// let tree = Tree::build(&PointCloud::new(surfels)?);
/// let traversal = Traversal::new(&tree, CutOptions { max_solid_angle: 0.1, ..Default::default() })?;
/// let receiver = Receiver::new(Vec3::new(3.5, 2.0, 3.5), -Vec3::Y)?;
/// let cuts = traversal.cuts(Scheme::Packet, &[receiver]);
/// assert!(!cuts[0].splats.is_empty());
/// assert_eq!(cuts, traversal.cuts(Scheme::Scalar, &[receiver]));
/// println!("ran on {}", traversal.isa());
/// # Ok::<(), pbgi::Error>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Traversal<'t> {
    pub(crate) tree: &'t Tree,
    pub(crate) max_solid_angle: f32,
    light_offset: f32,
    pub(crate) hybrid_threshold: u32,
    isa: Isa,
}

impl<'t> Traversal<'t> {
    /// Validates the options and resolves the instruction set.
    pub fn new(tree: &'t Tree, options: CutOptions) -> Result<Self, Error> {
        let (max_solid_angle, light_offset) = (options.max_solid_angle, options.light_offset);
        for (name, v) in [
            ("max_solid_angle", max_solid_angle),
            ("light_offset", light_offset),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::InvalidParameter {
                    name,
                    value: v.to_string(),
                    expected: "a finite number ≥ 0",
                });
            }
        }
        if options.hybrid_threshold > LANES as u32 + 1 {
            return Err(Error::InvalidParameter {
                name: "hybrid_threshold",
                value: options.hybrid_threshold.to_string(),
                expected: "0 to 17",
            });
        }
        let isa = match options.isa {
            Some(isa) => isa.require()?,
            None => Isa::from_env()?.unwrap_or_else(Isa::best),
        };
        Ok(Self {
            tree,
            max_solid_angle,
            light_offset,
            hybrid_threshold: options.hybrid_threshold,
            isa,
        })
    }

    /// The instruction-set path the kernels run on.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// The tree.
    pub fn tree(&self) -> &'t Tree {
        self.tree
    }

    /// Ω.
    pub fn max_solid_angle(&self) -> f32 {
        self.max_solid_angle
    }

    /// The weight of a node's light offset in the far test.
    pub fn light_offset(&self) -> f32 {
        self.light_offset
    }

    /// The far test's parameters.
    #[inline(always)]
    pub(crate) fn far(&self) -> classify::Far<f32> {
        classify::Far {
            max_solid_angle: self.max_solid_angle,
            light_offset: self.light_offset,
        }
    }

    /// Traverses the tree for every receiver, on this thread, reporting to `sink`.
    /// Packet and hybrid take the receivers 16 at a time in the given order:
    /// order them coherently (screen tiles, Morton order) for full lanes.
    ///
    /// Panics if `sink` takes fewer receivers than given
    /// ([`CutSink::RECEIVERS`]: a [`PacketCut`](crate::microbuffer::PacketCut)
    /// holds one packet), in release builds too: its lanes would fold
    /// receivers together and shade them wrong without a word. [`try_run`](Self::try_run)
    /// returns that as an error instead.
    pub fn run<S: CutSink>(&self, scheme: Scheme, receivers: &[Receiver], sink: &mut S) -> TraversalStats {
        self.try_run(scheme, receivers, sink)
            .unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`run`](Self::run), with more receivers than `sink` takes an
    /// [`Error::TooManyReceivers`].
    pub fn try_run<S: CutSink>(
        &self,
        scheme: Scheme,
        receivers: &[Receiver],
        sink: &mut S,
    ) -> Result<TraversalStats, Error> {
        if receivers.len() > S::RECEIVERS {
            return Err(Error::TooManyReceivers {
                given: receivers.len(),
                most: S::RECEIVERS,
            });
        }
        Ok(dispatch(
            self.isa,
            run::Run {
                t: self,
                scheme,
                receivers,
                sink,
            },
        ))
    }

    /// The cut of every receiver (sorted), computed in parallel.
    pub fn cuts(&self, scheme: Scheme, receivers: &[Receiver]) -> Vec<Cut> {
        receivers
            .par_chunks(4 * LANES)
            .flat_map_iter(|chunk| {
                let mut rec = CutRecorder::new(chunk.len());
                self.run(scheme, chunk, &mut rec);
                rec.into_cuts()
            })
            .collect()
    }
}
