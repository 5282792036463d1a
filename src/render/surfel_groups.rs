//! Which surfels share one gather of the environment's light or of an
//! extra bounce (`render::bounces`): flat groups, each gathered at one
//! receiver that stands for all of its surfels.

use std::collections::{BTreeMap, HashMap};

use glam::{IVec3, Vec3};

use crate::points::Surfel;
use crate::tree::{NodeId, Tree};

/// Surfels that share one gather of the environment's light or of an
/// extra bounce, at the least: a subtree of at most this many, flat within
/// [`FLAT`] (about a 3 × 3 patch). Gathering at every surfel was most of a
/// frame with a sky and of `--bounces 2`; groups of 8 take about half of
/// it at the same error and bias (docs/lab/gather-cost.md has the figures).
const SURFEL_GROUP: usize = 8;

/// The most surfels of `surfels` that share one gather, for about
/// `gathers` of them (`0`: [`SURFEL_GROUP`]): each group then stands for
/// the same share of the scene's area at any density, so that a bake of
/// 10⁷ surfels gathers about as often as one of 52,000.
pub(super) fn group_size(surfels: usize, gathers: u32) -> usize {
    match gathers {
        0 => SURFEL_GROUP,
        g => SURFEL_GROUP.max(surfels / g as usize),
    }
}

/// Cosine of the widest normal cone a group of surfels sharing one gather
/// may have (18°, as the sparse lattice's one surface).
const FLAT: f32 = 0.95;

/// The receivers of grouped gathers (position, unit normal) and each one's
/// surfels, a partition of the cloud.
#[derive(Clone, Debug, Default)]
pub(super) struct Groups {
    pub receivers: Vec<(Vec3, Vec3)>,
    pub members: Vec<Vec<u32>>,
}

impl Groups {
    /// Whether groups of at most `group` surfels come from the surfels' tree
    /// ([`Groups::new`] reads it only then).
    pub(super) fn need_tree(group: usize) -> bool {
        group <= SURFEL_GROUP
    }

    /// Groups of about `group` surfels ([`group_size`]). Up to
    /// [`SURFEL_GROUP`], the tree's flat subtrees of at most that many
    /// (`tree`, which [`Groups::need_tree`] says is needed); past it (a
    /// budget finer than the gathers asked for), cells of a grid over the
    /// surfels that hold about `group` each, split by facing and into
    /// connected pieces, with no tree at all: at 10⁷ surfels a tree over
    /// the dark surfels, built only to group them, was a third of the bake.
    pub(super) fn new(surfels: &[Surfel], group: usize, tree: Option<&Tree>) -> Groups {
        match tree {
            Some(tree) if Self::need_tree(group) => tree_groups(tree, surfels, group),
            _ => grid_groups(surfels, group),
        }
    }
}

/// [`Groups::new`] past [`SURFEL_GROUP`]: the surfels by cell of a grid
/// whose cells hold the disks of about `group` surfels on a flat face, the
/// cells in order, each cell's surfels split by [`facings`] and into
/// [`pieces`], each piece gathered at [`facing_receiver`].
fn grid_groups(surfels: &[Surfel], group: usize) -> Groups {
    let mut groups = Groups::default();
    if surfels.is_empty() {
        return groups;
    }
    let mean: f64 = surfels.iter().map(|s| (s.radius as f64).powi(2)).sum::<f64>() / surfels.len() as f64;
    let side = ((group as f64 * std::f64::consts::PI * mean).sqrt() as f32).max(f32::MIN_POSITIVE);
    let mut cells: BTreeMap<[i32; 3], Vec<u32>> = BTreeMap::new();
    for (i, s) in surfels.iter().enumerate() {
        let c = (s.position / side).floor().as_ivec3();
        cells.entry(c.to_array()).or_default().push(i as u32);
    }
    for cell in cells.values() {
        for f in facings(cell, surfels) {
            for piece in pieces(&f, surfels) {
                groups.receivers.push(facing_receiver(&piece, surfels));
                groups.members.push(piece);
            }
        }
    }
    groups
}

/// [`Groups::new`] up to [`SURFEL_GROUP`]: the largest subtrees of at most
/// `group` leaves whose normal cone is within [`FLAT`], a receiver at the
/// area centroid facing the mean normal; every other surfel alone.
fn tree_groups(tree: &Tree, surfels: &[Surfel], group: usize) -> Groups {
    let mut leaves = vec![0u32; tree.len()];
    count(tree, 0, &mut leaves);
    let (mut receivers, mut members) = (Vec::new(), Vec::new());
    let mut stack: Vec<NodeId> = if tree.is_empty() { Vec::new() } else { vec![0] };
    while let Some(n) = stack.pop() {
        let v = tree.node(n);
        let flat = v.surfel.is_some() || v.cone_cos >= FLAT;
        if leaves[n as usize] as usize <= group && flat {
            let mut m = Vec::new();
            collect(tree, n, &mut m);
            let normal = v.normal.normalize_or(v.cone_axis);
            let r = m.iter().map(|&i| surfels[i as usize].radius).sum::<f32>() / m.len() as f32;
            // A hair above the surface, so it does not see itself edge-on.
            receivers.push((v.centroid + normal * (r * 1e-3), normal));
            members.push(m);
        } else if let Some(l) = v.children {
            stack.extend([l + 1, l]);
        }
    }
    Groups { receivers, members }
}

/// `members` split by facing, in order: those within [`FLAT`] of the
/// first one left, then those within [`FLAT`] of their mean normal (a cone
/// about the mean holds more than one about its edge, and it is the mean
/// that the group's receiver faces), then again over the rest.
fn facings(members: &[u32], surfels: &[Surfel]) -> Vec<Vec<u32>> {
    let mut rest = members.to_vec();
    let mut out = Vec::new();
    while let Some(&first) = rest.first() {
        let within = |axis: Vec3| -> (Vec<u32>, Vec<u32>) {
            rest.iter()
                .partition(|&&i| surfels[i as usize].normal.dot(axis) >= FLAT)
        };
        let (near, _) = within(surfels[first as usize].normal);
        let mut mean = Vec3::ZERO;
        for &i in &near {
            let s = &surfels[i as usize];
            mean += s.normal * (s.radius * s.radius);
        }
        let (mut same, mut other) = within(mean.normalize_or_zero());
        if same.is_empty() {
            (same, other) = within(surfels[first as usize].normal);
        }
        out.push(same);
        rest = other;
    }
    out
}

/// `members` (one facing) split into connected pieces, in order of their
/// first surfel: two surfels join where their disks lie within their own
/// diameters of touching (pooled small triangles' surfels leave gaps: at
/// touching alone, the dragon's facings fell apart into 3.5 times as many
/// gathers). A facing of a subtree may hold parts of two surfaces that face
/// the same way (a floor and a slab's top beside it), which one gather
/// would not stand for.
fn pieces(members: &[u32], surfels: &[Surfel]) -> Vec<Vec<u32>> {
    let reach = members
        .iter()
        .map(|&i| surfels[i as usize].radius)
        .fold(0.0f32, f32::max);
    // Cells of four times the largest radius: joined surfels lie in the
    // same or adjacent cells.
    let cell = |p: Vec3| (p / (4.0 * reach).max(f32::MIN_POSITIVE)).floor().as_ivec3();
    let mut grid: HashMap<IVec3, Vec<usize>> = HashMap::new();
    for (k, &i) in members.iter().enumerate() {
        grid.entry(cell(surfels[i as usize].position))
            .or_default()
            .push(k);
    }
    let mut parent: Vec<usize> = (0..members.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    for (k, &i) in members.iter().enumerate() {
        let s = &surfels[i as usize];
        let c = cell(s.position);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(near) = grid.get(&(c + IVec3::new(dx, dy, dz))) else {
                        continue;
                    };
                    for &j in near {
                        let t = &surfels[members[j] as usize];
                        if s.position.distance(t.position) <= 2.0 * (s.radius + t.radius) {
                            let (a, b) = (root(&mut parent, k), root(&mut parent, j));
                            parent[a.max(b)] = a.min(b);
                        }
                    }
                }
            }
        }
    }
    let mut out: Vec<Vec<u32>> = Vec::new();
    let mut slot = vec![usize::MAX; members.len()];
    for (k, &i) in members.iter().enumerate() {
        let r = root(&mut parent, k);
        if slot[r] == usize::MAX {
            slot[r] = out.len();
            out.push(Vec::new());
        }
        out[slot[r]].push(i);
    }
    out
}

/// The receiver of one facing's surfels: at the surfel nearest their area
/// centroid (a facing of a subtree need not be one piece, and its centroid
/// may lie off every surface), a hair above it, facing their mean normal.
fn facing_receiver(members: &[u32], surfels: &[Surfel]) -> (Vec3, Vec3) {
    let (mut centroid, mut normal, mut area) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
    for &i in members {
        let s = &surfels[i as usize];
        let a = s.radius * s.radius;
        centroid += s.position * a;
        normal += s.normal * a;
        area += a;
    }
    let centroid = centroid / area.max(f32::MIN_POSITIVE);
    let first = &surfels[members[0] as usize];
    let normal = normal.normalize_or(first.normal);
    // At a surfel, not at the centroid: that lies under a convex part of a
    // curved surface, where the receiver's rays meet the surface at once
    // and the sky is lost.
    let mut at = first;
    for &i in members {
        let s = &surfels[i as usize];
        if s.position.distance_squared(centroid) < at.position.distance_squared(centroid) {
            at = s;
        }
    }
    (at.position + normal * (at.radius * 1e-3), normal)
}

/// Leaves below each node, into `leaves`; returns `node`'s.
fn count(tree: &Tree, node: NodeId, leaves: &mut [u32]) -> u32 {
    let c = match tree.left_child(node) {
        None => 1,
        Some(l) => count(tree, l, leaves) + count(tree, l + 1, leaves),
    };
    leaves[node as usize] = c;
    c
}

/// The surfels below `node`.
fn collect(tree: &Tree, node: NodeId, out: &mut Vec<u32>) {
    match (tree.node(node).surfel, tree.left_child(node)) {
        (Some(s), _) => out.push(s),
        (None, Some(l)) => {
            collect(tree, l, out);
            collect(tree, l + 1, out);
        }
        (None, None) => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::points::PointCloud;

    /// A floor, and 20 cm beside it a thin slab's two faces 1 cm apart (a
    /// subtree of a few surfels holds both sides; a grid's cell, the floor's
    /// edge and the slab's top): 400 surfels each, every third the floor's.
    fn floor_and_slab() -> PointCloud {
        let mut surfels = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let (u, v) = (i as f32 * 0.05, j as f32 * 0.05);
                let s = |position, normal| Surfel {
                    position,
                    normal,
                    radius: 0.03,
                    radiance: Vec3::ZERO,
                };
                surfels.push(s(Vec3::new(u, 0.0, v), Vec3::Y));
                surfels.push(s(Vec3::new(1.15 + u, 0.0, v), -Vec3::Y));
                surfels.push(s(Vec3::new(1.15 + u, 0.01, v), Vec3::Y));
            }
        }
        PointCloud::new(surfels).unwrap()
    }

    /// Groups of at most `group`, as [`groups`] makes them: asserts that
    /// they partition the surfels, that none holds more than `group` or
    /// mixes the slab's faces, and that each receiver lies on its surfels'
    /// face; returns how many gathers the floor and the slab take.
    fn gathers_of_floor_and_slab(group: usize) -> (usize, usize) {
        let cloud = floor_and_slab();
        let tree = Tree::build(&cloud);
        let Groups { receivers, members } = Groups::new(cloud.surfels(), group, Some(&tree));
        let mut seen = vec![0; cloud.len()];
        for ((p, n), m) in receivers.iter().zip(&members) {
            assert!(!m.is_empty(), "an empty group");
            assert!(m.len() <= group || !Groups::need_tree(group), "{}", m.len());
            for &i in m {
                seen[i as usize] += 1;
                let s = &cloud.surfels()[i as usize];
                assert!(s.normal.dot(*n) > FLAT, "{} against {n}", s.normal);
                assert!((*p - s.position).dot(s.normal).abs() < 1e-3);
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "not a partition");
        let floor = members.iter().filter(|m| m.iter().any(|&i| i % 3 == 0)).count();
        (floor, members.len() - floor)
    }

    /// In groups of 8 (the tree's subtrees), the floor's 400 surfels share
    /// gathers; the slab's, whose small subtrees hold both faces, are mostly
    /// gathered one by one.
    #[test]
    fn groups_partition_the_surfels_face_by_face() {
        let (floor, _) = gathers_of_floor_and_slab(SURFEL_GROUP);
        assert!(floor * 4 < 400, "{floor} gathers for the floor's 400 surfels");
    }

    /// In larger groups (a finer budget: the grid's cells) the floor takes
    /// a few gathers, and so does the slab, whose faces share cells: they
    /// are split by facing, never gathered as one.
    #[test]
    fn larger_groups_share_more_and_split_a_thin_slab_by_facing() {
        let (floor, slab) = gathers_of_floor_and_slab(64);
        assert!(floor * 16 < 400, "{floor} gathers for the floor's 400 surfels");
        assert!(slab * 16 < 800, "{slab} gathers for the slab's 800 surfels");
    }

    /// A facing of a cell that holds two surfaces facing the same way (a
    /// floor, and a slab's top beside it) is two pieces, two gathers.
    #[test]
    fn a_facing_falls_into_its_connected_pieces() {
        let cloud = floor_and_slab();
        let up: Vec<u32> = (0..cloud.len() as u32)
            .filter(|&i| cloud.surfels()[i as usize].normal.y > 0.0)
            .collect();
        let f = facings(&up, cloud.surfels());
        assert_eq!(f.len(), 1);
        let p = pieces(&f[0], cloud.surfels());
        assert_eq!(p.len(), 2, "{:?}", p.iter().map(Vec::len).collect::<Vec<_>>());
        assert!(p.iter().all(|p| p.len() == 400));
    }

    /// Groups grow with the surfels past the gathers asked for, so that a
    /// finer bake gathers about as often; never below 8.
    #[test]
    fn groups_grow_with_the_surfels_past_the_gathers_asked_for() {
        assert_eq!(group_size(51_993, 6_500), SURFEL_GROUP);
        assert_eq!(group_size(1_000_000, 6_500), 153);
        assert_eq!(group_size(10_000_000, 6_500), 1_538);
        assert_eq!(group_size(10_000_000, 0), SURFEL_GROUP);
        assert_eq!(group_size(100, 6_500), SURFEL_GROUP);
    }
}
