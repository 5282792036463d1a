//! A compact tree's part of a tree file (format version
//! [`COMPACT_VERSION`](super::file::COMPACT_VERSION)): its arrays as they
//! lie in memory, so the file is the tree's own size and a reader can take
//! each array in one piece. After the header and the surfels, every section
//! starting on a multiple of 64 bytes (zero bytes between):
//!
//! | size | section |
//! | --- | --- |
//! | 64 n | pair records ([`CompactPair`]), record 0 the root's |
//! | 32 n | inner nodes' packed splat records ([`PackedSplat`]), by child link (entry 0 unused, zero) |
//! | 12 n | leaves ([`PackedLeaf`]), by surfel |
//! | 88 per cluster | mixed nodes' facets ([`PackedFacets`]), by rank |
//!
//! A reader checks the structure before anything indexes by a link, then
//! the decoded values, then that each record decodes against its parent's
//! decoded sphere and holds the light offset the tree derives, and last
//! that the tree written again gives the file's bytes (padding and the
//! unused entry as the build writes them), record by record. Nothing is
//! derived again, so a mapped file ([`Store`]) is used where it lies.

use super::bytes::Reader;
use super::check::{self, Fault, Place};
use super::facets::PackedFacets;
use super::payload::{PackedLeaf, PackedSplat};
use super::quantize::{self, CompactPair};
use super::store::{Map, Store};
use super::{Facets, MIXED, NodeArrays, Payload, Rank, Tree};

/// Sections start on multiples of this.
const ALIGN: u64 = 64;

fn padded(x: u64) -> u64 {
    x.div_ceil(ALIGN) * ALIGN
}

/// Where each section starts, for `n` surfels and `clusters` mixed nodes,
/// the surfels ending at `surfels_end`; and where the last ends.
pub(super) struct Sections {
    pairs: u64,
    nodes_end: u64,
    facets: u64,
    facets_end: u64,
    pub end: u64,
}

impl Sections {
    pub fn of(surfels_end: u64, n: u64, clusters: u64) -> Sections {
        let pairs = padded(surfels_end);
        // Each a multiple of 4 bytes, from a multiple of 64.
        let node = (CompactPair::BYTES + PackedSplat::BYTES + PackedLeaf::BYTES) as u64;
        let nodes_end = pairs + node * n;
        let facets = padded(nodes_end);
        let facets_end = facets + PackedFacets::BYTES as u64 * clusters;
        Sections {
            pairs,
            nodes_end,
            facets,
            facets_end,
            end: padded(facets_end),
        }
    }
}

/// A compact tree's sections from byte `start` (the end of the surfels),
/// passed to `emit` a record (or a run of padding) at a time.
fn sections(tree: &Tree, start: u64, emit: &mut dyn FnMut(&[u8])) {
    let (NodeArrays::Compact(pairs), Payload::Compact { inner, leaves }, Facets::Compact(facets)) =
        (&tree.nodes, &tree.payload, &tree.facets)
    else {
        unreachable!("a compact tree's arrays are all compact");
    };
    let at = Sections::of(start, pairs.len() as u64, facets.len() as u64);
    let zeros = [0u8; ALIGN as usize];
    let mut record = Vec::with_capacity(PackedFacets::BYTES);
    let mut one = |put: &dyn Fn(&mut Vec<u8>)| {
        record.clear();
        put(&mut record);
        emit(&record);
    };
    one(&|out| out.extend_from_slice(&zeros[..(at.pairs - start) as usize]));
    pairs.iter().for_each(|p| one(&|out| p.put(out)));
    inner.iter().for_each(|p| one(&|out| p.put(out)));
    leaves.iter().for_each(|l| one(&|out| l.put(out)));
    one(&|out| out.extend_from_slice(&zeros[..(at.facets - at.nodes_end) as usize]));
    facets.iter().for_each(|f| one(&|out| f.put(out)));
    one(&|out| out.extend_from_slice(&zeros[..(at.end - at.facets_end) as usize]));
}

/// Appends a compact tree's sections; `out` holds the header and surfels.
pub(super) fn put(tree: &Tree, out: &mut Vec<u8>) {
    sections(tree, out.len() as u64, &mut |b| out.extend_from_slice(b));
}

/// The first byte from `start` on where `bytes` differ from the tree's
/// sections.
fn first_difference(tree: &Tree, bytes: &[u8], start: usize) -> Option<usize> {
    let (mut at, mut found) = (start, None);
    sections(tree, start as u64, &mut |b| {
        if found.is_none() {
            found = b
                .iter()
                .zip(&bytes[at..])
                .position(|(x, y)| x != y)
                .map(|i| at + i);
        }
        at += b.len();
    });
    found
}

/// Node `k`'s stored light offset is the one the tree derives of its
/// centroids ([`Tree::derive`]).
fn light_offset_derived(tree: &Tree, pairs: &[CompactPair], k: u32) -> bool {
    let offset = tree.splat_record(k).expect("a node").light_offset();
    let (p, s) = NodeArrays::locate(k);
    let pair = &pairs[p];
    pair.light_offset[s] == quantize::light_offset_steps(pair.base, pair.steps(s), offset)
}

/// A section's fault as the reader reports it: the byte offset of the
/// record at fault, and what is wrong.
pub(super) type Invalid = (u64, String);

/// Reads the sections [`put`] wrote for `n` surfels and `clusters` mixed
/// nodes of a tree of depth `depth`, from `bytes` (the whole file, less its
/// checksum, of the length [`Sections::of`] gives), and checks them (see the
/// module's notes). Where `map` is the file `bytes` lie in, the arrays are
/// used in place.
pub(super) fn get(
    bytes: &[u8],
    map: Option<&Map>,
    surfels_end: usize,
    n: usize,
    clusters: usize,
    depth: u32,
) -> Result<Tree, Invalid> {
    let at = Sections::of(surfels_end as u64, n as u64, clusters as u64);
    fn array<T: super::store::Plain>(
        bytes: &[u8],
        map: Option<&Map>,
        at: usize,
        len: usize,
        get: fn(&mut Reader) -> T,
    ) -> Store<T> {
        Store::take(map, at, len, || {
            let mut rd = Reader { bytes, at };
            (0..len).map(|_| get(&mut rd)).collect()
        })
    }
    let pairs_at = at.pairs as usize;
    let inner_at = pairs_at + CompactPair::BYTES * n;
    let leaves_at = inner_at + PackedSplat::BYTES * n;
    let mut tree = Tree {
        nodes: NodeArrays::Compact(array(bytes, map, pairs_at, n, CompactPair::get)),
        payload: Payload::Compact {
            inner: array(bytes, map, inner_at, n, PackedSplat::get),
            leaves: array(bytes, map, leaves_at, n, PackedLeaf::get),
        },
        mixed: Rank::default(),
        facets: Facets::Compact(array(bytes, map, at.facets as usize, clusters, PackedFacets::get)),
        depth,
    };
    let place = |fault: Fault| {
        let offset = match fault.place {
            Place::Node(k) => at.pairs + CompactPair::BYTES as u64 * NodeArrays::locate(k).0 as u64,
            Place::Cluster(i) => at.facets + PackedFacets::BYTES as u64 * i as u64,
            Place::Depth => 60,
        };
        (offset, fault.what)
    };
    // Links first: everything after indexes by them.
    check::structure(&tree, n).map_err(place)?;
    let kinds = (0..tree.len() as u32).map(|k| tree.splat_record(k).map(|r| r.kind));
    tree.mixed = Rank::new(kinds.map(|kind| kind == Some(MIXED)));
    let mixed = (0..tree.len()).filter(|&k| tree.mixed.get(k).is_some()).count();
    if mixed != clusters {
        return Err((56, format!("{clusters} clusters, but {mixed} mixed nodes")));
    }
    check::values(&tree)
        .and_then(|()| check::bases(&tree))
        .map_err(place)?;
    if let NodeArrays::Compact(pairs) = &tree.nodes
        && let Some(k) = (0..tree.len() as u32).find(|&k| !light_offset_derived(&tree, pairs, k))
    {
        return Err(place(Fault {
            place: Place::Node(k),
            what: format!("node {k}: a light offset other than the one its centroids give"),
        }));
    }
    if let Some(i) = first_difference(&tree, bytes, surfels_end) {
        return Err((
            i as u64,
            "differs from the tree written again (padding, or the unused splat record)".into(),
        ));
    }
    Ok(tree)
}
