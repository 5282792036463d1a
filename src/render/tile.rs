//! One 4×4-pixel tile of a frame: its camera samples, their direct light,
//! and their indirect light: interpolated from the frame's lattice of sparse
//! gathers (`sparse`) or its world-space records (`cached`), or gathered at the sample itself when no lattice
//! point around it lies on its surface, when its material is glossy or
//! bumped (`Frame::gathers_per_sample`), or when every sample
//! gathers (`Gathers::All`, the dense render).

use std::time::Instant;

use glam::Vec3;

use super::cached::{Incident, Shared};
use super::frame::{Frame, PacketPoint, TileResult, Timers};
use super::options::Component;
use super::output::RenderError;
use super::share::{Group, Unserved, centre_rank, quarter, share};
use super::sparse::Served;
use crate::cut::{Receiver, TraversalStats};
use crate::gather::{Gather, Gatherer};
use crate::rng::mix;
use crate::simd::LANES;

/// Camera sample `s` of a point that takes the irradiance of gather
/// `usize` (its place among the tile's gathering samples).
type Sharing = (u32, PacketPoint, usize);

/// What a tile's gathers leave: each camera sample's light (`[k * spp +
/// s]`), the traversal counters and the number of receivers gathered.
struct Gathered {
    adds: Vec<Vec3>,
    stats: TraversalStats,
    count: usize,
}

impl Frame<'_> {
    /// Renders `tile`: per camera sample its receivers and their direct
    /// light, then the gathers, in packets of up to 16 receivers.
    pub(crate) fn render_tile(
        &self,
        tile: usize,
        gathers: [&Gather; 2],
        shared: Option<&Shared>,
        incident: &Incident,
        timers: &Timers,
    ) -> Result<TileResult, RenderError> {
        let opts = &self.opts;
        let window = self.window();
        let w = window.width();
        let eye = self.camera.origin;
        // Made when a tile first has receivers for it (most tiles have no
        // glossy ones).
        let mut gatherers: [Option<Gatherer>; 2] = [None, None];
        let pixels = self.tile_pixels(tile);
        let spp = opts.spp as usize;
        // What camera sample `s` of pixel `k` adds, at `[k * spp + s]`: its
        // direct light (emission, light samples, or the environment its ray
        // escapes to) and its indirect light.
        let mut adds = vec![Vec3::ZERO; pixels.len() * spp];
        // Samples that gather themselves, and those the lattice serves with
        // their irradiance.
        let (mut own, mut served) = (Vec::new(), Vec::new());
        // The light of the samples the incident caches served.
        let mut reflected = Vec::new();
        let samples = self.trace_samples(&pixels, |s, mut points, misses| {
            let t0 = Instant::now();
            // Camera rays that leave the scene see the environment (light
            // that bounced nowhere: direct).
            if opts.component != Component::Indirect {
                for &(k, l) in misses {
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
                    // Where the cache settled this sample.
                    let slot = s as usize * pixels.len() + pp.pixel;
                    let sp = &pp.point;
                    let per_sample = self.gathers_per_sample(sp.material);
                    if let Some(i) = self.incident_cache(sp.material).filter(|_| per_sample) {
                        let l = incident.light(self, i, (tile, slot), &pp)?;
                        match l {
                            Some(l) => reflected.push((s, pp, l)),
                            None => own.push((s, pp, Group::Alone)),
                        }
                        continue;
                    }
                    match shared.filter(|_| !per_sample) {
                        Some(l) => {
                            let from = l.irradiance((tile, slot), pp.film, sp.position, sp.normal, eye)?;
                            match from {
                                Served::Light(e) => served.push((s, pp, e)),
                                Served::NoCorner => own.push((s, pp, Group::Pixel)),
                                Served::Changing => {
                                    let q = quarter(pp.film, pixels[pp.pixel]);
                                    own.push((s, pp, Group::Quarter(q)))
                                }
                            }
                        }
                        None => own.push((s, pp, Group::Alone)),
                    }
                }
            }
            Ok::<_, RenderError>(direct)
        })?;
        let mut acc = Gathered {
            adds,
            stats: TraversalStats::default(),
            count: 0,
        };
        // Sparse gathers: a pixel's samples that gather themselves on one
        // surface share one gather (the dense render keeps every one).
        let (own, sharing) = self.share_gathers(own, &pixels, eye);
        let e = self.gather_all(&own, &pixels, &mut acc, gathers, &mut gatherers, timers)?;
        if opts.component != Component::Direct {
            // Light not gathered at the sample itself: each sample gets one
            // indirect term, whether gathered, interpolated, shared or
            // reflected from the incident caches' records.
            let interpolated = served.into_iter().map(|(s, pp, e)| {
                let l = self.indirect(&pp, e, None);
                (s, pp, l, "interpolation from the lattice or the cache")
            });
            let shared = sharing.into_iter().map(|(s, pp, leader)| {
                let l = self.indirect(&pp, e[leader], None);
                (s, pp, l, "a gather shared in the pixel")
            });
            let reflected = reflected
                .into_iter()
                .map(|(s, pp, l)| (s, pp, l, "reflection of the cache's records"));
            for (s, pp, l, stage) in interpolated.chain(shared).chain(reflected) {
                if !l.is_finite() {
                    return Err(non_finite(stage, &pixels, &pp, s, l));
                }
                acc.adds[pp.pixel * spp + s as usize] += l;
            }
        }
        let Gathered { adds, stats, count } = acc;
        let out = pixels
            .iter()
            .zip(adds.chunks(spp))
            .zip(samples)
            .map(|((&(x, y), adds), n)| {
                let sum = adds.iter().fold(Vec3::ZERO, |a, &b| a + b);
                ((y - window.y0) * w + x - window.x0, sum / n as f32)
            })
            .collect();
        Ok((out, stats, count))
    }

    /// Splits the samples that gather themselves into those that gather
    /// and those that share another's gather ([`share`]), with that one's
    /// index among the former. The first sample of a pixel to gather is
    /// picked at random (per pixel, from the seed), so no stratum of the
    /// pixel is favoured; in a quarter, the one nearest its centre.
    fn share_gathers(
        &self,
        own: Vec<(u32, PacketPoint, Group)>,
        pixels: &[(u32, u32)],
        eye: Vec3,
    ) -> (Vec<(u32, PacketPoint)>, Vec<Sharing>) {
        let spp = self.opts.spp;
        let width = self.camera.width;
        let samples: Vec<Unserved> = own
            .iter()
            .map(|(s, pp, group)| {
                let (x, y) = pixels[pp.pixel];
                let rank = match group {
                    Group::Quarter(q) => centre_rank(pp.film, (x, y), *q),
                    _ => {
                        let pix = u64::from(y * width + x);
                        let start = (mix(self.opts.seed ^ pix.wrapping_mul(0x9E37_79B9_7F4A_7C15))
                            % u64::from(spp)) as u32;
                        (s + spp - start) % spp
                    }
                };
                Unserved {
                    pixel: pp.pixel,
                    rank,
                    position: pp.point.position,
                    normal: pp.point.normal,
                    group: *group,
                }
            })
            .collect();
        let takes = share(&samples, eye);
        // Each gathering sample's place among them, in `own`'s order.
        let place: Vec<usize> = takes
            .iter()
            .scan(0, |n, t| {
                *n += usize::from(t.is_none());
                Some(*n - 1)
            })
            .collect();
        let (mut gathers, mut sharing) = (Vec::new(), Vec::new());
        for ((s, pp, _), t) in own.into_iter().zip(&takes) {
            match t {
                None => gathers.push((s, pp)),
                Some(j) => sharing.push((s, pp, place[*j])),
            }
        }
        (gathers, sharing)
    }

    /// Cuts, splats and convolves camera samples `(s, point)` of `pixels`,
    /// 16 to a packet, those with a glossy lobe apart with the second
    /// gatherer (its own Ω and N): adds each one's indirect light to
    /// `acc.adds`, and returns what each gathered (irradiance, or
    /// occlusion), in `points`' order.
    fn gather_all<'g, 't>(
        &self,
        points: &[(u32, PacketPoint)],
        pixels: &[(u32, u32)],
        acc: &mut Gathered,
        gathers: [&'g Gather<'t>; 2],
        gatherers: &mut [Option<Gatherer<'g, 't>>; 2],
        timers: &Timers,
    ) -> Result<Vec<Vec3>, RenderError> {
        let spp = self.opts.spp as usize;
        let mut gathered = vec![Vec3::ZERO; points.len()];
        let apart = self.glossy_apart();
        let glossy =
            |(_, pp): &(u32, PacketPoint)| apart && self.scene.materials[pp.point.material].glossy.is_some();
        for ((gatherer, gather), lobe) in gatherers.iter_mut().zip(gathers).zip([false, true]) {
            let group: Vec<usize> = (0..points.len())
                .filter(|&i| glossy(&points[i]) == lobe)
                .collect();
            for chunk in group.chunks(LANES) {
                let gatherer = gatherer.get_or_insert_with(|| gather.gatherer());
                let packet: Vec<&PacketPoint> = chunk.iter().map(|&i| &points[i].1).collect();
                let receivers = packet
                    .iter()
                    .map(|pp| Receiver::new(pp.point.position, pp.point.receiver_normal))
                    .collect::<Result<Vec<_>, _>>()?;
                let t1 = Instant::now();
                acc.stats.merge(&gatherer.cut(&receivers)?);
                let t2 = Instant::now();
                timers.trav.add((t2 - t1).as_secs_f64());
                let out = self.gathered(&packet, gatherer);
                timers.shading.add(t2.elapsed().as_secs_f64());
                for (&i, (e, l)) in chunk.iter().zip(out) {
                    let (s, pp) = &points[i];
                    if !l.is_finite() {
                        return Err(non_finite("gather", pixels, pp, *s, l));
                    }
                    if self.opts.component != Component::Direct {
                        acc.adds[pp.pixel * spp + *s as usize] += l;
                    }
                    gathered[i] = e;
                }
                acc.count += chunk.len();
            }
        }
        Ok(gathered)
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
