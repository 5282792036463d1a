//! The sweep: point-based curves, each holding its settings fixed while the
//! camera samples per pixel rise, and the path tracer's curve of rising
//! paths per pixel; every image measured against the reference.

use std::time::Instant;

use super::compare::{compare, emitter_mask};
use super::error::ReportError;
use super::eta::Eta;
use crate::cut::{CutOptions, SchemeChoice};
use crate::render::{Gathers, Image, ReferenceOptions, RenderOptions, Timings, render, render_reference};
use crate::scene::Scene;

/// Which renderer made an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The point-based renderer.
    PointBased,
    /// The path tracer.
    PathTracer,
    /// Path tracing and a denoiser, rendered outside the sweep (Mitsuba 3
    /// or `pbgi reference`, then Intel OIDN: `scripts/denoised.sh`) and
    /// measured against the same reference ([`external_points`](super::external_points)).
    Denoised,
}

/// The label of the path tracer's curve.
pub const PATH_TRACER: &str = "path tracer";

/// One image of the sweep: what it cost and its error.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorPoint {
    /// Which renderer.
    pub method: Method,
    /// Its curve: a point-based curve's label, or [`PATH_TRACER`].
    pub label: String,
    /// Camera samples (point-based) or paths (path tracer) per pixel.
    pub spp: u32,
    /// Seconds for surfels and tree (0 for the path tracer).
    pub pre_s: f64,
    /// Traversal thread-seconds.
    pub trav_s: f64,
    /// Splatting + convolution thread-seconds.
    pub shading_s: f64,
    /// Wall-clock seconds of the whole image.
    pub total_s: f64,
    /// Relative RMSE against the reference, emitters left out.
    pub rel_rmse: f64,
    /// The share of `rel_rmse` that the image's mean offset makes
    /// ([`Comparison::floor`](super::compare::Comparison::floor)): where
    /// the offset is a bias, more samples do not take the error below it.
    pub floor: f64,
}

/// A point-based curve: its settings, fixed along it, and the camera samples
/// per pixel of its points, which set the cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// Its name in tables and plots (unique within a sweep).
    pub label: String,
    /// Its settings; `spp` is overridden by each point's.
    pub options: RenderOptions,
    /// Camera samples per pixel of its points, cheapest first.
    pub spp: Vec<u32>,
    /// Each image through Intel OIDN, guided by its albedo and normals
    /// ([`Frame::guides`](crate::render::Frame::guides)), the guides and
    /// the denoise timed with it; needs the `denoise` feature.
    pub denoised: bool,
}

/// Camera samples per pixel along the default point-based curves.
pub const DEFAULT_SPP: [u32; 5] = [1, 2, 4, 8, 16];
/// Paths per pixel along the default path-tracer curve (its time grows in
/// proportion: 1024 spp is most of the default run).
pub const DEFAULT_PATH_TRACER_SPP: [u32; 4] = [16, 64, 256, 1024];
/// The errors of the equal-error table.
pub const DEFAULT_TARGETS: [f64; 3] = [0.05, 0.03, 0.02];

/// The gather settings a curve may change from the base; `None` keeps the
/// base's. This, [`Variant::apply`] and [`Variant::label`] are where a new
/// gather option joins the sweep.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Variant {
    /// Ω.
    pub max_solid_angle: Option<f32>,
    /// Microbuffer resolution N.
    pub microbuffer: Option<usize>,
    /// Where the gathers are.
    pub gathers: Option<Gathers>,
    /// Traversal scheme (the image is the same; the time is not).
    pub scheme: Option<SchemeChoice>,
    /// Area-light samples per camera sample.
    pub direct_samples: Option<u32>,
}

impl Variant {
    /// `base` with this variant's settings.
    pub fn apply(&self, base: &RenderOptions) -> RenderOptions {
        RenderOptions {
            cut: CutOptions {
                max_solid_angle: self.max_solid_angle.unwrap_or(base.cut.max_solid_angle),
                ..base.cut
            },
            microbuffer: self.microbuffer.unwrap_or(base.microbuffer),
            gathers: self.gathers.unwrap_or(base.gathers),
            scheme: self.scheme.unwrap_or(base.scheme),
            direct_samples: self.direct_samples.or(base.direct_samples),
            ..*base
        }
    }

    /// What it changes, e.g. "Ω 0.02, dense gathers"; "defaults" if nothing.
    pub fn label(&self) -> String {
        let parts: Vec<String> = [
            self.max_solid_angle.map(|o| format!("Ω {o}")),
            self.microbuffer.map(|n| format!("N {n}")),
            self.gathers.map(gathers_text),
            self.scheme.map(|s| format!("scheme {s}")),
            self.direct_samples.map(|n| format!("{n} direct samples")),
        ]
        .into_iter()
        .flatten()
        .collect();
        if parts.is_empty() {
            "defaults".into()
        } else {
            parts.join(", ")
        }
    }
}

fn gathers_text(g: Gathers) -> String {
    match g {
        Gathers::Sparse { spacing, threshold } => {
            format!("sparse gathers {spacing} px, threshold {threshold}")
        }
        Gathers::All => "dense gathers".into(),
        Gathers::Cache { threshold } => format!("cached gathers, threshold {threshold}"),
    }
}

/// The settings the curves vary, in words, for the report's header.
pub fn describe(o: &RenderOptions) -> String {
    format!(
        "Ω {}, N {}, {}, scheme {}, {} direct samples, {} bounce(s)",
        o.cut.max_solid_angle,
        o.microbuffer,
        gathers_text(o.gathers),
        o.scheme,
        o.light_samples(),
        o.bounces
    )
}

/// Dense gathers cost in proportion to the camera samples (each one
/// gathers), so their curve stops here to keep the default run short.
const DENSE_MAX_SPP: u32 = 4;
/// A smaller Ω lowers the gather's bias, which shows only where the noise is
/// low: from this many camera samples on.
const SMALL_OMEGA_MIN_SPP: u32 = 4;

/// The fast side of the curves: a cut and microbuffer so coarse that the
/// gather costs less than the camera samples' own work where a frame's
/// error is their noise. Sponza at 4 spp: 3.2 s for 5.59 % against the
/// defaults' 9.1 s for 5.38 %; the nave, whose error is its bias sooner,
/// loses by it (docs/lab/BENCHMARKS.md, "The fast side of the curve").
const COARSE: (f32, usize) = (0.5, 8);

/// The curves below start here: they trade a little of the gather's or the
/// direct light's accuracy for time, which pays only once the camera
/// samples' noise is low.
const LATE_MIN_SPP: u32 = 8;
/// Between the coarse gather and the base's: the base's Ω at this
/// microbuffer resolution, where the coarse gather's bias shows (Sponza at
/// 32 spp: Ω 0.15, N 10, 1.94 % in 14.4 s; N 14, 1.85 % in 18.7 s; Ω 0.5,
/// N 8, 2.40 %).
const MEDIUM_MICROBUFFER: usize = 10;
/// Area-light samples per camera sample along the curves that spend the
/// direct light's rays on camera samples instead.
const FEW_DIRECT_SAMPLES: u32 = 2;

/// The default curves: `base` (what `pbgi render` uses) at every `spp` and
/// 2× and 4× the last, Ω 0.4× the base's at the higher ones, dense gathers
/// at the lower ones, and the coarse gather `COARSE` at the base's, where
/// the base is finer; from `LATE_MIN_SPP` on, the base's Ω at N
/// `MEDIUM_MICROBUFFER`, and with `emitters` (area lights:
/// `Scene::has_emitters`) the base and the coarse gather again at
/// `FEW_DIRECT_SAMPLES` per camera sample: a pixel's light
/// noise falls with its light samples whichever camera sample takes them,
/// its edges' noise only with camera samples (the nave at 32 spp × 2 is at
/// 2.95 % where 16 × 8 is at 3.41 %, in the same time).
/// Curves equal to an earlier one, or left without points, are dropped.
pub fn default_curves(base: &RenderOptions, spp: &[u32], emitters: bool) -> Vec<Curve> {
    // Rounded to 4 decimals, so the curve's label reads `Ω 0.06`, not
    // `Ω 0.060000002`.
    let small_omega = ((f64::from(base.cut.max_solid_angle) * 0.4 * 1e4).round() / 1e4) as f32;
    // Two more points, 2× and 4× the last: where a curve's error stops
    // falling (its floor) is measured, not only fitted.
    let last = spp.iter().copied().max().unwrap_or(1);
    let extended: Vec<u32> = spp.iter().copied().chain([2 * last, 4 * last]).collect();
    let coarse = base.cut.max_solid_angle < COARSE.0 && base.microbuffer > COARSE.1;
    let late: Vec<u32> = extended.iter().copied().filter(|&s| s >= LATE_MIN_SPP).collect();
    let when = |yes: bool| if yes { late.clone() } else { Vec::new() };
    let few = emitters && base.light_samples() > FEW_DIRECT_SAMPLES;
    let variants = [
        (Variant::default(), extended.clone()),
        (
            Variant {
                max_solid_angle: Some(small_omega),
                ..Variant::default()
            },
            spp.iter()
                .copied()
                .filter(|&s| s >= SMALL_OMEGA_MIN_SPP)
                .collect(),
        ),
        (
            Variant {
                gathers: Some(Gathers::All),
                ..Variant::default()
            },
            spp.iter().copied().filter(|&s| s <= DENSE_MAX_SPP).collect(),
        ),
        (
            Variant {
                max_solid_angle: Some(COARSE.0),
                microbuffer: Some(COARSE.1),
                ..Variant::default()
            },
            if coarse { extended.clone() } else { Vec::new() },
        ),
        (
            Variant {
                microbuffer: Some(MEDIUM_MICROBUFFER),
                ..Variant::default()
            },
            when(base.microbuffer > MEDIUM_MICROBUFFER),
        ),
        (
            Variant {
                direct_samples: Some(FEW_DIRECT_SAMPLES),
                ..Variant::default()
            },
            when(few),
        ),
        (
            Variant {
                max_solid_angle: Some(COARSE.0),
                microbuffer: Some(COARSE.1),
                direct_samples: Some(FEW_DIRECT_SAMPLES),
                ..Variant::default()
            },
            when(few && coarse),
        ),
    ];
    let mut curves: Vec<Curve> = Vec::new();
    for (v, spp) in variants {
        let options = v.apply(base);
        if !spp.is_empty() && curves.iter().all(|c| c.options != options) {
            curves.push(Curve {
                label: v.label(),
                options,
                spp,
                denoised: false,
            });
        }
    }
    curves
}

/// Curves given as lists, one per combination (an empty list keeps the
/// base's value), each at every `spp`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Grid {
    /// Ω values.
    pub max_solid_angles: Vec<f32>,
    /// Microbuffer resolutions.
    pub microbuffers: Vec<usize>,
    /// Where the gathers are.
    pub gathers: Vec<Gathers>,
    /// Traversal schemes.
    pub schemes: Vec<SchemeChoice>,
    /// Area-light samples per camera sample.
    pub direct_samples: Vec<u32>,
}

impl Grid {
    /// The old full sweep: eight Ω from 0.3 to 0.001 at microbuffer 8, 16
    /// and the base's.
    pub fn full(base: &RenderOptions) -> Self {
        let mut microbuffers = vec![8, 16];
        if !microbuffers.contains(&base.microbuffer) {
            microbuffers.push(base.microbuffer);
        }
        Grid {
            max_solid_angles: vec![0.3, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001],
            microbuffers,
            ..Grid::default()
        }
    }

    /// Whether no list is given.
    pub fn is_empty(&self) -> bool {
        self.max_solid_angles.is_empty()
            && self.microbuffers.is_empty()
            && self.gathers.is_empty()
            && self.schemes.is_empty()
            && self.direct_samples.is_empty()
    }

    /// One curve per combination, at every `spp`.
    pub fn curves(&self, base: &RenderOptions, spp: &[u32]) -> Vec<Curve> {
        fn or_keep<T: Copy>(v: &[T]) -> Vec<Option<T>> {
            if v.is_empty() {
                vec![None]
            } else {
                v.iter().copied().map(Some).collect()
            }
        }
        let mut curves = Vec::new();
        for max_solid_angle in or_keep(&self.max_solid_angles) {
            for microbuffer in or_keep(&self.microbuffers) {
                for gathers in or_keep(&self.gathers) {
                    for scheme in or_keep(&self.schemes) {
                        for direct_samples in or_keep(&self.direct_samples) {
                            let v = Variant {
                                max_solid_angle,
                                microbuffer,
                                gathers,
                                scheme,
                                direct_samples,
                            };
                            let options = v.apply(base);
                            // A value listed twice would make two curves of one label.
                            if curves.iter().all(|c: &Curve| c.options != options) {
                                curves.push(Curve {
                                    label: v.label(),
                                    options,
                                    spp: spp.to_vec(),
                                    denoised: false,
                                });
                            }
                        }
                    }
                }
            }
        }
        curves
    }
}

/// What the sweep renders.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOptions {
    /// The point-based curves.
    pub curves: Vec<Curve>,
    /// Paths per pixel along the path tracer's curve, cheapest first.
    pub path_tracer_spp: Vec<u32>,
    /// The path tracer's indirect bounces (the curves' own are in their options).
    pub bounces: u32,
}

impl SweepOptions {
    /// The default curves on `base` for a scene with or without area
    /// lights (`emitters`), and the default path-tracer curve.
    pub fn new(base: &RenderOptions, emitters: bool) -> Self {
        Self {
            curves: default_curves(base, &DEFAULT_SPP, emitters),
            path_tracer_spp: DEFAULT_PATH_TRACER_SPP.to_vec(),
            bounces: base.bounces,
        }
    }

    /// The images in the order they are rendered: `(curve, spp)`, the
    /// path tracer's curve `None`. Round-robin over the curves, cheapest
    /// points first, so every curve's cost is measured early (the time-left
    /// estimate needs one point per curve).
    pub fn jobs(&self) -> Vec<(Option<usize>, u32)> {
        let lists: Vec<(Option<usize>, &[u32])> = std::iter::once((None, &self.path_tracer_spp[..]))
            .chain(self.curves.iter().enumerate().map(|(i, c)| (Some(i), &c.spp[..])))
            .collect();
        let rounds = lists.iter().map(|l| l.1.len()).max().unwrap_or(0);
        (0..rounds)
            .flat_map(|k| {
                lists
                    .iter()
                    .filter_map(move |&(c, spp)| spp.get(k).map(|&s| (c, s)))
            })
            .collect()
    }
}

/// Where a sweep stands, for a progress bar.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepProgress {
    /// Images finished.
    pub done: usize,
    /// Images in all.
    pub images: usize,
    /// The image being rendered ("done" at the end).
    pub what: String,
    /// Seconds since the sweep began.
    pub elapsed_s: f64,
    /// Estimated seconds left; `None` until every curve has a measured point.
    pub remaining_s: Option<f64>,
}

/// Checks that `reference` is the size `scene`'s camera renders.
pub fn check_reference(scene: &Scene, reference: &Image) -> Result<(), ReportError> {
    let camera = (scene.camera.width, scene.camera.height);
    let size = (reference.width, reference.height);
    if size == camera {
        Ok(())
    } else {
        Err(ReportError::ReferenceSize {
            reference: size,
            camera,
        })
    }
}

/// Renders every point of `opts` and measures it against `reference`
/// ([`compare`], emitters left out). `progress` is called as the
/// images advance and once at the end. The points come back grouped by
/// curve (the point-based ones in `opts.curves`' order, then the path
/// tracer's), cheapest first within each.
pub fn error_sweep(
    scene: &Scene,
    reference: &Image,
    opts: &SweepOptions,
    progress: &(dyn Fn(&SweepProgress) + Sync),
) -> Result<Vec<ErrorPoint>, ReportError> {
    check_reference(scene, reference)?;
    // Before any image: a 0 would fail only minutes in.
    let lists = opts.curves.iter().map(|c| (c.label.as_str(), &c.spp));
    if let Some((curve, _)) = lists
        .chain([(PATH_TRACER, &opts.path_tracer_spp)])
        .find(|(_, spp)| spp.contains(&0))
    {
        return Err(ReportError::NoSamples { curve: curve.into() });
    }
    let mask = emitter_mask(scene);
    let jobs = opts.jobs();
    let start = Instant::now();
    let mut eta = Eta::new(&jobs);
    let mut points = Vec::with_capacity(jobs.len());
    for (i, &(curve, spp)) in jobs.iter().enumerate() {
        let what = match curve {
            Some(c) => format!("{}, {spp} spp", opts.curves[c].label),
            None => format!("{PATH_TRACER}, {spp} spp"),
        };
        let image_start = Instant::now();
        let tick = |fraction: f64| {
            progress(&SweepProgress {
                done: i,
                images: jobs.len(),
                what: what.clone(),
                elapsed_s: start.elapsed().as_secs_f64(),
                remaining_s: eta.remaining(i, fraction, image_start.elapsed().as_secs_f64()),
            })
        };
        tick(0.0);
        let on_part = |done: usize, total: usize| tick(done as f64 / total.max(1) as f64);
        let point = match curve {
            Some(c) => {
                let ro = RenderOptions {
                    spp,
                    ..opts.curves[c].options
                };
                let (image, t) = if opts.curves[c].denoised {
                    denoised(scene, &ro, &on_part)?
                } else {
                    let out = render(scene, &ro, &on_part)?;
                    (out.image, out.timings)
                };
                let m = compare(&image, reference, &mask)?;
                ErrorPoint {
                    method: Method::PointBased,
                    label: opts.curves[c].label.clone(),
                    spp,
                    pre_s: t.pre,
                    trav_s: t.trav,
                    shading_s: t.shading,
                    total_s: t.total_wall,
                    rel_rmse: m.rel_rmse,
                    floor: m.floor,
                }
            }
            None => {
                let ro = ReferenceOptions {
                    spp,
                    bounces: opts.bounces as i32,
                    // Not the reference's own seed: its noise must not cancel.
                    seed: 0x5EED_0000 + u64::from(spp),
                    ..Default::default()
                };
                let out = render_reference(scene, &ro, &on_part)?;
                let m = compare(&out.image, reference, &mask)?;
                ErrorPoint {
                    method: Method::PathTracer,
                    label: PATH_TRACER.into(),
                    spp,
                    pre_s: 0.0,
                    trav_s: 0.0,
                    shading_s: 0.0,
                    total_s: out.seconds,
                    rel_rmse: m.rel_rmse,
                    floor: m.floor,
                }
            }
        };
        eta.measured(i, image_start.elapsed().as_secs_f64());
        points.push((curve.unwrap_or(usize::MAX), point));
    }
    progress(&SweepProgress {
        done: jobs.len(),
        images: jobs.len(),
        what: "done".into(),
        elapsed_s: start.elapsed().as_secs_f64(),
        remaining_s: Some(0.0),
    });
    // Stable: within a curve the jobs already run cheapest first.
    points.sort_by_key(|p| p.0);
    Ok(points.into_iter().map(|p| p.1).collect())
}

/// A point-based image through Intel OIDN, guided by its albedo and
/// normals, with its timings: the guides and the denoise count in its wall
/// clock.
#[cfg(feature = "denoise")]
fn denoised(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Image, Timings), ReportError> {
    let frame = crate::render::Frame::prepare(scene, opts)?;
    let out = frame.render(progress)?;
    let start = Instant::now();
    let image = crate::render::denoise(&out.image, &frame.guides()).map_err(ReportError::Denoise)?;
    let mut timings = out.timings;
    timings.total_wall += start.elapsed().as_secs_f64();
    Ok((image, timings))
}

/// Without the `denoise` feature there is no denoiser to run.
#[cfg(not(feature = "denoise"))]
fn denoised(
    _: &Scene,
    _: &RenderOptions,
    _: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Image, Timings), ReportError> {
    Err(ReportError::NoDenoiser)
}
