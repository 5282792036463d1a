//! What splatting reads of each node (its [`SplatRecord`] and radiance),
//! stored whole or packed, and which node's facets a mixed node's are (its
//! facets themselves are in `tree/facets.rs`).
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
use super::bytes::{Reader, put_f32, put_i16, put_u16};
use super::store::{Plain, Store};
use super::{Cluster, LEAF, LEAF_BIT, NodeArrays, NodeId, SplatRecord, Tree, field};
use crate::points::Surfel;

/// How a tree stores what splatting reads of its nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Precision {
    /// `f32` fields: 80 bytes a node, and 260 a mixed node's facets. The
    /// reference the compact tree is measured against.
    Full,
    /// Quantized against each node's bounding sphere: 32 bytes an inner
    /// node, 12 a leaf, 88 a mixed node's facets. The renderer's default:
    /// its images match the full tree's within noise, in under half the
    /// memory.
    #[default]
    Compact,
}

/// Offset steps per bounding radius, and normal steps per unit.
pub(super) const STEPS: f64 = 32767.0;
/// Mantissa steps of the brightest radiance channel.
pub(super) const MANTISSA: f64 = 65535.0;
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
pub(super) fn step(x: f64) -> i16 {
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
pub(super) fn pack_radiance(l: Vec3) -> ([u16; 3], u8) {
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
pub(super) fn unpack_radiance(m: [u16; 3], e: u8) -> Vec3 {
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

    /// Bytes of one record in a tree file: its memory image, little-endian,
    /// padding zero.
    pub(crate) const BYTES: usize = 32;

    /// Appends the record's bytes.
    pub(crate) fn put(&self, out: &mut Vec<u8>) {
        put_f32(out, self.area);
        for v in self.centroid.iter().chain(&self.light).chain(&self.normal) {
            put_i16(out, *v);
        }
        self.radiance.iter().for_each(|&v| put_u16(out, v));
        out.extend_from_slice(&[self.exponent, self.kind, 0, 0]);
    }

    /// Reads a record [`put`](Self::put) wrote.
    pub(crate) fn get(rd: &mut Reader) -> PackedSplat {
        let mut p = PackedSplat {
            area: rd.f32(),
            ..PackedSplat::default()
        };
        for v in p.centroid.iter_mut().chain(&mut p.light).chain(&mut p.normal) {
            *v = rd.i16();
        }
        p.radiance.iter_mut().for_each(|v| *v = rd.u16());
        (p.exponent, p.kind) = (rd.u8(), rd.u8());
        rd.skip(2);
        p
    }
}

/// A leaf's splat record: its area and radiance, in 12 bytes. The rest is
/// its surfel's disk as its pair record holds it (centre, and normal as the
/// cone's axis), so a leaf costs no splat record of 32 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
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

    /// Bytes of one leaf in a tree file: its memory image, little-endian,
    /// padding zero.
    pub(crate) const BYTES: usize = 12;

    /// Appends the leaf's bytes.
    pub(crate) fn put(&self, out: &mut Vec<u8>) {
        put_f32(out, self.area);
        self.radiance.iter().for_each(|&v| put_u16(out, v));
        out.extend_from_slice(&[self.exponent, 0]);
    }

    /// Reads a leaf [`put`](Self::put) wrote.
    pub(crate) fn get(rd: &mut Reader) -> PackedLeaf {
        let area = rd.f32();
        let radiance = [rd.u16(), rd.u16(), rd.u16()];
        let exponent = rd.u8();
        rd.skip(1);
        PackedLeaf {
            area,
            radiance,
            exponent,
        }
    }
}

// SAFETY: `repr(C)`, integers and floats; `put` writes the memory image.
unsafe impl Plain for PackedSplat {}
// SAFETY: as for `PackedSplat`.
unsafe impl Plain for PackedLeaf {}

const _: () = assert!(std::mem::size_of::<PackedSplat>() == PackedSplat::BYTES);
const _: () = assert!(std::mem::size_of::<PackedLeaf>() == PackedLeaf::BYTES);

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
        inner: Store<PackedSplat>,
        leaves: Store<PackedLeaf>,
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
    pub(super) fn unpack(&self, p: &PackedSplat, node: NodeId) -> (SplatRecord, f32) {
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
