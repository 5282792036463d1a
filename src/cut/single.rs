//! Single: one receiver, 16 nodes in the lanes at once.
//!
//! Both children of a traversed node are always tested, and siblings are
//! adjacent in the tree, so the stack holds *sibling pairs* (the left child's
//! id): one step pops 8 pairs into the 16 lanes, loads each field as 8
//! contiguous two-float chunks, and pushes one entry per traversed lane,
//! branch-free. The three masks come from the shared vector node test.

use std::simd::{Select, prelude::*};

use super::test::{
    F32s, LANES, NodeLanes, Outcome, ReceiverLanes, classify, for_each_lane, lane_mask, load_node,
    outcome_scalar,
};
use super::{CutSink, Traversal, TraversalStats};
use crate::tree::{LEAF_BIT, PairRecord, field};

/// Sibling pairs per step.
const PAIRS: usize = LANES / 2;

/// A pair stack with room to write a whole step's pushes without checks.
#[derive(Clone, Debug, Default)]
pub(crate) struct PairStack {
    buf: Vec<u32>,
    len: usize,
}

impl PairStack {
    #[inline(always)]
    fn reserve_step(&mut self) {
        // Pops read up to PAIRS entries past `len`, pushes write up to LANES.
        if self.buf.len() < self.len + LANES + PAIRS {
            self.buf.resize((self.len + LANES + PAIRS) * 2, 0);
        }
    }
}

/// Tests `node` for one receiver, then finishes its subtree 16 nodes at a time.
#[inline(always)]
pub(crate) fn traverse_node<S: CutSink>(
    t: &Traversal,
    rec: &ReceiverLanes<f32>,
    index: usize,
    node: u32,
    stack: &mut PairStack,
    sink: &mut S,
    stats: &mut TraversalStats,
) {
    let a = &t.tree.nodes;
    let child = a.child(node);
    stats.node_tests += 1;
    match outcome_scalar(&load_node(a, node), rec, t.omega, child & LEAF_BIT != 0) {
        Outcome::Discard => {
            if S::DISCARDS {
                sink.discard(index, node)
            }
        }
        Outcome::Splat => sink.splat(index, node),
        Outcome::Traverse => {
            stack.len = 0;
            stack.reserve_step();
            stack.buf[0] = child;
            stack.len = 1;
            traverse_pairs(t, &rec.splat(), index, stack, sink, stats);
        }
    }
}

/// Field `j` of pair records `ids[i]` into lanes `2i, 2i + 1`.
#[inline(always)]
fn load_field(pairs: &[&PairRecord; PAIRS], j: usize) -> F32s {
    F32s::from_array(std::array::from_fn(|l| pairs[l / 2].f[j][l & 1]))
}

#[inline(always)]
fn load_pair_nodes(pairs: &[&PairRecord; PAIRS]) -> NodeLanes<F32s> {
    NodeLanes {
        cx: load_field(pairs, field::CX),
        cy: load_field(pairs, field::CY),
        cz: load_field(pairs, field::CZ),
        r: load_field(pairs, field::R),
        ax: load_field(pairs, field::AX),
        ay: load_field(pairs, field::AY),
        az: load_field(pairs, field::AZ),
        cos: load_field(pairs, field::COS),
        sin: load_field(pairs, field::SIN),
    }
}

/// Traverses the sibling pairs on `stack` until it is empty.
#[inline(always)]
fn traverse_pairs<S: CutSink>(
    t: &Traversal,
    rec: &ReceiverLanes<F32s>,
    index: usize,
    stack: &mut PairStack,
    sink: &mut S,
    stats: &mut TraversalStats,
) {
    let a = &t.tree.nodes;
    let omega = F32s::splat(t.omega);
    let lane_id = Simd::from_array(std::array::from_fn::<u32, LANES, _>(|l| (l & 1) as u32)) - Simd::splat(1);
    while stack.len > 0 {
        stack.reserve_step();
        let count = stack.len.min(PAIRS);
        let start = stack.len - count;
        stack.len = start;
        // Entries past the popped ones are stale pair records (or zero-filled
        // slack), so every lane reads a valid pair; lanes past `2 * pairs` are masked.
        let ids: [u32; PAIRS] = stack.buf[start..start + PAIRS]
            .try_into()
            .expect("slack reserved");

        // SAFETY: the stack and its slack only ever hold pair records read
        // from the tree's child links, or 0 (the root's record), all in range.
        let pairs: [&PairRecord; PAIRS] =
            std::array::from_fn(|i| unsafe { a.pairs.get_unchecked(ids[i] as usize) });
        let node = load_pair_nodes(&pairs);
        let child = Simd::from_array(std::array::from_fn::<u32, LANES, _>(|l| {
            pairs[l / 2].child[l & 1]
        }));
        // Node ids of the lanes: 2p − 1 + slot.
        let node_ids =
            Simd::from_array(std::array::from_fn::<u32, LANES, _>(|l| ids[l / 2])) * Simd::splat(2) + lane_id;
        let (discard, far) = classify(&node, rec, omega);
        let leaf = (child & Simd::splat(LEAF_BIT)).simd_ne(Simd::splat(0));

        let valid = lane_mask(2 * count);
        let discard = discard.to_bitmask() as u16 & valid;
        let far = far.to_bitmask() as u16;
        let leaf = leaf.to_bitmask() as u16;
        let splat = valid & !discard & (far | leaf);
        let traverse = valid & !discard & !far & !leaf;

        let active = 2 * count as u64;
        stats.node_tests += active;
        stats.active_lanes += active;
        stats.lane_slots += LANES as u64;

        let node_ids = node_ids.to_array();
        sink.splat_nodes(index, &node_ids, splat);
        if S::DISCARDS {
            for_each_lane(discard, |l| sink.discard(index, node_ids[l]));
        }
        // Branch-free push of every traversed lane's child pair. Every lane
        // writes, so the slack past `len` must only ever hold valid pair ids:
        // lanes not traversed write 0.
        let child = Mask::<i32, LANES>::from_bitmask(traverse as u64)
            .select(child, Simd::splat(0))
            .to_array();
        let mut len = stack.len;
        for (l, &c) in child.iter().enumerate() {
            stack.buf[len] = c;
            len += ((traverse >> l) & 1) as usize;
        }
        stack.len = len;
    }
}
