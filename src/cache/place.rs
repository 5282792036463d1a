//! Where a cache's records go and how they are gathered: a cell's
//! candidate surfel, and the records of a level's cells gathered in
//! packets of 16 neighbours of one facing, with what each keeps.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::grid::{Grid, Key, cell_of};
use super::{Cache, CacheError, NONE, Prepared, Record, facing};
use crate::cut::Receiver;
use crate::gather::Gather;
use crate::microbuffer::{Convolution, Gradients, Table};
use crate::simd::LANES;

impl Cache {
    /// The record candidate of the cell and facing `k`: the leaf of that
    /// facing nearest the cell's centre (the first in code order among
    /// equals), if any.
    pub(super) fn candidate(&self, k: Key) -> Option<(Vec3, Vec3)> {
        let (c, level, f) = cell_of(k);
        let (lo, hi) = Grid::codes(c, level);
        let a = self.codes.partition_point(|&x| x < lo);
        let b = self.codes.partition_point(|&x| x < hi);
        let centre = self.grid.centre(c, level);
        let mut best: Option<(f32, usize)> = None;
        for i in a..b {
            let (p, n) = self.leaves[i];
            let d = (p - centre).length_squared();
            if facing(n) == f && best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, i));
            }
        }
        best.map(|(_, i)| self.leaves[i])
    }

    /// Gathers the records of cells `keys` (sorted) and files them.
    pub(super) fn gather_cells(
        &mut self,
        keys: &[Key],
        gather: &Gather,
        what: Convolution,
        out: &mut Prepared,
    ) -> Result<(), CacheError> {
        let found: Vec<Option<(Vec3, Vec3)>> = keys.par_iter().map(|&k| self.candidate(k)).collect();
        // Sorted keys run facing by facing, neighbours in Morton order: a
        // packet's receivers face one way and share most of their cuts.
        let asked: Vec<(Vec3, Vec3)> = found.iter().flatten().copied().collect();
        let keep = self.incident.is_some();
        if keep {
            // The table of the gather's buffers (one per resolution).
            self.table
                .get_or_insert_with(|| Table::shared(gather.options().microbuffer));
        }
        let packets = asked
            .par_chunks(LANES)
            .map_init(
                || gather.gatherer(),
                |g, chunk| -> Result<_, CacheError> {
                    let receivers = chunk
                        .iter()
                        .map(|&(p, n)| Receiver::new(p, n))
                        .collect::<Result<Vec<_>, _>>()?;
                    let t0 = Instant::now();
                    let stats = g.cut(&receivers)?;
                    let t1 = Instant::now();
                    let e = g.shade(what);
                    let slopes: Vec<Gradients> = match what {
                        // The one gradient a lookup applies, from the
                        // composition `shade` just made.
                        Convolution::Irradiance => g
                            .buffers()
                            .iter()
                            .take(e.len())
                            .map(|b| Gradients {
                                rotation: b.turning(),
                                distance: f32::INFINITY,
                                ..Gradients::default()
                            })
                            .collect(),
                        Convolution::Occlusion => vec![Gradients::default(); e.len()],
                    };
                    // Occlusion leaves no light to keep: dark pixels.
                    let mut seen = Vec::new();
                    if keep {
                        for b in g.buffers().iter().take(e.len()) {
                            let mut l = Vec::new();
                            match what {
                                Convolution::Irradiance => b.incident(&mut l),
                                Convolution::Occlusion => l.resize(b.pixels(), Vec3::ZERO),
                            }
                            seen.push(l);
                        }
                    }
                    let e: Vec<(Vec3, Gradients)> = e.into_iter().zip(slopes).collect();
                    Ok((
                        e,
                        seen,
                        stats,
                        (t1 - t0).as_secs_f64(),
                        t1.elapsed().as_secs_f64(),
                    ))
                },
            )
            .collect::<Result<Vec<_>, _>>()?;
        let mut light = Vec::with_capacity(asked.len());
        let mut seen_all = Vec::new();
        for (chunk, (e, seen, stats, trav, shading)) in asked.chunks(LANES).zip(packets) {
            out.stats.merge(&stats);
            out.trav += trav;
            out.shading += shading;
            for (&(position, _), (e, g)) in chunk.iter().zip(e) {
                if !e.is_finite() || !g.translation.iter().chain(&g.rotation).all(|v| v.is_finite()) {
                    return Err(CacheError::NonFinite { position, value: e });
                }
                light.push((e, g));
            }
            for (&(position, _), l) in chunk.iter().zip(seen) {
                if let Some(&value) = l.iter().find(|v| !v.is_finite()) {
                    return Err(CacheError::NonFinite { position, value });
                }
                seen_all.push(l);
            }
        }
        let mut seen_all = seen_all.into_iter();
        // One light per candidate, in `found`'s order.
        let mut next = 0;
        for (&k, f) in keys.iter().zip(&found) {
            let index = match *f {
                Some((position, normal)) => {
                    let (e, gradients) = light[next];
                    if let (Some(all), Some(l)) = (self.incident.as_mut(), seen_all.next()) {
                        all.extend(l);
                    }
                    self.records.push(Record {
                        position,
                        normal,
                        e,
                        gradients,
                    });
                    next += 1;
                    out.records += 1;
                    self.records.len() as u32 - 1
                }
                None => NONE,
            };
            self.cells.insert(k, index);
        }
        Ok(())
    }
}
