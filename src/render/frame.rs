//! A frame: the scene made ready (ray queries, lights, surfels, tree: the
//! paper's `pre.`), then per 4×4-pixel tile and camera sample the packet of
//! receivers, its direct light, its cuts, splatting and convolution.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::bake::{BakeOptions, bake};
use super::bounces::gather_bounce;
use super::image::Image;
use super::light::Lights;
use super::options::RenderOptions;
use super::output::{RenderError, RenderOutput, Stage, Timings};
use super::shading::{ShadingPoint, shading_point};
use super::tile::TileResult;
use super::trace::Tracer;
use crate::cut::{Receiver, Scheme, SchemeChoice, TraversalStats};
use crate::environment::Environment;
use crate::error::Error;
use crate::gather::{Gather, GatherOptions, Gatherer, ReceiverOrder};
use crate::microbuffer::{Convolution, MicroBuffer};
use crate::points::{PointCloud, Surfel};
use crate::rng::{Rng, mix};
use crate::scene::Scene;
use crate::simd::LANES;
use crate::tree::Tree;

/// Seconds summed over threads.
#[derive(Default)]
pub(crate) struct Accum(AtomicU64);
impl Accum {
    pub(crate) fn add(&self, seconds: f64) {
        self.0.fetch_add((seconds * 1e9) as u64, Ordering::Relaxed);
    }
    fn seconds(&self) -> f64 {
        self.0.load(Ordering::Relaxed) as f64 * 1e-9
    }
}

/// The Table-1 columns a render times.
#[derive(Default)]
pub(crate) struct Timers {
    pub trav: Accum,
    pub others: Accum,
    pub direct: Accum,
}

/// One receiver of a packet: the pixel of its tile (0..16), where the camera
/// ray hit, and where its direct-light samples start in its pixel's
/// scrambled (0,2)-sequence (`Lights::reflected`).
pub(crate) struct PacketPoint {
    pub pixel: usize,
    pub point: ShadingPoint,
    pub light_first: u32,
    pub light_scramble: [u32; 2],
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
    pub(crate) needs_points: bool,
    /// What the open part of a receiver's hemisphere sees, and camera rays
    /// that leave the scene (none in AO mode).
    environment: Option<Arc<Environment>>,
}

/// The gather options of a render: its cut, microbuffer and environment,
/// over coherent packets (screen tiles; surfels in tree order).
fn gather_options(
    opts: &RenderOptions,
    scheme: SchemeChoice,
    environment: &Option<Arc<Environment>>,
) -> GatherOptions {
    GatherOptions {
        cut: opts.cut,
        microbuffer: opts.microbuffer,
        scheme,
        order: ReceiverOrder::Coherent,
        environment: environment.clone(),
    }
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
        if let Some(g) = opts.gathers
            && !(1..=opts.spp).contains(&g)
        {
            return Err(Error::InvalidParameter {
                name: "gathers",
                value: g.to_string(),
                expected: "1 to spp",
            }
            .into());
        }
        crate::microbuffer::MicroBuffer::new(opts.microbuffer)?;
        let mut stages = Vec::new();
        let environment = if opts.ao {
            None
        } else {
            scene.environment.clone().map(Arc::new)
        };
        // The environment's light arrives through the gather: it needs the
        // surfels (as occluders) even without bounces.
        let needs_points = opts.ao || opts.bounces > 0 || environment.is_some();
        let scheme = opts.scheme.resolve(LANES);

        let t_pre = Instant::now();
        let tracer = Tracer::new(scene);
        let lights = Lights::new(scene);
        let bake_opts = BakeOptions {
            density: opts.surfel_density(scene)?,
            light_samples: if opts.ao { 0 } else { opts.surfel_light_samples },
            seed: opts.seed,
        };
        let (tree, surfels) = if needs_points {
            let baked = bake(scene, &tracer, &lights, &bake_opts)?;
            stages.push(Stage {
                name: "surfels + direct light at surfels",
                skipped: opts.ao.then(|| "AO mode: surfels carry no radiance".to_string()),
            });
            let gopts = gather_options(opts, SchemeChoice::Fixed(scheme), &environment);
            let mut direct: Vec<Vec3> = baked.cloud.surfels().iter().map(|s| s.radiance).collect();
            let mut cloud = baked.cloud;
            if environment.is_some() {
                // The environment's light at the surfels, gathered with the
                // surfels as occluders only (no radiance of their own): with
                // no bounce, the receivers see only that occlusion.
                let dark = PointCloud::new(
                    cloud
                        .surfels()
                        .iter()
                        .map(|s| Surfel {
                            radiance: Vec3::ZERO,
                            ..*s
                        })
                        .collect(),
                )?;
                if opts.bounces == 0 {
                    cloud = dark;
                } else {
                    cloud = gather_bounce(&dark, &direct, &baked.albedo, &Tree::build(&dark), &gopts)?;
                    direct = cloud.surfels().iter().map(|s| s.radiance).collect();
                }
            }
            let mut tree = Tree::build(&cloud);
            for _ in 1..opts.bounces.max(1) {
                cloud = gather_bounce(&cloud, &direct, &baked.albedo, &tree, &gopts)?;
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
            environment,
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

    /// The gather with this frame's options: the traversal, the microbuffers
    /// and the shading pipeline of its scheme, over the frame's tiles
    /// (coherent packets).
    pub(crate) fn gather(&self) -> Result<Gather<'_>, Error> {
        self.gather_with(self.opts.scheme)
    }

    /// [`gather`](Self::gather) with another scheme (for benchmarks).
    pub(crate) fn gather_with(&self, scheme: SchemeChoice) -> Result<Gather<'_>, Error> {
        Gather::new(&self.tree, &gather_options(&self.opts, scheme, &self.environment))
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
    /// the pixel), the rays that hit a visible surface. `misses` (if given)
    /// gets the others: each pixel's index in the tile and the environment's
    /// radiance along its ray.
    pub(crate) fn packet(
        &self,
        pixels: &[(u32, u32)],
        s: u32,
        mut misses: Option<&mut Vec<(usize, Vec3)>>,
    ) -> Vec<PacketPoint> {
        let cam = &self.scene.camera;
        let grid = (self.opts.spp as f32).sqrt().ceil() as u32;
        let light_first = s.wrapping_mul(self.light_samples());
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
            match self.tracer.closest(cam.origin, dir, f32::INFINITY) {
                Some(hit) => {
                    if let Some(point) = shading_point(self.scene, &self.tracer, cam.origin, dir, &hit) {
                        // One scramble per pixel: its camera samples' light
                        // samples are consecutive blocks of one sequence.
                        let h = mix(self.opts.seed ^ u64::from(pix).wrapping_mul(0xA24B_AED4_963E_E407));
                        points.push(PacketPoint {
                            pixel: k,
                            point,
                            light_first,
                            light_scramble: [h as u32, (h >> 32) as u32],
                        });
                    }
                }
                None => {
                    if let (Some(m), Some(env)) = (misses.as_deref_mut(), &self.environment) {
                        m.push((k, env.radiance(dir)));
                    }
                }
            }
        }
        points
    }

    /// Which camera samples of each pixel of a tile gather: `gathers`
    /// consecutive samples (mod `spp`) from a random start per pixel, so
    /// every stratum is equally likely and the gathered light unbiased.
    pub(crate) fn gathering(&self, pixels: &[(u32, u32)], gathers: u32) -> Vec<u32> {
        let (spp, cam) = (self.opts.spp, &self.scene.camera);
        pixels
            .iter()
            .map(|&(x, y)| {
                let pix = u64::from(y * cam.width + x);
                let mut rng = Rng::new(self.opts.seed ^ pix.wrapping_mul(0x9E37_79B9_7F4A_7C15));
                if gathers >= spp {
                    0
                } else {
                    (rng.next_u64() % u64::from(spp)) as u32
                }
            })
            .collect()
    }

    /// Light samples at each camera sample's receiver.
    pub(crate) fn light_samples(&self) -> u32 {
        self.opts.direct_samples.unwrap_or(self.opts.spp.min(16))
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
                let lobe = m.lobe();
                let fd = m.albedo * std::f32::consts::FRAC_1_PI;
                let (n, wo) = (sp.normal, sp.wo);
                let f = |wi: Vec3| match &lobe {
                    Some(l) => fd + l.eval(n, wo, wi),
                    None => fd,
                };
                sp.emitted
                    + self.lights.reflected(
                        &self.tracer,
                        sp.position,
                        n,
                        self.light_samples(),
                        pp.light_first,
                        pp.light_scramble,
                        f,
                    )
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

    /// Splats each point's cut (the packet `gatherer` cut last) into its
    /// microbuffer and convolves: the indirect light (or `1 − AO`) at each point.
    pub(crate) fn shade(&self, points: &[&PacketPoint], gatherer: &mut Gatherer) -> Vec<Vec3> {
        self.gathered(points, gatherer)
            .into_iter()
            .map(|(_, l)| l)
            .collect()
    }

    /// [`shade`](Self::shade), with each point's irradiance (or occlusion)
    /// before its material: what a nearby point of the same surface reuses.
    pub(crate) fn gathered(&self, points: &[&PacketPoint], gatherer: &mut Gatherer) -> Vec<(Vec3, Vec3)> {
        let what = if self.opts.ao {
            Convolution::Occlusion
        } else {
            Convolution::Irradiance
        };
        let out = gatherer.shade(what);
        let bufs = gatherer.buffers();
        points
            .iter()
            .zip(bufs.iter())
            .zip(out)
            .map(|((pp, mb), e)| (e, self.indirect(pp, e, Some(mb))))
            .collect()
    }

    /// The light `pp` reflects towards the camera from its gathered
    /// irradiance `e` (`1 − e` in AO mode), plus its glossy lobe's
    /// convolution of `mb` (a material with a lobe needs its own).
    pub(crate) fn indirect(&self, pp: &PacketPoint, e: Vec3, mb: Option<&MicroBuffer>) -> Vec3 {
        let sp = &pp.point;
        let m = &self.scene.materials[sp.material];
        if self.opts.ao {
            Vec3::splat(1.0 - e.x)
        } else {
            let mut l = m.albedo * std::f32::consts::FRAC_1_PI * e;
            if let (Some(lobe), Some(mb)) = (m.lobe(), mb) {
                l += mb.glossy(&self.tree, sp.wo, &lobe);
            }
            l
        }
    }

    /// Renders the image: per tile and camera sample, direct light, the cut
    /// of each receiver, splatting and convolution. `progress` is called with
    /// the number of tiles done each time one finishes (out of the total,
    /// given first with 0 done).
    pub fn render(&self, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<RenderOutput, RenderError> {
        let wall = Instant::now();
        let gather = self.gather()?;
        let (w, h) = (self.scene.camera.width, self.scene.camera.height);
        let tiles_total = self.tiles();
        progress(0, tiles_total);
        let done = AtomicU64::new(0);
        let timers = Timers::default();

        let tiles: Vec<TileResult> = (0..tiles_total)
            .into_par_iter()
            .map(|tile| {
                let out = self.render_tile(tile, &gather, &timers)?;
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(d as usize, tiles_total);
                Ok(out)
            })
            .collect::<Result<_, RenderError>>()?;

        let mut pixels = vec![Vec3::ZERO; (w * h) as usize];
        let mut stats = TraversalStats::default();
        let mut receivers = 0;
        for (out, st, n) in tiles {
            for (i, c) in out {
                pixels[i as usize] = c;
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
                trav: timers.trav.seconds(),
                others: timers.others.seconds(),
                direct: timers.direct.seconds(),
                total_wall: self.pre + wall.elapsed().as_secs_f64(),
            },
            stats,
            scheme: self.scheme,
            choice: self.opts.scheme,
            isa: gather.path().isa,
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
