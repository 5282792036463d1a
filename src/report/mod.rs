//! What the speed costs in accuracy: Table-1 timings per scheme ([`bench`])
//! and the error of the point-based image against the path-traced ground
//! truth as the solid-angle threshold Ω and the microbuffer resolution vary
//! ([`error_sweep`]), next to the path tracer's own error at rising sample
//! counts.
//!
//! The error is the relative RMSE over the pixels that see no emitter
//! directly, not even in part ([`emitter_mask`]): `sqrt(Σ‖I − R‖² / Σ‖R‖²)` over those pixels
//! and the three channels, `R` the reference. Emitters seen directly are left
//! out because both renderers show them exactly and their radiance would
//! dominate the sums.

pub mod bench;
pub mod compare;
#[cfg(feature = "plots")]
pub mod plot;

use std::fmt::Write as _;

use crate::cut::{CutOptions, Scheme, SchemeChoice};
use crate::render::{Image, ReferenceOptions, RenderError, RenderOptions, render, render_reference};
use crate::scene::Scene;

pub use bench::{BenchOptions, BenchRow, bench};
pub use compare::{
    Comparison, compare, emitter_mask, error_image, mean_reference, relative_rmse, side_by_side,
};

/// How an image of the sweep was made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// The point-based renderer.
    PointBased {
        /// Traversal scheme.
        scheme: Scheme,
        /// Solid-angle threshold Ω (0: every leaf splatted).
        max_solid_angle: f32,
        /// Microbuffer resolution.
        microbuffer: usize,
    },
    /// The path tracer.
    PathTracer {
        /// Paths per pixel.
        spp: u32,
    },
}

/// One point of error against run time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorPoint {
    /// How the image was made.
    pub method: Method,
    /// Seconds for surfels and tree (0 for the path tracer).
    pub pre_s: f64,
    /// Traversal thread-seconds.
    pub trav_s: f64,
    /// Splatting + convolution thread-seconds.
    pub others_s: f64,
    /// Wall-clock seconds of the whole image.
    pub total_s: f64,
    /// Relative RMSE against the reference.
    pub rel_rmse: f64,
}

/// What the sweep varies.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOptions {
    /// Settings of every point-based image but those varied.
    pub render: RenderOptions,
    /// Ω values, swept for every scheme at the default microbuffer resolution.
    pub max_solid_angles: Vec<f32>,
    /// Microbuffer resolutions, swept with `max_solid_angles` for the first scheme.
    pub microbuffers: Vec<usize>,
    /// Schemes (images are identical across schemes; their times differ).
    pub schemes: Vec<Scheme>,
    /// Also render the Ω = 0 image (every leaf splatted; slow): it splits
    /// the hierarchy's error from the point discretization's.
    pub max_solid_angle_zero: bool,
    /// Paths per pixel of the path tracer's points.
    pub path_tracer_spp: Vec<u32>,
    /// Indirect bounces for both renderers.
    pub bounces: u32,
}

impl Default for SweepOptions {
    fn default() -> Self {
        Self {
            render: RenderOptions {
                direct_samples: Some(16),
                ..RenderOptions::default()
            },
            max_solid_angles: vec![0.3, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001],
            microbuffers: vec![8, 16],
            schemes: Scheme::ALL.to_vec(),
            max_solid_angle_zero: true,
            path_tracer_spp: vec![1, 4, 16, 64, 256],
            bounces: 1,
        }
    }
}

impl SweepOptions {
    /// The point-based settings the sweep visits, in order.
    pub fn point_based(&self) -> Vec<Method> {
        let default_n = self.render.microbuffer;
        let mut v = Vec::new();
        for &scheme in &self.schemes {
            for &max_solid_angle in &self.max_solid_angles {
                v.push(Method::PointBased {
                    scheme,
                    max_solid_angle,
                    microbuffer: default_n,
                });
            }
        }
        if let Some(&scheme) = self.schemes.first() {
            for &n in self.microbuffers.iter().filter(|&&n| n != default_n) {
                for &max_solid_angle in &self.max_solid_angles {
                    v.push(Method::PointBased {
                        scheme,
                        max_solid_angle,
                        microbuffer: n,
                    });
                }
            }
            if self.max_solid_angle_zero {
                v.push(Method::PointBased {
                    scheme,
                    max_solid_angle: 0.0,
                    microbuffer: default_n,
                });
            }
        }
        v
    }

    /// Number of images the sweep renders.
    pub fn len(&self) -> usize {
        self.point_based().len() + self.path_tracer_spp.len()
    }

    /// Whether the sweep renders nothing.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Renders every point of `opts` and measures it against `reference`.
/// `progress(done, total, what)` is called before each image and at the end.
pub fn error_sweep(
    scene: &Scene,
    reference: &Image,
    opts: &SweepOptions,
    progress: &(dyn Fn(usize, usize, &str) + Sync),
) -> Result<Vec<ErrorPoint>, RenderError> {
    let mask = emitter_mask(scene);
    let total = opts.len();
    let mut points = Vec::with_capacity(total);
    for (i, method) in opts.point_based().into_iter().enumerate() {
        let Method::PointBased {
            scheme,
            max_solid_angle,
            microbuffer,
        } = method
        else {
            unreachable!("point_based yields point-based methods")
        };
        progress(
            i,
            total,
            &format!("{scheme}, Ω {max_solid_angle}, microbuffer {microbuffer}"),
        );
        let ro = RenderOptions {
            cut: CutOptions {
                max_solid_angle,
                ..opts.render.cut
            },
            scheme: SchemeChoice::Fixed(scheme),
            microbuffer,
            bounces: opts.bounces,
            ..opts.render
        };
        let out = render(scene, &ro, &|_, _| {})?;
        let t = &out.timings;
        points.push(ErrorPoint {
            method,
            pre_s: t.pre,
            trav_s: t.trav,
            others_s: t.others,
            total_s: t.total_wall,
            rel_rmse: relative_rmse(&out.image, reference, &mask)?,
        });
    }
    let done = points.len();
    for (j, &spp) in opts.path_tracer_spp.iter().enumerate() {
        progress(done + j, total, &format!("path tracer, {spp} spp"));
        let ro = ReferenceOptions {
            spp,
            bounces: opts.bounces as i32,
            // Not the reference's own seed: its noise must not cancel.
            seed: 0x5EED_0000 + spp as u64,
            ..Default::default()
        };
        let out = render_reference(scene, &ro, &|_, _| {})?;
        points.push(ErrorPoint {
            method: Method::PathTracer { spp },
            pre_s: 0.0,
            trav_s: 0.0,
            others_s: 0.0,
            total_s: out.seconds,
            rel_rmse: relative_rmse(&out.image, reference, &mask)?,
        });
    }
    progress(total, total, "done");
    Ok(points)
}

/// The path tracer's time to reach `error`, read off its error-vs-time
/// points on log-log axes (interpolated between the two that bracket it,
/// else extrapolated along `1/√t` from the nearest).
pub fn path_tracer_time_for(points: &[ErrorPoint], error: f64) -> Option<f64> {
    let mut pt: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| matches!(p.method, Method::PathTracer { .. }) && p.total_s > 0.0 && p.rel_rmse > 0.0)
        .map(|p| (p.total_s, p.rel_rmse))
        .collect();
    pt.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (first, last) = (*pt.first()?, *pt.last()?);
    for w in pt.windows(2) {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        if (e0 >= error && error >= e1) || (e1 >= error && error >= e0) {
            if e0 == e1 {
                return Some(t0);
            }
            let f = (error.ln() - e0.ln()) / (e1.ln() - e0.ln());
            return Some((t0.ln() + f * (t1.ln() - t0.ln())).exp());
        }
    }
    // Outside the measured range: error ∝ 1/√t.
    let (t, e) = if error < last.1 { last } else { first };
    Some(t * (e / error).powi(2))
}

/// The sweep as CSV: one line per image.
pub fn to_csv(scene: &str, points: &[ErrorPoint]) -> String {
    let mut s = String::from(
        "scene,method,scheme,max_solid_angle,microbuffer,spp,pre_s,trav_s,others_s,total_s,rel_rmse\n",
    );
    for p in points {
        let (method, scheme, max_solid_angle, n, spp) = match p.method {
            Method::PointBased {
                scheme,
                max_solid_angle,
                microbuffer,
            } => (
                "pbgi",
                scheme.name(),
                max_solid_angle.to_string(),
                microbuffer.to_string(),
                String::new(),
            ),
            Method::PathTracer { spp } => ("path-tracer", "", String::new(), String::new(), spp.to_string()),
        };
        let _ = writeln!(
            s,
            "{scene},{method},{scheme},{max_solid_angle},{n},{spp},{:.6},{:.6},{:.6},{:.6},{:.6}",
            p.pre_s, p.trav_s, p.others_s, p.total_s, p.rel_rmse
        );
    }
    s
}

/// Reads back what [`to_csv`] wrote: the scene's name and the points (so a
/// plot or table can be redrawn without rendering again). A malformed line
/// is an error naming its number.
pub fn from_csv(text: &str) -> Result<(String, Vec<ErrorPoint>), String> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == to_csv("", &[]).trim() => {}
        _ => return Err("line 1: not the header of an error sweep's CSV".into()),
    }
    let mut scene = String::new();
    let mut points = Vec::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let bad = |what: &str| format!("line {}: {what}: {line}", i + 1);
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 11 {
            return Err(bad("expected 11 fields"));
        }
        let num = |k: usize| f[k].parse::<f64>().map_err(|_| bad("not a number"));
        let method = match f[1] {
            "pbgi" => Method::PointBased {
                scheme: f[2].parse().map_err(|_| bad("unknown scheme"))?,
                max_solid_angle: f[3].parse().map_err(|_| bad("bad Ω"))?,
                microbuffer: f[4].parse().map_err(|_| bad("bad microbuffer"))?,
            },
            "path-tracer" => Method::PathTracer {
                spp: f[5].parse().map_err(|_| bad("bad spp"))?,
            },
            _ => return Err(bad("unknown method")),
        };
        scene = f[0].to_string();
        points.push(ErrorPoint {
            method,
            pre_s: num(6)?,
            trav_s: num(7)?,
            others_s: num(8)?,
            total_s: num(9)?,
            rel_rmse: num(10)?,
        });
    }
    Ok((scene, points))
}

/// The sweep as a Markdown table, with the figure that matters most: at the
/// default settings, the point-based error and time next to the path
/// tracer's time for the same error.
pub fn to_markdown(
    scene: &str,
    points: &[ErrorPoint],
    default: &RenderOptions,
    reference_spp: Option<u32>,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## {scene}: error against run time\n");
    if let Some(spp) = reference_spp {
        let _ = writeln!(s, "Reference: the path tracer at {spp} spp. ");
    }
    let _ = writeln!(
        s,
        "Relative RMSE over the pixels that do not see an emitter; times in seconds \
         (pre., trav. and others summed over threads, total is wall clock).\n"
    );
    let _ = writeln!(
        s,
        "| method | scheme | Ω | N | spp | pre. | trav. | others | total | rel. RMSE |"
    );
    let _ = writeln!(s, "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for p in points {
        match p.method {
            Method::PointBased {
                scheme,
                max_solid_angle,
                microbuffer,
            } => {
                let _ = writeln!(
                    s,
                    "| pbgi | {scheme} | {max_solid_angle} | {microbuffer} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.4} |",
                    default.spp, p.pre_s, p.trav_s, p.others_s, p.total_s, p.rel_rmse
                );
            }
            Method::PathTracer { spp } => {
                let _ = writeln!(
                    s,
                    "| path tracer | | | | {spp} | | | | {:.3} | {:.4} |",
                    p.total_s, p.rel_rmse
                );
            }
        }
    }
    let at_default = points.iter().find(|p| {
        matches!(p.method, Method::PointBased { max_solid_angle, microbuffer, .. }
            if max_solid_angle == default.cut.max_solid_angle && microbuffer == default.microbuffer)
    });
    if let Some(p) = at_default {
        let _ = write!(
            s,
            "\nAt the default settings (Ω {}, microbuffer {}): relative RMSE {:.4} in {:.3} s",
            default.cut.max_solid_angle, default.microbuffer, p.rel_rmse, p.total_s
        );
        match path_tracer_time_for(points, p.rel_rmse) {
            Some(t) => {
                let _ = writeln!(
                    s,
                    "; the path tracer needs about {t:.3} s for the same error ({:.1}×).",
                    t / p.total_s
                );
            }
            None => {
                let _ = writeln!(s, ".");
            }
        }
    }
    s
}
