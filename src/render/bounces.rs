//! Gathers at the surfels: the environment's light (`--sky`, an envmap)
//! and extra bounces (`--bounces 2+`), each from the current cloud.

use std::collections::HashMap;

use glam::{IVec3, Vec3};

use super::trace::Tracer;
use crate::error::Error;
use crate::gather::{Gather, GatherOptions};
use crate::microbuffer::{MicroBuffer, NearField, Sight};
use crate::points::{PointCloud, Surfel};
use crate::tree::{NodeId, Tree};
use rayon::prelude::*;

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

/// One more bounce at the surfels: each surfel's radiance becomes its direct
/// part plus `albedo/π · E`, with `E` gathered from the current cloud once
/// per group of at most `group` surfels ([`group_size`]: a subtree of
/// `tree` whose normals lie within [`FLAT`]'s cone, gathered at its
/// centroid), with `rays` as the gather's near field (the sky by rays) if
/// given.
#[allow(clippy::too_many_arguments)]
pub(super) fn gather_bounce(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    tree: &Tree,
    group: usize,
    opts: &GatherOptions,
    rays: Option<&dyn NearField>,
    tick: &(dyn Fn(usize, usize) + Sync),
) -> Result<PointCloud, Error> {
    let gather = Gather::new(tree, opts)?;
    let gather = match rays {
        Some(field) => gather.with_near_field(field),
        None => gather,
    };
    add_gathered(cloud, direct, albedo, tree, group, tick, |part| {
        gather.irradiance(part)
    })
}

/// The environment's light at the surfels, grouped as [`gather_bounce`]'s,
/// by rays alone (`rays` tells which directions leave the scene): with the
/// sky by rays, the surfels are no occluders the gather needs, so no cut
/// is taken and nothing is splatted (the same light as a gather over the
/// surfels made black, without its traversal and composition).
#[allow(clippy::too_many_arguments)]
pub(super) fn gather_sky(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    tree: &Tree,
    group: usize,
    opts: &GatherOptions,
    rays: &dyn NearField,
    tick: &(dyn Fn(usize, usize) + Sync),
) -> Result<PointCloud, Error> {
    let proto = MicroBuffer::new(opts.microbuffer)?.with_environment(opts.environment.clone());
    let empty = Tree::default();
    add_gathered(cloud, direct, albedo, tree, group, tick, |part| {
        Ok(part
            .par_chunks(64)
            .flat_map_iter(|chunk| {
                let mut mb = proto.clone();
                let empty = &empty;
                chunk.iter().map(move |&(p, n)| {
                    mb.reset(p, n);
                    mb.set_near_field(empty, rays);
                    mb.irradiance_inline(empty)
                })
            })
            .collect())
    })
}

/// Each surfel's radiance: its direct part plus `albedo/π · E`, `E` from
/// `gather` at its group's receiver (in runs of neighbours, the groups in
/// tree order, a progress report after each).
fn add_gathered(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    tree: &Tree,
    group: usize,
    tick: &(dyn Fn(usize, usize) + Sync),
    gather: impl Fn(&[(Vec3, Vec3)]) -> Result<Vec<Vec3>, Error>,
) -> Result<PointCloud, Error> {
    let surfels = cloud.surfels();
    let (receivers, members) = groups(tree, surfels, group);
    // A receiver's light is the same in any packet or run.
    let run = (receivers.len() / 64).max(4096);
    let mut gathered = Vec::with_capacity(receivers.len());
    tick(0, receivers.len());
    for part in receivers.chunks(run) {
        gathered.extend(gather(part)?);
        tick(gathered.len(), receivers.len());
    }
    let mut e = vec![Vec3::ZERO; surfels.len()];
    for (g, m) in gathered.iter().zip(&members) {
        for &i in m {
            e[i as usize] = *g;
        }
    }
    let next: Vec<Surfel> = surfels
        .iter()
        .zip(&e)
        .zip(direct.iter().zip(albedo))
        .map(|((s, e), (d, a))| Surfel {
            radiance: (*d + *a * std::f32::consts::FRAC_1_PI * *e).max(Vec3::ZERO),
            ..*s
        })
        .collect();
    PointCloud::new(next)
}

/// The sky by rays alone, for the surfels' gathers (they have no near
/// field): which directions leave the scene.
#[derive(Clone, Copy)]
pub(super) struct SkyRays<'a>(pub &'a Tracer);

impl NearField for SkyRays<'_> {
    fn trace(&self, _: Vec3, _: Vec3, _: Vec3, _: f32) -> Option<Vec3> {
        None
    }

    fn near_leaves(&self) -> bool {
        false
    }

    fn escapes(&self, origin: Vec3, normal: Vec3, dir: Vec3) -> Option<bool> {
        Some(self.0.escapes(origin, normal, dir))
    }

    fn escapes_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<bool>) -> bool {
        self.0.escapes_each(origin, normal, dirs, out);
        true
    }

    fn sight_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<Sight>) -> bool {
        self.0.sight_each(origin, normal, dirs, out);
        true
    }
}

/// The receivers of grouped gathers and each one's surfels: the largest
/// subtrees of at most `group` leaves whose normal cone is within
/// [`FLAT`], a receiver at the area centroid facing the mean normal. A
/// subtree of more than [`SURFEL_GROUP`] and at most `group` leaves whose
/// cone is wider (at a fine budget, a thin wall's two faces fall in one)
/// is split by its surfels' facing instead ([`facings`]), and each facing
/// into its connected [`pieces`]; every other surfel is alone.
fn groups(tree: &Tree, surfels: &[Surfel], group: usize) -> (Vec<(Vec3, Vec3)>, Vec<Vec<u32>>) {
    let mut leaves = vec![0u32; tree.len()];
    count(tree, 0, &mut leaves);
    let (mut receivers, mut members) = (Vec::new(), Vec::new());
    let mut stack: Vec<NodeId> = if tree.is_empty() { Vec::new() } else { vec![0] };
    while let Some(n) = stack.pop() {
        let v = tree.node(n);
        let flat = v.surfel.is_some() || v.cone_cos >= FLAT;
        let k = leaves[n as usize] as usize;
        if k <= group && flat {
            let mut m = Vec::new();
            collect(tree, n, &mut m);
            let normal = v.normal.normalize_or(v.cone_axis);
            let r = m.iter().map(|&i| surfels[i as usize].radius).sum::<f32>() / m.len() as f32;
            // A hair above the surface, so it does not see itself edge-on.
            receivers.push((v.centroid + normal * (r * 1e-3), normal));
            members.push(m);
        } else if k <= group && k > SURFEL_GROUP {
            let mut m = Vec::new();
            collect(tree, n, &mut m);
            for f in facings(&m, surfels) {
                for piece in pieces(&f, surfels) {
                    receivers.push(facing_receiver(&piece, surfels));
                    members.push(piece);
                }
            }
        } else if let Some(l) = v.children {
            stack.extend([l + 1, l]);
        }
    }
    (receivers, members)
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

    /// A floor, and a thin slab's two faces 1 cm apart (a subtree of a few
    /// surfels holds both sides): 400 surfels each, every third the floor's.
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
                surfels.push(s(Vec3::new(2.0 + u, 0.0, v), -Vec3::Y));
                surfels.push(s(Vec3::new(2.0 + u, 0.01, v), Vec3::Y));
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
        let (receivers, members) = groups(&tree, cloud.surfels(), group);
        let mut seen = vec![0; cloud.len()];
        for ((p, n), m) in receivers.iter().zip(&members) {
            assert!(!m.is_empty() && m.len() <= group, "{}", m.len());
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

    /// In groups of 8, the floor's 400 surfels share gathers; the slab's,
    /// whose small subtrees hold both faces, are mostly gathered one by one.
    #[test]
    fn groups_partition_the_surfels_face_by_face() {
        let (floor, _) = gathers_of_floor_and_slab(SURFEL_GROUP);
        assert!(floor * 4 < 400, "{floor} gathers for the floor's 400 surfels");
    }

    /// In larger groups (a finer budget) the floor takes a few gathers, and
    /// so does the slab: a subtree that holds both its faces is split by
    /// facing rather than into single surfels.
    #[test]
    fn larger_groups_share_more_and_split_a_thin_slab_by_facing() {
        let (floor, slab) = gathers_of_floor_and_slab(64);
        assert!(floor * 16 < 400, "{floor} gathers for the floor's 400 surfels");
        assert!(slab * 8 < 800, "{slab} gathers for the slab's 800 surfels");
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
