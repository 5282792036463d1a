//! A packet's cuts in the form its shading pipeline takes them, and the one
//! call that shades them.

use glam::Vec3;

use crate::cut::{CutSink, Receiver, Scheme, Traversal, TraversalStats};
use crate::microbuffer::{Convolution, MicroBuffer, PacketCut, shade_cuts, shade_packet};
use crate::simd::{Isa, LANES};
use crate::tree::{NodeId, Tree};

/// Splat lists of one packet, filled by the traversal and splatted afterwards
/// so traversal and splatting are timed apart.
pub(crate) struct SplatLists(Vec<Vec<NodeId>>);

impl SplatLists {
    pub fn new() -> Self {
        SplatLists(vec![Vec::new(); LANES])
    }

    pub fn clear(&mut self) {
        for l in &mut self.0 {
            l.clear();
        }
    }
}

impl CutSink for SplatLists {
    #[inline]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.0[receiver].push(node);
    }
}

/// A packet's cuts as the shading pipeline of the scheme wants them: per
/// receiver lists for the scalar reference (shaded one node at a time), each
/// node with its lanes for the vector schemes (shaded 16 lanes at a time).
pub(crate) enum PacketCuts {
    Lists(SplatLists),
    Lanes(PacketCut),
}

impl PacketCuts {
    /// The form `scheme`'s pipeline uses.
    pub fn for_scheme(scheme: Scheme, tree: &Tree) -> Self {
        match scheme {
            Scheme::Scalar => PacketCuts::Lists(SplatLists::new()),
            _ => PacketCuts::Lanes(PacketCut::new(tree)),
        }
    }

    /// Cuts `receivers` (one packet) into `self`, which is cleared first.
    pub fn run(&mut self, traversal: &Traversal, scheme: Scheme, receivers: &[Receiver]) -> TraversalStats {
        match self {
            PacketCuts::Lists(l) => {
                l.clear();
                traversal.run(scheme, receivers, l)
            }
            PacketCuts::Lanes(c) => {
                c.clear();
                traversal.run(scheme, receivers, c)
            }
        }
    }
}

impl PacketCuts {
    /// Splats the packet's cuts into `bufs` (one per receiver, reset to it)
    /// through the scheme's shading pipeline on path `isa`, and convolves.
    pub fn shade(&mut self, isa: Isa, tree: &Tree, bufs: &mut [MicroBuffer], what: Convolution) -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; bufs.len()];
        let shaded = match self {
            PacketCuts::Lists(l) => shade_cuts(isa, bufs, tree, &l.0, what, &mut out),
            PacketCuts::Lanes(c) => shade_packet(isa, bufs, tree, c, what, &mut out),
        };
        // The path is the traversal's (detected) and a packet is ≤ 16 receivers
        // with a list and a buffer each: nothing a caller's data can break.
        shaded.expect("a packet of a detected path");
        out
    }
}
