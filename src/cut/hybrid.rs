//! Hybrid: packet traversal (see [`packet`](super::packet)) that hands an
//! entry to single traversal once fewer than the threshold of its lanes are
//! active, as Embree does for ray packets. Each active lane then finishes that
//! entry's subtree on its own with 16 nodes in the lanes; the packet goes on
//! with the rest of its stack, so coherent parts of the tree stay packeted.
//!
//! The paper's variant (on the first sparse entry, every lane takes its share
//! of the whole pending stack and the packet ends) was measured slower here:
//! the first sparse entry comes early, so it degenerates to single (box of
//! 10⁵ surfels, 4096 receivers, AVX2: 41–49 ms against 23–24 ms per entry).

use super::nodes::Pairs;
use super::single::{self, PairStack};
use super::{CutSink, Receiver, Traversal, TraversalStats};
use crate::simd::set_bits;

/// Finishes the subtree of `node` for each lane of `mask` with single traversal.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish<S: CutSink, N: Pairs + ?Sized>(
    t: &Traversal,
    a: &N,
    receivers: &[Receiver],
    base: usize,
    node: u32,
    mask: u16,
    scratch: &mut PairStack,
    sink: &mut S,
    stats: &mut TraversalStats,
) {
    stats.switches += 1;
    for l in set_bits(mask) {
        scratch.clear();
        scratch.push_node(node);
        single::traverse(t, a, &receivers[l].lanes(), base + l, scratch, sink, stats);
    }
}
