//! The bounding-sphere hierarchy (BSH): a binary tree over the surfels, stored
//! as sibling-pair records, structure-of-arrays within each pair, so the
//! kernels load node fields straight into lanes.
//!
//! Node `0` is the root. Siblings are adjacent (`left`, `left + 1`) and a left
//! subtree is stored before its right sibling's, so the depth-first kernels walk
//! memory mostly forwards. Leaves hold exactly one surfel.
//!
//! The build splits at the median along the widest axis of the surfel
//! positions, with the surfel index breaking ties, so it is `O(n log n)`,
//! deterministic, of depth `⌈log₂ n⌉`, and terminates on any input (a million
//! coincident surfels included). Bounds are computed in `f64` and rounded
//! outwards to `f32`; every operation is homogeneous in the coordinates, so
//! scaling the input by `2^k` scales the tree's spheres by exactly `2^k`.
//!
//! A tree is stored at a [`Precision`]: `f32` fields, or compact, with each
//! pair record's node-test fields in 16-bit steps against its parent's
//! sphere (`tree/quantize.rs`) and each node's splat record and radiance in 32
//! bytes (`tree/payload.rs`), its bounds still bounds. The build
//! writes either in place.
//!
//! [`file`](mod@file) writes the surfels and their tree to a `.pbgi` file and reads it
//! back, checked whole, so a render can skip building them.

use glam::Vec3;

use crate::points::PointCloud;

mod bound;
mod build;
pub(crate) mod bytes;
pub(crate) use bound::FacetPlanes;
mod check;
mod compact_file;
mod facets;
pub mod file;
mod payload;
pub(crate) mod quantize;
mod store;

pub(crate) use facets::{ClusterRef, Facets};
pub use file::{BakeRecord, TreeFile, TreeFileError};
pub use payload::Precision;
pub(crate) use payload::{PackedLeaf, Payload, Rank};
pub(crate) use quantize::CompactPair;
use store::Store;

/// Index of a node in a [`Tree`].
pub type NodeId = u32;

/// Bit set in [`NodeArrays::child`] for a leaf; the low bits hold its surfel.
pub(crate) const LEAF_BIT: u32 = 1 << 31;

/// Bound on the tree depth (levels below the root): `⌈log₂ MAX_SURFELS⌉`.
pub const MAX_DEPTH: usize = 30;

/// Levels the split by orientation (a hollow solid's two sides, which need
/// not hold half the surfels each) may add to the median split's
/// `⌈log₂ n⌉`: a tree of `n` surfels is at most `⌈log₂ n⌉ + EXTRA_DEPTH`
/// deep, and never deeper than [`MAX_DEPTH`].
pub const EXTRA_DEPTH: usize = 4;

/// Index of a field in [`PairRecord::f`].
pub(crate) mod field {
    pub const CX: usize = 0;
    pub const CY: usize = 1;
    pub const CZ: usize = 2;
    pub const R: usize = 3;
    pub const AX: usize = 4;
    pub const AY: usize = 5;
    pub const AZ: usize = 6;
    pub const COS: usize = 7;
    pub const SIN: usize = 8;
    /// How far the node's light centroid lies from its area centroid
    /// ([`super::Tree::derive`]; not stored in a tree file).
    pub const LIGHT_OFFSET: usize = 9;
    /// Fields a tree file stores.
    pub const STORED: usize = 9;
    pub const COUNT: usize = 10;
}

/// The node-test fields of two sibling nodes, structure-of-arrays within the
/// pair: `f[field][slot]`. Both children of a traversed node are always tested
/// together, so a pair is the unit the kernels load: single reads field `j`
/// of 8 pairs as 8 contiguous two-float chunks straight into 16 lanes, and a
/// pair spans at most two cache lines (ten with one array per field).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct PairRecord {
    /// Per field: bounding-sphere centre x, y, z and radius (the sphere holds
    /// every disk below the node); normal-cone axis x, y, z (unit); cosine and
    /// sine of the cone half-angle, rounded outwards (a cone wider than a
    /// hemisphere is stored as `(0, 1)`, which never culls); how far its
    /// light centroid lies from its area centroid.
    pub f: [[f32; 2]; field::COUNT],
    /// Per slot: the pair record of the node's children, or `LEAF_BIT | surfel`.
    pub child: [u32; 2],
}

/// The node-test fields of the whole tree. Node `n` lives in record
/// `(n + 1) / 2`, slot `(n + 1) % 2`: the root alone in record 0 (slot 1), then
/// the sibling pairs `(2p − 1, 2p)` in record `p`. Full records hold `f32`
/// fields; compact ones ([`quantize`]) 16-bit steps against the parent.
#[derive(Clone, Debug)]
pub(crate) enum NodeArrays {
    Full(Vec<PairRecord>),
    Compact(Store<CompactPair>),
}

impl Default for NodeArrays {
    fn default() -> Self {
        NodeArrays::Full(Vec::new())
    }
}

impl NodeArrays {
    /// Record and slot of node `n`.
    #[inline(always)]
    pub fn locate(n: u32) -> (usize, usize) {
        let m = n as usize + 1;
        (m >> 1, m & 1)
    }

    /// First node id of pair record `p` (its slot 0).
    #[inline(always)]
    pub fn first_of_pair(p: u32) -> u32 {
        (2 * p).wrapping_sub(1)
    }

    /// Field `j` of node `n` (decoded).
    #[inline(always)]
    pub fn get(&self, n: u32, j: usize) -> f32 {
        let (p, s) = Self::locate(n);
        match self {
            NodeArrays::Full(pairs) => pairs[p].f[j][s],
            NodeArrays::Compact(pairs) => pairs[p].decoded(s)[j],
        }
    }

    /// Every field of node `n` (decoded once), in the order of [`field`].
    #[inline(always)]
    pub fn fields(&self, n: u32) -> [f32; field::COUNT] {
        let (p, s) = Self::locate(n);
        match self {
            NodeArrays::Full(pairs) => std::array::from_fn(|j| pairs[p].f[j][s]),
            NodeArrays::Compact(pairs) => pairs[p].decoded(s),
        }
    }

    /// Child pair record of node `n`, or `LEAF_BIT | surfel`.
    #[inline(always)]
    pub fn child(&self, n: u32) -> u32 {
        let (p, s) = Self::locate(n);
        match self {
            NodeArrays::Full(pairs) => pairs[p].child[s],
            NodeArrays::Compact(pairs) => pairs[p].child[s],
        }
    }

    /// Number of pair records.
    pub fn pairs(&self) -> usize {
        match self {
            NodeArrays::Full(pairs) => pairs.len(),
            NodeArrays::Compact(pairs) => pairs.len(),
        }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        (2 * self.pairs()).saturating_sub(1)
    }

    /// Bytes of a pair record.
    pub fn pair_bytes(&self) -> usize {
        match self {
            NodeArrays::Full(_) => std::mem::size_of::<PairRecord>(),
            NodeArrays::Compact(_) => std::mem::size_of::<CompactPair>(),
        }
    }

    /// Sets node `n`'s light offset (at least `offset`, in a compact record).
    fn set_light_offset(&mut self, n: u32, offset: f32) {
        let (p, s) = Self::locate(n);
        match self {
            NodeArrays::Full(pairs) => pairs[p].f[field::LIGHT_OFFSET][s] = offset,
            NodeArrays::Compact(pairs) => {
                let pair = &mut pairs.owned_mut()[p];
                pair.light_offset[s] = quantize::light_offset_steps(pair.base, pair.steps(s), offset);
            }
        }
    }
}

/// What splatting reads of a node, in one aligned 64-byte record (one cache
/// line): where it is splatted and where its light comes from, the area
/// below it, the area-weighted mean normal, its kind, and what the
/// microbuffer derives of its bounds ([`SplatRecord::derive`]), so that a
/// splat reads no other node array.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct SplatRecord {
    /// Where the node is splatted ([`NodeView::centroid`]).
    pub centroid: [f32; 3],
    pub area: f32,
    pub normal: [f32; 3],
    /// [`PLANAR`], [`LEAF`] or [`MIXED`].
    pub kind: u32,
    /// Where its light comes from ([`NodeView::light_centroid`]).
    pub light_centroid: [f32; 3],
    /// How far the node's surface may rise above its centroid along a unit
    /// direction at sine `s` to its normal: `rise·s + lift` (a leaf: its
    /// disk's radius and 0; a planar cluster: `R` and `R·sin β`, its plane
    /// and how far its surfels leave it; a mixed one: unbounded).
    pub rise: f32,
    pub lift: f32,
    /// A cluster's bounding radius `R` (0 for a leaf).
    pub radius: f32,
    /// Whether a cluster's light centroid (a mixed one's: a facet's) is not
    /// its area centroid.
    pub shifted: bool,
}

impl SplatRecord {
    /// How far the light centroid lies from the area centroid
    /// ([`crate::CutOptions::light_offset`]).
    pub(crate) fn light_offset(&self) -> f32 {
        Vec3::from_array(self.light_centroid).distance(Vec3::from_array(self.centroid))
    }

    /// `rise`, `lift` and `radius` of a node of kind `kind`, area `area`,
    /// bounding radius `radius` and cone sine `sin`.
    #[inline(always)]
    pub(crate) fn bounds(kind: u32, area: f32, radius: f32, sin: f32) -> (f32, f32, f32) {
        match kind {
            LEAF => ((area * std::f32::consts::FRAC_1_PI).sqrt(), 0.0, 0.0),
            PLANAR => (radius, radius * sin, radius),
            _ => (0.0, f32::INFINITY, radius),
        }
    }

    /// Fills the derived fields from the node's bounding radius `radius`,
    /// its cone's sine `sin` and, for a [`MIXED`] node, its `cluster`.
    pub(crate) fn derive(&mut self, radius: f32, sin: f32, cluster: &Cluster) {
        (self.rise, self.lift, self.radius) = Self::bounds(self.kind, self.area, radius, sin);
        self.shifted = match self.kind {
            PLANAR => self.light_centroid != self.centroid,
            MIXED => cluster
                .light
                .iter()
                .zip(&cluster.plane)
                .any(|(l, p)| l[..] != p[..3]),
            _ => false,
        };
    }
}

/// An inner node whose surfels' normals form one [`Cluster`] facet: it
/// shows its mean normal's projected area and its mean radiance.
pub(crate) const PLANAR: u32 = 0;
/// A leaf: its surfel's disk.
pub(crate) const LEAF: u32 = 1;
/// An inner node whose normals form two or three facets: it shows the
/// projected area and the radiance of its [`Cluster`] toward the receiver.
pub(crate) const MIXED: u32 = 2;
/// Facets of a cluster.
pub(crate) const FACETS: usize = 3;

/// A cluster's light by direction, as up to three facets: the surfels
/// grouped by normal, each group with its area `A`, area-weighted mean normal
/// `n̄` and mean radiance `L̄`. Seen from unit direction `u` it shows the area
/// `Σ A·max(0, n̄·u)` and the radiance `Σ L̄·A·max(0, n̄·u) / area`, exact for a
/// cluster of at most three flat pieces (a box's corner, a wall's foot, a
/// thin panel's two sides), where one mean normal and one mean radiance show
/// a corner's cluster with its floor's light blended with its wall's, and
/// one holding both sides of a panel with no area at all.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct Cluster {
    /// Per facet: `A·n̄ / A_node` (x, y, z: the area-weighted normal sum as a
    /// fraction of the node's area, so at most 1 in length and free of the
    /// scene's scale), then its mean radiance `P/A` (r, g, b).
    pub facet: [[f32; 6]; FACETS],
    /// Per facet, where it lies, in units of the node's bounding radius `R`:
    /// its area-weighted centroid less the node's area centroid (x, y, z:
    /// at most 2 in length), then how far its surfels' disks leave the
    /// plane through that centroid along its mean normal. The microbuffer shows each facet
    /// as the disk of its area on that plane (its outline and its depth),
    /// where one round cone at the centre, `±R` deep, merged a box's top with
    /// the floor behind it and let the light behind its edges through.
    pub plane: [[f32; 4]; FACETS],
    /// Per facet, where its light comes from, in the same units: its
    /// light centroid (its surfels weighted by area times `|L|₁`; its area
    /// centroid where they send none) less the node's area centroid.
    pub light: [[f32; 3]; FACETS],
}

impl Cluster {
    /// No light in any direction (what a node that is not [`MIXED`] reads).
    pub(crate) const NONE: Cluster = Cluster {
        facet: [[0.0; 6]; FACETS],
        plane: [[0.0; 4]; FACETS],
        light: [[0.0; 3]; FACETS],
    };
}

/// A read-only view of one node, for inspection and tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeView {
    /// Bounding-sphere centre.
    pub center: Vec3,
    /// Bounding-sphere radius.
    pub radius: f32,
    /// Normal-cone axis.
    pub cone_axis: Vec3,
    /// Cosine of the cone half-angle (0 for a cone of a hemisphere or wider).
    pub cone_cos: f32,
    /// Sine of the cone half-angle.
    pub cone_sin: f32,
    /// Total surfel area below the node (saturating at `f32::MAX`).
    pub area: f32,
    /// Area-weighted mean normal (not normalized: shorter where normals spread).
    pub normal: Vec3,
    /// Area-weighted mean outgoing radiance.
    pub radiance: Vec3,
    /// Area centroid: where the node is splatted, its surface.
    pub centroid: Vec3,
    /// Light centroid: where its light comes from, the surfels' positions
    /// weighted by area times radiance (`|L|₁`); the area centroid where
    /// they send none.
    pub light_centroid: Vec3,
    /// How far the light centroid lies from the area centroid, as the far
    /// test reads it (a compact tree rounds it up to its next step).
    pub light_offset: f32,
    /// Left child (the right one is `left + 1`), `None` for a leaf.
    pub children: Option<NodeId>,
    /// The surfel of a leaf (index into the cloud), `None` for an inner node.
    pub surfel: Option<u32>,
}

/// The bounding-sphere hierarchy over a [`PointCloud`].
///
/// ```
/// use pbgi::{PointCloud, Surfel, Tree};
/// use glam::Vec3;
///
/// let surfels = (0..100)
///     .map(|i| Surfel {
///         position: Vec3::new(i as f32, 0.0, 0.0),
///         normal: Vec3::Y,
///         radius: 0.5,
///         radiance: Vec3::ONE,
///     })
///     .collect();
/// let tree = Tree::build(&PointCloud::new(surfels)?);
/// assert_eq!(tree.len(), 199);
/// assert_eq!(tree.depth(), 7);
/// # Ok::<(), pbgi::Error>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct Tree {
    pub(crate) nodes: NodeArrays,
    /// What splatting reads of each node, at the tree's [`Precision`].
    pub(crate) payload: Payload,
    /// Which nodes are [`MIXED`]; a mixed node's rank is the index of its
    /// facets in `facets`.
    pub(crate) mixed: Rank,
    /// The facets of the [`MIXED`] nodes (and, in a full tree, what is
    /// derived of them), at the tree's [`Precision`].
    pub(crate) facets: Facets,
    depth: u32,
}

impl Tree {
    /// Builds the hierarchy at [`Precision::Full`]. `O(n log n)`,
    /// deterministic, parallel over subtrees.
    pub fn build(cloud: &PointCloud) -> Tree {
        Tree::build_with(cloud, Precision::Full)
    }

    /// Builds the hierarchy with its payload at `precision`, written in
    /// place as the build goes: no node is held twice.
    pub fn build_with(cloud: &PointCloud, precision: Precision) -> Tree {
        let surfels = cloud.surfels();
        let n = surfels.len();
        let nodes = (2 * n).saturating_sub(1);
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut pairs = match precision {
            Precision::Full => NodeArrays::Full(vec![PairRecord::default(); n]),
            Precision::Compact => NodeArrays::Compact(vec![CompactPair::default(); n].into()),
        };
        let mut cluster: Vec<Option<Box<Cluster>>> = vec![None; nodes];
        let mut payload = match precision {
            Precision::Full => Payload::Full {
                splat: vec![SplatRecord::default(); nodes],
                radiance: vec![Vec3::ZERO; nodes],
            },
            Precision::Compact => Payload::Compact {
                inner: vec![Default::default(); n].into(),
                leaves: surfels.iter().map(PackedLeaf::of).collect::<Vec<_>>().into(),
            },
        };
        if n == 0 {
            return Tree {
                nodes: pairs,
                payload,
                facets: Facets::new(Vec::new(), precision),
                ..Tree::default()
            };
        }
        let (mut root, below) = build::Out::new(&mut pairs, &mut payload, &mut cluster).split(1);
        let budget = (build::ceil_log2(n) + EXTRA_DEPTH).min(MAX_DEPTH);
        // The root has pair record 0 to itself, in slot 1.
        let sphere = match precision {
            Precision::Full => build::Base::Full,
            Precision::Compact => build::Base::Root,
        };
        let top = build::build_subtree(surfels, &mut order, below, 1, budget, sphere);
        let depth = top.depth;
        // The root's record's base is the root's own full sphere.
        root.set_base(0, top.base);
        root.write(0, 1, top);
        let mut tree = Tree {
            nodes: pairs,
            payload,
            mixed: Rank::new(cluster.iter().map(Option::is_some)),
            facets: Facets::new(cluster.into_iter().flatten().map(|c| *c).collect(), precision),
            depth,
        };
        tree.derive();
        tree
    }

    /// Fills what is derived of the stored fields, where the tree is built
    /// or read: each splat record's bounds ([`SplatRecord::derive`]), and
    /// each node's light offset `|l − c|` (`l`, `c` its light and area
    /// centroids; [`crate::CutOptions::light_offset`]).
    pub(crate) fn derive(&mut self) {
        let mut planes = Vec::new();
        for k in 0..self.len() as u32 {
            let (r, sin) = (self.nodes.get(k, field::R), self.nodes.get(k, field::SIN));
            // Only a full tree derives anything of the facets here.
            let full = matches!(self.facets, Facets::Full { .. });
            let c = match self.cluster_of(k) {
                Some(c) if full => c.get(),
                _ => Cluster::NONE,
            };
            if let Payload::Full { splat, .. } = &mut self.payload {
                splat[k as usize].derive(r, sin, &c);
            }
            let rec = self.splat_record(k).expect("k < len");
            if let (Facets::Full { .. }, Some(_)) = (&self.facets, self.mixed.get(k as usize)) {
                planes.push(FacetPlanes::of(&rec, r, &c));
            }
            // Both centroids lie in the sphere (built so, or checked in a
            // file before this runs): at most `2R`, finite.
            self.nodes.set_light_offset(k, rec.light_offset());
        }
        if let Facets::Full { planes: p, .. } = &mut self.facets {
            *p = planes;
        }
    }

    /// Whether the tree's arrays lie in a mapped tree file (`TreeFile::open`,
    /// feature `mmap`) rather than in memory of their own.
    pub fn is_mapped(&self) -> bool {
        matches!(&self.nodes, NodeArrays::Compact(p) if p.is_mapped())
    }

    /// Number of nodes (`2n − 1` for `n` surfels, 0 for an empty cloud).
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True for the tree of an empty cloud.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Levels below the root (0 for a single surfel); at most [`MAX_DEPTH`].
    pub fn depth(&self) -> usize {
        self.depth as usize
    }

    /// Bytes of node data per surfel (the traversal fields, the splat
    /// records and radiance, and the facets of the mixed nodes with what is
    /// derived of them).
    pub fn bytes_per_surfel(&self) -> f64 {
        let pairs = self.nodes.pairs() * self.nodes.pair_bytes();
        let surfels = self.len().div_ceil(2).max(1);
        let facets = self.facets.len() * self.facet_bytes();
        (pairs + self.payload_bytes() + facets + self.mixed.bytes()) as f64 / surfels as f64
    }

    /// True when `node` is a leaf.
    #[inline]
    pub fn is_leaf(&self, node: NodeId) -> bool {
        self.nodes.child(node) & LEAF_BIT != 0
    }

    /// Left child of an inner node (the right one is `left + 1`).
    #[inline]
    pub fn left_child(&self, node: NodeId) -> Option<NodeId> {
        let c = self.nodes.child(node);
        (c & LEAF_BIT == 0).then(|| NodeArrays::first_of_pair(c))
    }

    /// Everything known about one node. Panics if `node` is out of range.
    pub fn node(&self, node: NodeId) -> NodeView {
        let a = &self.nodes;
        let g = |j| a.get(node, j);
        let c = a.child(node);
        let s = self.splat_record(node).expect("node in range");
        NodeView {
            center: Vec3::new(g(field::CX), g(field::CY), g(field::CZ)),
            radius: g(field::R),
            cone_axis: Vec3::new(g(field::AX), g(field::AY), g(field::AZ)),
            cone_cos: g(field::COS),
            cone_sin: g(field::SIN),
            area: s.area,
            normal: Vec3::from_array(s.normal),
            radiance: self.radiance(node),
            centroid: Vec3::from_array(s.centroid),
            light_centroid: Vec3::from_array(s.light_centroid),
            light_offset: g(field::LIGHT_OFFSET),
            children: self.left_child(node),
            surfel: (c & LEAF_BIT != 0).then_some(c & !LEAF_BIT),
        }
    }

    /// Total surfel area below `node` (shading payload).
    #[inline]
    pub fn area(&self, node: NodeId) -> f32 {
        self.splat_record(node).expect("node in range").area
    }

    /// Area-weighted mean normal below `node` (length ≤ 1; shorter where normals spread).
    #[inline]
    pub fn mean_normal(&self, node: NodeId) -> Vec3 {
        Vec3::from_array(self.splat_record(node).expect("node in range").normal)
    }

    /// Bounding-sphere radius of `node`.
    #[inline(always)]
    pub(crate) fn bounding_radius(&self, node: NodeId) -> f32 {
        if (node as usize) < self.len() {
            self.nodes.get(node, field::R)
        } else {
            0.0
        }
    }

    /// Bounding-sphere centre and radius of `node`.
    #[inline]
    pub fn sphere(&self, node: NodeId) -> (Vec3, f32) {
        let f = self.nodes.fields(node);
        (Vec3::new(f[field::CX], f[field::CY], f[field::CZ]), f[field::R])
    }

    /// Parent of every node (`None` for the root), for invariant checks.
    pub fn parents(&self) -> Vec<Option<NodeId>> {
        let mut parent = vec![None; self.len()];
        for k in 0..self.len() as u32 {
            if let Some(l) = self.left_child(k) {
                parent[l as usize] = Some(k);
                parent[l as usize + 1] = Some(k);
            }
        }
        parent
    }
}
