//! Tree cuts: for each receiver, the nodes whose disks are splatted.
//!
//! One node test ([`node_test`]) and four traversals over it, one file each:
//! [`scalar`] (the reference), [`single`] (16 nodes of one receiver in the
//! lanes), [`packet`] (16 receivers in the lanes, one node at a time) and
//! [`hybrid`] (packet, then single once few lanes of an entry stay active).
//! [`dispatch`] compiles them for AVX-512, AVX2, NEON and portable code and
//! picks one at run time.
//!
//! The cut is a function of (tree, receiver, Ω) alone: every scheme visits the
//! same (receiver, node) pairs and reports the same splats and discards, in
//! its own order.

pub mod dispatch;
pub mod hybrid;
pub mod node_test;
pub mod packet;
pub mod scalar;
pub mod single;

use std::fmt;
use std::str::FromStr;

use glam::Vec3;
use rayon::prelude::*;

pub use dispatch::Isa;
pub use node_test::{LANES, Outcome};

use crate::error::{Error, Invalid};
use crate::points::check_normal;
use crate::tree::{NodeId, Tree};
use node_test::ReceiverLanes;

/// A point being shaded: position and unit normal of its tangent plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    position: Vec3,
    normal: Vec3,
}

impl Receiver {
    /// A receiver at `position` facing `normal` (unit length, see
    /// [`NORMAL_TOLERANCE`](crate::error::NORMAL_TOLERANCE)).
    pub fn new(position: Vec3, normal: Vec3) -> Result<Self, Error> {
        let fail = |reason| Err(Error::InvalidReceiver { index: 0, reason });
        if !position.is_finite() {
            return fail(Invalid::NonFinite { field: "position" });
        }
        if let Err(reason) = check_normal(normal) {
            return fail(reason);
        }
        Ok(Self { position, normal })
    }

    /// Builds many receivers, naming the first invalid one by its index.
    pub fn from_pairs(pairs: impl IntoIterator<Item = (Vec3, Vec3)>) -> Result<Vec<Self>, Error> {
        pairs
            .into_iter()
            .enumerate()
            .map(|(index, (p, n))| {
                Self::new(p, n).map_err(|e| match e {
                    Error::InvalidReceiver { reason, .. } => Error::InvalidReceiver { index, reason },
                    other => other,
                })
            })
            .collect()
    }

    /// Position.
    #[inline(always)]
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// Unit normal.
    #[inline(always)]
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    #[inline(always)]
    pub(crate) fn lanes(&self) -> ReceiverLanes<f32> {
        ReceiverLanes {
            px: self.position.x,
            py: self.position.y,
            pz: self.position.z,
            nx: self.normal.x,
            ny: self.normal.y,
            nz: self.normal.z,
        }
    }
}

/// Receives the outcome of a traversal. `receiver` is the index of the
/// receiver in the slice given to [`Traversal::run`].
///
/// Every scheme reports the same set of calls, in its own order; a sink whose
/// result must not depend on the scheme must therefore not depend on the order
/// (a z-buffer keeping the minimum of `(depth, node)` does not).
pub trait CutSink {
    /// Whether [`discard`](Self::discard) is wanted; when `false` the kernels
    /// skip that bookkeeping entirely.
    const DISCARDS: bool = false;

    /// `node` is in the cut of `receiver`.
    fn splat(&mut self, receiver: usize, node: NodeId);

    /// `node` was culled for `receiver` (only called when [`DISCARDS`](Self::DISCARDS)).
    #[inline(always)]
    fn discard(&mut self, receiver: usize, node: NodeId) {
        let _ = (receiver, node);
    }

    /// A vector step of one receiver: `nodes[l]` is in its cut for every set
    /// bit `l` of `lanes`. Override to consume whole steps at once.
    #[inline(always)]
    fn splat_nodes(&mut self, receiver: usize, nodes: &[NodeId; LANES], lanes: u16) {
        // A plain loop, not a closure: a sink's `splat` inlined into a large
        // closure may leave it out of line, compiled for the baseline target.
        let mut bits = lanes;
        while bits != 0 {
            let l = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            self.splat(receiver, nodes[l]);
        }
    }

    /// A packet step: `node` is in the cut of receiver `base + l` for every
    /// set bit `l` of `lanes`. Override to consume whole steps at once.
    #[inline(always)]
    fn splat_receivers(&mut self, base: usize, node: NodeId, lanes: u16) {
        let mut bits = lanes;
        while bits != 0 {
            let l = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            self.splat(base + l, node);
        }
    }
}

/// The cut of one receiver, sorted by node.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Cut {
    /// Nodes splatted.
    pub splats: Vec<NodeId>,
    /// Nodes discarded (below the horizon or facing away).
    pub discards: Vec<NodeId>,
}

impl Cut {
    /// Checks the cut invariants (DESIGN §2) against `tree`: splats and
    /// discards partition the leaves (each leaf has exactly one
    /// ancestor-or-self among them), so none lies below another.
    pub fn check(&self, tree: &Tree) -> Result<(), String> {
        let n = tree.len();
        if n == 0 {
            return if self.splats.is_empty() && self.discards.is_empty() {
                Ok(())
            } else {
                Err("cut of an empty tree is not empty".into())
            };
        }
        let mut mark = vec![0u8; n];
        for &k in self.splats.iter().chain(&self.discards) {
            let k = k as usize;
            if k >= n {
                return Err(format!("node {k} is out of range"));
            }
            if mark[k] != 0 {
                return Err(format!("node {k} is reported twice"));
            }
            mark[k] = 1;
        }
        // Walk down from the root: each leaf must meet exactly one marked node.
        let mut stack = vec![(0u32, 0u32)];
        while let Some((k, above)) = stack.pop() {
            let here = above + mark[k as usize] as u32;
            if here > 1 {
                return Err(format!("node {k} lies below another node of the cut"));
            }
            match tree.left_child(k) {
                Some(l) => {
                    stack.push((l, here));
                    stack.push((l + 1, here));
                }
                None if here == 0 => return Err(format!("leaf {k} is not covered by the cut")),
                None => {}
            }
        }
        Ok(())
    }
}

/// A sink that records every receiver's [`Cut`].
#[derive(Clone, Debug, Default)]
pub struct CutRecorder {
    cuts: Vec<Cut>,
}

impl CutRecorder {
    /// A recorder for `receivers` receivers.
    pub fn new(receivers: usize) -> Self {
        Self {
            cuts: vec![Cut::default(); receivers],
        }
    }

    /// The cuts, each sorted.
    pub fn into_cuts(mut self) -> Vec<Cut> {
        for c in &mut self.cuts {
            c.splats.sort_unstable();
            c.discards.sort_unstable();
        }
        self.cuts
    }
}

impl CutSink for CutRecorder {
    const DISCARDS: bool = true;
    #[inline]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.cuts[receiver].splats.push(node);
    }
    #[inline]
    fn discard(&mut self, receiver: usize, node: NodeId) {
        self.cuts[receiver].discards.push(node);
    }
}

/// A sink that only counts splats (for benchmarks).
#[derive(Clone, Copy, Debug, Default)]
pub struct SplatCounter {
    /// Splats seen.
    pub splats: u64,
}

impl CutSink for SplatCounter {
    #[inline(always)]
    fn splat(&mut self, _receiver: usize, _node: NodeId) {
        self.splats += 1;
    }
    #[inline(always)]
    fn splat_nodes(&mut self, _receiver: usize, _nodes: &[NodeId; LANES], lanes: u16) {
        self.splats += lanes.count_ones() as u64;
    }
    #[inline(always)]
    fn splat_receivers(&mut self, _base: usize, _node: NodeId, lanes: u16) {
        self.splats += lanes.count_ones() as u64;
    }
}

/// How the traversal is vectorized.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Scheme {
    /// The reference: one receiver, one node at a time.
    Scalar,
    /// One receiver, 16 nodes at a time.
    Single,
    /// 16 receivers, one node at a time.
    Packet,
    /// Packet, handing an entry to single once fewer than
    /// [`CutOptions::hybrid_threshold`] of its lanes are active.
    Hybrid,
}

impl Scheme {
    /// All schemes, the reference first.
    pub const ALL: [Scheme; 4] = [Scheme::Scalar, Scheme::Single, Scheme::Packet, Scheme::Hybrid];

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Scalar => "scalar",
            Scheme::Single => "single",
            Scheme::Packet => "packet",
            Scheme::Hybrid => "hybrid",
        }
    }
}

impl fmt::Display for Scheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Packets of fewer receivers than this run [`Scheme::Single`] under
/// [`auto_scheme`]. Packet costs about as much per node step with one active
/// lane as with sixteen (≈3.5 scalar node tests, from its 4.3–4.9× speed-up
/// at ~85 % lane use), single ≈0.5 per receiver and node: below about six
/// receivers one at a time is cheaper.
pub const AUTO_SINGLE_BELOW: usize = 6;

/// The scheme the `auto` choice runs on one packet of `receivers` receivers:
/// [`Scheme::Packet`], the fastest on every scene measured (BENCHMARKS.md,
/// the glossy and bump ones included, where hybrid's switching cost more than
/// it saved), and [`Scheme::Single`] for packets too sparse to fill lanes
/// (tiles at the image's edge or at silhouettes against the background).
/// Every scheme gives the same cut, so the choice changes only the time.
pub fn auto_scheme(receivers: usize) -> Scheme {
    if receivers < AUTO_SINGLE_BELOW {
        Scheme::Single
    } else {
        Scheme::Packet
    }
}

impl FromStr for Scheme {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        Scheme::ALL
            .into_iter()
            .find(|x| x.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| Error::UnknownScheme { value: s.to_string() })
    }
}

/// Traversal parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutOptions {
    /// Ω: a node is splatted when its disk of radius R subtends less than
    /// this, `π R² < Ω d²` (steradians, ≥ 0; 0 splats leaves only).
    pub max_solid_angle: f32,
    /// Hybrid: an entry with fewer active lanes than this goes to single
    /// (0 never switches, 17 always does).
    pub hybrid_threshold: u32,
    /// Instruction-set path: `None` takes `PBGI_ISA` if set, else the best
    /// this CPU runs.
    pub isa: Option<Isa>,
}

impl Default for CutOptions {
    fn default() -> Self {
        Self {
            max_solid_angle: 0.05,
            hybrid_threshold: 2,
            isa: None,
        }
    }
}

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
    pub(crate) omega: f32,
    pub(crate) hybrid_threshold: u32,
    isa: Isa,
}

impl<'t> Traversal<'t> {
    /// Validates the options and resolves the instruction set.
    pub fn new(tree: &'t Tree, options: CutOptions) -> Result<Self, Error> {
        let omega = options.max_solid_angle;
        if !(omega.is_finite() && omega >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "max_solid_angle",
                value: omega.to_string(),
                expected: "a finite number ≥ 0",
            });
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
            omega,
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
        self.omega
    }

    /// Traverses the tree for every receiver, on this thread, reporting to `sink`.
    /// Packet and hybrid take the receivers 16 at a time in the given order:
    /// order them coherently (screen tiles, Morton order) for full lanes.
    pub fn run<S: CutSink>(&self, scheme: Scheme, receivers: &[Receiver], sink: &mut S) -> TraversalStats {
        dispatch::run(self, scheme, receivers, sink)
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
