//! The traversal kernel: all receivers of a call through one scheme, the
//! body each instruction-set clone compiles (`simd::dispatch`).

use super::nodes::Pairs;
use super::{CutSink, Receiver, Scheme, Traversal, TraversalStats, packet, scalar, single};
use crate::simd::LANES;
use crate::simd::dispatch::Kernel;
use crate::tree::NodeArrays;

/// The traversal kernel: `scheme` over all receivers into `sink`.
pub(super) struct Run<'a, 't, S> {
    pub t: &'a Traversal<'t>,
    pub scheme: Scheme,
    pub receivers: &'a [Receiver],
    pub sink: &'a mut S,
}

impl<S: CutSink> Kernel for Run<'_, '_, S> {
    type Output = TraversalStats;

    #[inline(always)]
    fn run(self) -> TraversalStats {
        let Run {
            t,
            scheme,
            receivers,
            sink,
        } = self;
        let mut stats = TraversalStats {
            receivers: receivers.len() as u64,
            ..Default::default()
        };
        if t.tree.is_empty() {
            return stats;
        }
        match &t.tree.nodes {
            NodeArrays::Full(pairs) => run_on(t, pairs.as_slice(), scheme, receivers, sink, &mut stats),
            NodeArrays::Compact(pairs) => run_on(t, &pairs[..], scheme, receivers, sink, &mut stats),
        }
        stats
    }
}

/// `scheme` over all receivers, on the pair records `a`.
#[inline(always)]
fn run_on<S: CutSink, N: Pairs + ?Sized>(
    t: &Traversal,
    a: &N,
    scheme: Scheme,
    receivers: &[Receiver],
    sink: &mut S,
    stats: &mut TraversalStats,
) {
    let mut scratch = single::PairStack::default();
    match scheme {
        Scheme::Scalar => {
            for (i, r) in receivers.iter().enumerate() {
                stats.node_tests += scalar::traverse(t, a, &r.lanes(), i, sink);
            }
        }
        Scheme::Single => {
            for (i, r) in receivers.iter().enumerate() {
                scratch.clear();
                scratch.push_node(0);
                single::traverse(t, a, &r.lanes(), i, &mut scratch, sink, stats);
            }
        }
        Scheme::Packet => {
            for (c, chunk) in receivers.chunks(LANES).enumerate() {
                packet::traverse::<S, N, false>(t, a, chunk, c * LANES, &mut scratch, sink, stats);
            }
        }
        Scheme::Hybrid => {
            for (c, chunk) in receivers.chunks(LANES).enumerate() {
                packet::traverse::<S, N, true>(t, a, chunk, c * LANES, &mut scratch, sink, stats);
            }
        }
    }
}
