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
//! decoded sphere, and last that the tree written again gives the file's
//! bytes: padding, the unused entry and the light offsets (which the build
//! derives) are then as the build writes them.

use super::bytes::Reader;
use super::check::{self, Fault, Place};
use super::facets::PackedFacets;
use super::payload::{PackedLeaf, PackedSplat};
use super::quantize::CompactPair;
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
    facets: u64,
    pub end: u64,
}

impl Sections {
    pub fn of(surfels_end: u64, n: u64, clusters: u64) -> Sections {
        let pairs = padded(surfels_end);
        // Each a multiple of 4 bytes, from a multiple of 64.
        let node = (CompactPair::BYTES + PackedSplat::BYTES + PackedLeaf::BYTES) as u64;
        let facets = padded(pairs + node * n);
        let end = padded(facets + PackedFacets::BYTES as u64 * clusters);
        Sections { pairs, facets, end }
    }
}

/// Zero bytes up to `to`.
fn pad(out: &mut Vec<u8>, to: u64) {
    out.resize(to as usize, 0);
}

/// Appends a compact tree's sections; `out` holds the header and surfels.
pub(super) fn put(tree: &Tree, out: &mut Vec<u8>) {
    let (NodeArrays::Compact(pairs), Payload::Compact { inner, leaves }, Facets::Compact(facets)) =
        (&tree.nodes, &tree.payload, &tree.facets)
    else {
        unreachable!("a compact tree's arrays are all compact");
    };
    let at = Sections::of(out.len() as u64, pairs.len() as u64, facets.len() as u64);
    pad(out, at.pairs);
    pairs.iter().for_each(|p| p.put(out));
    inner.iter().for_each(|p| p.put(out));
    leaves.iter().for_each(|l| l.put(out));
    pad(out, at.facets);
    facets.iter().for_each(|f| f.put(out));
    pad(out, at.end);
}

/// A section's fault as the reader reports it: the byte offset of the
/// record at fault, and what is wrong.
pub(super) type Invalid = (u64, String);

/// Reads the sections [`put`] wrote for `n` surfels and `clusters` mixed
/// nodes of a tree of depth `depth`, from `bytes` (the whole file, less its
/// checksum, of the length [`Sections::of`] gives), and checks them (see the
/// module's notes).
pub(super) fn get(
    bytes: &[u8],
    surfels_end: usize,
    n: usize,
    clusters: usize,
    depth: u32,
) -> Result<Tree, Invalid> {
    let at = Sections::of(surfels_end as u64, n as u64, clusters as u64);
    let mut rd = Reader {
        bytes,
        at: at.pairs as usize,
    };
    let pairs: Vec<CompactPair> = (0..n).map(|_| CompactPair::get(&mut rd)).collect();
    let inner = (0..n).map(|_| PackedSplat::get(&mut rd)).collect();
    let leaves = (0..n).map(|_| PackedLeaf::get(&mut rd)).collect();
    rd.at = at.facets as usize;
    let facets = (0..clusters).map(|_| PackedFacets::get(&mut rd)).collect();
    let mut tree = Tree {
        nodes: NodeArrays::Compact(pairs),
        payload: Payload::Compact { inner, leaves },
        mixed: Rank::default(),
        facets: Facets::Compact(facets),
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
    tree.derive();
    let mut again = bytes[..surfels_end].to_vec();
    put(&tree, &mut again);
    if let Some(i) = (0..again.len()).find(|&i| again[i] != bytes[i]) {
        return Err((
            i as u64,
            "differs from the tree written again (padding, the unused record, or a light offset \
             other than the one the tree derives)"
                .into(),
        ));
    }
    Ok(tree)
}
