//! A world-space irradiance cache: records of gathered irradiance on the
//! scene's surfaces, shared by every camera sample, tile and frame that
//! sees them (Ward, Rubinstein and Clear 1988), placed so that the light
//! at a point is a function of the scene and that point alone.
//!
//! **Where records go.** An octree of cells spans the tree's bounding
//! cube (`grid`). A cell at a level holds at most one record per facing
//! (the six axis directions): the surfel of that facing nearest the cell's
//! centre, gathered where it lies, made only where a point of that facing
//! asks for it. A record's place and light depend on its
//! cell alone, never on who asked for it, in which order or on which thread.
//!
//! **What a point takes.** At each level from level 2 (cells 1/32 of
//! the cube's side; coarser ones span too much of a room), a point blends
//! the records of its facing in the 27 cells around its own that lie on
//! its surface (the
//! screen lattice's plane and normal tests, [`Record::covers`]) and within a
//! cell's side of it, weighted by `(1 − d/h)²`: the value at the point of
//! the plane that fits their light by weighted least squares in its tangent
//! plane, held within their range (their weighted mean where they lie
//! nearly on a line). Where they weigh too little
//! in all (no record near it on its surface) or differ by more than
//! `threshold` of their sum, it looks one level finer; at the finest level
//! (cells about two surfel radii across) it is served, or told to gather
//! itself (no record on its surface, or light that still changes by more
//! than twice the threshold). The choice reads the records alone, so a tile,
//! a crop or a later frame gets the bits a full render from scratch gets.
//!
//! **Who gathers.** [`Cache::prepare`] runs level by level over the points a
//! frame will ask for: the cells they need that hold no record yet are
//! gathered in packets of 16 neighbours facing one way, then the points
//! that must look finer go on to the next level. A later frame gathers
//! only the cells no earlier one needed.

mod blend;
pub mod file;
mod grid;
mod place;
pub(crate) mod record;

use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;

use crate::brdf::GlossyLobe;
use crate::cut::TraversalStats;
use crate::error::Error;
use crate::gather::Gather;
use crate::microbuffer::{Convolution, Table, reflect, tilted};
use crate::points::dominant_axis;
use crate::simd::LANES;
use crate::tree::Tree;
use crate::tree::file::Fnv1a;
use blend::{Around, Blend};
pub use file::CacheFileError;
use grid::{Grid, Key, KeyMap, cell_of, key};
pub use record::Record;
#[cfg(feature = "render")]
pub(crate) use record::same_surface;

/// Settings of a [`Cache`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheOptions {
    /// Relative difference between the records a point blends that sends
    /// it one level finer.
    pub threshold: f32,
    /// Whether each record also keeps the light each pixel of its
    /// microbuffer let through (its incident radiance), so that glossy
    /// lobes near it are convolved from the records ([`Cache::reflect`]).
    pub incident: bool,
}

/// The threshold a cache refines at unless told otherwise: where the
/// records of a surface differ by more than 0.4 of their sum. Lower ones
/// lower its error at high sample counts, for more gathers
/// (`docs/lab/cache.md`).
pub const DEFAULT_THRESHOLD: f32 = 0.4;

impl Default for CacheOptions {
    fn default() -> Self {
        CacheOptions {
            threshold: DEFAULT_THRESHOLD,
            incident: false,
        }
    }
}

/// The least total weight of the records a point blends: below it, no
/// record lies near enough on its surface, and it looks finer.
const MIN_WEIGHT: f32 = 0.25;

/// The coarsest level that makes and serves records: its cells are
/// `1/(8·2^COARSEST)` of the cube's side. Coarser cells span much of a
/// room, and records that far apart agree within the threshold while the
/// light between them curves away from any blend of them: on the nave,
/// serving from level 0 left 4.4 % relative RMSE against the dense render
/// (1.1 % from level 2, with 16 % more gathers), and every scene measured
/// gained (docs/lab/cache.md).
const COARSEST: u32 = 2;

/// The finest cells are at least this many median surfel radii across.
const FINEST_RADII: f32 = 2.0;

/// Distance off a record's plane, relative to the cube's side, that is
/// rounding.
const SAME_PLANE: f32 = 1e-4;

/// What the cache gives a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lookup {
    /// The blended light of the records on its surface.
    Light(Vec3),
    /// No record lies on its surface near it, even at the finest level (a
    /// thin object, a point outside the surfels' cube): it gathers.
    Uncovered,
    /// At the finest level its records still differ by more than twice
    /// the threshold: the light changes within a cell, and it gathers.
    Changing,
}

/// What a call of [`Cache::prepare`] gathered.
#[derive(Clone, Debug, Default)]
pub struct Prepared {
    /// Records gathered.
    pub records: usize,
    /// Traversal counters of their gathers.
    pub stats: TraversalStats,
    /// Seconds in the cuts and in splatting and convolving, summed over threads.
    pub trav: f64,
    /// See `trav`.
    pub shading: f64,
    /// What [`Cache::lookup`] gives each point, in the order of the points
    /// asked for, as the records stand when `prepare` returns: each point
    /// settled while its records were made, so that it is not blended
    /// twice.
    pub lookups: Vec<Lookup>,
    /// The level each point settled at (what [`Cache::reflect`] reads).
    pub levels: Vec<u8>,
}

/// Why [`Cache::prepare`] failed.
#[derive(Debug)]
pub enum CacheError {
    /// The gather refused a receiver or its options.
    Gather(Error),
    /// A record's gather gave a value or a gradient that is not finite.
    NonFinite {
        /// The record's place.
        position: Vec3,
        /// What it gathered.
        value: Vec3,
    },
}

impl From<Error> for CacheError {
    fn from(e: Error) -> Self {
        CacheError::Gather(e)
    }
}

impl std::fmt::Display for CacheError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CacheError::Gather(e) => e.fmt(f),
            CacheError::NonFinite { position, value } => {
                write!(
                    f,
                    "a cache record at {position} gathered a value or gradient that is not finite (E = {value})"
                )
            }
        }
    }
}

impl std::error::Error for CacheError {}

/// The records gathered so far over one tree, and where each may serve.
pub struct Cache {
    grid: Grid,
    /// A hash of the leaves the records are gathered over (their places,
    /// sizes and light): a cache file names the tree it belongs to.
    tree_hash: u64,
    threshold: f32,
    slack: f32,
    /// The leaves, sorted by their finest Morton code: code, position,
    /// normal.
    codes: Vec<u64>,
    leaves: Vec<(Vec3, Vec3)>,
    /// Per cell and facing asked for: its record's index in `records`, or
    /// [`NONE`] where the cell holds no surfel of that facing.
    cells: KeyMap<u32>,
    records: Vec<Record>,
    /// With [`CacheOptions::incident`]: the records' microbuffer table,
    /// and per record its pixels' incident light, record after record.
    table: Option<Arc<Table>>,
    incident: Option<Vec<Vec3>>,
}

/// A cell without a record.
const NONE: u32 = u32::MAX;

/// Which of the six axis directions `n` is closest to: receivers (and
/// records) facing one way share most of their cuts.
#[inline]
pub(crate) fn facing(n: Vec3) -> u8 {
    let axis = dominant_axis(n);
    axis as u8 * 2 + u8::from(n[axis] < 0.0)
}

impl Cache {
    /// An empty cache over the surfels of `tree`.
    pub fn new(tree: &Tree, opts: CacheOptions) -> Self {
        let mut leaves: Vec<(Vec3, Vec3, f32)> = Vec::new();
        let mut hash = Fnv1a::default();
        for k in 0..tree.len() as u32 {
            if tree.is_leaf(k) {
                let v = tree.node(k);
                let light = tree.radiance(k);
                for x in [v.centroid, v.normal, light]
                    .iter()
                    .flat_map(|v| v.to_array())
                    .chain([v.radius])
                {
                    hash.write(&x.to_bits().to_le_bytes());
                }
                leaves.push((v.centroid, v.normal.normalize_or(Vec3::Z), v.radius));
            }
        }
        let (centre, radius) = if tree.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            tree.sphere(0)
        };
        let radius = radius.max(f32::MIN_POSITIVE);
        let mut radii: Vec<f32> = leaves.iter().map(|l| l.2).collect();
        let r = if radii.is_empty() {
            radius
        } else {
            let mid = radii.len() / 2;
            *radii.select_nth_unstable_by(mid, f32::total_cmp).1
        };
        // Levels until a cell is about FINEST_RADII surfel radii across.
        let mut levels = 1;
        while levels <= grid::MAX_LEVEL && 2.0 * radius / Grid::across(levels) as f32 >= FINEST_RADII * r {
            levels += 1;
        }
        let grid = Grid::new(centre, radius, levels);
        let mut coded: Vec<(u64, u32)> = leaves
            .iter()
            .enumerate()
            .map(|(i, l)| (grid.code(l.0), i as u32))
            .collect();
        coded.sort_unstable();
        Cache {
            grid,
            tree_hash: hash.0,
            threshold: opts.threshold,
            slack: SAME_PLANE * 2.0 * radius,
            codes: coded.iter().map(|c| c.0).collect(),
            leaves: coded
                .iter()
                .map(|&(_, i)| (leaves[i as usize].0, leaves[i as usize].1))
                .collect(),
            cells: KeyMap::default(),
            records: Vec::new(),
            table: None,
            incident: opts.incident.then(Vec::new),
        }
    }

    /// Records gathered so far.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// Whether no record was gathered yet.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The records, in the order they were made.
    pub fn records(&self) -> &[Record] {
        &self.records
    }

    /// The records' receivers in the packets a render from scratch gathers
    /// them in: level by level, each level's cells in key order (facing,
    /// then Morton order), 16 to a packet. For timing the schemes on the
    /// receivers the cache gathers.
    pub fn packets(&self) -> Vec<Vec<(Vec3, Vec3)>> {
        let mut held: Vec<(Key, u32)> = self
            .cells
            .iter()
            .filter(|e| *e.1 != NONE)
            .map(|(&k, &i)| (k, i))
            .collect();
        held.sort_unstable();
        let mut out = Vec::new();
        for level in held.chunk_by(|a, b| cell_of(a.0).1 == cell_of(b.0).1) {
            for chunk in level.chunks(LANES) {
                let at = |i: u32| &self.records[i as usize];
                out.push(
                    chunk
                        .iter()
                        .map(|&(_, i)| (at(i).position, at(i).normal))
                        .collect(),
                );
            }
        }
        out
    }

    /// The first level records are made and read at: [`COARSEST`], or
    /// the finest where the cube has fewer levels.
    fn first_level(&self) -> u32 {
        COARSEST.min(self.grid.levels - 1)
    }

    /// Levels of cells.
    pub fn levels(&self) -> u32 {
        self.grid.levels
    }

    /// Gathers the records that `points` (position, unit normal) will ask
    /// [`lookup`](Self::lookup) for and that are not there yet, with
    /// `gather`'s convolution `what`.
    pub fn prepare(
        &mut self,
        points: &[(Vec3, Vec3)],
        gather: &Gather,
        what: Convolution,
    ) -> Result<Prepared, CacheError> {
        let mut out = Prepared {
            lookups: vec![Lookup::Uncovered; points.len()],
            levels: vec![0; points.len()],
            ..Prepared::default()
        };
        let mut pending: Vec<u32> = (0..points.len() as u32).collect();
        for level in self.first_level()..self.grid.levels {
            if pending.is_empty() {
                break;
            }
            // The cells of the pending points, then their neighbourhoods,
            // each for the points' facing.
            let mut own: Vec<Key> = pending
                .par_iter()
                .filter_map(|&i| {
                    let (p, n) = points[i as usize];
                    self.grid.cell(p, level).map(|c| key(c, level, facing(n)))
                })
                .collect();
            own.par_sort_unstable();
            own.dedup();
            let mut keys: Vec<Key> = own
                .iter()
                .flat_map(|&k| {
                    let (c, level, f) = cell_of(k);
                    neighbours(c, level, f)
                })
                .filter(|k| !self.cells.contains_key(k))
                .collect();
            keys.par_sort_unstable();
            keys.dedup();
            self.gather_cells(&keys, gather, what, &mut out)?;
            // A level's records are all made now: what a point takes here
            // is what `lookup` will find (no later level changes it).
            // Points come in tile order, so neighbours mostly share a
            // cell: each split keeps the last cell's records at hand.
            let settled: Vec<Option<Lookup>> = pending
                .par_iter()
                .map_init(Around::default, |near, &i| {
                    let (p, n) = points[i as usize];
                    match self.grid.cell(p, level) {
                        None => Some(Lookup::Uncovered),
                        Some(_) => self.settled(p, n, level, near),
                    }
                })
                .collect();
            let mut next = Vec::with_capacity(pending.len());
            for (&i, l) in pending.iter().zip(settled) {
                match l {
                    Some(l) => {
                        out.lookups[i as usize] = l;
                        out.levels[i as usize] = level as u8;
                    }
                    None => next.push(i),
                }
            }
            pending = next;
        }
        Ok(out)
    }

    /// The light at `p` (unit normal `n`) from the records
    /// [`prepare`](Self::prepare) made for it.
    pub fn lookup(&self, p: Vec3, n: Vec3) -> Lookup {
        for level in self.first_level()..self.grid.levels {
            if self.grid.cell(p, level).is_none() {
                return Lookup::Uncovered;
            }
            if let Some(l) = self.settled(p, n, level, &mut Around::default()) {
                return l;
            }
        }
        Lookup::Uncovered
    }

    /// The light a glossy lobe at `p` (normal `n`, as asked of
    /// [`prepare`](Self::prepare); shading normal `shading`, seen from
    /// `wo`) reflects from the incident light of the records it settled on
    /// at `level` ([`Prepared::levels`]): each record's light convolved
    /// with the lobe in its own frame, weighted as the blend weighs it.
    /// Zero without [`CacheOptions::incident`].
    pub fn reflect(&self, p: Vec3, n: Vec3, level: u32, lobe: &GlossyLobe, shading: Vec3, wo: Vec3) -> Vec3 {
        self.convolve(p, n, level, |t, normal, light| {
            reflect(t, normal, light, lobe, shading, wo)
        })
    }

    /// The irradiance at `p` (normal `n`, as asked of
    /// [`prepare`](Self::prepare)) about the shading normal `shading` a
    /// bump or normal map tilts it to, from the incident light of the
    /// records it settled on at `level`, weighted as in
    /// [`reflect`](Self::reflect). Zero without [`CacheOptions::incident`].
    pub fn tilted(&self, p: Vec3, n: Vec3, level: u32, shading: Vec3) -> Vec3 {
        self.convolve(p, n, level, |t, normal, light| tilted(t, normal, light, shading))
    }

    /// `f` (the table, a normal, incident light) over the records of
    /// `level` around `p` on its surface, weighted as a blend weighs
    /// them. Records that face exactly one way (a flat surface's) share a
    /// frame, so their light is summed, weighted, before `f` reads it
    /// once; the groups and the sums follow [`neighbours`] order.
    fn convolve(&self, p: Vec3, n: Vec3, level: u32, f: impl Fn(&Table, Vec3, &[Vec3]) -> Vec3) -> Vec3 {
        let (Some(all), Some(table)) = (&self.incident, &self.table) else {
            return Vec3::ZERO;
        };
        let Some(c) = self.grid.cell(p, level) else {
            return Vec3::ZERO;
        };
        let pixels = table.dir.len();
        let h = self.grid.cell_size(level);
        let mut around = Around::default();
        let mut near = [(0u32, 0.0f32); 27];
        let mut len = 0;
        for &i in self.records_around(c, level, facing(n), &mut around) {
            if let Some(w) = self.weight(&self.records[i as usize], p, n, h) {
                near[len] = (i, w);
                len += 1;
            }
        }
        let near = &near[..len];
        let light = |i: u32| &all[i as usize * pixels..(i as usize + 1) * pixels];
        let normal = |i: u32| self.records[i as usize].normal;
        let (mut sum, mut weight) = (Vec3::ZERO, 0.0);
        let mut done = [false; 27];
        let mut mixed = Vec::new();
        for a in 0..near.len() {
            if done[a] {
                continue;
            }
            let (i, w) = near[a];
            weight += w;
            // Later records of the same normal: none of them is done, or
            // `a` would be.
            let mut same = (a + 1..near.len())
                .filter(|&b| normal(near[b].0) == normal(i))
                .peekable();
            if same.peek().is_none() {
                sum += f(table, normal(i), light(i)) * w;
                continue;
            }
            mixed.clear();
            mixed.extend(light(i).iter().map(|l| *l * w));
            for b in same {
                done[b] = true;
                let (j, v) = near[b];
                for (m, l) in mixed.iter_mut().zip(light(j)) {
                    *m += *l * v;
                }
                weight += v;
            }
            sum += f(table, normal(i), &mixed);
        }
        if weight > 0.0 { sum / weight } else { Vec3::ZERO }
    }

    /// What `p` takes at `level`, or `None` where it looks finer.
    fn settled(&self, p: Vec3, n: Vec3, level: u32, near: &mut Around) -> Option<Lookup> {
        let b = self.blend(p, n, level, near);
        let finest = level + 1 == self.grid.levels;
        let spread = b.hi - b.lo;
        if !finest {
            return (b.weight >= MIN_WEIGHT && spread <= self.threshold * (b.hi + b.lo))
                .then(|| Lookup::Light(b.light()));
        }
        Some(if b.weight <= 0.0 {
            Lookup::Uncovered
        } else if spread > 2.0 * self.threshold * (b.hi + b.lo) {
            Lookup::Changing
        } else {
            Lookup::Light(b.light())
        })
    }

    /// The records of the 27 cells around cell `c` of `level` for facing
    /// `f`, in [`neighbours`] order, kept in `near` for the next point of
    /// the same cell and facing.
    #[inline]
    fn records_around<'a>(&self, c: [u32; 3], level: u32, f: u8, near: &'a mut Around) -> &'a [u32] {
        let own = key(c, level, f);
        if near.key != Some(own) {
            near.key = Some(own);
            near.len = 0;
            for k in neighbours(c, level, f) {
                if let Some(&i) = self.cells.get(&k)
                    && i != NONE
                {
                    near.records[near.len] = i;
                    near.len += 1;
                }
            }
        }
        &near.records[..near.len]
    }

    /// The weight of record `r` in a blend at `p` (unit normal `n`), cells
    /// `h` across: `(1 − d/h)²` where it lies within a cell's side on the
    /// point's surface, else none.
    #[inline]
    fn weight(&self, r: &Record, p: Vec3, n: Vec3, h: f32) -> Option<f32> {
        let d = (r.position - p).length() / h;
        (d < 1.0 && r.covers(p, n, self.slack)).then_some((1.0 - d) * (1.0 - d))
    }

    /// The records of `level` around `p` on its surface, blended, in
    /// [`neighbours`] order (so the sums' bits do not depend on `near`).
    #[inline]
    fn blend(&self, p: Vec3, n: Vec3, level: u32, near: &mut Around) -> Blend {
        let mut b = Blend::empty();
        let Some(c) = self.grid.cell(p, level) else {
            return b;
        };
        let h = self.grid.cell_size(level);
        let (t, bt) = n.any_orthonormal_pair();
        for &i in self.records_around(c, level, facing(n), near) {
            let r = &self.records[i as usize];
            let Some(w) = self.weight(r, p, n, h) else {
                continue;
            };
            let off = r.position - p;
            let e = r.turned(n);
            b.sum += e * w;
            b.weight += w;
            let l = e.x + e.y + e.z;
            b.lo = b.lo.min(l);
            b.hi = b.hi.max(l);
            let (u, v) = (off.dot(t) / h, off.dot(bt) / h);
            b.su += w * u;
            b.sv += w * v;
            b.suu += w * u * u;
            b.suv += w * u * v;
            b.svv += w * v * v;
            b.seu += e * (w * u);
            b.sev += e * (w * v);
            b.elo = b.elo.min(e);
            b.ehi = b.ehi.max(e);
        }
        b
    }
}

/// The keys of the 27 cells around `c` at `level` (itself included) that
/// lie inside the cube, for facing `f`, in a fixed order.
#[inline]
fn neighbours(c: [u32; 3], level: u32, f: u8) -> impl Iterator<Item = Key> {
    let n = Grid::across(level) as i64;
    (0..27).filter_map(move |i| {
        let d = [i % 3 - 1, i / 3 % 3 - 1, i / 9 - 1];
        let q = [0, 1, 2].map(|a| i64::from(c[a]) + d[a]);
        q.iter()
            .all(|&v| (0..n).contains(&v))
            .then(|| key(q.map(|v| v as u32), level, f))
    })
}

#[cfg(test)]
mod tests;
