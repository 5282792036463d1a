//! Packet: 16 receivers in the lanes, one node at a time, depth first on a
//! shared stack whose entries carry the mask of lanes still traversing (the
//! paper's node queue and mask queue).

use super::classify::{ReceiverLanes, classify};
use super::hybrid;
use super::nodes::Pairs;
use super::single::PairStack;
use super::{CutSink, Receiver, Traversal, TraversalStats};
use crate::simd::{F32s, LANES, lane_mask, set_bits};
use crate::tree::{LEAF_BIT, MAX_DEPTH, NodeArrays};

/// Receivers `base..base + receivers.len()` (at most 16) as lanes; unused
/// lanes repeat the first receiver and stay masked off.
#[inline(always)]
pub(crate) fn load_receivers(receivers: &[Receiver]) -> ReceiverLanes<F32s> {
    debug_assert!(!receivers.is_empty() && receivers.len() <= LANES);
    // Plain loops (no closures passed around): everything here must inline
    // into the caller's clone.
    let mut f = [[0.0f32; LANES]; 6];
    #[allow(clippy::needless_range_loop)] // `l` picks a receiver and a lane
    for l in 0..LANES {
        let r = receivers.get(l).unwrap_or(&receivers[0]);
        let (p, n) = (r.position(), r.normal());
        f[0][l] = p.x;
        f[1][l] = p.y;
        f[2][l] = p.z;
        f[3][l] = n.x;
        f[4][l] = n.y;
        f[5][l] = n.z;
    }
    ReceiverLanes {
        px: F32s::from_array(f[0]),
        py: F32s::from_array(f[1]),
        pz: F32s::from_array(f[2]),
        nx: F32s::from_array(f[3]),
        ny: F32s::from_array(f[4]),
        nz: F32s::from_array(f[5]),
    }
}

/// Traverses for up to 16 receivers (`base` is the first one's index for the
/// sink). With `HYBRID`, an entry with fewer than `t.hybrid_threshold` active
/// lanes is handed to [`hybrid::finish`] instead.
#[inline(always)]
pub(crate) fn traverse<S: CutSink, N: Pairs + ?Sized, const HYBRID: bool>(
    t: &Traversal,
    a: &N,
    receivers: &[Receiver],
    base: usize,
    scratch: &mut PairStack,
    sink: &mut S,
    stats: &mut TraversalStats,
) {
    if a.count() == 0 {
        return;
    }
    let recs = load_receivers(receivers);
    let test = t.far().splat();
    // Depth first, both children pushed: at most depth + 1 entries.
    let mut nodes = [0u32; MAX_DEPTH + 2];
    let mut masks = [0u16; MAX_DEPTH + 2];
    masks[0] = lane_mask(receivers.len());
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let (k, mask) = (nodes[sp], masks[sp]);
        let active = mask.count_ones();
        if HYBRID && active < t.hybrid_threshold {
            hybrid::finish(t, a, receivers, base, k, mask, scratch, sink, stats);
            continue;
        }
        stats.node_tests += active as u64;
        stats.active_lanes += active as u64;
        stats.lane_slots += LANES as u64;

        let (node, child) = a.node(k);
        let node = node.splat();
        let (discard, far) = classify(&node, &recs, &test);
        let discard = discard.to_bitmask() as u16 & mask;
        let kept = mask & !discard;
        let (splat, traverse) = if child & LEAF_BIT != 0 {
            (kept, 0)
        } else {
            let far = far.to_bitmask() as u16;
            (kept & far, kept & !far)
        };
        sink.splat_receivers(base, k, splat);
        if S::DISCARDS {
            for l in set_bits(discard) {
                sink.discard(base + l, k);
            }
        }
        if traverse != 0 {
            let left = NodeArrays::first_of_pair(child);
            nodes[sp] = left + 1;
            masks[sp] = traverse;
            nodes[sp + 1] = left;
            masks[sp + 1] = traverse;
            sp += 2;
        }
    }
}
