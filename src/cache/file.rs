//! The cache on disk: its records and empty cells, tied to the tree they
//! were gathered over and to the gather's settings, so a camera path, a
//! later run or a farm's machines take up records made once. std only.
//!
//! Layout, every field little-endian:
//!
//! | offset | size | field |
//! | --- | --- | --- |
//! | 0 | 8 | magic `PBGICACH` |
//! | 8 | 4 | format version ([`VERSION`]) |
//! | 12 | 8 | the tree's hash: its leaves' places, sizes and light |
//! | 20 | 8 | the settings' hash: what else a gather depends on, given by the caller |
//! | 28 | 20 | the cube: levels u32, corner (3 f32), side f32 |
//! | 48 | 8 | counts: records `r`, empty cells `k` (u32 each) |
//! | 56 | 120 r | records: key u64, position, normal, `E`, translational and rotational gradients (3 each), distance |
//! | | 8 k | empty cells (no surfel of that facing): key u64 |
//! | end − 8 | 8 | FNV-1a 64 of every byte before it |
//!
//! Keys name a cell and a facing (`grid`) and run ascending in each part,
//! so the bytes depend on the records alone, not on the frame, tile or
//! thread that made them. A reader checks, in this order, the magic, the
//! version, the counts against the length (before allocating), the
//! checksum, the tree, the settings and the cube, and then every entry: its
//! key names a cell of the cube, no key comes twice, a record sits exactly
//! on its cell's surfel (the one [`Cache::prepare`] would gather at), an
//! empty cell holds no surfel of its facing, and every value is finite (the
//! light and its turn within what a gather can give). A
//! file that passes gives the bits a render from scratch gives.

use std::fmt;
use std::io::{Read, Write};

use super::grid::{Grid, Key, cell_of, key};
use super::{Cache, CacheOptions, NONE, Record};
use crate::microbuffer::Gradients;
use crate::points::MAX_RADIANCE;
use crate::tree::Tree;
use crate::tree::bytes::{Reader, checksum, put_f32, put_u32, put_u64, put_vec3};

/// The first eight bytes of a cache file.
pub const MAGIC: [u8; 8] = *b"PBGICACH";
/// The format version this library reads and writes.
pub const VERSION: u32 = 1;

const HEADER: usize = 56;
const RECORD: usize = 120;
const EMPTY: usize = 8;
const CHECKSUM: usize = 8;

/// Why a cache file could not be read, or does not belong to this render.
#[derive(Debug)]
#[non_exhaustive]
pub enum CacheFileError {
    /// Reading failed.
    Io(std::io::Error),
    /// The file ends at byte `offset`, before the `needed` bytes its header promises.
    Truncated {
        /// The file's length.
        offset: u64,
        /// The length it should have.
        needed: u64,
    },
    /// Not a cache file: the first eight bytes are not [`MAGIC`].
    BadMagic {
        /// The bytes found (fewer for a shorter file).
        found: Vec<u8>,
    },
    /// A version this library does not read.
    UnsupportedVersion {
        /// The file's version.
        found: u32,
        /// The one read here ([`VERSION`]).
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
    /// The records were gathered over another tree, with other settings or
    /// in another cube: they would give this render a wrong image.
    Mismatch {
        /// What differs: `"tree"`, `"settings"` or `"cube"`.
        what: &'static str,
        /// Its value in the file.
        file: String,
        /// Its value here.
        expected: String,
    },
    /// An entry is out of range or does not fit the tree.
    Invalid {
        /// The byte offset of the entry at fault.
        offset: u64,
        /// What is wrong.
        what: String,
    },
}

impl fmt::Display for CacheFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CacheFileError::Io(e) => write!(f, "reading the cache file: {e}"),
            CacheFileError::Truncated { offset, needed } => write!(
                f,
                "cache file truncated: it ends at byte {offset}, {needed} bytes expected"
            ),
            CacheFileError::BadMagic { found } => write!(
                f,
                "not a pbgi cache file (byte 0: {:?}, expected {:?})",
                String::from_utf8_lossy(found),
                String::from_utf8_lossy(&MAGIC)
            ),
            CacheFileError::UnsupportedVersion { found, supported } => write!(
                f,
                "cache file format version {found} at byte 8, this pbgi reads version {supported}: make it again"
            ),
            CacheFileError::TrailingBytes { offset } => {
                write!(f, "cache file continues past its end at byte {offset}")
            }
            CacheFileError::Checksum {
                offset,
                stored,
                computed,
            } => write!(
                f,
                "cache file corrupted: checksum at byte {offset} is {stored:016x}, the bytes give {computed:016x}"
            ),
            CacheFileError::Mismatch { what, file, expected } => {
                let which = match *what {
                    "tree" => "over another tree: its surfels' places, sizes or light differ",
                    "settings" => {
                        "with other settings: the scene, or the gather's Ω, microbuffer, bounces, seed or density"
                    }
                    _ => "in another cube",
                };
                write!(
                    f,
                    "the cache was made {which} ({what} {file} in the file, {expected} here): \
                     make it again for this render, or render with what it was made for"
                )
            }
            CacheFileError::Invalid { offset, what } => write!(f, "cache file byte {offset}: {what}"),
        }
    }
}

impl std::error::Error for CacheFileError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            CacheFileError::Io(e) => Some(e),
            _ => None,
        }
    }
}

impl Cache {
    /// Writes the cache, `settings` the caller's hash of what its gathers
    /// depend on beyond the tree (Ω, the microbuffer, the near field, the
    /// convolution); [`load`](Self::load) must be given the same.
    pub fn save(&self, mut w: impl Write, settings: u64) -> std::io::Result<()> {
        w.write_all(&self.to_bytes(settings))?;
        w.flush()
    }

    /// The file's bytes (see the module's notes).
    pub fn to_bytes(&self, settings: u64) -> Vec<u8> {
        let mut full: Vec<(Key, &Record)> = Vec::new();
        let mut empty: Vec<Key> = Vec::new();
        for (&k, &i) in &self.cells {
            match self.records.get(i as usize) {
                Some(r) if i != NONE => full.push((k, r)),
                _ => empty.push(k),
            }
        }
        full.sort_unstable_by_key(|e| e.0);
        empty.sort_unstable();
        let mut out = Vec::with_capacity(HEADER + RECORD * full.len() + EMPTY * empty.len() + CHECKSUM);
        out.extend_from_slice(&MAGIC);
        put_u32(&mut out, VERSION);
        put_u64(&mut out, self.tree_hash);
        put_u64(&mut out, settings);
        put_u32(&mut out, self.grid.levels);
        put_vec3(&mut out, self.grid.origin);
        put_f32(&mut out, self.grid.size);
        put_u32(&mut out, full.len() as u32);
        put_u32(&mut out, empty.len() as u32);
        for (k, r) in full {
            put_u64(&mut out, k);
            for v in [r.position, r.normal, r.e] {
                put_vec3(&mut out, v);
            }
            let g = &r.gradients;
            g.translation
                .iter()
                .chain(&g.rotation)
                .for_each(|&v| put_vec3(&mut out, v));
            put_f32(&mut out, g.distance);
        }
        for k in empty {
            put_u64(&mut out, k);
        }
        let sum = checksum(&out);
        put_u64(&mut out, sum);
        out
    }

    /// A cache over `tree` holding the records of a file written by
    /// [`save`](Self::save), checked whole first (see the module's notes).
    /// It reads the header, then at most the length the header gives (and
    /// one byte more, to see trailing bytes).
    pub fn load(
        mut r: impl Read,
        tree: &Tree,
        opts: CacheOptions,
        settings: u64,
    ) -> Result<Cache, CacheFileError> {
        let mut bytes = Vec::new();
        let io = CacheFileError::Io;
        r.by_ref()
            .take(HEADER as u64)
            .read_to_end(&mut bytes)
            .map_err(io)?;
        if bytes.len() == HEADER && bytes[..8] == MAGIC && bytes[8..12] == VERSION.to_le_bytes() {
            let more = file_len(&bytes) - HEADER as u64 + 1;
            r.take(more).read_to_end(&mut bytes).map_err(io)?;
        }
        Self::from_bytes(&bytes, tree, opts, settings)
    }

    /// [`load`](Self::load) from bytes in memory.
    pub fn from_bytes(
        bytes: &[u8],
        tree: &Tree,
        opts: CacheOptions,
        settings: u64,
    ) -> Result<Cache, CacheFileError> {
        let len = bytes.len() as u64;
        let truncated = |needed: usize| CacheFileError::Truncated {
            offset: len,
            needed: needed as u64,
        };
        let head = &bytes[..bytes.len().min(8)];
        if head != MAGIC {
            return Err(if MAGIC.starts_with(head) {
                truncated(8)
            } else {
                CacheFileError::BadMagic { found: head.to_vec() }
            });
        }
        if bytes.len() < 12 {
            return Err(truncated(12));
        }
        let mut rd = Reader { bytes, at: 8 };
        let version = rd.u32();
        if version != VERSION {
            return Err(CacheFileError::UnsupportedVersion {
                found: version,
                supported: VERSION,
            });
        }
        if bytes.len() < HEADER {
            return Err(truncated(HEADER));
        }
        let needed = file_len(bytes);
        if len < needed {
            return Err(CacheFileError::Truncated { offset: len, needed });
        }
        if len > needed {
            return Err(CacheFileError::TrailingBytes { offset: needed });
        }
        let end = bytes.len() - CHECKSUM;
        let stored = u64::from_le_bytes(bytes[end..].try_into().expect("8 bytes"));
        let computed = checksum(&bytes[..end]);
        if stored != computed {
            return Err(CacheFileError::Checksum {
                offset: end as u64,
                stored,
                computed,
            });
        }

        // The file holds records' irradiance alone: a cache read from it
        // keeps no incident light.
        let mut cache = Cache::new(
            tree,
            CacheOptions {
                incident: false,
                ..opts
            },
        );
        let mismatch =
            |what, file: String, expected: String| Err(CacheFileError::Mismatch { what, file, expected });
        let (tree_hash, file_settings) = (rd.u64(), rd.u64());
        if tree_hash != cache.tree_hash {
            return mismatch(
                "tree",
                format!("{tree_hash:016x}"),
                format!("{:016x}", cache.tree_hash),
            );
        }
        if file_settings != settings {
            return mismatch(
                "settings",
                format!("{file_settings:016x}"),
                format!("{settings:016x}"),
            );
        }
        let cube = (rd.u32(), rd.vec3(), rd.f32());
        let here = (cache.grid.levels, cache.grid.origin, cache.grid.size);
        // Bits, not values: a NaN in the file must not pass.
        let bits = |c: (u32, glam::Vec3, f32)| (c.0, c.1.to_array().map(f32::to_bits), c.2.to_bits());
        if bits(cube) != bits(here) {
            return mismatch("cube", format!("{cube:?}"), format!("{here:?}"));
        }
        let (full, empty) = (rd.u32(), rd.u32());
        cache.records.reserve(full as usize);
        let mut last: Option<Key> = None;
        for i in 0..full as usize + empty as usize {
            let at = rd.at;
            let invalid = |what: String| CacheFileError::Invalid {
                offset: at as u64,
                what,
            };
            let k = rd.u64();
            if i == full as usize {
                last = None;
            }
            if last.is_some_and(|l| l >= k) {
                return Err(invalid(format!("key {k:#x} out of order")));
            }
            last = Some(k);
            let (c, level, facing) = cell_of(k);
            if level >= cache.grid.levels
                || facing >= 6
                || c.iter().any(|&v| v >= Grid::across(level))
                || key(c, level, facing) != k
            {
                return Err(invalid(format!("key {k:#x} names no cell of the cube")));
            }
            let surfel = cache.candidate(k);
            let index = if i < full as usize {
                let (position, normal, e) = (rd.vec3(), rd.vec3(), rd.vec3());
                let mut v = [glam::Vec3::ZERO; 6];
                v.iter_mut().for_each(|v| *v = rd.vec3());
                let gradients = Gradients {
                    translation: [v[0], v[1], v[2]],
                    rotation: [v[3], v[4], v[5]],
                    distance: rd.f32(),
                };
                if surfel != Some((position, normal)) {
                    return Err(invalid(format!(
                        "the record at {position} is not at its cell's surfel: it was made over another tree"
                    )));
                }
                // A gather's irradiance and its turn are at most π times the
                // brightest surfel's radiance: a larger one is no gather's,
                // and would overflow a blend.
                let bound = 4.0 * MAX_RADIANCE;
                // Lane-wise compares: a NaN fails each, where
                // `min_element` would pass it by.
                if !(e.cmpge(glam::Vec3::ZERO).all() && e.cmple(glam::Vec3::splat(bound)).all())
                    || !v[3..]
                        .iter()
                        .all(|v| v.abs().cmple(glam::Vec3::splat(bound)).all())
                    || !v.iter().all(|v| v.is_finite())
                    || gradients.distance.is_nan()
                    || gradients.distance <= 0.0
                {
                    return Err(invalid(format!(
                        "the record at {position} holds a light or gradient out of range (E = {e})"
                    )));
                }
                cache.records.push(Record {
                    position,
                    normal,
                    e,
                    gradients,
                });
                cache.records.len() as u32 - 1
            } else {
                if surfel.is_some() {
                    return Err(invalid(format!("cell {k:#x} is marked empty but holds a surfel")));
                }
                NONE
            };
            if cache.cells.insert(k, index).is_some() {
                return Err(invalid(format!("cell {k:#x} comes twice")));
            }
        }
        Ok(cache)
    }
}

/// The length the header of `bytes` (at least [`HEADER`] long) promises.
fn file_len(bytes: &[u8]) -> u64 {
    let count = |at: usize| u64::from(u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes")));
    (HEADER + CHECKSUM) as u64 + RECORD as u64 * count(48) + EMPTY as u64 * count(52)
}
