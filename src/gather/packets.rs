//! One packet at a time: its cuts in the form its shading pipeline takes
//! them, its microbuffers, and the two steps (cut, then shade) a caller that
//! forms its own packets (the renderer's screen tiles) runs.

use glam::Vec3;

use super::{Gather, Pipeline};
use crate::cut::{CutSink, Receiver, Scheme, Traversal, TraversalStats};
use crate::error::Error;
use crate::microbuffer::{
    Convolution, MicroBuffer, NearField, PacketCut, shade_cuts_near, shade_packet_near,
};
use crate::simd::{Isa, LANES};
use crate::tree::{NodeId, Tree};

/// Splat lists of one packet, filled by the traversal and splatted afterwards
/// so traversal and splatting are timed apart.
pub(crate) struct SplatLists(Vec<Vec<NodeId>>);

impl SplatLists {
    fn new() -> Self {
        SplatLists(vec![Vec::new(); LANES])
    }

    fn clear(&mut self) {
        for l in &mut self.0 {
            l.clear();
        }
    }
}

impl CutSink for SplatLists {
    /// One list per receiver of a packet.
    const RECEIVERS: usize = LANES;

    #[inline]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.0[receiver].push(node);
    }
}

/// A packet's cuts as its pipeline wants them: per receiver lists for the
/// scalar pipeline (shaded one node at a time), each node with its lanes for
/// the 16-lane one (shaded 16 lanes at a time).
pub(crate) enum PacketCuts {
    Lists(SplatLists),
    Lanes(PacketCut),
}

impl PacketCuts {
    fn new(pipeline: Pipeline, tree: &Tree) -> Self {
        match pipeline {
            Pipeline::Scalar => PacketCuts::Lists(SplatLists::new()),
            Pipeline::Lanes => PacketCuts::Lanes(PacketCut::new(tree)),
        }
    }

    /// Cuts `receivers` (one packet) into `self`, which is cleared first.
    fn run(
        &mut self,
        traversal: &Traversal,
        scheme: Scheme,
        receivers: &[Receiver],
    ) -> Result<TraversalStats, Error> {
        match self {
            PacketCuts::Lists(l) => {
                l.clear();
                traversal.try_run(scheme, receivers, l)
            }
            PacketCuts::Lanes(c) => {
                c.clear();
                traversal.try_run(scheme, receivers, c)
            }
        }
    }

    /// Splats the cuts into `bufs` (one per receiver, reset to it) through
    /// the pipeline on path `isa`, and convolves.
    fn shade(
        &mut self,
        isa: Isa,
        tree: &Tree,
        bufs: &mut [MicroBuffer],
        what: Convolution,
        near: Option<&dyn NearField>,
    ) -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; bufs.len()];
        let shaded = match self {
            PacketCuts::Lists(l) => shade_cuts_near(isa, bufs, tree, &l.0, what, near, &mut out),
            PacketCuts::Lanes(c) => shade_packet_near(isa, bufs, tree, c, what, near, &mut out),
        };
        // The path is the traversal's (detected) and a packet is at most 16
        // receivers with a list and a buffer each: nothing data can break.
        shaded.expect("a packet of a detected path");
        out
    }
}

/// One thread's gathering: a packet's cuts and its 16 microbuffers, reused
/// from packet to packet. Made by [`Gather::gatherer`]; [`cut`](Self::cut)
/// a packet, then [`shade`](Self::shade) it.
pub struct Gatherer<'g, 't> {
    gather: &'g Gather<'t>,
    cuts: PacketCuts,
    bufs: Vec<MicroBuffer>,
    receivers: Vec<Receiver>,
}

impl<'g, 't> Gatherer<'g, 't> {
    pub(super) fn new(gather: &'g Gather<'t>) -> Self {
        Gatherer {
            gather,
            cuts: PacketCuts::new(gather.path.pipeline, gather.tree()),
            bufs: vec![gather.proto.clone(); LANES],
            receivers: Vec::with_capacity(LANES),
        }
    }

    /// Traverses the tree for one packet (at most 16 receivers, best
    /// neighbours: the lanes share a traversal), with the scheme the options
    /// give for a packet of that size. Errors on more than 16.
    pub fn cut(&mut self, receivers: &[Receiver]) -> Result<TraversalStats, Error> {
        let scheme = self.gather.opts.scheme.resolve(receivers.len());
        let stats = self.cuts.run(&self.gather.traversal, scheme, receivers)?;
        self.receivers.clear();
        self.receivers.extend_from_slice(receivers);
        Ok(stats)
    }

    /// Splats the last cut packet into its receivers' microbuffers and
    /// convolves: irradiance `E` (RGB) or occlusion (in every channel) per
    /// receiver. The buffers keep the splats for [`buffers`](Self::buffers).
    pub fn shade(&mut self, what: Convolution) -> Vec<Vec3> {
        self.shade_tilted(what, std::iter::empty())
    }

    /// [`shade`](Self::shade), each receiver's irradiance convolved about
    /// its own normal of `normals` where that is not the receiver's (a
    /// normal map's: [`MicroBuffer::tilt`]).
    pub fn shade_tilted(&mut self, what: Convolution, normals: impl Iterator<Item = Vec3>) -> Vec<Vec3> {
        let bufs = &mut self.bufs[..self.receivers.len()];
        for (b, r) in bufs.iter_mut().zip(&self.receivers) {
            b.reset(r.position(), r.normal());
        }
        for ((b, r), n) in bufs.iter_mut().zip(&self.receivers).zip(normals) {
            if n != r.normal() {
                b.tilt(n);
            }
        }
        let g = self.gather;
        self.cuts.shade(g.path.isa, g.tree(), bufs, what, g.near)
    }

    /// The microbuffers of the last shaded packet, one per receiver (for
    /// convolutions of their own: [`MicroBuffer::glossy`]).
    pub fn buffers(&self) -> &[MicroBuffer] {
        &self.bufs[..self.receivers.len()]
    }
}
