//! The paper's Table 1 for one scene: `pre.` (surfels + tree), `trav.` for
//! each scheme, `shading` (splatting + convolution), with speed-ups over the
//! scalar reference, lane utilization and nodes tested per receiver.
//!
//! Every scheme traverses the same receivers (the camera's primary hits, in
//! 4×4-pixel packets, as [`render`](crate::render::render) forms them), and
//! the cuts are checked against the scalar reference's with an
//! order-independent checksum: a scheme that cut differently fails the
//! benchmark instead of reporting a speed-up. With
//! [`BenchReceivers::Records`] the receivers are instead the world-space
//! cache's records, in the packets a render from scratch gathers them in:
//! fewer, and less coherent than a 4×4 block of pixels.

use std::simd::{Select, prelude::*};
use std::time::Instant;

use rayon::prelude::*;

use crate::cut::{CutSink, Receiver, Scheme, SchemeChoice, Traversal, TraversalStats};
use crate::microbuffer::Convolution;
use crate::render::{Frame, Gathers, PacketPoint, RenderError, RenderOptions};
use crate::rng::mix;
use crate::scene::Scene;
use crate::simd::{Isa, LANES};
use crate::tree::NodeId;

/// Benchmark settings.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchOptions {
    /// The render settings (Ω, microbuffer, density, camera samples, ISA…);
    /// its `scheme` is ignored: every scheme of `schemes` runs.
    pub render: RenderOptions,
    /// The schemes to time (`Auto`: the renderer's per-packet choice); the
    /// scalar reference is always timed (first).
    pub schemes: Vec<SchemeChoice>,
    /// Rounds over the schemes; each figure is the fastest of its rounds.
    pub rounds: u32,
    /// Whose receivers are cut.
    pub receivers: BenchReceivers,
}

/// Whose receivers a bench cuts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BenchReceivers {
    /// The camera's primary hits, one 4×4-pixel packet per tile and camera
    /// sample: what the dense render and the screen lattice gather.
    #[default]
    Camera,
    /// The records of the world-space cache (`Gathers::Cache`, at the
    /// render's threshold, else the cache's default), 16 neighbours of one
    /// facing to a packet: a render of the frame makes them first, untimed.
    Records,
}

impl BenchReceivers {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            BenchReceivers::Camera => "camera",
            BenchReceivers::Records => "records",
        }
    }
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            render: RenderOptions {
                spp: 1,
                ..RenderOptions::default()
            },
            schemes: Scheme::ALL
                .into_iter()
                .map(SchemeChoice::Fixed)
                .chain([SchemeChoice::Auto])
                .collect(),
            rounds: 1,
            receivers: BenchReceivers::Camera,
        }
    }
}

/// One (scene, scheme) row of Table 1.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchRow {
    /// Scene name.
    pub scene: String,
    /// Traversal scheme (`auto`: per packet, as the renderer chooses).
    pub scheme: SchemeChoice,
    /// Instruction-set path it ran on.
    pub isa: Isa,
    /// Worker threads.
    pub threads: usize,
    /// Surfels in the cloud.
    pub surfels: usize,
    /// Tree bytes per surfel.
    pub bytes_per_surfel: f64,
    /// Whose receivers were cut.
    pub kind: BenchReceivers,
    /// Receivers cut.
    pub receivers: usize,
    /// Seconds for surfels (with their direct light) and tree.
    pub pre_s: f64,
    /// Seconds for the cuts of every receiver with this scheme.
    pub trav_s: f64,
    /// Seconds for splatting the cuts into the microbuffers and convolving:
    /// the scalar pipeline (one node, one pixel at a time) for the scalar
    /// reference, the 16-lane one for the vector schemes (the same cuts, so
    /// measured once per scene, pipeline and round; the fastest round).
    pub shading_s: f64,
    /// The scalar traversal's time over this one's, from the same run.
    pub speedup_vs_scalar: f64,
    /// Active lanes over lane slots (vector schemes).
    pub lane_utilization: Option<f64>,
    /// Node tests per receiver.
    pub nodes_per_receiver: f64,
    /// Splats per receiver.
    pub splats_per_receiver: f64,
}

impl BenchRow {
    /// `pre. + trav. + shading`: the frame's point-based work.
    pub fn frame_s(&self) -> f64 {
        self.pre_s + self.trav_s + self.shading_s
    }

    /// One JSON object (no dependency on a JSON crate: every field is a
    /// number or a plain string). `others_s` repeats `shading_s`, its
    /// old name, for one release; scripts should read `shading_s`.
    pub fn to_json(&self) -> String {
        let opt = |x: Option<f64>| x.map_or("null".to_string(), |v| format!("{v:.6}"));
        format!(
            concat!(
                "{{\"scene\":\"{}\",\"scheme\":\"{}\",\"isa\":\"{}\",\"threads\":{},",
                "\"surfels\":{},\"bytes_per_surfel\":{:.1},\"receiver_kind\":\"{}\",\"receivers\":{},",
                "\"pre_s\":{:.6},\"trav_s\":{:.6},\"shading_s\":{:.6},\"others_s\":{:.6},\"frame_s\":{:.6},",
                "\"speedup_vs_scalar\":{:.4},\"lane_utilization\":{},",
                "\"nodes_per_receiver\":{:.1},\"splats_per_receiver\":{:.1}}}"
            ),
            json_escape(&self.scene),
            self.scheme,
            self.isa,
            self.threads,
            self.surfels,
            self.bytes_per_surfel,
            self.kind.name(),
            self.receivers,
            self.pre_s,
            self.trav_s,
            self.shading_s,
            self.shading_s,
            self.frame_s(),
            self.speedup_vs_scalar,
            opt(self.lane_utilization),
            self.nodes_per_receiver,
            self.splats_per_receiver,
        )
    }
}

pub(crate) fn json_escape(s: &str) -> String {
    s.chars()
        .flat_map(|c| match c {
            '"' => vec!['\\', '"'],
            '\\' => vec!['\\', '\\'],
            c if (c as u32) < 0x20 => format!("\\u{:04x}", c as u32).chars().collect(),
            c => vec![c],
        })
        .collect()
}

/// murmur3's 32-bit finalizer: spreads a node index over 32 bits.
#[inline(always)]
fn hash32(x: u32) -> u32 {
    let mut h = x ^ 0x9E37_79B9;
    h = (h ^ (h >> 16)).wrapping_mul(0x85EB_CA6B);
    h = (h ^ (h >> 13)).wrapping_mul(0xC2B2_AE35);
    h ^ (h >> 16)
}

/// [`hash32`] in every lane (vector `*` wraps): a single step hashes its 16 nodes at once.
#[inline(always)]
fn hash32_lanes(x: Simd<u32, LANES>) -> Simd<u32, LANES> {
    let k = Simd::splat;
    let mut h = x ^ k(0x9E37_79B9);
    h = (h ^ (h >> k(16))) * k(0x85EB_CA6B);
    h = (h ^ (h >> k(13))) * k(0xC2B2_AE35);
    h ^ (h >> k(16))
}

/// Counts splats and sums a checksum of each receiver's cut that does not
/// depend on the order the scheme reports it in: per receiver `Σ hash(node)`.
/// It takes each scheme's vector steps whole (one hash per packet step, 16
/// hashes in the lanes per single step), as a sink of a vector scheme should,
/// so `trav.` times the traversal rather than per-splat bookkeeping.
struct CutDigest {
    /// Per receiver of the packet (wrapping sums).
    sums: Simd<u64, LANES>,
    splats: u64,
}

impl CutSink for CutDigest {
    #[inline(always)]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        let s = &mut self.sums.as_mut_array()[receiver];
        *s = s.wrapping_add(u64::from(hash32(node)));
        self.splats += 1;
    }

    #[inline(always)]
    fn splat_receivers(&mut self, base: usize, node: NodeId, lanes: u16) {
        debug_assert!(base == 0, "a packet's receivers start at 0");
        let h = Simd::splat(u64::from(hash32(node)));
        let m = Mask::<i64, LANES>::from_bitmask(u64::from(lanes));
        self.sums += m.select(h, Simd::splat(0));
        self.splats += u64::from(lanes.count_ones());
    }

    #[inline(always)]
    fn splat_nodes(&mut self, receiver: usize, nodes: &[NodeId; LANES], lanes: u16) {
        let h = hash32_lanes(Simd::from_array(*nodes));
        let m = Mask::<i32, LANES>::from_bitmask(u64::from(lanes));
        let sum = m.select(h, Simd::splat(0)).cast::<u64>().reduce_sum();
        let s = &mut self.sums.as_mut_array()[receiver];
        *s = s.wrapping_add(sum);
        self.splats += u64::from(lanes.count_ones());
    }
}

/// One packet of receivers, ready to cut and shade.
struct Packet {
    /// The camera hits, shaded as the renderer shades them; `None` for
    /// records, whose light is the irradiance.
    points: Option<Vec<PacketPoint>>,
    receivers: Vec<crate::cut::Receiver>,
    /// Index of the packet's first receiver in the frame.
    first: usize,
}

/// Times every scheme of `opts` on `scene`; one row per scheme, the scalar
/// reference first. `progress(done, total)` counts timed passes.
pub fn bench(
    scene: &Scene,
    opts: &BenchOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<BenchRow>, RenderError> {
    let scalar = SchemeChoice::Fixed(Scheme::Scalar);
    let mut schemes = vec![scalar];
    schemes.extend(opts.schemes.iter().copied().filter(|&s| s != scalar));
    let rounds = opts.rounds.max(1) as usize;
    let passes = rounds * schemes.len() + 1;
    progress(0, passes);
    let mut done = 0;

    let mut render = opts.render;
    if opts.receivers == BenchReceivers::Records && !matches!(render.gathers, Gathers::Cache { .. }) {
        render.gathers = Gathers::CACHE;
    }
    let frame = Frame::prepare(scene, &render)?;
    let traversal = Traversal::new(frame.tree(), frame.opts.cut)?;
    let threads = rayon::current_num_threads();

    let mut packets: Vec<Packet> = match opts.receivers {
        // Every camera sample of every tile, one packet each.
        BenchReceivers::Camera => (0..frame.tiles())
            .into_par_iter()
            .flat_map_iter(|tile| {
                let pixels = frame.tile_pixels(tile);
                (0..frame.opts.spp)
                    .map(|s| frame.packet(&pixels, s, None))
                    .filter(|p| !p.is_empty())
                    .collect::<Vec<_>>()
            })
            .map(|points| {
                let receivers = Frame::receivers(&points)?;
                Ok(Packet {
                    points: Some(points),
                    receivers,
                    first: 0,
                })
            })
            .collect::<Result<_, crate::Error>>()?,
        BenchReceivers::Records => {
            frame.render(&|_, _| {})?;
            frame
                .cache_packets()
                .into_iter()
                .map(|chunk| {
                    let receivers = chunk
                        .iter()
                        .map(|&(p, n)| Receiver::new(p, n))
                        .collect::<Result<_, _>>()?;
                    Ok(Packet {
                        points: None,
                        receivers,
                        first: 0,
                    })
                })
                .collect::<Result<_, crate::Error>>()?
        }
    };
    let mut first = 0;
    for p in &mut packets {
        p.first = first;
        first += p.receivers.len();
    }
    let receivers = first;

    // trav.: wall clock of the cuts of every packet, per scheme.
    let mut best = vec![f64::INFINITY; schemes.len()];
    let mut results: Vec<Option<(TraversalStats, u64, u64)>> = vec![None; schemes.len()];
    for _ in 0..rounds {
        for (i, &choice) in schemes.iter().enumerate() {
            let t0 = Instant::now();
            let (stats, digest, splats) = packets
                .par_iter()
                .map(|p| {
                    let mut sink = CutDigest {
                        sums: Simd::splat(0),
                        splats: 0,
                    };
                    let scheme = choice.resolve(p.receivers.len());
                    let stats = traversal.run(scheme, &p.receivers, &mut sink);
                    let digest = sink.sums.as_array()[..p.receivers.len()]
                        .iter()
                        .enumerate()
                        .fold(0u64, |acc, (l, &s)| {
                            acc.wrapping_add(mix(s ^ mix((p.first + l) as u64)))
                        });
                    (stats, digest, sink.splats)
                })
                .reduce(
                    || (TraversalStats::default(), 0, 0),
                    |(mut a, da, sa), (b, db, sb)| {
                        a.merge(&b);
                        (a, da.wrapping_add(db), sa + sb)
                    },
                );
            best[i] = best[i].min(t0.elapsed().as_secs_f64());
            results[i] = Some((stats, digest, splats));
            done += 1;
            progress(done, passes);
        }
    }
    let scalar_digest = results[0].as_ref().map(|r| r.1);
    for (i, r) in results.iter().enumerate() {
        if r.as_ref().map(|r| r.1) != scalar_digest {
            return Err(RenderError::Check(format!(
                "{}: the {} cuts differ from the scalar reference's",
                scene.name, schemes[i]
            )));
        }
    }

    // shading: splatting and convolution of the (identical) cuts, timed apart
    // from the traversal that makes them, in both pipelines: the scalar one
    // (the scalar row's) and the 16-lane one (every other row's).
    // Thread-seconds over threads.
    let mut shading = [f64::INFINITY; 2];
    for _ in 0..rounds {
        for (o, scheme) in shading.iter_mut().zip([Scheme::Scalar, Scheme::Packet]) {
            let gather = frame.gather_with(SchemeChoice::Fixed(scheme))?;
            let shade_ns: u64 = packets
                .par_iter()
                .map_init(
                    || gather.gatherer(),
                    |g, p| {
                        g.cut(&p.receivers).expect("a packet of at most 16");
                        let t0 = Instant::now();
                        match &p.points {
                            Some(points) => {
                                let points: Vec<_> = points.iter().collect();
                                std::hint::black_box(frame.shade(&points, g));
                            }
                            None => {
                                std::hint::black_box(g.shade(Convolution::Irradiance));
                            }
                        }
                        t0.elapsed().as_nanos() as u64
                    },
                )
                .sum();
            *o = o.min(shade_ns as f64 * 1e-9 / threads as f64);
        }
    }
    progress(passes, passes);

    let tree = frame.tree();
    let scalar_trav = best[0];
    Ok(schemes
        .iter()
        .enumerate()
        .map(|(i, &scheme)| {
            let (stats, _, splats) = results[i].expect("every scheme ran");
            BenchRow {
                scene: scene.name.clone(),
                scheme,
                isa: traversal.isa(),
                threads,
                surfels: frame.surfels,
                bytes_per_surfel: tree.bytes_per_surfel(),
                kind: opts.receivers,
                receivers,
                pre_s: frame.pre_seconds(),
                trav_s: best[i],
                shading_s: if scheme == scalar { shading[0] } else { shading[1] },
                speedup_vs_scalar: scalar_trav / best[i],
                lane_utilization: stats.lane_utilization(),
                nodes_per_receiver: stats.nodes_per_receiver(),
                splats_per_receiver: splats as f64 / receivers.max(1) as f64,
            }
        })
        .collect())
}
