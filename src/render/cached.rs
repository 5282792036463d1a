//! The world-space cache's side of a frame ([`Gathers::Cache`]): the
//! frame's camera samples are traced once to tell the cache where they
//! lie, the cache gathers the records they need that no earlier frame of
//! this bake made, and each sample then takes its light from the records
//! (`crate::cache`). The records depend on the scene alone, so a crop, a
//! thread count or a later frame keeps the bits of a render from scratch.

use std::io::{Read, Write};

use glam::Vec3;
use rayon::prelude::*;

use super::bake::bake_record;
use super::frame::{Frame, PacketPoint, Timers};
use super::options::Gathers;
use super::output::RenderError;
use super::sparse::{Lattice, Served};
use crate::cache::{Cache, CacheError, CacheFileError, CacheOptions, Lookup, Prepared};
use crate::cut::TraversalStats;
use crate::gather::Gather;
use crate::microbuffer::Convolution;
use crate::tree::file::Fnv1a;

/// Where a frame's camera samples take their indirect light from, when
/// they do not gather it themselves.
pub(crate) enum Shared<'a> {
    /// The screen lattice of [`Gathers::Sparse`].
    Lattice(&'a Lattice),
    /// What each sample takes from the world-space records of
    /// [`Gathers::Cache`], settled when they were made.
    Cache(&'a Settled),
}

impl Shared<'_> {
    /// The irradiance at a camera sample through film point `film` that
    /// hit `p` with normal `n`, in slot `slot` of tile `tile`, or
    /// why it gathers itself.
    #[inline]
    pub fn irradiance(
        &self,
        (tile, slot): (usize, usize),
        film: (f32, f32),
        p: Vec3,
        n: Vec3,
        eye: Vec3,
    ) -> Result<Served, RenderError> {
        Ok(match self {
            Shared::Lattice(l) => l.irradiance(film, p, n, eye),
            Shared::Cache(c) => match c.get(tile, slot, p, n)?.0 {
                Lookup::Light(e) => Served::Light(e),
                Lookup::Uncovered => Served::NoCorner,
                Lookup::Changing => Served::Changing,
            },
        })
    }
}

/// What the cache gives each camera sample that asks it, settled while
/// its records were made ([`Prepared::lookups`](crate::cache::Prepared)),
/// so that no sample blends its records twice. A tile asks by the sample's
/// slot, `s × pixels + k` for camera sample `s` of its pixel `k`: an
/// adaptive tile asks for some of the samples the frame traced.
pub(crate) struct Settled {
    lookups: Vec<Lookup>,
    levels: Vec<u8>,
    /// A hash of each sample's place, checked when it is read: a tile that
    /// traced another sample in a slot would take another sample's light.
    marks: Vec<u32>,
    /// Where each tile's samples begin, and the end.
    starts: Vec<usize>,
    /// Each tile's slots (from `slot_starts[tile]`): the sample's index
    /// among the tile's, or [`NO_SAMPLE`].
    slots: Vec<u32>,
    slot_starts: Vec<usize>,
}

/// A slot whose sample the cache did not settle (a miss, or another list's).
const NO_SAMPLE: u32 = u32::MAX;

/// One tile's samples of one list: their places and each slot's index among them.
#[derive(Default)]
struct TileSamples {
    points: Vec<(Vec3, Vec3)>,
    slots: Vec<u32>,
}

impl Settled {
    /// The place hash of a sample.
    #[inline]
    fn mark(p: Vec3, n: Vec3) -> u32 {
        let mut h = Fnv1a::default();
        for x in p.to_array().into_iter().chain(n.to_array()) {
            h.write(&x.to_bits().to_le_bytes());
        }
        let h = h.0;
        (h ^ h >> 32) as u32
    }

    /// The sample in slot `slot` of tile `tile`, which lies at `p` facing `n`: what it
    /// takes, and the level it settled at.
    #[inline]
    fn get(&self, tile: usize, slot: usize, p: Vec3, n: Vec3) -> Result<(Lookup, u32), RenderError> {
        let (a, b) = (self.slot_starts[tile], self.slot_starts[tile + 1]);
        let j = if a + slot < b {
            self.slots[a + slot]
        } else {
            NO_SAMPLE
        };
        if j != NO_SAMPLE {
            let i = self.starts[tile] + j as usize;
            if self.marks[i] == Self::mark(p, n) {
                return Ok((self.lookups[i], u32::from(self.levels[i])));
            }
        }
        Err(RenderError::Check(format!(
            "tile {tile} asked the cache for its sample in slot {slot} at {p}, which the frame did not trace there"
        )))
    }
}

/// The caches whose records keep their incident light, by what they
/// serve: samples whose bump or normal map tilts the irradiance
/// ([`TILTED`], gathered at the render's Ω and N), and samples with a
/// lobe ([`LOBED`], at the glossy Ω and N). Neither is written to a cache
/// file: each frame of a run rebuilds what it lacks, so a run from a file
/// keeps the bits of one from scratch.
pub(crate) type IncidentCaches = [Option<Cache>; 2];

/// The incident cache of tilted samples.
pub(crate) const TILTED: usize = 0;
/// The incident cache of samples with a lobe.
pub(crate) const LOBED: usize = 1;

/// The incident caches and what each of a frame's samples settled on.
pub(crate) struct Incident<'a> {
    served: [Option<(&'a Cache, &'a Settled)>; 2],
}

impl Incident<'_> {
    /// The indirect light camera sample `pp`, in slot `slot` of tile `tile`, to
    /// ask incident cache `which`, reflects, or `None` where it gathers
    /// itself: its diffuse part from the records' blended irradiance (or
    /// their incident light about its tilted normal), its lobe convolved
    /// with their incident light, both about the normal it gathers about,
    /// as its own gather would.
    pub fn light(
        &self,
        frame: &Frame,
        which: usize,
        (tile, slot): (usize, usize),
        pp: &PacketPoint,
    ) -> Result<Option<Vec3>, RenderError> {
        let Some((cache, settled)) = self.served[which] else {
            return Ok(None);
        };
        let sp = &pp.point;
        let (p, n) = (sp.position, sp.receiver_normal);
        let (lookup, level) = settled.get(tile, slot, p, n)?;
        let Lookup::Light(e) = lookup else {
            return Ok(None);
        };
        let e = if sp.normal == n {
            e
        } else {
            cache.tilted(p, n, level, sp.normal)
        };
        let mut l = sp.albedo * std::f32::consts::FRAC_1_PI * e;
        if let Some(lobe) = frame.scene.materials[sp.material].lobe() {
            l += cache.reflect(p, n, level, &lobe, n, sp.wo);
        }
        Ok(Some(l))
    }
}

/// What the cache gathered for one frame, and what its samples take.
pub(crate) struct CacheGathers {
    pub stats: TraversalStats,
    pub count: usize,
    pub settled: Settled,
    /// The same for the samples the incident caches serve.
    pub incident: [Option<Settled>; 2],
}

impl Frame<'_> {
    /// A hash of what this frame's records depend on beyond its tree: how
    /// the surfels were made (the bake record: the scene, its lights and
    /// environment, the seed, the density, the bounces), Ω, the
    /// microbuffer, the near field and the convolution. A cache file
    /// carries it, and [`load_cache`](Self::load_cache) refuses another.
    pub fn cache_settings(&self) -> u64 {
        let b = bake_record(self.scene, &self.opts);
        let mut h = Fnv1a::default();
        for x in [b.scene, b.seed] {
            h.write(&x.to_le_bytes());
        }
        let ao = matches!(self.convolution(), Convolution::Occlusion);
        for x in [
            b.density.to_bits(),
            b.light_samples,
            b.bounces,
            u32::from(b.ao)
                | u32::from(b.gathered) << 1
                | u32::from(self.near_field()) << 2
                | u32::from(ao) << 3,
            b.max_solid_angle.to_bits(),
            b.microbuffer,
            self.opts.cut.max_solid_angle.to_bits(),
            self.opts.microbuffer as u32,
        ] {
            h.write(&x.to_le_bytes());
        }
        h.0
    }

    /// Takes up the records of a cache file ([`save_cache`](Self::save_cache),
    /// this scene and settings, any earlier run or machine) in place of
    /// those gathered so far, and says how many it holds. Frames then
    /// gather only the records it lacks; the image keeps the bits of a
    /// render from scratch. Errors: the render does not gather through the
    /// cache, or the file is unreadable, damaged or made for another tree
    /// or settings ([`RenderError::CacheFile`]).
    pub fn load_cache(&mut self, r: impl Read) -> Result<usize, RenderError> {
        let threshold = self.cache_threshold()?;
        let c = Cache::load(
            r,
            &self.tree,
            CacheOptions {
                threshold,
                incident: false,
            },
            self.cache_settings(),
        )?;
        let n = c.len();
        *self
            .cache
            .get_mut()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(c);
        Ok(n)
    }

    /// Writes the records gathered so far (with those loaded) as a cache
    /// file, and says how many. Errors: the render does not gather through
    /// the cache, or writing failed.
    pub fn save_cache(&self, w: impl Write) -> Result<usize, RenderError> {
        let threshold = self.cache_threshold()?;
        let mut held = self.held_cache();
        let c = held.get_or_insert_with(|| {
            Cache::new(
                &self.tree,
                CacheOptions {
                    threshold,
                    incident: false,
                },
            )
        });
        c.save(w, self.cache_settings())
            .map_err(|e| RenderError::CacheFile(CacheFileError::Io(e)))?;
        Ok(c.len())
    }

    /// Records the cache holds (gathered or loaded); 0 without one.
    pub fn cache_len(&self) -> usize {
        self.held_cache().as_ref().map_or(0, Cache::len)
    }

    /// The cache's records' receivers in the packets a render from scratch
    /// gathers them in ([`Cache::packets`]); none without a cache. For the
    /// report's benchmark.
    #[cfg(feature = "lab")]
    pub(crate) fn cache_packets(&self) -> Vec<Vec<(Vec3, Vec3)>> {
        self.held_cache().as_ref().map_or_else(Vec::new, Cache::packets)
    }

    /// The frame's cache, locked (a render that panicked holding it left
    /// records that are each whole: they are kept).
    pub(crate) fn held_cache(&self) -> std::sync::MutexGuard<'_, Option<Cache>> {
        self.cache
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The cache's threshold, or why this render has no cache.
    fn cache_threshold(&self) -> Result<f32, RenderError> {
        match self.opts.gathers {
            Gathers::Cache { threshold } => Ok(threshold),
            g => Err(RenderError::Check(format!(
                "a cache file serves a render that gathers through the cache (--gathers cache), not one whose gathers are {g}"
            ))),
        }
    }

    /// Where samples take their light from: the lattice, else the cache.
    pub(crate) fn shared<'a>(
        lattice: Option<&'a Lattice>,
        cache: Option<&'a CacheGathers>,
    ) -> Option<Shared<'a>> {
        match (lattice, cache) {
            (Some(l), _) => Some(Shared::Lattice(l)),
            (None, Some(c)) => Some(Shared::Cache(&c.settled)),
            (None, None) => None,
        }
    }

    /// What the incident caches serve: their records and what the
    /// frame's samples settled on, where they gathered for them.
    pub(crate) fn incident<'a>(cached: Option<&'a CacheGathers>, caches: &'a IncidentCaches) -> Incident<'a> {
        let served = [TILTED, LOBED].map(|i| Some((caches[i].as_ref()?, cached?.incident[i].as_ref()?)));
        Incident { served }
    }

    /// Which incident cache serves camera samples of `material`, if any:
    /// with the cache, [`LOBED`] for a glossy lobe at least
    /// [`glossy_cache_roughness`](super::RenderOptions::glossy_cache_roughness)
    /// rough, [`TILTED`] for a diffuse surface with a bump or normal map.
    pub(crate) fn incident_cache(&self, material: usize) -> Option<usize> {
        let m = &self.scene.materials[material];
        if !matches!(self.opts.gathers, Gathers::Cache { .. }) || self.opts.ao {
            return None;
        }
        match m.glossy {
            Some(g) => (g.roughness >= self.opts.glossy_cache_roughness).then_some(LOBED),
            None => (m.bump.is_some() || m.normal_map.is_some()).then_some(TILTED),
        }
    }

    /// Gathers into `cache` (made here on a frame's first render with the
    /// cache) the records the window's camera samples need, and into the
    /// incident caches those of the samples they serve (the lobed ones
    /// with `glossy`, the gather at the glossy Ω and N); `None` unless the
    /// render gathers through the cache.
    pub(crate) fn prepare_cache(
        &self,
        cache: &mut Option<Cache>,
        incident: &mut IncidentCaches,
        gather: &Gather,
        glossy: Option<&Gather>,
        timers: &Timers,
    ) -> Result<Option<CacheGathers>, RenderError> {
        let Gathers::Cache { threshold } = self.opts.gathers else {
            return Ok(None);
        };
        if !self.needs_points {
            return Ok(None);
        }
        // The receivers the tiles will ask for: the same camera samples,
        // traced the same way (`Frame::packet`), those that take the
        // irradiance alone and those each incident cache serves (by the
        // normal they gather about).
        // Every camera sample a tile may take: an adaptive one takes those
        // past the first in some pixels only.
        let spp = self.opts.spp as usize;
        let mut per_tile: Vec<[TileSamples; 3]> = (0..self.tiles())
            .into_par_iter()
            .with_max_len(1)
            .map(|tile| {
                let pixels = self.tile_pixels(tile);
                let mut out: [TileSamples; 3] = Default::default();
                for s in 0..spp {
                    for pp in self.packet(&pixels, s as u32, None) {
                        let (m, sp) = (pp.point.material, &pp.point);
                        let (list, place) = if !self.gathers_per_sample(m) {
                            (0, (sp.position, sp.normal))
                        } else if let Some(i) = self.incident_cache(m) {
                            (1 + i, (sp.position, sp.receiver_normal))
                        } else {
                            continue;
                        };
                        let t = &mut out[list];
                        if t.slots.is_empty() {
                            t.slots = vec![NO_SAMPLE; spp * pixels.len()];
                        }
                        t.slots[s * pixels.len() + pp.pixel] = t.points.len() as u32;
                        t.points.push(place);
                    }
                }
                out
            })
            .collect();
        let opts = |incident| CacheOptions { threshold, incident };
        let cache = cache.get_or_insert_with(|| Cache::new(&self.tree, opts(false)));
        let wanted = [TILTED, LOBED].map(|i| per_tile.iter().any(|t| !t[1 + i].points.is_empty()));
        let (mut stats, mut count) = (TraversalStats::default(), 0);
        // The points of list `i` of every tile settled in `cache`.
        let mut settle_in = |cache: &mut Cache, i: usize, gather: &Gather| {
            let (settled, prepared) = settle(
                cache,
                per_tile.iter_mut().map(|t| std::mem::take(&mut t[i])),
                gather,
                self.convolution(),
            )?;
            timers.trav.add(prepared.trav);
            timers.shading.add(prepared.shading);
            stats.merge(&prepared.stats);
            count += prepared.records;
            Ok::<_, RenderError>(settled)
        };
        let settled = settle_in(cache, 0, gather)?;
        let mut served = [None, None];
        for (i, g) in [(TILTED, Some(gather)), (LOBED, glossy)] {
            let Some(g) = g.filter(|_| wanted[i]) else {
                continue;
            };
            let c = incident[i].get_or_insert_with(|| Cache::new(&self.tree, opts(true)));
            served[i] = Some(settle_in(c, 1 + i, g)?);
        }
        Ok(Some(CacheGathers {
            stats,
            count,
            settled,
            incident: served,
        }))
    }
}

/// Has `cache` gather what the points of each tile (in tile order) need,
/// and keeps what each settled on in that order. Each tile's list is
/// dropped once copied: a frame's points are most of its memory.
fn settle(
    cache: &mut Cache,
    per_tile: impl Iterator<Item = TileSamples>,
    gather: &Gather,
    what: Convolution,
) -> Result<(Settled, Prepared), RenderError> {
    let (mut starts, mut slot_starts) = (vec![0], vec![0]);
    let (mut points, mut slots) = (Vec::new(), Vec::new());
    for t in per_tile {
        points.extend_from_slice(&t.points);
        starts.push(points.len());
        slots.extend_from_slice(&t.slots);
        slot_starts.push(slots.len());
    }
    let mut prepared = cache.prepare(&points, gather, what).map_err(|e| match e {
        CacheError::Gather(e) => RenderError::from(e),
        CacheError::NonFinite { position, value } => RenderError::NonFinite {
            stage: "gather at a cache record",
            place: format!("the record at {position}"),
            value: value.to_array(),
        },
    })?;
    let marks = points.par_iter().map(|&(p, n)| Settled::mark(p, n)).collect();
    let settled = Settled {
        lookups: std::mem::take(&mut prepared.lookups),
        levels: std::mem::take(&mut prepared.levels),
        marks,
        starts,
        slots,
        slot_starts,
    };
    Ok((settled, prepared))
}
