//! Rendering a scene with point-based global illumination: camera rays give
//! the receivers (4×4 pixel tiles make the packets), the kernels give their
//! cuts, the microbuffer splats and convolves them, direct light comes from
//! shadow rays. Stages a scene does not need are left out, and said so.

use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use crate::brdf::GlossyLobe;
use crate::cut::{CutOptions, CutSink, Isa, LANES, Receiver, Scheme, Traversal, TraversalStats, auto_scheme};
use crate::error::Error;
use crate::light::Lights;
use crate::microbuffer::{Convolution, MicroBuffer, PacketCut, shade_cuts, shade_packet};
use crate::points::bake::{BakeOptions, bake};
use crate::points::{PointCloud, Surfel};
use crate::scene::{Bump, Material, Scene, SceneError};
use crate::synthetic::Rng;
use crate::trace::{Hit, Tracer};
use crate::tree::{NodeId, Tree};

/// Which scheme the renderer runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SchemeChoice {
    /// Per packet, [`auto_scheme`]: packet, single for sparse packets.
    Auto,
    /// A named scheme.
    Fixed(Scheme),
}

/// Render settings; the defaults render the Cornell box in about a second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Traversal scheme.
    pub scheme: SchemeChoice,
    /// Ω of the node test.
    pub max_solid_angle: f32,
    /// Hybrid switch threshold (active lanes).
    pub hybrid_threshold: u32,
    /// Microbuffer resolution N (an N×N octahedral grid over the hemisphere).
    pub microbuffer: usize,
    /// Indirect bounces: 0 direct only, 1 direct + one bounce (Mitsuba's `max_depth` 3), …
    pub bounces: u32,
    /// Camera samples per pixel (each a receiver).
    pub spp: u32,
    /// Light samples per receiver for direct light (`None`: `spp`, at most 16).
    pub direct_samples: Option<u32>,
    /// Ambient-occlusion mode: no radiance at all, `1 − AO` as a grey image.
    pub ao: bool,
    /// Surfels per unit area.
    pub density: f32,
    /// Area-light samples per surfel.
    pub surfel_light_samples: u32,
    /// Instruction-set path (`None`: `PBGI_ISA`, else the best).
    pub isa: Option<Isa>,
    /// Seed of every random choice.
    pub seed: u64,
}

impl fmt::Display for SchemeChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SchemeChoice::Auto => f.write_str("auto"),
            SchemeChoice::Fixed(s) => s.fmt(f),
        }
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            scheme: SchemeChoice::Auto,
            max_solid_angle: 0.05,
            hybrid_threshold: 2,
            microbuffer: 12,
            bounces: 1,
            spp: 4,
            direct_samples: None,
            ao: false,
            density: 2000.0,
            surfel_light_samples: 16,
            isa: None,
            seed: 1,
        }
    }
}

/// A linear RGB image, row-major from the top-left corner.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear radiance per pixel.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// 8-bit sRGB, clamped (no other tone mapping).
    pub fn to_srgb8(&self) -> Vec<u8> {
        let encode = |x: f32| {
            let x = x.clamp(0.0, 1.0);
            let s = if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0 + 0.5) as u8
        };
        self.pixels
            .iter()
            .flat_map(|p| [encode(p.x), encode(p.y), encode(p.z)])
            .collect()
    }
}

/// Seconds per stage, summed over threads (the paper's Table 1 columns).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Point cloud (surfels + their direct light + extra bounces) and tree.
    pub pre: f64,
    /// Cut traversal.
    pub trav: f64,
    /// Splatting and convolution.
    pub others: f64,
    /// Camera rays and direct light at the receivers.
    pub direct: f64,
    /// Wall-clock seconds of the whole render.
    pub total_wall: f64,
}

/// One pipeline stage and whether it ran.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stage {
    /// What it is.
    pub name: &'static str,
    /// `None` if it ran, else why it was left out.
    pub skipped: Option<String>,
}

/// What a render produced.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The image.
    pub image: Image,
    /// Stage times.
    pub timings: Timings,
    /// Traversal counters over all receivers.
    pub stats: TraversalStats,
    /// The scheme that ran (on full packets, under `auto`).
    pub scheme: Scheme,
    /// The choice it came from.
    pub choice: SchemeChoice,
    /// The instruction-set path that ran.
    pub isa: Isa,
    /// Surfels in the cloud (0 when none was needed).
    pub surfels: usize,
    /// Receivers shaded.
    pub receivers: usize,
    /// Every stage, run or left out.
    pub stages: Vec<Stage>,
}

/// Errors of a render.
#[derive(Debug)]
#[non_exhaustive]
pub enum RenderError {
    /// The scene is unusable.
    Scene(SceneError),
    /// A kernel-layer error (options, ISA, invalid surfels).
    Kernel(Error),
    /// A self-check failed (a scheme's cuts differ from the reference's, or
    /// an image does not match its reference's size).
    Check(String),
}

impl std::fmt::Display for RenderError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RenderError::Scene(e) => e.fmt(f),
            RenderError::Kernel(e) => e.fmt(f),
            RenderError::Check(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for RenderError {}

impl From<Error> for RenderError {
    fn from(e: Error) -> Self {
        RenderError::Kernel(e)
    }
}

impl From<SceneError> for RenderError {
    fn from(e: SceneError) -> Self {
        RenderError::Scene(e)
    }
}

/// Splat lists of one packet, filled by the traversal and splatted afterwards
/// so traversal and splatting are timed apart.
pub(crate) struct SplatLists(pub Vec<Vec<NodeId>>);

impl SplatLists {
    pub fn new() -> Self {
        SplatLists(vec![Vec::new(); LANES])
    }

    pub fn clear(&mut self) {
        for l in &mut self.0 {
            l.clear();
        }
    }
}

impl CutSink for SplatLists {
    #[inline]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.0[receiver].push(node);
    }
}

/// A packet's cuts as the shading pipeline of the scheme wants them: per
/// receiver lists for the scalar reference (shaded one node at a time), each
/// node with its lanes for the vector schemes (shaded 16 lanes at a time).
pub(crate) enum PacketCuts {
    Lists(SplatLists),
    Lanes(PacketCut),
}

impl PacketCuts {
    /// The form `scheme`'s pipeline uses.
    pub fn for_scheme(scheme: Scheme, tree: &Tree) -> Self {
        match scheme {
            Scheme::Scalar => PacketCuts::Lists(SplatLists::new()),
            _ => PacketCuts::Lanes(PacketCut::new(tree)),
        }
    }

    /// Cuts `receivers` (one packet) into `self`, which is cleared first.
    pub fn run(&mut self, traversal: &Traversal, scheme: Scheme, receivers: &[Receiver]) -> TraversalStats {
        match self {
            PacketCuts::Lists(l) => {
                l.clear();
                traversal.run(scheme, receivers, l)
            }
            PacketCuts::Lanes(c) => {
                c.clear();
                traversal.run(scheme, receivers, c)
            }
        }
    }
}

/// Tilts `n` by the procedural bump at `p`.
fn bumped(n: Vec3, p: Vec3, bump: &Bump) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let w = std::f32::consts::TAU * bump.frequency;
    let tilt = t * (w * p.dot(t)).sin() + b * (w * p.dot(b) + 1.3).sin();
    (n + tilt * bump.amplitude).normalize()
}

/// A shading point: where a camera ray hit, how to shade it.
pub(crate) struct ShadingPoint {
    /// Hit point, moved off the surface by the tracer's epsilon.
    pub position: Vec3,
    /// Shading normal on the viewer's side.
    pub normal: Vec3,
    /// Unit direction back to the viewer.
    pub wo: Vec3,
    /// Material index.
    pub material: usize,
    /// Emitted radiance towards the viewer.
    pub emitted: Vec3,
}

pub(crate) fn shading_point(
    scene: &Scene,
    tracer: &Tracer,
    origin: Vec3,
    dir: Vec3,
    hit: &Hit,
) -> Option<ShadingPoint> {
    let mesh = &scene.meshes[hit.mesh as usize];
    let material: &Material = &scene.materials[mesh.material];
    let mut ng = hit.geometric_normal;
    let front = ng.dot(dir) < 0.0;
    if !front {
        if !material.two_sided {
            return None; // a one-sided surface seen from behind is black
        }
        ng = -ng;
    }
    let position = origin + dir * hit.t;
    let mut normal = match &mesh.normals {
        Some(normals) => {
            let t = mesh.triangles[hit.triangle as usize];
            let (u, v) = (hit.uv.x, hit.uv.y);
            let ns = normals[t[0] as usize] * (1.0 - u - v)
                + normals[t[1] as usize] * u
                + normals[t[2] as usize] * v;
            let ns = ns.normalize_or(ng);
            if ns.dot(ng) > 0.0 { ns } else { ng }
        }
        None => ng,
    };
    if let Some(b) = &material.bump {
        normal = bumped(normal, position, b);
    }
    let emitted = if front {
        mesh.emission.unwrap_or(Vec3::ZERO)
    } else {
        Vec3::ZERO
    };
    Some(ShadingPoint {
        position: position + ng * tracer.epsilon(),
        normal,
        wo: -dir,
        material: mesh.material,
        emitted,
    })
}

/// One tile's pixels (index, radiance), traversal counters and receiver count.
type TileResult = (Vec<(u32, Vec3)>, TraversalStats, usize);

struct Accum(AtomicU64);
impl Accum {
    fn new() -> Self {
        Accum(AtomicU64::new(0))
    }
    fn add(&self, seconds: f64) {
        self.0.fetch_add((seconds * 1e9) as u64, Ordering::Relaxed);
    }
    fn seconds(&self) -> f64 {
        self.0.load(Ordering::Relaxed) as f64 * 1e-9
    }
}

/// One receiver of a packet: the pixel of its tile (0..16), where the camera
/// ray hit, and the random stream of its direct-light samples.
pub(crate) struct PacketPoint {
    pub pixel: usize,
    pub point: ShadingPoint,
    pub rng: Rng,
}

/// A scene made ready to render: ray queries, lights, surfels and their tree
/// (the paper's `pre.` column), and the resolved scheme. [`render`] runs it
/// whole; the benchmark and the error report run its stages one by one.
pub struct Frame<'s> {
    pub(crate) scene: &'s Scene,
    pub(crate) opts: RenderOptions,
    pub(crate) tracer: Tracer,
    pub(crate) lights: Lights,
    pub(crate) tree: Tree,
    pub(crate) surfels: usize,
    pub(crate) scheme: Scheme,
    pub(crate) pre: f64,
    pub(crate) stages: Vec<Stage>,
    needs_points: bool,
}

impl<'s> Frame<'s> {
    /// Validates the options, builds the ray queries, bakes the surfels
    /// (with extra bounces if asked) and builds the tree.
    pub fn prepare(scene: &'s Scene, opts: &RenderOptions) -> Result<Self, RenderError> {
        scene.validate()?;
        if opts.spp == 0 {
            return Err(Error::InvalidParameter {
                name: "spp",
                value: "0".into(),
                expected: "at least 1",
            }
            .into());
        }
        MicroBuffer::new(opts.microbuffer)?;
        let mut stages = Vec::new();
        let needs_points = opts.ao || opts.bounces > 0;
        let scheme = match opts.scheme {
            SchemeChoice::Fixed(s) => s,
            SchemeChoice::Auto => auto_scheme(LANES),
        };

        let t_pre = Instant::now();
        let tracer = Tracer::new(scene);
        let lights = Lights::new(scene);
        let bake_opts = BakeOptions {
            density: opts.density,
            light_samples: if opts.ao { 0 } else { opts.surfel_light_samples },
            seed: opts.seed,
        };
        let (tree, surfels) = if needs_points {
            let baked = bake(scene, &tracer, &lights, &bake_opts)?;
            stages.push(Stage {
                name: "surfels + direct light at surfels",
                skipped: opts.ao.then(|| "AO mode: surfels carry no radiance".to_string()),
            });
            let direct: Vec<Vec3> = baked.cloud.surfels().iter().map(|s| s.radiance).collect();
            let mut cloud = baked.cloud;
            let mut tree = Tree::build(&cloud);
            for _ in 1..opts.bounces.max(1) {
                cloud = gather_bounce(&cloud, &direct, &baked.albedo, &tree, scheme, opts)?;
                tree = Tree::build(&cloud);
            }
            stages.push(Stage {
                name: "extra bounces gathered at surfels",
                skipped: (opts.bounces <= 1).then(|| format!("--bounces {} needs none", opts.bounces)),
            });
            let n = cloud.len();
            (tree, n)
        } else {
            stages.push(Stage {
                name: "surfels, tree and cuts",
                skipped: Some("--bounces 0: direct light only".into()),
            });
            (Tree::build(&PointCloud::default()), 0)
        };
        let pre = t_pre.elapsed().as_secs_f64();
        stages.push(Stage {
            name: "glossy lobe convolution",
            skipped: (!scene.has_glossy() || opts.ao).then(|| "no glossy material".to_string()),
        });
        stages.push(Stage {
            name: "hybrid packet→single switching",
            skipped: (scheme != Scheme::Hybrid).then(|| format!("scheme {scheme}")),
        });
        stages.push(Stage {
            name: "direct light at receivers",
            skipped: (opts.ao || lights.is_empty()).then(|| {
                if opts.ao {
                    "AO mode".to_string()
                } else {
                    "the scene has no light".to_string()
                }
            }),
        });
        Ok(Frame {
            scene,
            opts: *opts,
            tracer,
            lights,
            tree,
            surfels,
            scheme,
            pre,
            stages,
            needs_points,
        })
    }

    /// The tree of the surfels (empty when the render needs none).
    pub fn tree(&self) -> &Tree {
        &self.tree
    }

    /// Seconds spent in [`prepare`](Self::prepare) on surfels and tree.
    pub fn pre_seconds(&self) -> f64 {
        self.pre
    }

    /// The scheme `opts.scheme` resolved to for a full packet.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// The scheme for a packet of `receivers` receivers.
    pub(crate) fn scheme_for(&self, receivers: usize) -> Scheme {
        match self.opts.scheme {
            SchemeChoice::Auto => auto_scheme(receivers),
            SchemeChoice::Fixed(s) => s,
        }
    }

    /// The traversal with this frame's options and `scheme`'s needs.
    pub(crate) fn traversal(&self) -> Result<Traversal<'_>, Error> {
        Traversal::new(
            &self.tree,
            CutOptions {
                max_solid_angle: self.opts.max_solid_angle,
                hybrid_threshold: self.opts.hybrid_threshold,
                isa: self.opts.isa,
            },
        )
    }

    /// Number of 4×4-pixel tiles.
    pub(crate) fn tiles(&self) -> usize {
        let c = &self.scene.camera;
        (c.width.div_ceil(4) * c.height.div_ceil(4)) as usize
    }

    /// The pixels `(x, y)` of `tile`, row by row (fewer at the image's edges).
    pub(crate) fn tile_pixels(&self, tile: usize) -> Vec<(u32, u32)> {
        let c = &self.scene.camera;
        let tiles_x = c.width.div_ceil(4);
        let (tx, ty) = ((tile as u32 % tiles_x) * 4, (tile as u32 / tiles_x) * 4);
        (0..16)
            .map(|i| (tx + i % 4, ty + i / 4))
            .filter(|&(x, y)| x < c.width && y < c.height)
            .collect()
    }

    /// One packet: camera sample `s` of each pixel of a tile (stratified over
    /// the pixel), the rays that hit a visible surface.
    pub(crate) fn packet(&self, pixels: &[(u32, u32)], s: u32) -> Vec<PacketPoint> {
        let cam = &self.scene.camera;
        let grid = (self.opts.spp as f32).sqrt().ceil() as u32;
        let mut points = Vec::with_capacity(pixels.len());
        for (k, &(x, y)) in pixels.iter().enumerate() {
            let pix = y * cam.width + x;
            let mut rng = Rng::new(
                self.opts.seed ^ ((pix as u64) << 20 | s as u64).wrapping_mul(0xD1B5_4A32_D192_ED03),
            );
            let (sx, sy) = (s % grid, s / grid % grid);
            let fx = x as f32 + (sx as f32 + rng.f32()) / grid as f32;
            let fy = y as f32 + (sy as f32 + rng.f32()) / grid as f32;
            let dir = cam.ray_direction(fx, fy);
            if let Some(hit) = self.tracer.closest(cam.origin, dir, f32::INFINITY)
                && let Some(point) = shading_point(self.scene, &self.tracer, cam.origin, dir, &hit)
            {
                points.push(PacketPoint { pixel: k, point, rng });
            }
        }
        points
    }

    /// Emission plus direct light at each point (zero in AO mode).
    pub(crate) fn direct(&self, points: &mut [PacketPoint]) -> Vec<Vec3> {
        if self.opts.ao {
            return vec![Vec3::ZERO; points.len()];
        }
        points
            .iter_mut()
            .map(|pp| {
                let sp = &pp.point;
                let m = &self.scene.materials[sp.material];
                let lobe = m.glossy.map(|g| GlossyLobe {
                    specular: g.specular,
                    roughness: g.roughness,
                });
                let fd = m.albedo * std::f32::consts::FRAC_1_PI;
                let (n, wo) = (sp.normal, sp.wo);
                let f = |wi: Vec3| match &lobe {
                    Some(l) => fd + l.eval(n, wo, wi),
                    None => fd,
                };
                let samples = self.opts.direct_samples.unwrap_or(self.opts.spp.min(16));
                sp.emitted
                    + self
                        .lights
                        .reflected(&self.tracer, sp.position, n, samples, &mut pp.rng, f)
            })
            .collect()
    }

    /// The receivers of `points`.
    pub(crate) fn receivers(points: &[PacketPoint]) -> Result<Vec<Receiver>, Error> {
        points
            .iter()
            .map(|pp| Receiver::new(pp.point.position, pp.point.normal))
            .collect()
    }

    /// Splats each point's cut into its microbuffer and convolves, on path
    /// `isa`: the indirect light (or `1 − AO`) at each point. `bufs` holds at
    /// least one buffer per point.
    pub(crate) fn shade(
        &self,
        points: &[PacketPoint],
        cuts: &mut PacketCuts,
        bufs: &mut [MicroBuffer],
        isa: Isa,
    ) -> Vec<Vec3> {
        let tree = &self.tree;
        let bufs = &mut bufs[..points.len()];
        for (mb, pp) in bufs.iter_mut().zip(points) {
            mb.reset(pp.point.position, pp.point.normal);
        }
        let what = if self.opts.ao {
            Convolution::Occlusion
        } else {
            Convolution::Irradiance
        };
        let mut out = vec![Vec3::ZERO; points.len()];
        match cuts {
            PacketCuts::Lists(l) => shade_cuts(isa, bufs, tree, &l.0, what, &mut out),
            PacketCuts::Lanes(c) => shade_packet(isa, bufs, tree, c, what, &mut out),
        }
        points
            .iter()
            .zip(bufs.iter())
            .zip(out)
            .map(|((pp, mb), e)| {
                let sp = &pp.point;
                let m = &self.scene.materials[sp.material];
                if self.opts.ao {
                    Vec3::splat(1.0 - e.x)
                } else {
                    let mut l = m.albedo * std::f32::consts::FRAC_1_PI * e;
                    if let Some(g) = m.glossy {
                        let lobe = GlossyLobe {
                            specular: g.specular,
                            roughness: g.roughness,
                        };
                        l += mb.glossy(tree, sp.wo, &lobe);
                    }
                    l
                }
            })
            .collect()
    }

    /// Renders the image: per tile and camera sample, direct light, the cut
    /// of each receiver, splatting and convolution. `progress` is called with
    /// the number of tiles done each time one finishes (out of the total,
    /// given first with 0 done).
    pub fn render(&self, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<RenderOutput, RenderError> {
        let wall = Instant::now();
        let opts = &self.opts;
        let traversal = self.traversal()?;
        let mb_proto = MicroBuffer::new(opts.microbuffer)?;
        let (w, h) = (self.scene.camera.width, self.scene.camera.height);
        let tiles_total = self.tiles();
        progress(0, tiles_total);
        let done = AtomicU64::new(0);
        let (acc_trav, acc_others, acc_direct) = (Accum::new(), Accum::new(), Accum::new());

        let tiles: Vec<TileResult> = (0..tiles_total)
            .into_par_iter()
            .map(|tile| {
                let mut stats = TraversalStats::default();
                let mut cuts = PacketCuts::for_scheme(self.scheme, &self.tree);
                let mut bufs = vec![mb_proto.clone(); LANES];
                let mut receivers_done = 0;
                let pixels = self.tile_pixels(tile);
                let mut sums = vec![Vec3::ZERO; pixels.len()];
                for s in 0..opts.spp {
                    let t0 = Instant::now();
                    let mut points = self.packet(&pixels, s);
                    let direct = self.direct(&mut points);
                    acc_direct.add(t0.elapsed().as_secs_f64());
                    receivers_done += points.len();
                    let mut indirect = vec![Vec3::ZERO; points.len()];
                    if self.needs_points && !points.is_empty() {
                        let receivers = Self::receivers(&points)?;
                        let t1 = Instant::now();
                        let scheme = self.scheme_for(receivers.len());
                        stats.merge(&cuts.run(&traversal, scheme, &receivers));
                        let t2 = Instant::now();
                        acc_trav.add((t2 - t1).as_secs_f64());
                        indirect = self.shade(&points, &mut cuts, &mut bufs, traversal.isa());
                        acc_others.add(t2.elapsed().as_secs_f64());
                    }
                    for ((pp, d), l) in points.iter().zip(&direct).zip(&indirect) {
                        sums[pp.pixel] += *d + *l;
                    }
                }
                let out = pixels
                    .iter()
                    .zip(&sums)
                    .map(|(&(x, y), sum)| (y * w + x, *sum / opts.spp as f32))
                    .collect();
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(d as usize, tiles_total);
                Ok((out, stats, receivers_done))
            })
            .collect::<Result<_, Error>>()?;

        let mut pixels = vec![Vec3::ZERO; (w * h) as usize];
        let mut stats = TraversalStats::default();
        let mut receivers = 0;
        for (out, st, n) in tiles {
            for (i, c) in out {
                // Never let a NaN out: a broken sample becomes black, and is counted in tests.
                pixels[i as usize] = if c.is_finite() { c } else { Vec3::ZERO };
            }
            stats.merge(&st);
            receivers += n;
        }
        Ok(RenderOutput {
            image: Image {
                width: w,
                height: h,
                pixels,
            },
            timings: Timings {
                pre: self.pre,
                trav: acc_trav.seconds(),
                others: acc_others.seconds(),
                direct: acc_direct.seconds(),
                total_wall: self.pre + wall.elapsed().as_secs_f64(),
            },
            stats,
            scheme: self.scheme,
            choice: self.opts.scheme,
            isa: traversal.isa(),
            surfels: self.surfels,
            receivers,
            stages: self.stages.clone(),
        })
    }
}

/// Renders `scene`: [`Frame::prepare`] then [`Frame::render`]. `progress` is
/// called with the number of tiles done each time one finishes (out of the
/// total, given first with 0 done).
pub fn render(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderOutput, RenderError> {
    Frame::prepare(scene, opts)?.render(progress)
}

/// One more bounce at the surfels: each surfel's radiance becomes its direct
/// part plus `albedo/π · E`, with `E` gathered from the current cloud.
fn gather_bounce(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    tree: &Tree,
    scheme: Scheme,
    opts: &RenderOptions,
) -> Result<PointCloud, Error> {
    let traversal = Traversal::new(
        tree,
        CutOptions {
            max_solid_angle: opts.max_solid_angle,
            hybrid_threshold: opts.hybrid_threshold,
            isa: opts.isa,
        },
    )?;
    let surfels = cloud.surfels();
    // The receivers sit a hair above their surfel so it does not see itself edge-on.
    let receivers: Vec<Receiver> = surfels
        .iter()
        .map(|s| Receiver::new(s.position + s.normal * (s.radius * 1e-3), s.normal))
        .collect::<Result<_, _>>()?;
    let proto = MicroBuffer::new(opts.microbuffer)?;
    // The surfels' packets (tree order: neighbours) through the scheme's
    // shading pipeline, as in `Frame::shade`.
    let isa = traversal.isa();
    let gathered: Vec<Vec3> = receivers
        .par_chunks(LANES)
        .map_init(
            || (PacketCuts::for_scheme(scheme, tree), vec![proto.clone(); LANES]),
            |(cuts, buffers), chunk| {
                cuts.run(&traversal, scheme, chunk);
                let buffers = &mut buffers[..chunk.len()];
                for (b, r) in buffers.iter_mut().zip(chunk) {
                    b.reset(r.position(), r.normal());
                }
                let mut out = vec![Vec3::ZERO; chunk.len()];
                match cuts {
                    PacketCuts::Lists(l) => {
                        shade_cuts(isa, buffers, tree, &l.0, Convolution::Irradiance, &mut out)
                    }
                    PacketCuts::Lanes(c) => {
                        shade_packet(isa, buffers, tree, c, Convolution::Irradiance, &mut out)
                    }
                }
                out
            },
        )
        .flatten_iter()
        .collect();
    let next: Vec<Surfel> = surfels
        .iter()
        .zip(&gathered)
        .zip(direct.iter().zip(albedo))
        .map(|((s, e), (d, a))| Surfel {
            radiance: (*d + *a * std::f32::consts::FRAC_1_PI * *e).max(Vec3::ZERO),
            ..*s
        })
        .collect();
    PointCloud::new(next)
}
