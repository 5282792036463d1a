//! The world-space cache's side of a frame ([`Gathers::Cache`]): the
//! frame's camera samples are traced once to tell the cache where they
//! lie, the cache gathers the records they need that no earlier frame of
//! this bake made, and each sample then takes its light from the records
//! (`crate::cache`). The records depend on the scene alone, so a crop, a
//! thread count or a later frame keeps the bits of a render from scratch.

use glam::Vec3;
use rayon::prelude::*;

use super::frame::{Frame, Timers};
use super::options::Gathers;
use super::output::RenderError;
use super::sparse::{Lattice, Served};
use crate::cache::{Cache, CacheError, CacheOptions, Lookup};
use crate::cut::TraversalStats;
use crate::gather::Gather;

/// Where a frame's camera samples take their indirect light from, when
/// they do not gather it themselves.
pub(crate) enum Shared<'a> {
    /// The screen lattice of [`Gathers::Sparse`].
    Lattice(&'a Lattice),
    /// The world-space records of [`Gathers::Cache`].
    Cache(&'a Cache),
}

impl Shared<'_> {
    /// The irradiance at a camera sample through film point `film` that
    /// hit `p` with normal `n`, or why it gathers itself.
    #[inline]
    pub fn irradiance(&self, film: (f32, f32), p: Vec3, n: Vec3, eye: Vec3) -> Served {
        match self {
            Shared::Lattice(l) => l.irradiance(film, p, n, eye),
            Shared::Cache(c) => match c.lookup(p, n) {
                Lookup::Light(e) => Served::Light(e),
                Lookup::Uncovered => Served::NoCorner,
                Lookup::Changing => Served::Changing,
            },
        }
    }
}

/// What the cache gathered for one frame.
#[derive(Default)]
pub(crate) struct CacheGathers {
    pub stats: TraversalStats,
    pub count: usize,
}

impl Frame<'_> {
    /// Where samples take their light from: the lattice, else the cache.
    pub(crate) fn shared<'a>(lattice: Option<&'a Lattice>, cache: Option<&'a Cache>) -> Option<Shared<'a>> {
        match (lattice, cache) {
            (Some(l), _) => Some(Shared::Lattice(l)),
            (None, Some(c)) => Some(Shared::Cache(c)),
            (None, None) => None,
        }
    }

    /// Gathers into `cache` (made here on a frame's first render with the
    /// cache) the records the window's camera samples need; `None` unless
    /// the render gathers through the cache.
    pub(crate) fn prepare_cache(
        &self,
        cache: &mut Option<Cache>,
        gather: &Gather,
        timers: &Timers,
    ) -> Result<Option<CacheGathers>, RenderError> {
        let Gathers::Cache { threshold } = self.opts.gathers else {
            return Ok(None);
        };
        if !self.needs_points {
            return Ok(None);
        }
        let cache = cache.get_or_insert_with(|| Cache::new(&self.tree, CacheOptions { threshold }));
        // The receivers the tiles will ask for: the same camera samples,
        // traced the same way (`Frame::packet`).
        let spp = self.opts.spp;
        let points: Vec<(Vec3, Vec3)> = (0..self.tiles())
            .into_par_iter()
            .with_max_len(1)
            .flat_map_iter(|tile| {
                let pixels = self.tile_pixels(tile);
                (0..spp)
                    .flat_map(|s| self.packet(&pixels, s, None))
                    .filter(|pp| !self.gathers_per_sample(pp.point.material))
                    .map(|pp| (pp.point.position, pp.point.normal))
                    .collect::<Vec<_>>()
            })
            .collect();
        let prepared = cache
            .prepare(&points, gather, self.convolution())
            .map_err(|e| match e {
                CacheError::Gather(e) => RenderError::from(e),
                CacheError::NonFinite { position, value } => RenderError::NonFinite {
                    stage: "gather at a cache record",
                    place: format!("the record at {position}"),
                    value: value.to_array(),
                },
            })?;
        timers.trav.add(prepared.trav);
        timers.shading.add(prepared.shading);
        Ok(Some(CacheGathers {
            stats: prepared.stats,
            count: prepared.records,
        }))
    }
}
