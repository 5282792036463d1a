//! A frame: the scene made ready (ray queries, lights, surfels, tree: the
//! paper's `pre.`, or the surfels and tree from a tree file), then per
//! 4×4-pixel tile and camera sample the packet of receivers, its direct
//! light, its cuts, splatting and convolution. A crop renders the tiles of
//! the frame's grid that meet its window: a pixel's samples are seeded by
//! its place in the full frame, so it comes out the same, bit for bit.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::bake::{
    bake_record, build, check_options, check_record, environment, gather_options, loaded_stages,
    needs_points, tracer_and_lights,
};
use super::image::Image;
use super::light::{Brdf, LightSamples, Lights};
use super::options::{Crop, Direct, RenderOptions};
use super::output::{PreTimings, Progress, RenderError, RenderOutput, Stage, Timings};
use super::shading::ShadingPoint;
use super::trace::Tracer;
use crate::cache::Cache;
use crate::cut::{Scheme, SchemeChoice, TraversalStats};
use crate::environment::Environment;
use crate::error::Error;
use crate::gather::{Gather, Gatherer};
use crate::microbuffer::{Convolution, MicroBuffer};
use crate::scene::{Camera, Scene, SceneError};
use crate::simd::LANES;
use crate::tree::{Tree, TreeFile};

/// One tile's pixels (index in the window, radiance), traversal counters
/// and gathers (`Frame::render_tile`).
pub(crate) type TileResult = (Vec<(u32, Vec3)>, TraversalStats, usize);

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
    pub shading: Accum,
    pub direct: Accum,
}

/// One receiver of a packet: the pixel of its tile (0..16), the film point
/// its camera ray went through, where it hit, and where its direct-light samples start in its pixel's
/// scrambled (0,2)-sequence (`Lights::reflected`).
pub(crate) struct PacketPoint {
    pub pixel: usize,
    pub film: (f32, f32),
    pub point: ShadingPoint,
    pub light_first: u32,
    /// Its light samples, `light_first..light_first + light_count`.
    pub light_count: u32,
    pub light_scramble: [u32; 2],
}

/// A scene made ready to render: ray queries, lights, surfels and their tree
/// (the paper's `pre.` column), and the resolved scheme. [`render`] runs it
/// whole; the benchmark and the error report run its stages one by one.
pub struct Frame<'s> {
    pub(crate) scene: &'s Scene,
    /// The view rendered: the scene's camera, or a pose of a camera path
    /// ([`set_camera`](Self::set_camera)).
    pub(crate) camera: Camera,
    pub(crate) opts: RenderOptions,
    pub(crate) tracer: Tracer,
    pub(crate) lights: Lights,
    pub(crate) tree: Tree,
    pub(crate) surfels: usize,
    pub(crate) scheme: Scheme,
    pub(crate) pre: f64,
    pub(crate) pre_parts: PreTimings,
    pub(crate) stages: Vec<Stage>,
    pub(crate) needs_points: bool,
    /// What the open part of a receiver's hemisphere sees, and camera rays
    /// that leave the scene (none in AO mode).
    pub(crate) environment: Option<Arc<Environment>>,
    /// The world-space records gathered so far (`Gathers::Cache`): a
    /// later frame of this bake gathers only what none before it needed.
    pub(super) cache: Mutex<Option<Cache>>,
    /// The records that keep their incident light, for the samples whose
    /// bump or normal map tilts them and those with lobes.
    pub(super) incident_caches: Mutex<[Option<Cache>; 2]>,
}

impl<'s> Frame<'s> {
    /// Validates the options, builds the ray queries, bakes the surfels
    /// (with extra bounces if asked) and builds the tree.
    pub fn prepare(scene: &'s Scene, opts: &RenderOptions) -> Result<Self, RenderError> {
        Self::prepare_with(scene, opts, None, &|_, _, _| {})
    }

    /// [`prepare`](Self::prepare), telling `progress` which stage it is in
    /// and how far along (for a progress bar over a large scene's `pre.`).
    pub fn prepare_with_progress(
        scene: &'s Scene,
        opts: &RenderOptions,
        progress: &Progress,
    ) -> Result<Self, RenderError> {
        Self::prepare_with(scene, opts, None, progress)
    }

    /// [`prepare`](Self::prepare) with the surfels and tree of `file` (from
    /// [`bake_tree`](super::bake_tree), `pbgi bake`) instead of building
    /// them: the same frame, bit for bit. Errors: a tree baked from another
    /// scene or with other settings ([`RenderError::TreeMismatch`]).
    pub fn with_tree(scene: &'s Scene, opts: &RenderOptions, file: TreeFile) -> Result<Self, RenderError> {
        Self::prepare_with(scene, opts, Some(file), &|_, _, _| {})
    }

    fn prepare_with(
        scene: &'s Scene,
        opts: &RenderOptions,
        file: Option<TreeFile>,
        progress: &Progress,
    ) -> Result<Self, RenderError> {
        check_options(scene, opts)?;
        let environment = environment(scene, opts);
        let needs_points = needs_points(opts, &environment);
        let scheme = opts.scheme.resolve(LANES);
        let mut stages = Vec::new();

        let t_pre = Instant::now();
        let (tracer, lights) = tracer_and_lights(scene, progress);
        let mut pre_parts = PreTimings {
            tracer: t_pre.elapsed().as_secs_f64(),
            ..PreTimings::default()
        };
        let (tree, surfels) = match file {
            None => {
                let (cloud, tree) = build(
                    scene,
                    opts,
                    &tracer,
                    &lights,
                    &mut stages,
                    &mut pre_parts,
                    progress,
                )?;
                (tree, cloud.len())
            }
            Some(file) => {
                check_record(file.bake(), &bake_record(scene, opts))?;
                loaded_stages(opts, &file, &mut stages);
                let (_, cloud, tree) = file.into_parts();
                // A tree at the other precision is built from the surfels:
                // the same tree a bake at this precision holds.
                let tree = if tree.precision() == opts.tree_precision {
                    tree
                } else {
                    Tree::build_with(&cloud, opts.tree_precision)
                };
                (tree, cloud.len())
            }
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
            name: "near field by rays (within 3 surfel radii)",
            skipped: (!near_field(opts)).then(|| {
                format!(
                    "--bounces {}: the surfels carry bounces the rays' hits would not",
                    opts.bounces
                )
            }),
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
        stages.push(Stage {
            name: "area lights in closed form, times the samples' shadow ratio",
            skipped: match (opts.ao, opts.direct) {
                (true, _) => Some("AO mode".to_string()),
                (false, Direct::Sampled) => Some("--direct sampled".to_string()),
                (false, Direct::Ratio) => lights.why_sampled(),
            },
        });
        Ok(Frame {
            scene,
            camera: scene.camera,
            opts: *opts,
            tracer,
            lights,
            tree,
            surfels,
            scheme,
            pre,
            pre_parts,
            stages,
            needs_points,
            environment,
            cache: Mutex::new(None),
            incident_caches: Mutex::new([None, None]),
        })
    }

    /// Renders from `camera` from now on: a frame of a camera path, with the
    /// surfels, their light and the tree of this bake. The film must be the
    /// scene camera's (a crop and the tile grid are laid out on it).
    pub fn set_camera(&mut self, camera: Camera) -> Result<(), RenderError> {
        camera.validate()?;
        let (w, h) = (self.scene.camera.width, self.scene.camera.height);
        if (camera.width, camera.height) != (w, h) {
            return Err(RenderError::Scene(SceneError::Invalid {
                what: format!(
                    "camera {}×{}: a frame of this bake renders the scene's {w}×{h} film",
                    camera.width, camera.height
                ),
            }));
        }
        self.camera = camera;
        Ok(())
    }

    /// The camera rendered.
    pub fn camera(&self) -> &Camera {
        &self.camera
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
        let g = Gather::new(&self.tree, &gather_options(&self.opts, scheme, &self.environment))?;
        Ok(self.with_near_field(g))
    }

    /// Whether receivers see within a few surfel radii by rays
    /// (`microbuffer::near`).
    pub(crate) fn near_field(&self) -> bool {
        near_field(&self.opts)
    }

    /// `g`, with this frame's ray tracer as its near field where
    /// [`near_field`](Self::near_field) says so.
    fn with_near_field<'a>(&'a self, g: Gather<'a>) -> Gather<'a> {
        // With an environment, also for the sky by rays (`near_leaves`
        // says whether the leaves give way too).
        if self.near_field() || self.environment.is_some() {
            g.with_near_field(self)
        } else {
            g
        }
    }

    /// Whether receivers with a glossy lobe gather apart: some material has
    /// one, and the lobe is convolved (not in AO mode).
    pub(crate) fn glossy_apart(&self) -> bool {
        !self.opts.ao && self.scene.has_glossy()
    }

    /// The gather of the receivers whose material has a glossy lobe, at
    /// their own Ω and N (`None` where no material has one, or in AO mode).
    pub(crate) fn glossy_gather(&self) -> Result<Option<Gather<'_>>, Error> {
        if !self.glossy_apart() {
            return Ok(None);
        }
        let mut o = gather_options(&self.opts, self.opts.scheme, &self.environment);
        o.cut.max_solid_angle = self.opts.glossy_max_solid_angle;
        o.cut.light_offset = self.opts.glossy_light_offset;
        o.microbuffer = self.opts.glossy_microbuffer;
        Gather::new(&self.tree, &o).map(|g| Some(self.with_near_field(g)))
    }

    /// The window rendered: the crop, or the whole frame.
    pub(crate) fn window(&self) -> Crop {
        let c = &self.camera;
        self.opts.crop.unwrap_or(Crop::full(c.width, c.height))
    }

    /// The 4×4-pixel tiles of the frame's grid that meet the window: first
    /// column and row, and how many across and down. A crop keeps the full
    /// frame's grid, so its tiles' packets are the frame's, less the pixels
    /// outside it.
    fn tile_grid(&self) -> (u32, u32, u32, u32) {
        let w = self.window();
        let (tx, ty) = (w.x0 / 4, w.y0 / 4);
        (tx, ty, w.x1.div_ceil(4) - tx, w.y1.div_ceil(4) - ty)
    }

    /// Number of 4×4-pixel tiles in the window.
    pub(crate) fn tiles(&self) -> usize {
        let (_, _, nx, ny) = self.tile_grid();
        (nx * ny) as usize
    }

    /// The pixels `(x, y)` of `tile`, row by row (fewer at the window's edges).
    pub(crate) fn tile_pixels(&self, tile: usize) -> Vec<(u32, u32)> {
        let (tx0, ty0, nx, _) = self.tile_grid();
        let w = self.window();
        let (tx, ty) = ((tx0 + tile as u32 % nx) * 4, (ty0 + tile as u32 / nx) * 4);
        (0..16)
            .map(|i| (tx + i % 4, ty + i / 4))
            .filter(|&(x, y)| w.contains(x, y))
            .collect()
    }

    /// Light samples at each camera sample's receiver.
    pub(crate) fn light_samples(&self) -> u32 {
        self.opts.light_samples()
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
                let (n, wo) = (sp.normal, sp.wo);
                let brdf = Brdf {
                    diffuse: sp.albedo * std::f32::consts::FRAC_1_PI,
                    lobe: lobe.as_ref().map(|l| move |wi| l.eval(n, wo, wi)),
                };
                let samples = LightSamples {
                    count: pp.light_count,
                    first: pp.light_first,
                    scramble: pp.light_scramble,
                    ratio: self.opts.direct == Direct::Ratio,
                };
                sp.emitted + self.lights.reflected(&self.tracer, sp.position, n, samples, brdf)
            })
            .collect()
    }

    /// The receivers of `points`.
    #[cfg(feature = "lab")]
    pub(crate) fn receivers(points: &[PacketPoint]) -> Result<Vec<crate::cut::Receiver>, Error> {
        points
            .iter()
            .map(|pp| crate::cut::Receiver::new(pp.point.position, pp.point.receiver_normal))
            .collect()
    }

    /// Splats each point's cut (the packet `gatherer` cut last) into its
    /// microbuffer and convolves: the indirect light (or `1 − AO`) at each point.
    #[cfg(feature = "lab")]
    pub(crate) fn shade(&self, points: &[&PacketPoint], gatherer: &mut Gatherer) -> Vec<Vec3> {
        self.gathered(points, gatherer)
            .into_iter()
            .map(|(_, l)| l)
            .collect()
    }

    /// [`shade`](Self::shade), with each point's irradiance (or occlusion)
    /// before its material: what a nearby point of the same surface reuses.
    pub(crate) fn gathered(&self, points: &[&PacketPoint], gatherer: &mut Gatherer) -> Vec<(Vec3, Vec3)> {
        let out = gatherer.shade_tilted(self.convolution(), points.iter().map(|pp| pp.point.normal));
        let bufs = gatherer.buffers();
        points
            .iter()
            .zip(bufs.iter())
            .zip(out)
            .map(|((pp, mb), e)| (e, self.indirect(pp, e, Some(mb))))
            .collect()
    }

    /// What a gather's microbuffer is convolved into: irradiance, or
    /// occlusion in AO mode.
    pub(crate) fn convolution(&self) -> Convolution {
        if self.opts.ao {
            Convolution::Occlusion
        } else {
            Convolution::Irradiance
        }
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
            let mut l = sp.albedo * std::f32::consts::FRAC_1_PI * e;
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
        let glossy = self.glossy_gather()?;
        let window = self.window();
        let (w, h) = (window.width(), window.height());
        let tiles_total = self.tiles();
        progress(0, tiles_total);
        let done = AtomicU64::new(0);
        let timers = Timers::default();
        let lattice = self.lattice(&gather, &timers)?;
        let mut cache = self.held_cache();
        let mut incident_caches = self
            .incident_caches
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let cached = self.prepare_cache(
            &mut cache,
            &mut incident_caches,
            &gather,
            glossy.as_ref(),
            &timers,
        )?;
        let shared = Self::shared(lattice.as_ref(), cached.as_ref());
        let incident = Self::incident(cached.as_ref(), &incident_caches);

        // Every tile its own job: rayon's default split ran a quarter of
        // a large scene's tiles as one unsplittable run, on one core while
        // the other idled.
        let tiles: Vec<TileResult> = (0..tiles_total)
            .into_par_iter()
            .with_max_len(1)
            .map(|tile| {
                let out = self.render_tile(
                    tile,
                    [&gather, glossy.as_ref().unwrap_or(&gather)],
                    shared.as_ref(),
                    &incident,
                    &timers,
                )?;
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(d as usize, tiles_total);
                Ok(out)
            })
            .collect::<Result<_, RenderError>>()?;

        let mut pixels = vec![Vec3::ZERO; (w * h) as usize];
        let mut stats = TraversalStats::default();
        let mut receivers = 0;
        if let Some(l) = &lattice {
            stats.merge(&l.stats);
            receivers += l.count;
        }
        let (mut records, mut held) = (0, 0);
        if let Some(c) = &cached {
            stats.merge(&c.stats);
            receivers += c.count;
            records = c.count;
            held = cache
                .iter()
                .chain(incident_caches.iter().flatten())
                .map(Cache::len)
                .sum();
        }
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
                pre_parts: self.pre_parts,
                trav: timers.trav.seconds(),
                shading: timers.shading.seconds(),
                direct: timers.direct.seconds(),
                total_wall: self.pre + wall.elapsed().as_secs_f64(),
            },
            stats,
            scheme: self.scheme,
            choice: self.opts.scheme,
            isa: gather.path().isa,
            surfels: self.surfels,
            tree_bytes_per_surfel: self.tree.bytes_per_surfel(),
            receivers,
            records,
            cached: held,
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

/// Whether receivers see within a few surfel radii by rays: the rays'
/// hits are shaded with direct light, which is what the surfels carry
/// unless extra bounces were gathered at them.
fn near_field(opts: &RenderOptions) -> bool {
    opts.ao || opts.bounces <= 1
}
