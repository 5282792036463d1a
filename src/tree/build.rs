//! Building the hierarchy top down: where a node splits (at the median of
//! its widest axis, or by orientation where it holds both sides of a hollow
//! solid) and the depth budget that bounds the tree.

use glam::Vec3;

use super::bound::{BuildNode, Hiding};
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
    let (mut node, hiding) = bound::bound_node(surfels, order, lo, hi);
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
    let apart = back_to_back(surfels, order, lo, hi).or_else(|| behind(surfels, order, &hiding));
    let mid = match apart.filter(|&(_, back)| fits(back)) {
        // Both sides of a hollow solid (a room's wall, inside and outside)
        // go to different children, however close they lie: a
        // cluster holding both is drawn as neither (its mean normal
        // cancels) and shows the light of the side a receiver cannot see —
        // sky through closed walls, a sunlit outside inside the room. One
        // side alone is culled whole by the node test where it faces away.
        Some((apart, back)) => {
            order.sort_unstable_by_key(|&i| (apart.after(&surfels[i as usize]), i));
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

/// A solid is parted inside only where it is this thin against the node
/// along its axis: a wall between two spaces the node holds (a well and the
/// corridor's roof beyond its wall), not a block standing in one space,
/// whose sides see the same room around it (parted in its middle, the
/// Cornell box's blocks darkened its ceiling by half a per cent).
const THIN: f32 = 0.1;

/// How a node holding both sides of a solid parts them.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Apart {
    /// By the sign of the normal along `axis`: every face of the solid's
    /// `+` side lies on the `+` side of every one of its `−` side.
    Facing(usize),
    /// At `(axis, s)`, inside one solid: the node holds several (a wall
    /// and the one across a corridor behind it), so that faces of both
    /// signs lie on either side, and the sign of a normal parts no solid.
    Within(usize, f32),
    /// By a facet's plane that could hide another facet ([`Hiding`]): the
    /// surfels wholly behind it go first.
    Behind(Hiding),
}

impl Apart {
    /// Whether `s` goes to the second child.
    #[inline(always)]
    fn after(self, s: &Surfel) -> bool {
        match self {
            Apart::Facing(axis) => s.normal[axis] >= 0.0,
            Apart::Within(axis, at) => s.position[axis] >= at,
            Apart::Behind(plane) => !plane.behind(s),
        }
    }
}

/// Where the surfels of `order` hold both sides of a solid around a
/// hollow, if they do, how to part them; with it, how many go to the first
/// child. Both sides: some face `+axis` and some `−axis` (normals within
/// 60° of it, each side at least [`SIDE_SHARE`] of the area), and some face
/// looks at other surfels of the node (along any axis: the node is
/// concave, as a room's edge is, its floor in front of its wall). A convex
/// node (a slab, a box, a flat wall's two sides) its facets show from any
/// side; faces that face each other (a room's opposite walls) hold a space
/// that a spatial split parts as well.
///
/// Where every face of the `+` side lies on the `+` side of every one of
/// the `−` side (back to back, as a wall's inside and outside), they part
/// by facing ([`Apart::Facing`]). Of several axes, the one with the most
/// area on its lesser side. Else, on an axis where faces of both signs lie
/// on both sides (a well's wall, the corridor's outer wall behind it and
/// the corridor's roof between them), a solid is a `−` face with the next
/// face above it a `+` one: the highest `−` face and the lowest `+` one
/// each bound one. The node parts in the middle of such a solid
/// ([`Apart::Within`]), the one that leaves the most area on the lesser
/// side, at least [`SIDE_SHARE`] on each.
fn back_to_back(surfels: &[Surfel], order: &[u32], lo: Vec3, hi: Vec3) -> Option<(Apart, usize)> {
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
    let count = |apart: Apart| {
        order
            .iter()
            .filter(|&&i| !apart.after(&surfels[i as usize]))
            .count()
    };
    let both = |axis: usize| side[axis][0].min(side[axis][1]) > SIDE_SHARE * area;
    let mut best = None;
    let mut most = SIDE_SHARE * area;
    for axis in 0..3 {
        let lesser = side[axis][0].min(side[axis][1]);
        if lesser > most && low_plus[axis] >= high_minus[axis] {
            best = Some(axis);
            most = lesser;
        }
    }
    if let Some(axis) = best {
        let apart = Apart::Facing(axis);
        return Some((apart, count(apart)));
    }
    // Several solids: the `+` face nearest above the highest `−` one, and
    // the `−` face nearest below the lowest `+` one.
    let mut above = Vec3::INFINITY;
    let mut below = Vec3::NEG_INFINITY;
    for &i in order {
        let s = &surfels[i as usize];
        for axis in 0..3 {
            let (n, p) = (s.normal[axis], s.position[axis]);
            if n > 0.5 && p > high_minus[axis] {
                above[axis] = above[axis].min(p);
            } else if n < -0.5 && p < low_plus[axis] {
                below[axis] = below[axis].max(p);
            }
        }
    }
    let mut best = None;
    let mut most = SIDE_SHARE * area;
    for axis in (0..3).filter(|&axis| both(axis)) {
        let solids = [(high_minus[axis], above[axis]), (below[axis], low_plus[axis])];
        let thin =
            |&(a, b): &(f32, f32)| a.is_finite() && b.is_finite() && b - a < THIN * (hi[axis] - lo[axis]);
        for (a, b) in solids.into_iter().filter(thin) {
            let at = a + 0.5 * (b - a);
            let mut first = 0.0f64;
            for &i in order {
                let s = &surfels[i as usize];
                if s.position[axis] < at {
                    first += (s.radius as f64) * (s.radius as f64);
                }
            }
            let lesser = first.min(area - first);
            if lesser > most {
                best = Some(Apart::Within(axis, at));
                most = lesser;
            }
        }
    }
    best.map(|apart| (apart, count(apart)))
}

/// Of the planes of the node's facets that could hide others, the one that
/// leaves the most area on its lesser side (at least [`SIDE_SHARE`]), and
/// how many surfels lie behind it. A node that holds a wall's inside and
/// what lies beyond the wall (the roof of the corridor behind it, with the
/// wall's outside in another node, so that no axis holds both its sides)
/// parts there.
fn behind(surfels: &[Surfel], order: &[u32], hiding: &[Hiding]) -> Option<(Apart, usize)> {
    let area: f64 = order
        .iter()
        .map(|&i| {
            let r = surfels[i as usize].radius as f64;
            r * r
        })
        .sum();
    let mut best = None;
    let mut most = SIDE_SHARE * area;
    for plane in hiding {
        let (mut back, mut first) = (0, 0.0f64);
        for &i in order {
            let s = &surfels[i as usize];
            if plane.behind(s) {
                back += 1;
                first += (s.radius as f64) * (s.radius as f64);
            }
        }
        let lesser = first.min(area - first);
        if lesser > most {
            best = Some((Apart::Behind(*plane), back));
            most = lesser;
        }
    }
    best
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
