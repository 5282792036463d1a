//! A mixed node's facets ([`Cluster`]), stored whole with what the
//! microbuffer derives of them ([`FacetPlanes`]), or packed in 88 bytes
//! with those derived where they are read ([`Precision::Compact`]).

use glam::Vec3;

use super::bytes::{Reader, put_i16, put_u16};
use super::payload::{MANTISSA, Payload, STEPS, pack_radiance, step, unpack_radiance};
use super::store::{Plain, Store};
use super::{Cluster, FACETS, FacetPlanes, NodeId, Precision, Tree, field};

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
#[repr(C)]
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

    /// Bytes of one mixed node's facets in a tree file: their memory image,
    /// little-endian, padding zero.
    pub(crate) const BYTES: usize = 88;

    /// Appends the facets' bytes (in field order, as `repr(C)` lays them out:
    /// one byte of padding after the exponents).
    pub(crate) fn put(&self, out: &mut Vec<u8>) {
        self.normal.iter().flatten().for_each(|&v| put_i16(out, v));
        self.shown.iter().for_each(|&v| put_u16(out, v));
        self.radiance.iter().flatten().for_each(|&v| put_u16(out, v));
        out.extend_from_slice(&self.exponent);
        out.push(0);
        self.plane.iter().flatten().for_each(|&v| put_i16(out, v));
        self.lift.iter().for_each(|&v| put_u16(out, v));
        self.light.iter().flatten().for_each(|&v| put_i16(out, v));
    }

    /// Reads facets [`put`](Self::put) wrote.
    pub(crate) fn get(rd: &mut Reader) -> PackedFacets {
        let mut p = PackedFacets::default();
        p.normal.iter_mut().flatten().for_each(|v| *v = rd.i16());
        p.shown.iter_mut().for_each(|v| *v = rd.u16());
        p.radiance.iter_mut().flatten().for_each(|v| *v = rd.u16());
        p.exponent.iter_mut().for_each(|v| *v = rd.u8());
        rd.skip(1);
        p.plane.iter_mut().flatten().for_each(|v| *v = rd.i16());
        p.lift.iter_mut().for_each(|v| *v = rd.u16());
        p.light.iter_mut().flatten().for_each(|v| *v = rd.i16());
        p
    }
}

// SAFETY: `repr(C)`, integers and floats; `put` writes the memory image.
unsafe impl Plain for PackedFacets {}

const _: () = assert!(std::mem::size_of::<PackedFacets>() == PackedFacets::BYTES);

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
    Compact(Store<PackedFacets>),
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
            Precision::Compact => {
                Facets::Compact(cluster.iter().map(PackedFacets::pack).collect::<Vec<_>>().into())
            }
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

impl Tree {
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
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// A compact tree in a file reads back as a compact tree, to the facets
    /// and the planes it derives, bit for bit.
    #[test]
    fn compact_facets_read_back_from_a_file() {
        let cloud = crate::synthetic::box_with_blocks(3000, 5);
        let tree = Tree::build_with(&cloud, Precision::Compact);
        assert!(tree.facets.len() > 10, "{} mixed nodes", tree.facets.len());
        let file = crate::TreeFile::new(cloud, tree.clone(), Default::default()).expect("a built tree");
        let back = crate::TreeFile::from_bytes(&file.to_bytes()).expect("it reads back");
        assert_eq!(back.tree().precision(), Precision::Compact);
        for k in 0..tree.len() as NodeId {
            let facets = |t: &Tree| t.cluster_of(k).map(|c| c.get());
            assert_eq!(facets(back.tree()), facets(&tree), "node {k}");
            assert_eq!(back.tree().planes_of(k), tree.planes_of(k), "node {k}");
        }
    }
}
