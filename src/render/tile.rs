//! One 4×4-pixel tile of a frame: its camera samples, their direct light,
//! and the gathers that give their indirect light, decoupled from the
//! camera samples.
//!
//! The indirect light varies slowly over a surface, so a pixel gathers at
//! `gathers` of its camera samples (picked from a random start, every
//! stratum equally likely), and each other sample reuses the irradiance of
//! a gathered sample of its pixel that lies on the same surface: the same
//! plane up to rounding and a normal within [`SAME_NORMAL`]. A sample with no
//! such neighbour (a pixel across an edge, a contact, a silhouette) or with
//! a glossy lobe (whose convolution needs its own microbuffer) gathers
//! itself. The sample's own material reflects the reused irradiance, so a
//! pixel across a change of albedo stays exact. With every sample gathering
//! (`RenderOptions::gathers` `None`), this is the dense render, bit for bit.

use std::time::Instant;

use glam::Vec3;

use super::frame::{Frame, PacketPoint, TileResult, Timers};
use super::options::Component;
use super::output::RenderError;
use crate::cut::{Receiver, TraversalStats};
use crate::gather::{Gather, Gatherer};
use crate::simd::LANES;

/// Camera samples `(s, point)` of a tile.
type Samples = Vec<(u32, PacketPoint)>;

/// Cosine between two normals of one surface.
const SAME_NORMAL: f32 = 0.995;
/// Distance off a gathered point's plane, relative to the camera's
/// distance, that still counts as its plane (rounding only: two surfaces
/// a pixel straddles are far further apart).
const SAME_PLANE: f32 = 1e-4;

/// A gathered sample of a pixel: where, and the irradiance (or occlusion)
/// its microbuffer gave.
struct Record {
    position: Vec3,
    normal: Vec3,
    e: Vec3,
}

impl Record {
    /// Whether `pp` (seen from `eye`) lies on this record's surface.
    fn covers(&self, pp: &PacketPoint, eye: Vec3) -> bool {
        let p = &pp.point;
        self.normal.dot(p.normal) >= SAME_NORMAL
            && self.normal.dot(p.position - self.position).abs() <= SAME_PLANE * (p.position - eye).length()
    }
}

/// What a tile's gathers leave: each camera sample's light (`[k * spp +
/// s]`), each pixel's gathered records, the traversal counters and the
/// number of receivers gathered.
struct Gathered {
    adds: Vec<Vec3>,
    records: Vec<Vec<Record>>,
    stats: TraversalStats,
    count: usize,
}

impl Frame<'_> {
    /// Renders `tile`: per camera sample its receivers and their direct
    /// light, then the gathers, in packets of up to 16 receivers.
    pub(crate) fn render_tile(
        &self,
        tile: usize,
        gather: &Gather,
        timers: &Timers,
    ) -> Result<TileResult, RenderError> {
        let opts = &self.opts;
        let window = self.window();
        let w = window.width();
        let eye = self.scene.camera.origin;
        let mut gatherer = gather.gatherer();
        let pixels = self.tile_pixels(tile);
        let spp = opts.spp as usize;
        let gathers = opts.gathers.unwrap_or(opts.spp);
        // What camera sample `s` of pixel `k` adds, at `[k * spp + s]`: its
        // direct light (emission, light samples, or the environment its ray
        // escapes to) and its indirect light.
        let mut adds = vec![Vec3::ZERO; pixels.len() * spp];
        let start = self.gathering(&pixels, gathers);
        let (mut first, mut rest): (Samples, Samples) = (Vec::new(), Vec::new());
        let mut misses = Vec::new();
        for s in 0..opts.spp {
            let t0 = Instant::now();
            misses.clear();
            let mut points = self.packet(&pixels, s, Some(&mut misses));
            // Camera rays that leave the scene see the environment (light
            // that bounced nowhere: direct).
            if opts.component != Component::Indirect {
                for &(k, l) in &misses {
                    adds[k * spp + s as usize] = l;
                }
            }
            let direct = self.direct(&mut points);
            timers.direct.add(t0.elapsed().as_secs_f64());
            for (pp, d) in points.iter().zip(&direct) {
                if !d.is_finite() {
                    return Err(non_finite("direct light at receivers", &pixels, pp, s, *d));
                }
                if opts.component != Component::Indirect {
                    adds[pp.pixel * spp + s as usize] = *d;
                }
            }
            if self.needs_points {
                for pp in points {
                    if (s + opts.spp - start[pp.pixel]) % opts.spp < gathers {
                        first.push((s, pp));
                    } else {
                        rest.push((s, pp));
                    }
                }
            }
        }
        let mut acc = Gathered {
            adds,
            records: (0..pixels.len()).map(|_| Vec::new()).collect(),
            stats: TraversalStats::default(),
            count: 0,
        };
        self.gather_all(&first, &pixels, &mut acc, &mut gatherer, timers)?;
        // The other samples reuse a record of their pixel's surface, or
        // gather themselves.
        let mut own = Vec::new();
        for (s, pp) in rest {
            let glossy = self.scene.materials[pp.point.material].lobe().is_some();
            match acc.records[pp.pixel].iter().find(|r| r.covers(&pp, eye)) {
                Some(r) if !glossy => {
                    if opts.component != Component::Direct {
                        acc.adds[pp.pixel * spp + s as usize] += self.indirect(&pp, r.e, None);
                    }
                }
                _ => own.push((s, pp)),
            }
        }
        self.gather_all(&own, &pixels, &mut acc, &mut gatherer, timers)?;
        let Gathered {
            adds, stats, count, ..
        } = acc;
        let out = pixels
            .iter()
            .zip(adds.chunks(spp))
            .map(|(&(x, y), adds)| {
                let sum = adds.iter().fold(Vec3::ZERO, |a, &b| a + b);
                ((y - window.y0) * w + x - window.x0, sum / opts.spp as f32)
            })
            .collect();
        Ok((out, stats, count))
    }

    /// Cuts, splats and convolves camera samples `(s, point)` of `pixels`,
    /// 16 to a packet: adds each one's indirect light to `acc.adds` and
    /// keeps its irradiance in `acc.records`.
    fn gather_all(
        &self,
        points: &[(u32, PacketPoint)],
        pixels: &[(u32, u32)],
        acc: &mut Gathered,
        gatherer: &mut Gatherer,
        timers: &Timers,
    ) -> Result<(), RenderError> {
        let spp = self.opts.spp as usize;
        for chunk in points.chunks(LANES) {
            let points: Vec<&PacketPoint> = chunk.iter().map(|(_, pp)| pp).collect();
            let receivers = points
                .iter()
                .map(|pp| Receiver::new(pp.point.position, pp.point.normal))
                .collect::<Result<Vec<_>, _>>()?;
            let t1 = Instant::now();
            acc.stats.merge(&gatherer.cut(&receivers)?);
            let t2 = Instant::now();
            timers.trav.add((t2 - t1).as_secs_f64());
            let out = self.gathered(&points, gatherer);
            timers.others.add(t2.elapsed().as_secs_f64());
            for ((s, pp), (e, l)) in chunk.iter().zip(out) {
                if !l.is_finite() {
                    return Err(non_finite("gather", pixels, pp, *s, l));
                }
                if self.opts.component != Component::Direct {
                    acc.adds[pp.pixel * spp + *s as usize] += l;
                }
                acc.records[pp.pixel].push(Record {
                    position: pp.point.position,
                    normal: pp.point.normal,
                    e,
                });
            }
            acc.count += chunk.len();
        }
        Ok(())
    }
}

/// A non-finite value at camera sample `s` of `pp`'s pixel, at `stage`.
fn non_finite(stage: &'static str, pixels: &[(u32, u32)], pp: &PacketPoint, s: u32, v: Vec3) -> RenderError {
    let (x, y) = pixels[pp.pixel];
    RenderError::NonFinite {
        stage,
        place: format!("pixel ({x}, {y}), camera sample {s}"),
        value: v.to_array(),
    }
}
