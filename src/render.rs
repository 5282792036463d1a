//! Rendering a scene with point-based global illumination: camera rays give
//! the receivers (4×4 pixel tiles make the packets), the kernels give their
//! cuts, the microbuffer splats and convolves them, direct light comes from
//! shadow rays. Stages a scene does not need are left out, and said so.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use crate::brdf::GlossyLobe;
use crate::cut::{CutOptions, CutSink, Isa, LANES, Receiver, Scheme, Traversal, TraversalStats};
use crate::error::Error;
use crate::light::Lights;
use crate::microbuffer::{MicroBuffer, MicroBufferSink};
use crate::points::bake::{BakeOptions, bake};
use crate::points::{PointCloud, Surfel};
use crate::scene::{Bump, Material, Scene, SceneError};
use crate::synthetic::Rng;
use crate::trace::{Hit, Tracer};
use crate::tree::{NodeId, Tree};

/// Which scheme the renderer runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SchemeChoice {
    /// Packet for smooth diffuse scenes, hybrid where glossy lobes or bumps
    /// break packet coherence.
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
    /// Microbuffer resolution N (an N×N hemicube top face).
    pub microbuffer: usize,
    /// Indirect bounces: 0 direct only, 1 direct + one bounce (Mitsuba's `max_depth` 3), …
    pub bounces: u32,
    /// Camera samples per pixel (each a receiver), also the direct-light samples per receiver.
    pub spp: u32,
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

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            scheme: SchemeChoice::Auto,
            max_solid_angle: 0.05,
            hybrid_threshold: 2,
            microbuffer: 8,
            bounces: 1,
            spp: 4,
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
    /// The scheme that ran.
    pub scheme: Scheme,
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
}

impl std::fmt::Display for RenderError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RenderError::Scene(e) => e.fmt(f),
            RenderError::Kernel(e) => e.fmt(f),
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
struct SplatLists(Vec<Vec<NodeId>>);

impl CutSink for SplatLists {
    #[inline]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.0[receiver].push(node);
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
    fn add(&self, seconds: f64) {
        self.0.fetch_add((seconds * 1e9) as u64, Ordering::Relaxed);
    }
    fn seconds(&self) -> f64 {
        self.0.load(Ordering::Relaxed) as f64 * 1e-9
    }
}

/// Renders `scene`. `progress` is called with the number of tiles done each
/// time one finishes (out of `tiles_total`, given first with 0 done).
pub fn render(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<RenderOutput, RenderError> {
    scene.validate()?;
    if opts.spp == 0 {
        return Err(Error::InvalidParameter {
            name: "spp",
            value: "0".into(),
            expected: "at least 1",
        }
        .into());
    }
    let wall = Instant::now();
    let mut stages = Vec::new();
    let needs_points = opts.ao || opts.bounces > 0;
    let scheme = match opts.scheme {
        SchemeChoice::Fixed(s) => s,
        SchemeChoice::Auto if scene.has_glossy() || scene.has_bump() => Scheme::Hybrid,
        SchemeChoice::Auto => Scheme::Packet,
    };

    // pre.: tracer, lights, surfels, tree.
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

    let traversal = Traversal::new(
        &tree,
        CutOptions {
            max_solid_angle: opts.max_solid_angle,
            hybrid_threshold: opts.hybrid_threshold,
            isa: opts.isa,
        },
    )?;
    let mut mb_proto = MicroBuffer::new(opts.microbuffer)?;
    mb_proto.reset(Vec3::ZERO, Vec3::Z);
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

    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let tiles_x = w.div_ceil(4);
    let tiles_y = h.div_ceil(4);
    let tiles_total = (tiles_x * tiles_y) as usize;
    progress(0, tiles_total);
    let done = AtomicU64::new(0);
    let (acc_trav, acc_others, acc_direct) = (
        Accum(AtomicU64::new(0)),
        Accum(AtomicU64::new(0)),
        Accum(AtomicU64::new(0)),
    );
    let grid = (opts.spp as f32).sqrt().ceil() as u32;

    let tiles: Vec<TileResult> = (0..tiles_total)
        .into_par_iter()
        .map(|tile| {
            let (tx, ty) = ((tile as u32 % tiles_x) * 4, (tile as u32 / tiles_x) * 4);
            let mut stats = TraversalStats::default();
            let mut out: Vec<(u32, Vec3)> = Vec::with_capacity(16);
            let mut lists = SplatLists(vec![Vec::new(); LANES]);
            let mut mb = mb_proto.clone();
            let mut receivers_done = 0;
            let pixels: Vec<(u32, u32)> = (0..16)
                .map(|i| (tx + i % 4, ty + i / 4))
                .filter(|&(x, y)| x < w && y < h)
                .collect();
            let mut sums = vec![Vec3::ZERO; pixels.len()];
            for s in 0..opts.spp {
                let t0 = Instant::now();
                // One packet: sample `s` of each pixel of the tile.
                let mut points = Vec::with_capacity(16);
                for (k, &(x, y)) in pixels.iter().enumerate() {
                    let pix = y * w + x;
                    let mut rng = Rng::new(
                        opts.seed ^ ((pix as u64) << 20 | s as u64).wrapping_mul(0xD1B5_4A32_D192_ED03),
                    );
                    let (sx, sy) = (s % grid, s / grid % grid);
                    let fx = x as f32 + (sx as f32 + rng.f32()) / grid as f32;
                    let fy = y as f32 + (sy as f32 + rng.f32()) / grid as f32;
                    let dir = cam.ray_direction(fx, fy);
                    if let Some(hit) = tracer.closest(cam.origin, dir, f32::INFINITY)
                        && let Some(sp) = shading_point(scene, &tracer, cam.origin, dir, &hit)
                    {
                        points.push((k, sp, rng));
                    }
                }
                // Direct light (and emission) at each receiver.
                let mut direct = vec![Vec3::ZERO; points.len()];
                if !opts.ao {
                    for (i, (_, sp, rng)) in points.iter_mut().enumerate() {
                        let m = &scene.materials[sp.material];
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
                        direct[i] =
                            sp.emitted + lights.reflected(&tracer, sp.position, n, opts.spp.min(16), rng, f);
                    }
                }
                acc_direct.add(t0.elapsed().as_secs_f64());

                let mut indirect = vec![Vec3::ZERO; points.len()];
                if needs_points && !points.is_empty() {
                    let receivers: Vec<Receiver> = points
                        .iter()
                        .map(|(_, sp, _)| Receiver::new(sp.position, sp.normal))
                        .collect::<Result<_, _>>()?;
                    for l in lists.0.iter_mut() {
                        l.clear();
                    }
                    let t1 = Instant::now();
                    stats.merge(&traversal.run(scheme, &receivers, &mut lists));
                    let t2 = Instant::now();
                    acc_trav.add((t2 - t1).as_secs_f64());
                    for (i, (_, sp, _)) in points.iter().enumerate() {
                        mb.reset(sp.position, sp.normal);
                        for &node in &lists.0[i] {
                            mb.splat(&tree, node);
                        }
                        let m = &scene.materials[sp.material];
                        indirect[i] = if opts.ao {
                            Vec3::splat(1.0 - mb.occlusion())
                        } else {
                            let mut l = m.albedo * std::f32::consts::FRAC_1_PI * mb.irradiance(&tree);
                            if let Some(g) = m.glossy {
                                let lobe = GlossyLobe {
                                    specular: g.specular,
                                    roughness: g.roughness,
                                };
                                l += mb.glossy(&tree, sp.wo, &lobe);
                            }
                            l
                        };
                    }
                    acc_others.add(t2.elapsed().as_secs_f64());
                }
                receivers_done += points.len();
                for (i, (k, _, _)) in points.iter().enumerate() {
                    sums[*k] += direct[i] + indirect[i];
                }
            }
            for (k, &(x, y)) in pixels.iter().enumerate() {
                out.push((y * w + x, sums[k] / opts.spp as f32));
            }
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
            pre,
            trav: acc_trav.seconds(),
            others: acc_others.seconds(),
            direct: acc_direct.seconds(),
            total_wall: wall.elapsed().as_secs_f64(),
        },
        stats,
        scheme,
        isa: traversal.isa(),
        surfels,
        receivers,
        stages,
    })
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
    let gathered: Vec<Vec3> = receivers
        .par_chunks(LANES)
        .flat_map_iter(|chunk| {
            let mut buffers = vec![proto.clone(); chunk.len()];
            for (b, r) in buffers.iter_mut().zip(chunk) {
                b.reset(r.position(), r.normal());
            }
            let mut sink = MicroBufferSink {
                tree,
                buffers: &mut buffers,
            };
            traversal.run(scheme, chunk, &mut sink);
            buffers.iter().map(|b| b.irradiance(tree)).collect::<Vec<_>>()
        })
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
