//! Building the hierarchy top down: where a node splits (at the median of
//! its widest axis, or by orientation where it holds both sides of a hollow
//! solid) and the depth budget that bounds the tree.

use glam::Vec3;

use super::{BuildNode, LEAF_BIT, bound};
use crate::points::Surfel;

/// Subtrees smaller than this are built on the calling thread.
const PARALLEL_CUTOFF: usize = 4096;

/// Builds the subtree over `order` (surfel indices), returns its root and fills
/// `below` (exactly `2·len − 2` slots) with its descendants; `base` is the node
/// index of `below[0]`. Layout of `below`: both children, then the left child's
/// descendants, then the right child's.
/// `budget` is how many levels the subtree may have below its root (at least
/// the median split's `⌈log₂ len⌉`).
pub(super) fn build_subtree(
    surfels: &[Surfel],
    order: &mut [u32],
    below: &mut [BuildNode],
    base: u32,
    budget: usize,
) -> BuildNode {
    debug_assert_eq!(below.len(), 2 * order.len() - 2);
    let (lo, hi) = position_bounds(surfels, order);
    let mut node = bound::bound_node(surfels, order, lo, hi);
    if order.len() == 1 {
        node.child = LEAF_BIT | order[0];
        return node;
    }

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
    let (pair, rest) = below.split_at_mut(2);
    let (left_below, right_below) = rest.split_at_mut(2 * left_order.len() - 2);
    let left_base = base + 2;
    let right_base = left_base + left_below.len() as u32;
    let (l, r) = if len >= PARALLEL_CUTOFF {
        rayon::join(
            || build_subtree(surfels, left_order, left_below, left_base, budget - 1),
            || build_subtree(surfels, right_order, right_below, right_base, budget - 1),
        )
    } else {
        (
            build_subtree(surfels, left_order, left_below, left_base, budget - 1),
            build_subtree(surfels, right_order, right_below, right_base, budget - 1),
        )
    };
    node.depth = 1 + l.depth.max(r.depth);
    pair[0] = l;
    pair[1] = r;
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
