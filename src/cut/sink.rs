//! Sinks: what a traversal reports its splats (and discards) to. The kernels
//! are generic over the sink, so a microbuffer, a recorder or an embedder's
//! own consumer costs nothing extra.

use crate::simd::{LANES, set_bits};
use crate::tree::{NodeId, Tree};

/// Receives the outcome of a traversal. `receiver` is the index of the
/// receiver in the slice given to [`Traversal::run`](super::Traversal::run).
///
/// Every scheme reports the same set of calls, in its own order; a sink whose
/// result must not depend on the scheme must therefore not depend on the order
/// (a z-buffer keeping the minimum of `(depth, node)` does not).
pub trait CutSink {
    /// Whether [`discard`](Self::discard) is wanted; when `false` the kernels
    /// skip that bookkeeping entirely.
    const DISCARDS: bool = false;

    /// The most receivers one traversal may report to this sink
    /// ([`Traversal::run`](super::Traversal::run) refuses more).
    const RECEIVERS: usize = usize::MAX;

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
        for l in set_bits(lanes) {
            self.splat(receiver, nodes[l]);
        }
    }

    /// A packet step: `node` is in the cut of receiver `base + l` for every
    /// set bit `l` of `lanes`. Override to consume whole steps at once.
    #[inline(always)]
    fn splat_receivers(&mut self, base: usize, node: NodeId, lanes: u16) {
        for l in set_bits(lanes) {
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
    /// Checks the cut invariants (docs/design.md §2) against `tree`: splats and
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
