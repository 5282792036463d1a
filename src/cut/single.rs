//! Single: one receiver, up to 16 nodes from its stack in the lanes at once.
//! The three masks come from one vector test; traversed nodes push both
//! children back on the stack.

use std::simd::prelude::*;

use super::test::{F32s, LANES, ReceiverLanes, classify, for_each_lane, gather_nodes, lane_mask};
use super::{CutSink, Traversal, TraversalStats};
use crate::tree::LEAF_BIT;

/// Traverses for one receiver (the same in every lane) from the nodes on
/// `stack` until it is empty.
#[inline(always)]
pub(crate) fn traverse_from<S: CutSink>(
    t: &Traversal,
    rec: &ReceiverLanes<F32s>,
    index: usize,
    stack: &mut Vec<u32>,
    sink: &mut S,
    stats: &mut TraversalStats,
) {
    let a = &t.tree.nodes;
    let omega = F32s::splat(t.omega);
    while !stack.is_empty() {
        let len = stack.len();
        let count = len.min(LANES);
        let start = len - count;
        let ids = Simd::<u32, LANES>::load_or_default(&stack[start..]);
        stack.truncate(start);

        let ids_usize = ids.cast::<usize>();
        let node = gather_nodes(a, ids_usize);
        let child = Simd::<u32, LANES>::gather_or_default(&a.child, ids_usize);
        let (discard, far) = classify(&node, rec, omega);
        let leaf = (child & Simd::splat(LEAF_BIT)).simd_ne(Simd::splat(0));

        let valid = lane_mask(count);
        let discard = discard.to_bitmask() as u16 & valid;
        let far = far.to_bitmask() as u16;
        let leaf = leaf.to_bitmask() as u16;
        let splat = valid & !discard & (far | leaf);
        let traverse = valid & !discard & !far & !leaf;

        stats.node_tests += count as u64;
        stats.active_lanes += count as u64;
        stats.lane_slots += LANES as u64;

        let ids = ids.to_array();
        let child = child.to_array();
        for_each_lane(splat, |l| sink.splat(index, ids[l]));
        if S::DISCARDS {
            for_each_lane(discard, |l| sink.discard(index, ids[l]));
        }
        for_each_lane(traverse, |l| {
            stack.push(child[l] + 1);
            stack.push(child[l]);
        });
    }
}
