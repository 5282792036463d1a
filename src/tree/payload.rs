//! What splatting reads of each node (its [`SplatRecord`] and radiance, and
//! a mixed node's facets), stored whole or packed, and which node's facets
//! a mixed node's are.
//!
//! The packed form ([`Precision::Compact`]) quantizes against the node's own
//! bounding sphere, as Buchholz and Boubekeur quantize a PBGI tree: both
//! centroids as offsets in steps of `R / 32767` (they lie in the sphere, so
//! the offsets fit), the mean normal (at most unit length) in steps of
//! `1 / 32767`, the radiance with one exponent shared by its three 16-bit
//! mantissas, and the area whole: 32 bytes an inner node. A leaf is its
//! surfel's disk, which its pair record already holds (centre, radius, and
//! normal as the cone's axis): it keeps only its area and radiance, in 12
//! bytes ([`PackedLeaf`]). Rounding is to the nearest step, so the error has
//! no sign: a centroid moves by at most `R / 65534` per axis (a leaf's by
//! its parent's `R / 65534`), a radiance by a part in 65535 of its
//! brightest channel. Decoding is `+ − ×` on `f32` alone, the same on every
//! path, so a compact tree's images are as deterministic as a full one's.

use glam::Vec3;

use super::bound::disks_area;
use super::{Cluster, FACETS, FacetPlanes, LEAF, LEAF_BIT, NodeArrays, NodeId, SplatRecord, Tree, field};
use crate::points::Surfel;

/// How a tree stores what splatting reads of its nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Precision {
    /// `f32` fields: 80 bytes a node, and 260 a mixed node's facets.
    #[default]
    Full,
    /// Quantized against each node's bounding sphere: 32 bytes an inner
    /// node, 12 a leaf, 88 a mixed node's facets.
    Compact,
}

/// Offset steps per bounding radius, and normal steps per unit.
const STEPS: f64 = 32767.0;
/// Mantissa steps of the brightest radiance channel.
const MANTISSA: f64 = 65535.0;
/// Flag in [`PackedSplat::kind`]: the light centroid is not the area centroid.
const SHIFTED: u8 = 0x80;

/// One node's splat record and radiance, quantized (see the module's notes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct PackedSplat {
    pub area: f32,
    pub centroid: [i16; 3],
    pub light: [i16; 3],
    pub normal: [i16; 3],
    pub radiance: [u16; 3],
    /// The radiance's scale `2^(e − 127)` as an `f32` exponent field (0: black).
    pub exponent: u8,
    /// [`PLANAR`], [`LEAF`] or [`MIXED`], and [`SHIFTED`].
    pub kind: u8,
}

/// The nearest step of `x` in steps of `1 / STEPS`, within ±1.
fn step(x: f64) -> i16 {
    (x * STEPS).round().clamp(-STEPS, STEPS) as i16
}

/// `center + q·(r / 32767)`, on `f32`: how every path decodes an offset.
#[inline(always)]
fn offset(center: [f32; 3], r: f32, q: [i16; 3]) -> [f32; 3] {
    let unit = r * (1.0 / STEPS as f32);
    std::array::from_fn(|i| center[i] + f32::from(q[i]) * unit)
}

/// The offsets of `x` from `center` in steps of `r / 32767`.
fn offsets(x: [f32; 3], center: [f32; 3], r: f32) -> [i16; 3] {
    let unit = if r > 0.0 { 1.0 / r as f64 } else { 0.0 };
    std::array::from_fn(|i| step((x[i] as f64 - center[i] as f64) * unit))
}

/// Three non-negative channels as 16-bit mantissas and one `f32` exponent
/// field: the brightest channel's mantissa is at least 32768 (unless it is
/// below `2^-111`), so each channel is within a part in 65535 of the brightest.
fn pack_radiance(l: Vec3) -> ([u16; 3], u8) {
    let top = l.max_element();
    if top <= 0.0 {
        return ([0; 3], 0);
    }
    let biased = ((top.to_bits() >> 23) & 0xff) as i32;
    let mut e = (biased - 15).max(1);
    loop {
        let scale = f32::from_bits((e as u32) << 23) as f64;
        let m = l.to_array().map(|c| (c as f64 / scale).round());
        if m.iter().all(|&c| c <= MANTISSA) {
            return (m.map(|c| c as u16), e as u8);
        }
        e += 1;
    }
}

#[inline(always)]
fn unpack_radiance(m: [u16; 3], e: u8) -> Vec3 {
    let scale = f32::from_bits(u32::from(e) << 23);
    Vec3::new(
        f32::from(m[0]) * scale,
        f32::from(m[1]) * scale,
        f32::from(m[2]) * scale,
    )
}

impl PackedSplat {
    /// Packs node record `rec` and radiance `l` of a node with sphere
    /// (`center`, `r`) and facets `cluster`.
    pub(crate) fn pack(
        rec: &SplatRecord,
        l: Vec3,
        center: [f32; 3],
        r: f32,
        cluster: &Cluster,
    ) -> PackedSplat {
        let (radiance, exponent) = pack_radiance(l);
        let mut p = PackedSplat {
            area: rec.area,
            centroid: offsets(rec.centroid, center, r),
            light: offsets(rec.light_centroid, center, r),
            normal: rec.normal.map(|x| step(x as f64)),
            radiance,
            exponent,
            kind: rec.kind as u8,
        };
        // Whether the light is shifted, of the values a render reads.
        let mut full = p.unpack(center, r, 0.0);
        full.derive(r, 0.0, cluster);
        if full.shifted {
            p.kind |= SHIFTED;
        }
        p
    }

    /// The splat record of a node with sphere (`center`, `r`) and cone sine
    /// `sin`, with what [`SplatRecord::derive`] derives.
    #[inline(always)]
    pub(crate) fn unpack(&self, center: [f32; 3], r: f32, sin: f32) -> SplatRecord {
        let kind = u32::from(self.kind & !SHIFTED);
        let normal = self.normal.map(|q| f32::from(q) * (1.0 / STEPS as f32));
        let (rise, lift, radius) = SplatRecord::bounds(kind, self.area, r, sin);
        SplatRecord {
            centroid: offset(center, r, self.centroid),
            area: self.area,
            normal,
            kind,
            light_centroid: offset(center, r, self.light),
            rise,
            lift,
            radius,
            shifted: self.kind & SHIFTED != 0,
        }
    }

    /// The node's radiance.
    #[inline(always)]
    pub(crate) fn radiance(&self) -> Vec3 {
        unpack_radiance(self.radiance, self.exponent)
    }
}

/// A leaf's splat record: its area and radiance, in 12 bytes. The rest is
/// its surfel's disk as its pair record holds it (centre, and normal as the
/// cone's axis), so a leaf costs no splat record of 32 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct PackedLeaf {
    area: f32,
    radiance: [u16; 3],
    exponent: u8,
}

impl PackedLeaf {
    /// The leaf of surfel `s`.
    pub(crate) fn of(s: &Surfel) -> PackedLeaf {
        let (radiance, exponent) = pack_radiance(s.radiance);
        let r = s.radius as f64;
        PackedLeaf {
            area: disks_area(r * r),
            radiance,
            exponent,
        }
    }

    /// The leaf's splat record, of its node's test fields `f`.
    #[inline(always)]
    fn unpack(&self, f: [f32; field::COUNT]) -> SplatRecord {
        let (rise, lift, radius) = SplatRecord::bounds(LEAF, self.area, f[field::R], f[field::SIN]);
        let centroid = [f[field::CX], f[field::CY], f[field::CZ]];
        SplatRecord {
            centroid,
            area: self.area,
            normal: [f[field::AX], f[field::AY], f[field::AZ]],
            kind: LEAF,
            light_centroid: centroid,
            rise,
            lift,
            radius,
            shifted: false,
        }
    }

    #[inline(always)]
    fn radiance(&self) -> Vec3 {
        unpack_radiance(self.radiance, self.exponent)
    }
}

/// A mixed node's facets ([`Cluster`]) in 88 bytes, where they take 160
/// (and 100 more for what the microbuffer derives of them, which a compact
/// tree derives where it reads them). Per facet: its unit mean normal in
/// steps of `1 / 32767` and the length of `A·n̄ / A_node` in steps of
/// `1 / 65535`; its radiance as a node's is; its plane's and its light's
/// offsets (at most 2 in units of `R`) in steps of `2 / 32767`, and how far
/// its disks leave its plane in steps of `4 / 65535`, rounded up (it bounds
/// them). The plane's and the light's offsets share their steps, so a facet
/// whose light is at its centroid still is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct PackedFacets {
    normal: [[i16; 3]; FACETS],
    shown: [u16; FACETS],
    radiance: [[u16; 3]; FACETS],
    exponent: [u8; FACETS],
    plane: [[i16; 3]; FACETS],
    lift: [u16; FACETS],
    light: [[i16; 3]; FACETS],
}

/// Steps per unit of a facet's offsets (at most 2 in units of `R`).
const FACET_STEPS: f64 = STEPS / 2.0;
/// Steps per unit of how far a facet's disks leave its plane (at most 3·`R`).
const LIFT_STEPS: f64 = MANTISSA / 4.0;

impl PackedFacets {
    pub(crate) fn pack(c: &Cluster) -> PackedFacets {
        let mut p = PackedFacets::default();
        for i in 0..FACETS {
            let f = c.facet[i];
            let an = Vec3::new(f[0], f[1], f[2]).as_dvec3();
            let len = an.length();
            let n = if len > 0.0 { an / len } else { an };
            p.normal[i] = n.to_array().map(step);
            p.shown[i] = (len * MANTISSA).round().clamp(0.0, MANTISSA) as u16;
            (p.radiance[i], p.exponent[i]) = pack_radiance(Vec3::new(f[3], f[4], f[5]));
            let plane = c.plane[i];
            p.plane[i] = [plane[0], plane[1], plane[2]].map(|x| facet_step(x as f64));
            p.lift[i] = (plane[3] as f64 * LIFT_STEPS).ceil().clamp(0.0, MANTISSA) as u16;
            p.light[i] = c.light[i].map(|x| facet_step(x as f64));
        }
        p
    }

    /// The facets, decoded with `+ − ×` on `f32`.
    #[inline(always)]
    pub(crate) fn unpack(&self) -> Cluster {
        let mut c = Cluster::NONE;
        let unit = |q: i16| f32::from(q) * (1.0 / FACET_STEPS as f32);
        for i in 0..FACETS {
            let len = f32::from(self.shown[i]) * (1.0 / MANTISSA as f32);
            let n = self.normal[i].map(|q| f32::from(q) * (1.0 / STEPS as f32) * len);
            let l = unpack_radiance(self.radiance[i], self.exponent[i]);
            c.facet[i] = [n[0], n[1], n[2], l.x, l.y, l.z];
            let [x, y, z] = self.plane[i].map(unit);
            c.plane[i] = [x, y, z, f32::from(self.lift[i]) * (1.0 / LIFT_STEPS as f32)];
            c.light[i] = self.light[i].map(unit);
        }
        c
    }
}

/// A mixed node's facets where the tree holds them, decoded where read:
/// a reference, so what the microbuffer passes per splatted node stays
/// small (most nodes have no facets).
#[derive(Clone, Copy, Debug)]
pub(crate) enum ClusterRef<'a> {
    Whole(&'a Cluster),
    Packed(&'a PackedFacets),
}

impl ClusterRef<'_> {
    /// No facets: what a node that is not [`MIXED`](super::MIXED) reads.
    pub(crate) const NONE: ClusterRef<'static> = ClusterRef::Whole(&Cluster::NONE);

    #[inline(always)]
    pub(crate) fn get(self) -> Cluster {
        match self {
            ClusterRef::Whole(c) => *c,
            ClusterRef::Packed(p) => p.unpack(),
        }
    }
}

/// The nearest step of a facet's offset `x` (units of `R`, within ±2).
fn facet_step(x: f64) -> i16 {
    (x * FACET_STEPS).round().clamp(-STEPS, STEPS) as i16
}

/// The facets of the mixed nodes, in the order of their [`Rank`]: whole,
/// with what the microbuffer derives of them, or packed.
#[derive(Clone, Debug)]
pub(crate) enum Facets {
    Full {
        cluster: Vec<Cluster>,
        planes: Vec<FacetPlanes>,
    },
    Compact(Vec<PackedFacets>),
}

impl Default for Facets {
    fn default() -> Self {
        Facets::Full {
            cluster: Vec::new(),
            planes: Vec::new(),
        }
    }
}

impl Facets {
    /// The facets `cluster` stored at `precision` (what is derived of them
    /// is filled by [`Tree::derive`](super::Tree)).
    pub(crate) fn new(cluster: Vec<Cluster>, precision: Precision) -> Facets {
        match precision {
            Precision::Full => Facets::Full {
                cluster,
                planes: Vec::new(),
            },
            Precision::Compact => Facets::Compact(cluster.iter().map(PackedFacets::pack).collect()),
        }
    }

    /// Number of mixed nodes.
    pub(crate) fn len(&self) -> usize {
        match self {
            Facets::Full { cluster, .. } => cluster.len(),
            Facets::Compact(packed) => packed.len(),
        }
    }

    /// The facets of the `i`-th mixed node, if there is one.
    #[inline(always)]
    pub(crate) fn get(&self, i: usize) -> Option<ClusterRef<'_>> {
        match self {
            Facets::Full { cluster, .. } => cluster.get(i).map(ClusterRef::Whole),
            Facets::Compact(packed) => packed.get(i).map(ClusterRef::Packed),
        }
    }

    /// Bytes a mixed node.
    fn bytes(&self) -> usize {
        match self {
            Facets::Full { .. } => std::mem::size_of::<Cluster>() + std::mem::size_of::<FacetPlanes>(),
            Facets::Compact(_) => std::mem::size_of::<PackedFacets>(),
        }
    }
}

/// The splat records and radiance of every node.
#[derive(Clone, Debug)]
pub(crate) enum Payload {
    /// Indexed by node.
    Full {
        splat: Vec<SplatRecord>,
        radiance: Vec<Vec3>,
    },
    /// An inner node's indexed by its child link (the pair record of its
    /// children; record 0's is unused), a leaf's by its surfel.
    Compact {
        inner: Vec<PackedSplat>,
        leaves: Vec<PackedLeaf>,
    },
}

impl Default for Payload {
    fn default() -> Self {
        Payload::Full {
            splat: Vec::new(),
            radiance: Vec::new(),
        }
    }
}

/// Which nodes are set, and each set node's rank among them, in `O(1)`: a
/// bit per node and a count per 64 (the index of a mixed node's facets).
#[derive(Clone, Debug, Default)]
pub(crate) struct Rank {
    bits: Vec<u64>,
    before: Vec<u32>,
}

impl Rank {
    pub(crate) fn new(set: impl IntoIterator<Item = bool>) -> Rank {
        let mut r = Rank::default();
        let mut count = 0u32;
        for (k, s) in set.into_iter().enumerate() {
            if k % 64 == 0 {
                r.bits.push(0);
                r.before.push(count);
            }
            if s {
                *r.bits.last_mut().expect("pushed") |= 1 << (k % 64);
                count += 1;
            }
        }
        r
    }

    /// The rank of node `k` among the set ones, if it is set.
    #[inline(always)]
    pub(crate) fn get(&self, k: usize) -> Option<usize> {
        let word = *self.bits.get(k / 64)?;
        let bit = 1u64 << (k % 64);
        (word & bit != 0).then(|| self.before[k / 64] as usize + (word & (bit - 1)).count_ones() as usize)
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.bits.len() * 12
    }
}

impl Tree {
    /// How the tree stores what splatting reads.
    pub fn precision(&self) -> Precision {
        match self.nodes {
            NodeArrays::Full(_) => Precision::Full,
            NodeArrays::Compact(_) => Precision::Compact,
        }
    }

    /// What splatting reads of node `node` (`None` past the last node).
    #[inline(always)]
    pub(crate) fn splat_record(&self, node: NodeId) -> Option<SplatRecord> {
        let k = node as usize;
        match &self.payload {
            Payload::Full { splat, .. } => splat.get(k).copied(),
            Payload::Compact { inner, leaves } => {
                if k >= self.len() {
                    return None;
                }
                let link = self.nodes.child(node);
                if link & LEAF_BIT != 0 {
                    Some(
                        leaves
                            .get((link & !LEAF_BIT) as usize)?
                            .unpack(self.nodes.fields(node)),
                    )
                } else {
                    Some(self.unpack(inner.get(link as usize)?, node).0)
                }
            }
        }
    }

    /// Node `node`'s packed splat record `p`, decoded, and its bounding radius.
    #[inline(always)]
    fn unpack(&self, p: &PackedSplat, node: NodeId) -> (SplatRecord, f32) {
        let f = self.nodes.fields(node);
        let c = [f[field::CX], f[field::CY], f[field::CZ]];
        (p.unpack(c, f[field::R], f[field::SIN]), f[field::R])
    }

    /// Area-weighted mean outgoing radiance below `node`.
    #[inline(always)]
    pub fn radiance(&self, node: NodeId) -> Vec3 {
        match &self.payload {
            Payload::Full { radiance, .. } => radiance[node as usize],
            Payload::Compact { inner, leaves } => {
                let link = self.nodes.child(node);
                if link & LEAF_BIT != 0 {
                    leaves[(link & !LEAF_BIT) as usize].radiance()
                } else {
                    inner[link as usize].radiance()
                }
            }
        }
    }

    /// The facets of node `node`, if it is [`MIXED`](super::MIXED).
    #[inline(always)]
    pub(crate) fn cluster_of(&self, node: NodeId) -> Option<ClusterRef<'_>> {
        self.facets.get(self.mixed.get(node as usize)?)
    }

    /// What the microbuffer derives of node `node`'s facets, if it is
    /// [`MIXED`](super::MIXED): stored in a full tree, derived here in a
    /// compact one.
    #[inline(always)]
    pub(crate) fn planes_of(&self, node: NodeId) -> Option<FacetPlanes> {
        let i = self.mixed.get(node as usize)?;
        match &self.facets {
            Facets::Full { planes, .. } => planes.get(i).copied(),
            Facets::Compact(packed) => {
                // A mixed node is an inner one.
                let (rec, r) = match &self.payload {
                    Payload::Compact { inner, .. } => {
                        self.unpack(inner.get(self.nodes.child(node) as usize)?, node)
                    }
                    Payload::Full { splat, .. } => {
                        (*splat.get(node as usize)?, self.nodes.get(node, field::R))
                    }
                };
                Some(FacetPlanes::of(&rec, r, &packed.get(i)?.unpack()))
            }
        }
    }

    /// Bytes of the facets a mixed node.
    pub(crate) fn facet_bytes(&self) -> usize {
        self.facets.bytes()
    }

    /// Bytes of payload, all nodes'.
    pub(crate) fn payload_bytes(&self) -> usize {
        use std::mem::size_of_val;
        match &self.payload {
            Payload::Full { splat, radiance } => size_of_val(&splat[..]) + size_of_val(&radiance[..]),
            Payload::Compact { inner, leaves } => size_of_val(&inner[..]) + size_of_val(&leaves[..]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rank_counts_the_set_nodes_before_each() {
        let set: Vec<bool> = (0..200).map(|k| k % 3 == 0 || k == 130).collect();
        let rank = Rank::new(set.iter().copied());
        let mut count = 0;
        for (k, &s) in set.iter().enumerate() {
            assert_eq!(rank.get(k), s.then_some(count), "node {k}");
            count += usize::from(s);
        }
        assert_eq!(rank.get(200), None);
    }

    /// A facet of random values in their ranges (a fifth of them with no
    /// area, a fifth with the light at the plane's centroid).
    fn random_cluster(next: &mut impl FnMut() -> f32) -> Cluster {
        let mut c = Cluster::NONE;
        for i in 0..FACETS {
            let n = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or_zero();
            let shown = if next() < 0.2 { 0.0 } else { next() };
            let l = Vec3::new(next(), next() * 0.01, next() * 100.0);
            let an = n * shown;
            c.facet[i] = [an.x, an.y, an.z, l.x, l.y, l.z];
            let p = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 2.0;
            c.plane[i] = [p.x, p.y, p.z, next() * 3.0];
            let light = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 2.0;
            c.light[i] = if next() < 0.2 {
                p.to_array()
            } else {
                light.to_array()
            };
        }
        c
    }

    #[test]
    fn facets_come_back_within_half_a_step() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let offset_step = 0.5 / FACET_STEPS as f32 + 1e-7;
        for case in 0..2000 {
            let c = random_cluster(&mut next);
            let back = PackedFacets::pack(&c).unpack();
            for i in 0..FACETS {
                let (f, g) = (c.facet[i], back.facet[i]);
                let (an, bn) = (Vec3::new(f[0], f[1], f[2]), Vec3::new(g[0], g[1], g[2]));
                // The normal within a step of its direction (its three
                // components each within half a step), the length within half.
                assert!(
                    (an - bn).abs().max_element() <= 1.5 / STEPS as f32 * an.length() + 0.5 / MANTISSA as f32,
                    "case {case} facet {i}: {an} came back {bn}"
                );
                let (l, m) = (Vec3::new(f[3], f[4], f[5]), Vec3::new(g[3], g[4], g[5]));
                assert!(
                    (l - m).abs().max_element() <= l.max_element() / MANTISSA as f32,
                    "case {case} facet {i}: radiance {l} came back {m}"
                );
                let (p, q) = (c.plane[i], back.plane[i]);
                for a in 0..3 {
                    assert!(
                        (p[a] - q[a]).abs() <= offset_step,
                        "case {case} facet {i}: plane {p:?} came back {q:?}"
                    );
                    let (x, y) = (c.light[i][a], back.light[i][a]);
                    assert!(
                        (x - y).abs() <= offset_step,
                        "case {case} facet {i}: light {x} came back {y}"
                    );
                }
                // How far the disks leave the plane is a bound: rounded up.
                assert!(
                    q[3] >= p[3] && q[3] <= p[3] + 1.0 / LIFT_STEPS as f32 + 1e-6,
                    "case {case} facet {i}: lift {} came back {}",
                    p[3],
                    q[3]
                );
                // A light at its plane's centroid stays there.
                assert_eq!(
                    c.light[i][..] == p[..3],
                    back.light[i][..] == q[..3],
                    "case {case} facet {i}: whether the light is shifted changed"
                );
            }
        }
    }

    /// A compact tree in a file reads back to the facets and the planes it
    /// derives, bit for bit (a file holds what a compact tree decodes).
    #[test]
    fn compact_facets_read_back_from_a_file() {
        let cloud = crate::synthetic::box_with_blocks(3000, 5);
        let tree = Tree::build_with(&cloud, Precision::Compact);
        assert!(tree.facets.len() > 10, "{} mixed nodes", tree.facets.len());
        let file = crate::TreeFile::new(cloud, tree.clone(), Default::default()).expect("a built tree");
        let back = crate::TreeFile::from_bytes(&file.to_bytes()).expect("it reads back");
        assert_eq!(back.tree().precision(), Precision::Full);
        for k in 0..tree.len() as NodeId {
            let facets = |t: &Tree| t.cluster_of(k).map(|c| c.get());
            assert_eq!(facets(back.tree()), facets(&tree), "node {k}");
            assert_eq!(back.tree().planes_of(k), tree.planes_of(k), "node {k}");
        }
    }

    #[test]
    fn radiance_keeps_its_range_and_black() {
        for l in [
            Vec3::ZERO,
            Vec3::new(0.0, 1e-30, 0.0),
            Vec3::splat(3e38),
            Vec3::new(65535.0, 1.0, 0.5),
        ] {
            let (m, e) = pack_radiance(l);
            let back = unpack_radiance(m, e);
            let top = l.max_element();
            assert!(
                (back - l).abs().max_element() <= top / 65535.0,
                "{l} came back {back}"
            );
        }
    }
}
