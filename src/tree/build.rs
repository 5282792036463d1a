//! Building the hierarchy top down: where a node splits (at the median of
//! its widest axis, or by orientation where it holds both sides of a hollow
//! solid) and the depth budget that bounds the tree.

use glam::Vec3;

use super::bound::BuildNode;
use super::facets::PackedFacets;
use super::payload::PackedSplat;
use super::quantize::{self, CompactPair};
use super::{
    Cluster, LEAF, LEAF_BIT, MIXED, NodeArrays, PLANAR, PairRecord, Payload, SplatRecord, bound, field,
};
use crate::points::Surfel;

/// What a node's test fields are quantized against.
#[derive(Clone, Copy, Debug)]
pub(super) enum Base {
    /// Nothing: full precision.
    Full,
    /// Its own sphere (the root of a compact tree).
    Root,
    /// Its parent's decoded sphere.
    Parent([f32; 4]),
}

/// Where the build writes a run of nodes, from its first: their pair
/// records (siblings share one), and per node its payload and its facets.
/// A subtree's descendants are one such run, split between its children's
/// subtrees as the build recurses, so the arrays are written in place.
pub(super) struct Out<'a> {
    pairs: PairsOut<'a>,
    payload: PayloadOut<'a>,
    cluster: &'a mut [Option<Box<Cluster>>],
}

enum PairsOut<'a> {
    Full(&'a mut [PairRecord]),
    Compact(&'a mut [CompactPair]),
}

enum PayloadOut<'a> {
    /// Per node.
    Full(&'a mut [SplatRecord], &'a mut [Vec3]),
    /// Per pair record, its parent's (a leaf's is its surfel's, made apart).
    Compact(&'a mut [PackedSplat]),
}

impl<'a> Out<'a> {
    pub fn new(
        nodes: &'a mut NodeArrays,
        payload: &'a mut Payload,
        cluster: &'a mut [Option<Box<Cluster>>],
    ) -> Self {
        let pairs = match nodes {
            NodeArrays::Full(p) => PairsOut::Full(p),
            NodeArrays::Compact(p) => PairsOut::Compact(p.owned_mut()),
        };
        let payload = match payload {
            Payload::Full { splat, radiance } => PayloadOut::Full(splat, radiance),
            Payload::Compact { inner, .. } => PayloadOut::Compact(inner.owned_mut()),
        };
        Out {
            pairs,
            payload,
            cluster,
        }
    }

    /// The first `nodes` nodes (an even number, or the root alone) and the rest.
    pub fn split(self, nodes: usize) -> (Out<'a>, Out<'a>) {
        let at = nodes.div_ceil(2);
        let (p0, p1) = match self.pairs {
            PairsOut::Full(p) => {
                let (a, b) = p.split_at_mut(at);
                (PairsOut::Full(a), PairsOut::Full(b))
            }
            PairsOut::Compact(p) => {
                let (a, b) = p.split_at_mut(at);
                (PairsOut::Compact(a), PairsOut::Compact(b))
            }
        };
        let (c0, c1) = self.cluster.split_at_mut(nodes);
        let (l0, l1) = match self.payload {
            PayloadOut::Full(s, r) => {
                let ((s0, s1), (r0, r1)) = (s.split_at_mut(nodes), r.split_at_mut(nodes));
                (PayloadOut::Full(s0, r0), PayloadOut::Full(s1, r1))
            }
            PayloadOut::Compact(c) => {
                let (a, b) = c.split_at_mut(at);
                (PayloadOut::Compact(a), PayloadOut::Compact(b))
            }
        };
        (
            Out {
                pairs: p0,
                payload: l0,
                cluster: c0,
            },
            Out {
                pairs: p1,
                payload: l1,
                cluster: c1,
            },
        )
    }

    /// Sets the base of the run's pair `i / 2` (a compact tree's: the
    /// decoded sphere of the pair's parent).
    pub fn set_base(&mut self, i: usize, base: [f32; 4]) {
        if let PairsOut::Compact(p) = &mut self.pairs {
            p[i / 2].base = base;
        }
    }

    /// Writes `b` as the run's node `i`, in slot `slot` of its pair `i / 2`.
    pub fn write(&mut self, i: usize, slot: usize, b: BuildNode) {
        let leaf = b.child & LEAF_BIT != 0;
        // Children are stored by pair record: the left child `c` is odd.
        let child = if leaf { b.child } else { b.child.div_ceil(2) };
        match &mut self.pairs {
            PairsOut::Full(p) => {
                let pair = &mut p[i / 2];
                let values = [
                    b.center[0],
                    b.center[1],
                    b.center[2],
                    b.radius,
                    b.axis[0],
                    b.axis[1],
                    b.axis[2],
                    b.cos,
                    b.sin,
                ];
                debug_assert_eq!(field::STORED, values.len());
                for (j, v) in values.into_iter().enumerate() {
                    pair.f[j][slot] = v;
                }
                pair.child[slot] = child;
            }
            PairsOut::Compact(p) => p[i / 2].set(slot, &b.steps, child),
        }
        let rec = record(&b, leaf);
        if let PayloadOut::Full(s, r) = &mut self.payload {
            s[i] = rec;
            r[i] = b.radiance;
        }
        if rec.kind == MIXED {
            self.cluster[i] = Some(b.cluster.expect("a mixed node has its facets"));
        }
    }
}

impl Out<'_> {
    /// Writes the packed payload of `b`, the parent of the run's first pair
    /// record, in a compact tree (a full tree's is written with the node).
    fn write_parent(&mut self, b: &BuildNode) {
        if let PayloadOut::Compact(c) = &mut self.payload {
            // Whether the light is shifted, of the facets as a render reads them.
            let facets = b
                .cluster
                .as_deref()
                .map_or(Cluster::NONE, |c| PackedFacets::pack(c).unpack());
            c[0] = PackedSplat::pack(&record(b, false), b.radiance, b.center, b.radius, &facets);
        }
    }
}

/// The splat record of `b`, without what is derived of it.
fn record(b: &BuildNode, leaf: bool) -> SplatRecord {
    let kind = if leaf {
        LEAF
    } else if b.facets <= 1 {
        PLANAR
    } else {
        MIXED
    };
    SplatRecord {
        centroid: b.centroid,
        light_centroid: b.light_centroid,
        area: b.area,
        normal: b.normal.to_array(),
        kind,
        ..SplatRecord::default()
    }
}

/// Subtrees smaller than this are built on the calling thread.
const PARALLEL_CUTOFF: usize = 4096;

/// Builds the subtree over `order` (surfel indices), returns its root and
/// writes its descendants into `below` (exactly `2·len − 2` nodes); `base`
/// (odd) is the node id of the first. Layout of `below`: both children,
/// then the left child's descendants, then the right child's.
/// `budget` is how many levels the subtree may have below its root (at least
/// the median split's `⌈log₂ len⌉`).
/// `sphere`: what the node's test fields are quantized against.
pub(super) fn build_subtree(
    surfels: &[Surfel],
    order: &mut [u32],
    mut below: Out<'_>,
    base: u32,
    budget: usize,
    sphere: Base,
) -> BuildNode {
    debug_assert_eq!(below.cluster.len(), 2 * order.len() - 2);
    let (lo, hi) = position_bounds(surfels, order);
    let mut node = bound::bound_node(surfels, order, lo, hi);
    let children = match sphere {
        Base::Full => Base::Full,
        Base::Root | Base::Parent(_) => {
            let own = [node.center[0], node.center[1], node.center[2], node.radius];
            let from = if let Base::Parent(b) = sphere { b } else { own };
            let wide = node.cos == 0.0;
            let (steps, d) = quantize::quantize(from, node.center, node.axis, wide, surfels, order);
            // The facets' places are in units of the radius: rescaled to the decoded one.
            if let Some(c) = node.cluster.as_deref_mut() {
                let k = node.radius as f64 / d[field::R] as f64;
                for p in c.plane.iter_mut() {
                    for x in &mut p[..3] {
                        *x = (*x as f64 * k) as f32;
                    }
                    p[3] = bound::round_up(p[3] as f64 * k);
                }
                for l in c.light.iter_mut().flatten() {
                    *l = (*l as f64 * k) as f32;
                }
            }
            node.center = [d[field::CX], d[field::CY], d[field::CZ]];
            node.radius = d[field::R];
            node.axis = [d[field::AX], d[field::AY], d[field::AZ]];
            (node.cos, node.sin) = (d[field::COS], d[field::SIN]);
            node.steps = steps;
            node.base = from;
            Base::Parent(quantize::base_of(&d))
        }
    };
    if order.len() == 1 {
        node.child = LEAF_BIT | order[0];
        return node;
    }

    below.write_parent(&node);
    let len = order.len();
    let fits = |back: usize| budget > 0 && ceil_log2(back.max(len - back)) < budget;
    let mid = match back_to_back(surfels, order, lo, hi).filter(|&(_, back)| fits(back)) {
        // Both sides of a hollow solid (a room's wall, inside and outside)
        // go to different children, however close they lie: a
        // cluster holding both is drawn as neither (its mean normal
        // cancels) and shows the light of the side a receiver cannot see —
        // sky through closed walls, a sunlit outside inside the room. One
        // side alone is culled whole by the node test where it faces away.
        Some((axis, back)) => {
            order.sort_unstable_by_key(|&i| (surfels[i as usize].normal[axis] >= 0.0, i));
            back
        }
        // Else (or where the larger side would not fit in the depth
        // budget) the median along the widest axis; the index breaks ties, so
        // duplicate positions still split in two halves.
        None => {
            let ext = hi - lo;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = len / 2;
            order.select_nth_unstable_by(mid, |&i, &j| {
                let (a, b) = (
                    surfels[i as usize].position[axis],
                    surfels[j as usize].position[axis],
                );
                a.total_cmp(&b).then(i.cmp(&j))
            });
            mid
        }
    };
    let (left_order, right_order) = order.split_at_mut(mid);
    let (mut pair, rest) = below.split(2);
    let (left_below, right_below) = rest.split(2 * left_order.len() - 2);
    let left_base = base + 2;
    let right_base = left_base + 2 * left_order.len() as u32 - 2;
    let left = move || build_subtree(surfels, left_order, left_below, left_base, budget - 1, children);
    let right = move || {
        build_subtree(
            surfels,
            right_order,
            right_below,
            right_base,
            budget - 1,
            children,
        )
    };
    let (l, r) = if len >= PARALLEL_CUTOFF {
        rayon::join(left, right)
    } else {
        (left(), right())
    };
    node.depth = 1 + l.depth.max(r.depth);
    pair.write(0, 0, l);
    pair.write(1, 1, r);
    if let Base::Parent(b) = children {
        pair.set_base(0, b);
    }
    node.child = base;
    node
}

/// Below this share of a node's area on each side, two faces are not a
/// solid's sides but stray surfels (a curved surface's rim).
const SIDE_SHARE: f64 = 0.05;

/// The axis along which the surfels of `order` hold both sides of a solid
/// around a hollow, if they do: some face `+axis` and some `−axis`
/// (normals within 60° of it, each side at least [`SIDE_SHARE`] of the
/// area), every one facing `+axis` lies on the `+` side of every one facing
/// `−axis` (back to back, as a wall's inside and outside), and some face
/// looks at other surfels of the node (along any axis: the node is
/// concave, as a room's edge is, its floor in front of its wall). A convex
/// node (a slab, a box, a flat wall's two sides) its facets show from any
/// side; faces that face each other (a room's opposite walls) hold a space
/// that a spatial split parts as well. Of several axes, the one with the
/// most area on its lesser side; with it, how many surfels have a
/// negative component along it (they go to the first child).
fn back_to_back(surfels: &[Surfel], order: &[u32], lo: Vec3, hi: Vec3) -> Option<(usize, usize)> {
    // Per axis and side (`+`, `−`): the area, and the extreme positions
    // along the axis of those facing that way.
    let mut area = 0.0f64;
    let mut side = [[0.0f64; 2]; 3];
    let (mut low_plus, mut high_plus) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let (mut low_minus, mut high_minus) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &i in order {
        let s = &surfels[i as usize];
        let a = (s.radius as f64) * (s.radius as f64);
        area += a;
        for axis in 0..3 {
            let (n, p) = (s.normal[axis], s.position[axis]);
            if n > 0.5 {
                side[axis][0] += a;
                low_plus[axis] = low_plus[axis].min(p);
                high_plus[axis] = high_plus[axis].max(p);
            } else if n < -0.5 {
                side[axis][1] += a;
                low_minus[axis] = low_minus[axis].min(p);
                high_minus[axis] = high_minus[axis].max(p);
            }
        }
    }
    let concave = (0..3).any(|axis| hi[axis] > high_plus[axis] && high_plus[axis] > f32::NEG_INFINITY)
        || (0..3).any(|axis| lo[axis] < low_minus[axis] && low_minus[axis] < f32::INFINITY);
    if !concave {
        return None;
    }
    let mut best = None;
    let mut most = SIDE_SHARE * area;
    for axis in 0..3 {
        let lesser = side[axis][0].min(side[axis][1]);
        if lesser > most && low_plus[axis] >= high_minus[axis] {
            best = Some(axis);
            most = lesser;
        }
    }
    best.map(|axis| {
        let back = order
            .iter()
            .filter(|&&i| surfels[i as usize].normal[axis] < 0.0)
            .count();
        (axis, back)
    })
}

/// `⌈log₂ n⌉` (0 for `n ≤ 1`): the median split's depth over `n` surfels.
pub(super) fn ceil_log2(n: usize) -> usize {
    (usize::BITS - n.saturating_sub(1).leading_zeros()) as usize
}

fn position_bounds(surfels: &[Surfel], order: &[u32]) -> (Vec3, Vec3) {
    let mut lo = Vec3::INFINITY;
    let mut hi = Vec3::NEG_INFINITY;
    for &i in order {
        let p = surfels[i as usize].position;
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (lo, hi)
}
