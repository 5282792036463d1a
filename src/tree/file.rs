//! The baked tree on disk (`.pbgi`): the surfels with their radiance and
//! the tree over them, so a render (or many, on many machines) skips the
//! `pre.` stage. std only.
//!
//! Layout, every field little-endian:
//!
//! | offset | size | field |
//! | --- | --- | --- |
//! | 0 | 8 | magic `PBGITREE` |
//! | 8 | 4 | format version: [`VERSION`] for a full tree, [`COMPACT_VERSION`] for a compact one |
//! | 12 | 40 | [`BakeRecord`]: scene hash u64, seed u64, density f32, light samples u32, bounces u32, flags u32 (bit 0 AO, bit 1 gathered, bit 2 surfels inside solids left out), Ω f32, microbuffer u32 |
//! | 52 | 12 | counts: surfels `n`, clusters (facets of the mixed nodes), tree depth (u32 each) |
//! | 64 | 40 n | surfels: position, normal, radius, radiance |
//! | | | a compact tree: its arrays as they lie in memory (see below) |
//! | | 96 (2n − 1) | a full tree's nodes: centre, radius, cone axis, cos, sin, child, area, mean normal, kind, radiance, area centroid, light centroid |
//! | | 156 per cluster | a full tree's facets: 3 × (area-weighted normal, radiance), then 3 × (the facet's centroid less the node's area centroid, reach), then 3 × (the facet's light centroid less the node's area centroid), in units of the node's radius |
//! | end − 8 | 8 | FNV-1a 64 of every byte before it |
//!
//! A reader checks, in this order, the magic, the version, the counts
//! against the length (before allocating anything), the checksum, and then
//! the structure: the tree must be laid out exactly as [`Tree::build`] lays
//! it out (child links in range, each pair used once, every surfel in one
//! leaf, the depth within [`MAX_DEPTH`](super::MAX_DEPTH)) and every value finite and in range,
//! because the kernels index with the child links unchecked.
//!
//! A compact tree ([`Precision::Compact`](super::Precision)) is written as
//! it lies in memory, each array in one piece, from a multiple of 64 bytes
//! on: 64 bytes a pair record, 32 an inner node's packed splat record, 12 a
//! leaf, 88 a mixed node's facets. Its reader checks the same, and also that
//! each record is quantized against its parent's decoded sphere and that
//! the tree written again gives the file's bytes.

use std::fmt;
use std::io::{Read, Write};

pub use super::bytes::{Fnv1a, checksum};
use super::bytes::{Reader, put_f32, put_u32, put_u64};
use super::check::{self, Place};
use super::store::Map;
use super::{Cluster, MIXED, NodeArrays, PairRecord, Precision, SplatRecord, Tree, compact_file, field};
use crate::points::{PointCloud, Surfel};

/// The first eight bytes of a tree file.
pub const MAGIC: [u8; 8] = *b"PBGITREE";
/// The format version of a full tree, which this library reads and writes.
pub const VERSION: u32 = 3;
/// The format version of a compact tree, which this library reads and writes.
pub const COMPACT_VERSION: u32 = 4;

const HEADER: usize = 64;
const SURFEL: usize = 40;
const NODE: usize = 96;
const CLUSTER: usize = 156;
const CHECKSUM: usize = 8;
const AO: u32 = 1;
const GATHERED: u32 = 2;
const DROP_BURIED: u32 = 4;

/// How the surfels' radiance was made, recorded so a render can refuse a
/// tree that contradicts its own settings. The renderer fills it
/// (`pbgi::render::bake_tree`); a cloud made another way may leave it
/// default.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BakeRecord {
    /// A hash of what the surfels' light depends on in the scene (geometry,
    /// materials, lights, environment; not the camera).
    pub scene: u64,
    /// Seed of the surfels' placement and light samples.
    pub seed: u64,
    /// Surfels per unit area.
    pub density: f32,
    /// Area-light samples per surfel (0 in AO mode).
    pub light_samples: u32,
    /// Indirect bounces the render asked for (those beyond the first are
    /// gathered into the surfels' radiance).
    pub bounces: u32,
    /// Ambient-occlusion mode: the surfels carry no radiance.
    pub ao: bool,
    /// Whether surfels inside solids were left out
    /// (`pbgi::render::BakeOptions::drop_buried`).
    pub drop_buried: bool,
    /// Whether the surfels' radiance was gathered through the tree (extra
    /// bounces, environment light), and so depends on Ω and the microbuffer.
    pub gathered: bool,
    /// Ω of the gathers at the surfels.
    pub max_solid_angle: f32,
    /// Microbuffer resolution of the gathers at the surfels.
    pub microbuffer: u32,
}

/// The surfels and the tree over them, with how they were made: what a
/// `.pbgi` file holds.
///
/// ```
/// use pbgi::tree::{BakeRecord, TreeFile};
/// use pbgi::{PointCloud, Surfel, Tree};
/// use glam::Vec3;
///
/// let surfels = (0..10)
///     .map(|i| Surfel { position: Vec3::new(i as f32, 0.0, 0.0), normal: Vec3::Y, radius: 0.5, radiance: Vec3::ONE })
///     .collect();
/// let cloud = PointCloud::new(surfels)?;
/// let tree = Tree::build(&cloud);
/// let file = TreeFile::new(cloud, tree, BakeRecord::default()).unwrap();
/// let mut bytes = Vec::new();
/// file.save(&mut bytes)?;
/// let back = TreeFile::load(bytes.as_slice()).unwrap();
/// assert_eq!(back.tree().len(), 19);
/// assert_eq!(back.to_bytes(), bytes);
///
/// bytes[20] ^= 1; // one flipped bit
/// assert!(matches!(TreeFile::load(bytes.as_slice()), Err(pbgi::tree::TreeFileError::Checksum { .. })));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct TreeFile {
    bake: BakeRecord,
    cloud: PointCloud,
    tree: Tree,
}

/// Why a tree file could not be read.
#[derive(Debug)]
#[non_exhaustive]
pub enum TreeFileError {
    /// Reading failed.
    Io(std::io::Error),
    /// The file ends at byte `offset`, before the `needed` bytes its header promises.
    Truncated {
        /// The file's length.
        offset: u64,
        /// The length it should have.
        needed: u64,
    },
    /// Not a tree file: the first eight bytes are not [`MAGIC`].
    BadMagic {
        /// The bytes found (fewer for a shorter file).
        found: Vec<u8>,
    },
    /// A version this library does not read.
    UnsupportedVersion {
        /// The file's version.
        found: u32,
        /// The newest read here ([`COMPACT_VERSION`]; [`VERSION`] too).
        supported: u32,
    },
    /// Bytes after the checksum, from `offset` on.
    TrailingBytes {
        /// Where the file should end.
        offset: u64,
    },
    /// The checksum at `offset` does not match the bytes before it.
    Checksum {
        /// Where the checksum is stored.
        offset: u64,
        /// The checksum stored.
        stored: u64,
        /// The checksum of the bytes.
        computed: u64,
    },
    /// A field is out of range or the tree's structure is broken.
    Invalid {
        /// The byte offset of the record (or field) at fault.
        offset: u64,
        /// What is wrong.
        what: String,
    },
}

impl fmt::Display for TreeFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TreeFileError::Io(e) => write!(f, "reading the tree file: {e}"),
            TreeFileError::Truncated { offset, needed } => {
                write!(
                    f,
                    "tree file truncated: it ends at byte {offset}, {needed} bytes expected"
                )
            }
            TreeFileError::BadMagic { found } => write!(
                f,
                "not a pbgi tree file (byte 0: {:?}, expected {:?})",
                String::from_utf8_lossy(found),
                String::from_utf8_lossy(&MAGIC)
            ),
            TreeFileError::UnsupportedVersion { found, supported } => write!(
                f,
                "tree file format version {found} at byte 8, this pbgi reads versions {VERSION} to {supported}: bake it again"
            ),
            TreeFileError::TrailingBytes { offset } => {
                write!(f, "tree file continues past its end at byte {offset}")
            }
            TreeFileError::Checksum {
                offset,
                stored,
                computed,
            } => write!(
                f,
                "tree file corrupted: checksum at byte {offset} is {stored:016x}, the bytes give {computed:016x}"
            ),
            TreeFileError::Invalid { offset, what } => write!(f, "tree file byte {offset}: {what}"),
        }
    }
}

impl std::error::Error for TreeFileError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            TreeFileError::Io(e) => Some(e),
            _ => None,
        }
    }
}

impl TreeFile {
    /// Surfels, the tree built over them ([`Tree::build`], here or in an
    /// earlier run) and how they were made. Errors: a tree of another size
    /// than the cloud's.
    pub fn new(cloud: PointCloud, tree: Tree, bake: BakeRecord) -> Result<Self, TreeFileError> {
        let want = (2 * cloud.len()).saturating_sub(1);
        if tree.len() != want {
            return Err(TreeFileError::Invalid {
                offset: 0,
                what: format!(
                    "a tree of {} nodes over {} surfels (expected {want})",
                    tree.len(),
                    cloud.len()
                ),
            });
        }
        Ok(Self { bake, cloud, tree })
    }

    /// How the surfels were made.
    pub fn bake(&self) -> &BakeRecord {
        &self.bake
    }

    /// The surfels.
    pub fn cloud(&self) -> &PointCloud {
        &self.cloud
    }

    /// The tree over them.
    pub fn tree(&self) -> &Tree {
        &self.tree
    }

    /// Gives the parts back.
    pub fn into_parts(self) -> (BakeRecord, PointCloud, Tree) {
        (self.bake, self.cloud, self.tree)
    }

    /// Writes the file.
    pub fn save(&self, mut w: impl Write) -> std::io::Result<()> {
        w.write_all(&self.to_bytes())?;
        w.flush()
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let (tree, n) = (&self.tree, self.cloud.len());
        let version = match tree.precision() {
            Precision::Full => VERSION,
            Precision::Compact => COMPACT_VERSION,
        };
        let size = file_len(version, n as u64, tree.facets.len() as u64) as usize;
        let mut out = Vec::with_capacity(size);
        let b = &self.bake;
        out.extend_from_slice(&MAGIC);
        put_u32(&mut out, version);
        put_u64(&mut out, b.scene);
        put_u64(&mut out, b.seed);
        put_f32(&mut out, b.density);
        put_u32(&mut out, b.light_samples);
        put_u32(&mut out, b.bounces);
        put_u32(
            &mut out,
            if b.ao { AO } else { 0 }
                | if b.gathered { GATHERED } else { 0 }
                | if b.drop_buried { DROP_BURIED } else { 0 },
        );
        put_f32(&mut out, b.max_solid_angle);
        put_u32(&mut out, b.microbuffer);
        for count in [n, tree.facets.len(), tree.depth()] {
            put_u32(&mut out, count as u32);
        }
        for s in self.cloud.surfels() {
            for v in [s.position, s.normal] {
                v.to_array().iter().for_each(|&x| put_f32(&mut out, x));
            }
            put_f32(&mut out, s.radius);
            s.radiance.to_array().iter().for_each(|&x| put_f32(&mut out, x));
        }
        if version == COMPACT_VERSION {
            compact_file::put(tree, &mut out);
        }
        for k in (0..tree.len() as u32).filter(|_| version == VERSION) {
            (0..field::STORED).for_each(|j| put_f32(&mut out, tree.nodes.get(k, j)));
            put_u32(&mut out, tree.nodes.child(k));
            let s = tree.splat_record(k).expect("k < len");
            put_f32(&mut out, s.area);
            s.normal.iter().for_each(|&x| put_f32(&mut out, x));
            put_u32(&mut out, s.kind);
            tree.radiance(k)
                .to_array()
                .iter()
                .for_each(|&x| put_f32(&mut out, x));
            s.centroid.iter().for_each(|&x| put_f32(&mut out, x));
            s.light_centroid.iter().for_each(|&x| put_f32(&mut out, x));
        }
        for c in (0..tree.facets.len())
            .filter(|_| version == VERSION)
            .filter_map(|i| tree.facets.get(i))
            .map(|c| c.get())
        {
            c.facet.iter().flatten().for_each(|&x| put_f32(&mut out, x));
            c.plane.iter().flatten().for_each(|&x| put_f32(&mut out, x));
            c.light.iter().flatten().for_each(|&x| put_f32(&mut out, x));
        }
        let sum = checksum(&out);
        put_u64(&mut out, sum);
        debug_assert_eq!(out.len(), size);
        out
    }

    /// Reads a file written by [`save`](Self::save), checking it whole
    /// (see the module's notes) before anything uses it.
    /// It reads the header, then at most the length the header gives (and
    /// one byte more, to see trailing bytes): an endless stream is not read
    /// whole.
    pub fn load(mut r: impl Read) -> Result<Self, TreeFileError> {
        let mut bytes = Vec::new();
        let io = TreeFileError::Io;
        r.by_ref()
            .take(HEADER as u64)
            .read_to_end(&mut bytes)
            .map_err(io)?;
        let version = (bytes.len() == HEADER && bytes[..8] == MAGIC)
            .then(|| u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes")))
            .filter(|v| [VERSION, COMPACT_VERSION].contains(v));
        if let Some(version) = version {
            let more = header_file_len(version, &bytes) - HEADER as u64 + 1;
            r.take(more).read_to_end(&mut bytes).map_err(io)?;
        }
        Self::from_bytes(&bytes)
    }

    /// [`load`](Self::load) from bytes in memory.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, TreeFileError> {
        Self::read(bytes, None)
    }

    /// Maps the file at `path` into memory and checks it as
    /// [`load`](Self::load) does. A compact tree's arrays are then used where
    /// they lie in the file, so a render reads only the pages its cuts reach
    /// (on a little-endian machine; elsewhere they are read as `load` reads
    /// them). The surfels are read.
    ///
    /// The file must not be written in place while the tree is in use: pbgi
    /// writes a tree file under a new name and renames it over the old one
    /// ([`TreeFile::write_to`]), which leaves a mapped file as it was.
    #[cfg(feature = "mmap")]
    pub fn open(path: &std::path::Path) -> Result<Self, TreeFileError> {
        let file = std::fs::File::open(path).map_err(TreeFileError::Io)?;
        let meta = file.metadata().map_err(TreeFileError::Io)?;
        if !meta.is_file() || meta.len() < HEADER as u64 {
            // A device, a pipe, or too short to map usefully: read, as far
            // as the header says, for the tree or the error `load` gives.
            return Self::load(file);
        }
        // SAFETY: the map is only read, through the checks of `read` and
        // then through `Store` (see tree/store.rs for why it stays sound).
        let map = std::sync::Arc::new(unsafe { memmap2::Mmap::map(&file) }.map_err(TreeFileError::Io)?);
        let tree = Self::read(&map[..], Some(&map))?;
        // The checks read every page. Let them go from this process (they
        // stay in the page cache), so what stays resident is what the
        // render's cuts reach.
        // SAFETY: a shared, read-only file map: dropping its pages only
        // means reading them from the file again, the same bytes.
        #[cfg(unix)]
        let _ = unsafe { map.unchecked_advise(memmap2::UncheckedAdvice::DontNeed) };
        Ok(tree)
    }

    /// Writes the file at `path` under a new name (`path` with `.part`
    /// added) and renames it over `path`, so a render that has the old file
    /// mapped keeps reading it as it was.
    pub fn write_to(&self, path: &std::path::Path) -> std::io::Result<()> {
        let mut part = path.as_os_str().to_owned();
        part.push(".part");
        std::fs::write(&part, self.to_bytes())?;
        std::fs::rename(&part, path)
    }

    /// Reads and checks `bytes`, which lie in `map` when it is given.
    fn read(bytes: &[u8], map: Option<&Map>) -> Result<Self, TreeFileError> {
        let len = bytes.len() as u64;
        if bytes.len() < MAGIC.len() || bytes[..8] != MAGIC {
            let head = &bytes[..bytes.len().min(8)];
            return Err(if MAGIC.starts_with(head) {
                TreeFileError::Truncated {
                    offset: len,
                    needed: 8,
                }
            } else {
                TreeFileError::BadMagic { found: head.to_vec() }
            });
        }
        if bytes.len() < 12 {
            return Err(TreeFileError::Truncated {
                offset: len,
                needed: 12,
            });
        }
        let mut rd = Reader { bytes, at: 8 };
        let version = rd.u32();
        if ![VERSION, COMPACT_VERSION].contains(&version) {
            return Err(TreeFileError::UnsupportedVersion {
                found: version,
                supported: COMPACT_VERSION,
            });
        }
        if bytes.len() < HEADER {
            return Err(TreeFileError::Truncated {
                offset: len,
                needed: HEADER as u64,
            });
        }
        let scene = rd.u64();
        let seed = rd.u64();
        let density = rd.f32();
        let light_samples = rd.u32();
        let bounces = rd.u32();
        let flags = rd.u32();
        let max_solid_angle = rd.f32();
        let microbuffer = rd.u32();
        let (n, clusters, depth) = (rd.u32() as u64, rd.u32() as u64, rd.u32());
        let nodes = (2 * n).saturating_sub(1);
        let needed = header_file_len(version, bytes);
        if len < needed {
            return Err(TreeFileError::Truncated { offset: len, needed });
        }
        if len > needed {
            return Err(TreeFileError::TrailingBytes { offset: needed });
        }
        let end = bytes.len() - CHECKSUM;
        let stored = u64::from_le_bytes(bytes[end..].try_into().expect("8 bytes"));
        let computed = checksum(&bytes[..end]);
        if stored != computed {
            return Err(TreeFileError::Checksum {
                offset: end as u64,
                stored,
                computed,
            });
        }
        let invalid = |offset: usize, what: String| TreeFileError::Invalid {
            offset: offset as u64,
            what,
        };
        if flags & !(AO | GATHERED | DROP_BURIED) != 0 {
            return Err(invalid(40, format!("unknown flags {flags:#x}")));
        }
        if n > PointCloud::MAX_SURFELS as u64 {
            return Err(invalid(
                52,
                format!("{n} surfels, at most {} supported", PointCloud::MAX_SURFELS),
            ));
        }
        let bake = BakeRecord {
            scene,
            seed,
            density,
            light_samples,
            bounces,
            ao: flags & AO != 0,
            gathered: flags & GATHERED != 0,
            drop_buried: flags & DROP_BURIED != 0,
            max_solid_angle,
            microbuffer,
        };

        let surfels: Vec<Surfel> = (0..n)
            .map(|_| Surfel {
                position: rd.vec3(),
                normal: rd.vec3(),
                radius: rd.f32(),
                radiance: rd.vec3(),
            })
            .collect();
        let cloud = PointCloud::new(surfels).map_err(|e| match e {
            crate::Error::InvalidSurfel { index, .. } => invalid(HEADER + SURFEL * index, e.to_string()),
            e => invalid(HEADER, e.to_string()),
        })?;

        if version == COMPACT_VERSION {
            let tree = compact_file::get(&bytes[..end], map, rd.at, n as usize, clusters as usize, depth)
                .map_err(|(offset, what)| TreeFileError::Invalid { offset, what })?;
            return Ok(TreeFile { bake, cloud, tree });
        }
        let nodes_at = rd.at;
        let mut tree = Tree {
            depth,
            ..Tree::default()
        };
        let mut pairs = vec![PairRecord::default(); n as usize];
        let (mut splat, mut radiance) = (
            Vec::with_capacity(nodes as usize),
            Vec::with_capacity(nodes as usize),
        );
        let mut cluster = Vec::new();
        for k in 0..nodes as u32 {
            let (p, slot) = NodeArrays::locate(k);
            let pair = &mut pairs[p];
            for f in pair.f[..field::STORED].iter_mut() {
                f[slot] = rd.f32();
            }
            pair.child[slot] = rd.u32();
            let area = rd.f32();
            let normal = rd.vec3().to_array();
            let kind = rd.u32();
            radiance.push(rd.vec3());
            splat.push(SplatRecord {
                centroid: rd.vec3().to_array(),
                light_centroid: rd.vec3().to_array(),
                area,
                normal,
                kind,
                ..SplatRecord::default()
            });
            if kind == MIXED {
                cluster.push(Cluster::NONE);
            }
        }
        let clusters_at = rd.at;
        if cluster.len() as u64 != clusters {
            return Err(invalid(
                56,
                format!("{clusters} clusters, but {} mixed nodes", cluster.len()),
            ));
        }
        for c in cluster.iter_mut() {
            for x in c
                .facet
                .iter_mut()
                .flatten()
                .chain(c.plane.iter_mut().flatten())
                .chain(c.light.iter_mut().flatten())
            {
                *x = rd.f32();
            }
        }
        tree.nodes = NodeArrays::Full(pairs);
        tree.mixed = super::Rank::new(splat.iter().map(|s| s.kind == MIXED));
        tree.payload = super::Payload::Full { splat, radiance };
        tree.facets = super::Facets::new(cluster, super::Precision::Full);
        check::values(&tree)
            .and_then(|()| check::structure(&tree, n as usize))
            .map_err(|fault| {
                let offset = match fault.place {
                    Place::Node(k) => nodes_at + NODE * k as usize,
                    Place::Cluster(i) => clusters_at + CLUSTER * i,
                    Place::Depth => 60,
                };
                invalid(offset, fault.what)
            })?;
        // From checked values only: finite centroids within the sphere.
        tree.derive();
        Ok(TreeFile { bake, cloud, tree })
    }
}

/// The length a file of this header (at least [`HEADER`] bytes) and
/// version has.
fn header_file_len(version: u32, header: &[u8]) -> u64 {
    let count = |at: usize| {
        u64::from(u32::from_le_bytes(
            header[at..at + 4].try_into().expect("4 bytes"),
        ))
    };
    file_len(version, count(52), count(56))
}

/// The length of a file of `version` with `n` surfels and `clusters`
/// mixed nodes: at most 2^32 · 300 bytes, no overflow in u64.
fn file_len(version: u32, n: u64, clusters: u64) -> u64 {
    let surfels_end = HEADER as u64 + SURFEL as u64 * n;
    if version == COMPACT_VERSION {
        return compact_file::Sections::of(surfels_end, n, clusters).end + CHECKSUM as u64;
    }
    surfels_end + CHECKSUM as u64 + NODE as u64 * (2 * n).saturating_sub(1) + CLUSTER as u64 * clusters
}
