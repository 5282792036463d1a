//! Checks of a tree that did not come from [`Tree::build`] (one read from a
//! file): the kernels index by its child links unchecked and assume the
//! build's ranges, so a tree must pass both before use.

use glam::Vec3;

use super::{FACETS, LEAF, LEAF_BIT, MAX_DEPTH, MIXED, NodeArrays, NodeView, PLANAR, Tree, field};
use crate::points::MAX_COORDINATE;

/// Where a check failed.
pub(crate) enum Place {
    /// A node.
    Node(u32),
    /// The facets of a mixed node, by their index.
    Cluster(usize),
    /// The recorded depth.
    Depth,
}

/// A failed check: where, and what is wrong.
pub(crate) struct Fault {
    pub place: Place,
    pub what: String,
}

/// Mean normals are at most unit length, up to rounding.
const UNIT: f32 = 1.0 + 1e-3;

fn at(k: u32, what: String) -> Fault {
    Fault {
        place: Place::Node(k),
        what: format!("node {k}: {what}"),
    }
}

/// Whether `p` is finite and inside node `v`'s bounding sphere, up to the
/// rounding of its coordinates.
fn inside(p: Vec3, v: &NodeView) -> bool {
    p.is_finite() && (p - v.center).length() <= (v.radius + 2.0 * f32::EPSILON * p.abs().max_element()) * UNIT
}

/// Every node and facet value finite and within the range the build gives.
pub(crate) fn values(tree: &Tree) -> Result<(), Fault> {
    for k in 0..tree.len() as u32 {
        let v = tree.node(k);
        let kind = tree.splat_record(k).expect("k < len").kind;
        let problem = if !(v.center.is_finite() && v.center.abs().max_element() <= MAX_COORDINATE) {
            Some("centre not finite or beyond MAX_COORDINATE")
        } else if !(v.radius.is_finite() && v.radius >= 0.0) {
            Some("radius not finite and ≥ 0")
        } else if !(v.cone_axis.is_finite() && v.cone_axis.length() <= UNIT) {
            Some("cone axis not finite or longer than 1")
        } else if !((0.0..=1.0).contains(&v.cone_cos) && (0.0..=1.0).contains(&v.cone_sin)) {
            Some("cone cosine or sine outside [0, 1]")
        } else if !(v.area.is_finite() && v.area >= 0.0) {
            Some("area not finite and ≥ 0")
        } else if !(v.normal.is_finite() && v.normal.length() <= UNIT) {
            Some("mean normal not finite or longer than 1")
        } else if !(v.radiance.is_finite() && v.radiance.min_element() >= 0.0) {
            Some("radiance not finite and ≥ 0")
        } else if !inside(v.centroid, &v) || !inside(v.light_centroid, &v) {
            Some("area or light centroid not finite or outside the bounding sphere")
        } else if !matches!(kind, PLANAR | LEAF | MIXED) || (kind == LEAF) != tree.is_leaf(k) {
            Some("kind does not match the node (leaf, planar or mixed)")
        } else {
            None
        };
        if let Some(p) = problem {
            return Err(at(k, p.to_string()));
        }
    }
    for (i, c) in (0..tree.facets.len())
        .filter_map(|i| tree.facets.get(i))
        .map(|c| c.get())
        .enumerate()
    {
        let bad = c.facet.iter().any(|f| {
            let (an, l) = (Vec3::new(f[0], f[1], f[2]), Vec3::new(f[3], f[4], f[5]));
            !(an.is_finite() && an.length() <= UNIT && l.is_finite() && l.min_element() >= 0.0)
        }) || c.plane.iter().any(|p| {
            // The facet's and the node's centroids lie in the sphere; a disk
            // leaves its facet's plane by at most the sphere's diameter plus
            // its own radius.
            let off = Vec3::new(p[0], p[1], p[2]);
            !(off.is_finite() && off.length() <= 2.0 * UNIT && (0.0..=3.0 * UNIT).contains(&p[3]))
        }) || c.light.iter().any(|l| {
            let off = Vec3::from_array(*l);
            !(off.is_finite() && off.length() <= 2.0 * UNIT)
        });
        if bad {
            return Err(Fault {
                place: Place::Cluster(i),
                what: format!(
                    "cluster {i}: a facet's normal, radiance, plane or light centroid is out of range ({FACETS} facets)"
                ),
            });
        }
    }
    Ok(())
}

/// Each compact pair record below the root's decodes against its parent's
/// decoded sphere, bit for bit, as the build writes it (so a node's sphere
/// is quantized against the one that holds it). Nothing to check in a full
/// tree. Run after [`structure`]: it indexes by the child links.
pub(crate) fn bases(tree: &Tree) -> Result<(), Fault> {
    let NodeArrays::Compact(pairs) = &tree.nodes else {
        return Ok(());
    };
    for k in 0..tree.len() as u32 {
        let child = tree.nodes.child(k);
        if child & LEAF_BIT == 0 {
            let f = tree.nodes.fields(k);
            let sphere = [f[field::CX], f[field::CY], f[field::CZ], f[field::R]];
            if pairs[child as usize].base.map(f32::to_bits) != sphere.map(f32::to_bits) {
                return Err(at(
                    k,
                    format!("its children's record {child} decodes against another sphere than the node's"),
                ));
            }
        }
    }
    Ok(())
}

/// The tree is laid out as [`Tree::build`] lays it out: inner nodes take
/// the pair records in depth-first order (node 0's children are pair 1, the
/// left child's subtree follows), each surfel is in exactly one leaf, and
/// the depth is the recorded one, within [`MAX_DEPTH`].
pub(crate) fn structure(tree: &Tree, n: usize) -> Result<(), Fault> {
    if n == 0 {
        return if tree.depth == 0 {
            Ok(())
        } else {
            Err(Fault {
                place: Place::Depth,
                what: "depth of an empty tree is not 0".into(),
            })
        };
    }
    let mut seen = vec![false; n];
    let mut next_pair = 1u32;
    let mut depth = 0;
    let mut stack = vec![(0u32, 0usize)];
    while let Some((k, d)) = stack.pop() {
        if d > MAX_DEPTH {
            return Err(at(k, format!("deeper than {MAX_DEPTH} levels")));
        }
        depth = depth.max(d);
        let child = tree.nodes.child(k);
        if child & LEAF_BIT != 0 {
            let s = (child & !LEAF_BIT) as usize;
            match seen.get_mut(s) {
                Some(seen @ false) => *seen = true,
                Some(true) => return Err(at(k, format!("surfel {s} is in two leaves"))),
                None => return Err(at(k, format!("leaf of surfel {s}, but the cloud has {n}"))),
            }
        } else {
            if child != next_pair || child as usize >= n {
                return Err(at(
                    k,
                    format!("children in pair record {child}, expected {next_pair} (of {n})"),
                ));
            }
            next_pair += 1;
            let left = NodeArrays::first_of_pair(child);
            stack.push((left + 1, d + 1));
            stack.push((left, d + 1));
        }
    }
    // n − 1 inner nodes take pairs 1..n, so the n leaves hold every surfel.
    if next_pair as usize != n {
        return Err(at(
            0,
            format!("the tree reaches {} of {} pair records", next_pair, n),
        ));
    }
    if depth != tree.depth() {
        return Err(Fault {
            place: Place::Depth,
            what: format!("depth {} recorded, the tree's is {depth}", tree.depth),
        });
    }
    Ok(())
}
