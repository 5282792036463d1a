//! The scalar reference: one receiver, one node at a time, depth first with a
//! fixed-size stack, the node test short-circuited. Every speed-up is measured
//! against this, so it is kept as fast as plain scalar code gets.

use super::classify::{Outcome, ReceiverLanes, outcome_scalar};
use super::nodes::Pairs;
use super::{CutSink, Traversal};
use crate::tree::{LEAF_BIT, MAX_DEPTH, NodeArrays};

/// Traverses for one receiver; returns the number of nodes tested.
#[inline(always)]
pub(crate) fn traverse<S: CutSink, N: Pairs + ?Sized>(
    t: &Traversal,
    a: &N,
    rec: &ReceiverLanes<f32>,
    index: usize,
    sink: &mut S,
) -> u64 {
    if a.count() == 0 {
        return 0;
    }
    // Depth first, both children pushed: at most depth + 1 entries.
    let mut stack = [0u32; MAX_DEPTH + 2];
    let mut sp = 1;
    let mut tests = 0;
    while sp > 0 {
        sp -= 1;
        let k = stack[sp];
        tests += 1;
        let (node, child) = a.node(k);
        match outcome_scalar(&node, rec, &t.far(), child & LEAF_BIT != 0) {
            Outcome::Discard => {
                if S::DISCARDS {
                    sink.discard(index, k);
                }
            }
            Outcome::Splat => sink.splat(index, k),
            Outcome::Traverse => {
                let left = NodeArrays::first_of_pair(child);
                stack[sp] = left + 1;
                stack[sp + 1] = left;
                sp += 2;
            }
        }
    }
    tests
}
