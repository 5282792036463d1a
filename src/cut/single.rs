//! Single: one receiver, 16 nodes in the lanes at once.
//!
//! Both children of a traversed node are always tested, and siblings are
//! adjacent in the tree, so the stack holds *sibling pairs* (a pair record):
//! one step pops 8 entries into the 16 lanes, loads each field as 8
//! contiguous two-float chunks, and pushes one entry per traversed lane,
//! branch-free. An entry may also stand for one node of its pair alone (the
//! root, or a node handed over by the hybrid scheme): a flag bit masks off
//! the other slot's lane. The three masks come from the shared vector node test.

use std::simd::{Select, prelude::*};

use super::classify::{ReceiverLanes, classify};
use super::nodes::{PAIRS, Pairs};
use super::{CutSink, Traversal, TraversalStats};
use crate::simd::{F32s, LANES, lane_mask, set_bits};
use crate::tree::{LEAF_BIT, NodeArrays};

/// Entry flag: slot 0 of the pair is not to be tested.
const SKIP_SLOT0: u32 = 1 << 30;
/// Entry flag: slot 1 of the pair is not to be tested.
const SKIP_SLOT1: u32 = 1 << 31;
const PAIR_BITS: u32 = SKIP_SLOT0 - 1;

/// A stack of pair entries with room to write a whole step's pushes without checks.
#[derive(Clone, Debug, Default)]
pub(crate) struct PairStack {
    buf: Vec<u32>,
    len: usize,
    /// Entries at the bottom pushed by `push_node`, which may carry flags;
    /// everything above them is a child pair pushed by the traversal.
    seeds: usize,
}

impl PairStack {
    #[inline(always)]
    fn reserve_step(&mut self) {
        // Pops read up to PAIRS entries past `len`, pushes write up to LANES.
        if self.buf.len() < self.len + LANES + PAIRS {
            self.buf.resize((self.len + LANES + PAIRS) * 2, 0);
        }
    }

    /// Empties the stack.
    #[inline(always)]
    pub fn clear(&mut self) {
        self.len = 0;
        self.seeds = 0;
    }

    /// Pushes node `n` alone (before any traversal step).
    #[inline(always)]
    pub fn push_node(&mut self, n: u32) {
        debug_assert_eq!(self.seeds, self.len, "seeds go below traversal entries");
        let (p, slot) = NodeArrays::locate(n);
        let p = p as u32;
        // A left node pushed right after its right sibling makes a whole pair again.
        if slot == 0 && self.len > 0 && self.buf[self.len - 1] == p | SKIP_SLOT0 {
            self.buf[self.len - 1] = p;
            return;
        }
        let entry = p | if slot == 0 { SKIP_SLOT1 } else { SKIP_SLOT0 };
        self.reserve_step();
        self.buf[self.len] = entry;
        self.len += 1;
        self.seeds = self.len;
    }
}

/// Spreads the 8 low bits of `x` to the even bits of the result.
#[inline(always)]
fn spread(x: u16) -> u16 {
    let x = (x | (x << 4)) & 0x0F0F;
    let x = (x | (x << 2)) & 0x3333;
    (x | (x << 1)) & 0x5555
}

/// Traverses the entries on `stack` for one receiver until it is empty.
#[inline(always)]
pub(crate) fn traverse<S: CutSink, N: Pairs + ?Sized>(
    t: &Traversal,
    a: &N,
    rec: &ReceiverLanes<f32>,
    index: usize,
    stack: &mut PairStack,
    sink: &mut S,
    stats: &mut TraversalStats,
) {
    let rec = rec.splat();
    while stack.len > 0 {
        // Seeds (possibly flagged) sit at the bottom: only steps that reach
        // them pay for the flags.
        if stack.len - stack.len.min(PAIRS) < stack.seeds {
            step::<S, N, true>(t, a, &rec, index, stack, sink, stats);
        } else {
            step::<S, N, false>(t, a, &rec, index, stack, sink, stats);
        }
    }
}

/// One step: pops up to 8 entries, tests their nodes, reports, pushes.
#[inline(always)]
fn step<S: CutSink, N: Pairs + ?Sized, const FLAGS: bool>(
    t: &Traversal,
    a: &N,
    rec: &ReceiverLanes<F32s>,
    index: usize,
    stack: &mut PairStack,
    sink: &mut S,
    stats: &mut TraversalStats,
) {
    stack.reserve_step();
    let count = stack.len.min(PAIRS);
    let start = stack.len - count;
    stack.len = start;
    if FLAGS {
        stack.seeds = stack.seeds.min(start);
    }
    // Entries past the popped ones are stale unflagged entries (or zero-filled
    // slack), so every lane reads a valid record; lanes past `2 * count` are
    // masked off.
    let mut entries: [u32; PAIRS] = stack.buf[start..start + PAIRS]
        .try_into()
        .expect("slack reserved");
    let mut skipped = 0u16;
    if FLAGS {
        let e = Simd::<u32, PAIRS>::from_array(entries);
        let flag = |f: u32| (e & Simd::splat(f)).simd_ne(Simd::splat(0)).to_bitmask() as u16;
        skipped = spread(flag(SKIP_SLOT0)) | spread(flag(SKIP_SLOT1)) << 1;
        entries = (e & Simd::splat(PAIR_BITS)).to_array();
        // The pushes below overwrite only as many slots as they push, so
        // clear the popped seeds: no flagged entry may linger above `len`.
        stack.buf[start..start + PAIRS].fill(0);
    }
    debug_assert!(
        entries.iter().all(|&e| (e as usize) < a.count()),
        "entries {entries:x?} start {start} count {count} seeds {} flags {FLAGS} buf {:x?}",
        stack.seeds,
        &stack.buf[..(start + 24).min(stack.buf.len())]
    );
    // SAFETY: entries only ever hold pair records read from the tree's child
    // links or located from its node ids (flags stripped above), or 0 (the
    // root's record), all in range: `Tree::build` makes them so, and a tree
    // read from a file is refused unless its links are laid out the same
    // (`tree::file`, `check_structure`).
    let (node, child) = unsafe { a.lanes(&entries) };
    let (discard, far) = classify(&node, rec, &t.far().splat());
    let leaf = (child & Simd::splat(LEAF_BIT)).simd_ne(Simd::splat(0));

    let valid = lane_mask(2 * count) & !skipped;
    let discard = discard.to_bitmask() as u16 & valid;
    let far = far.to_bitmask() as u16;
    let leaf = leaf.to_bitmask() as u16;
    let splat = valid & !discard & (far | leaf);
    let traverse = valid & !discard & !far & !leaf;

    let active = valid.count_ones() as u64;
    stats.node_tests += active;
    stats.active_lanes += active;
    stats.lane_slots += LANES as u64;

    // Node ids of the lanes: 2p − 1 + slot.
    let slot = Simd::from_array(std::array::from_fn::<u32, LANES, _>(|l| (l & 1) as u32));
    let lane_entry = Simd::from_array(std::array::from_fn::<u32, LANES, _>(|l| entries[l / 2]));
    let node_ids = (lane_entry * Simd::splat(2) + slot - Simd::splat(1)).to_array();
    sink.splat_nodes(index, &node_ids, splat);
    if S::DISCARDS {
        for l in set_bits(discard) {
            sink.discard(index, node_ids[l]);
        }
    }
    // Branch-free push of every traversed lane's child pair. Every lane
    // writes, so the slack past `len` must only ever hold valid entries:
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
