//! How a render grows with the scene: each part of `pre.` and the frame,
//! and the peak memory, over scenes of 10⁴ to 10⁷ triangles and budgets of
//! 10⁴ to 10⁷ surfels (`pbgi bench --scale`).
//!
//! A case's peak memory is the process's resident peak from just before the
//! case (Linux resets it through `/proc/self/clear_refs`; elsewhere it is
//! not measured), so it holds the scene, the BVH, the surfels, their trees
//! and the image: all a render needs at once. Each stage's peak is measured
//! the same way from the stage's start, so it holds what earlier stages
//! left resident too. [`growth`] fits how each part grows with the surfels.

use std::fmt::Write as _;
use std::time::Instant;

use glam::Vec3;

use crate::render::{Frame, PreTimings, RenderError, RenderOptions};
use crate::scene::{Camera, FovAxis, Scene};

/// One case: what it rendered and what each part cost.
#[derive(Clone, Debug)]
pub struct ScaleRow {
    /// What the scene is (a file, or copies of one).
    pub label: String,
    /// Triangles in the scene.
    pub triangles: usize,
    /// The surfel budget asked for.
    pub budget: u32,
    /// The surfels made.
    pub surfels: usize,
    /// Seconds to read the scene (and make its copies), given by the caller.
    pub read: f64,
    /// The parts of `pre.`, wall clock.
    pub pre: PreTimings,
    /// Wall-clock seconds of the frame after `pre.` (cuts, shading, direct light).
    pub frame: f64,
    /// Wall-clock seconds of the whole case, reading included.
    pub total: f64,
    /// Peak resident memory of the case in bytes (`None` where it cannot be measured).
    pub peak_bytes: Option<u64>,
    /// The tree's bytes per surfel.
    pub tree_bytes_per_surfel: f64,
    /// Per stage, in the order the stages ran, its resident peak in bytes
    /// (a stage that ran twice, its larger); the frame's last. Empty where
    /// the peak cannot be measured.
    pub stage_peaks: Vec<(&'static str, u64)>,
}

/// `copies` copies of `scene`'s meshes side by side on a square grid (a
/// larger scene with the same detail), with a camera that frames them from
/// above the front. One copy is the scene with that camera.
pub fn copies(scene: &Scene, copies: usize) -> Scene {
    let (lo, hi) = bounds(scene.meshes.iter().flat_map(|m| &m.positions).copied());
    let size = hi - lo;
    let side = (copies as f64).sqrt().ceil() as usize;
    let mut out = Scene {
        name: format!("{}×{copies}", scene.name),
        meshes: Vec::new(),
        ..scene.clone()
    };
    for c in 0..copies {
        let offset = Vec3::new(
            (c % side) as f32 * size.x * 1.2,
            0.0,
            (c / side) as f32 * size.z * 1.2,
        );
        for m in &scene.meshes {
            let mut m = m.clone();
            m.positions.iter_mut().for_each(|p| *p += offset);
            out.meshes.push(m);
        }
    }
    let (lo, hi) = bounds(out.meshes.iter().flat_map(|m| &m.positions).copied());
    let (centre, extent) = ((lo + hi) * 0.5, (hi - lo).max_element().max(1e-6));
    out.camera = Camera {
        origin: centre + Vec3::new(0.0, 0.6, 1.4) * extent,
        target: centre,
        up: Vec3::Y,
        fov_degrees: 40.0,
        fov_axis: FovAxis::Smaller,
        ..scene.camera
    };
    out
}

fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    })
}

/// Renders `scene` with a surfel budget of `budget` (the rest of `opts` as
/// given) and times each part; `read` is what reading it took.
pub fn scale_row(
    label: &str,
    scene: &Scene,
    opts: &RenderOptions,
    budget: u32,
    read: f64,
    progress: &crate::render::Progress,
) -> Result<ScaleRow, RenderError> {
    let measured = reset_peak();
    let clock = Instant::now();
    let opts = RenderOptions {
        surfel_budget: Some(budget),
        ..*opts
    };
    let stages = std::sync::Mutex::new(StagePeaks::default());
    let watch = |stage: &'static str, done: usize, total: usize| {
        if measured {
            stages.lock().unwrap_or_else(|e| e.into_inner()).enter(stage);
        }
        progress(stage, done, total);
    };
    let frame = Frame::prepare_with_progress(scene, &opts, &watch)?;
    let tree_bytes_per_surfel = frame.tree().bytes_per_surfel();
    if measured {
        stages.lock().unwrap_or_else(|e| e.into_inner()).enter("frame");
    }
    let out = frame.render(&|_, _| {})?;
    let total = read + clock.elapsed().as_secs_f64();
    let mut stages = stages.into_inner().unwrap_or_else(|e| e.into_inner());
    if measured {
        stages.enter("");
    }
    Ok(ScaleRow {
        label: label.to_string(),
        triangles: scene.triangle_count(),
        budget,
        surfels: out.surfels,
        read,
        pre: out.timings.pre_parts,
        frame: out.timings.total_wall - out.timings.pre,
        total,
        peak_bytes: stages.done.iter().map(|&(_, b)| b).max(),
        tree_bytes_per_surfel,
        stage_peaks: stages.done,
    })
}

/// The stage running and the peaks of those that ended.
#[derive(Default)]
struct StagePeaks {
    current: Option<&'static str>,
    done: Vec<(&'static str, u64)>,
}

impl StagePeaks {
    /// Marks `stage` as running: the stage before it ends, its peak kept,
    /// and the peak is reset (`""`: none runs after).
    fn enter(&mut self, stage: &'static str) {
        if self.current == Some(stage) {
            return;
        }
        if let (Some(ended), Some(bytes)) = (self.current, peak()) {
            match self.done.iter_mut().find(|(s, _)| *s == ended) {
                Some((_, b)) => *b = (*b).max(bytes),
                None => self.done.push((ended, bytes)),
            }
        }
        self.current = (!stage.is_empty()).then_some(stage);
        reset_peak();
    }
}

/// Resets the process's recorded resident peak to its current size
/// (Linux); `false` where that is not possible.
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The process's resident peak since [`reset_peak`] (Linux: `VmHWM`).
fn peak() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A row's columns, seconds, bytes and bytes per surfel written by the
/// given functions.
fn cells(
    r: &ScaleRow,
    seconds: impl Fn(f64) -> String,
    bytes: impl Fn(Option<u64>) -> String,
    per_surfel: impl Fn(f64) -> String,
) -> Vec<String> {
    let mut c = vec![
        r.label.clone(),
        r.triangles.to_string(),
        r.budget.to_string(),
        r.surfels.to_string(),
    ];
    let p = &r.pre;
    c.extend([r.read, p.tracer, p.surfels, p.gathers, p.tree, r.frame, r.total].map(&seconds));
    c.push(bytes(r.peak_bytes));
    c.push(per_surfel(r.tree_bytes_per_surfel));
    c
}

/// The cases as a Markdown table.
pub fn scale_markdown(rows: &[ScaleRow]) -> String {
    let mut s = String::from(
        "| scene | triangles | budget | surfels | read | BVH | surfels + direct light | gathers at surfels | tree | \
         frame | total | peak memory | tree B/surfel |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for r in rows {
        let cells = cells(
            r,
            |t| format!("{t:.2} s"),
            |b| b.map_or_else(|| "—".to_string(), |b| format!("{:.0} MB", b as f64 / 1e6)),
            |x| format!("{x:.0}"),
        );
        let _ = writeln!(s, "| {} |", cells.join(" | "));
    }
    s
}

/// The cases as CSV, one line each, seconds and bytes unrounded.
pub fn scale_csv(rows: &[ScaleRow]) -> String {
    let mut s = String::from(
        "label,triangles,budget,surfels,read_s,bvh_s,surfels_s,gathers_s,tree_s,frame_s,total_s,peak_bytes,tree_bytes_per_surfel\n",
    );
    for r in rows {
        let cells = cells(
            r,
            |t| t.to_string(),
            |b| b.map_or_else(String::new, |b| b.to_string()),
            |x| x.to_string(),
        );
        let _ = writeln!(s, "{}", cells.join(","));
    }
    s
}

/// The smallest surfel budget of a case [`growth`] fits: below it, costs
/// that do not grow with the surfels (the BVH, the image) dominate.
pub const GROWTH_FROM: usize = 100_000;

/// How one part's cost grows with the surfels.
#[derive(Clone, Debug, PartialEq)]
pub struct Growth {
    /// The part (a column of the table).
    pub part: &'static str,
    /// `k` of the least-squares line through `ln cost` against `ln n`:
    /// the cost grows as `n^k`.
    pub exponent: f64,
    /// The largest factor between a case and the least-squares fit
    /// `cost = c·n·ln n` (1: n log n exactly).
    pub n_log_n_off: f64,
    /// The cases fitted.
    pub cases: usize,
    /// The fewest and the most surfels of the cases fitted.
    pub surfels: (usize, usize),
}

/// A part's name and how to read its cost off a case.
type Part = (&'static str, fn(&ScaleRow) -> Option<f64>);

/// The parts whose growth [`growth`] fits.
const GROWING: [Part; 6] = [
    ("surfels + direct light", |r| Some(r.pre.surfels)),
    ("gathers at surfels", |r| Some(r.pre.gathers)),
    ("tree", |r| Some(r.pre.tree)),
    ("frame", |r| Some(r.frame)),
    ("total", |r| Some(r.total)),
    ("peak memory", |r| r.peak_bytes.map(|b| b as f64)),
];

/// Per part, its growth over the cases of `by_surfels` (one mesh at
/// growing budgets) with a budget of at least [`GROWTH_FROM`]; a part with
/// fewer than two such cases of positive cost is left out.
pub fn growth(by_surfels: &[ScaleRow]) -> Vec<Growth> {
    let mut out = Vec::new();
    for (part, cost) in GROWING {
        let points: Vec<(f64, f64)> = by_surfels
            .iter()
            .filter(|r| r.budget as usize >= GROWTH_FROM)
            .filter_map(|r| Some((r.surfels as f64, cost(r)?)))
            .filter(|&(_, c)| c > 0.0)
            .collect();
        if points.len() < 2 || points.iter().all(|p| p.0 == points[0].0) {
            continue;
        }
        let m = points.len() as f64;
        let (mx, my) = points
            .iter()
            .fold((0.0, 0.0), |(x, y), &(n, c)| (x + n.ln() / m, y + c.ln() / m));
        let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(xy, xx), &(n, c)| {
            let dx = n.ln() - mx;
            (xy + dx * (c.ln() - my), xx + dx * dx)
        });
        // ln c of the n log n fit is the mean of ln(cost / (n ln n)).
        let residual = |&(n, c): &(f64, f64)| c.ln() - (n * n.ln()).ln();
        let lnc = points.iter().map(residual).sum::<f64>() / m;
        let off = points
            .iter()
            .map(|p| (residual(p) - lnc).abs())
            .fold(0.0, f64::max);
        out.push(Growth {
            part,
            exponent: sxy / sxx,
            n_log_n_off: off.exp(),
            cases: points.len(),
            surfels: (
                points.iter().map(|p| p.0 as usize).min().unwrap_or(0),
                points.iter().map(|p| p.0 as usize).max().unwrap_or(0),
            ),
        });
    }
    out
}

/// The growths as a Markdown table.
pub fn growth_markdown(growth: &[Growth]) -> String {
    let mut s = String::from(
        "| part | grows as surfels^k: k | the best c·n·ln n fit, off by up to | cases |\n| --- | ---: | ---: | ---: |\n",
    );
    for g in growth {
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.2}× | {} |",
            g.part, g.exponent, g.n_log_n_off, g.cases
        );
    }
    s
}

/// Each stage's resident peak as a Markdown table, one row a case, the
/// stages as columns in the order they first ran; empty where no peak was
/// measured.
pub fn stage_peaks_markdown(rows: &[ScaleRow]) -> String {
    let mut stages: Vec<&str> = Vec::new();
    for r in rows {
        for (s, _) in &r.stage_peaks {
            if !stages.contains(s) {
                stages.push(s);
            }
        }
    }
    if stages.is_empty() {
        return String::new();
    }
    let mut s = format!(
        "| scene | surfels | {} |\n| --- | ---: |{}\n",
        stages.join(" | "),
        " ---: |".repeat(stages.len())
    );
    for r in rows {
        let cells: Vec<String> = stages
            .iter()
            .map(|stage| {
                r.stage_peaks
                    .iter()
                    .find(|(s, _)| s == stage)
                    .map_or_else(|| "—".to_string(), |(_, b)| format!("{:.0} MB", *b as f64 / 1e6))
            })
            .collect();
        let _ = writeln!(s, "| {} | {} | {} |", r.label, r.surfels, cells.join(" | "));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_multiply_the_triangles_and_keep_the_first_in_place() {
        let scene = crate::scene::builtin::cornell_box();
        let four = copies(&scene, 4);
        assert_eq!(four.triangle_count(), 4 * scene.triangle_count());
        assert_eq!(four.meshes[0].positions, scene.meshes[0].positions);
        let (lo, hi) = bounds(scene.meshes.iter().flat_map(|m| &m.positions).copied());
        let (lo4, hi4) = bounds(four.meshes.iter().flat_map(|m| &m.positions).copied());
        // A 2×2 grid: twice as wide and deep plus the gap, as tall.
        assert!(((hi4.x - lo4.x) / (hi.x - lo.x) - 2.2).abs() < 1e-4);
        assert!(((hi4.y - lo4.y) / (hi.y - lo.y) - 1.0).abs() < 1e-6);
    }

    /// A case of `budget` surfels asked for, a few fewer made (as a real
    /// bake does), whose parts cost `seconds` of those made.
    fn case(budget: u32, seconds: impl Fn(f64) -> f64) -> ScaleRow {
        let surfels = budget as usize - 3;
        let seconds = seconds(surfels as f64);
        ScaleRow {
            label: "mesh".into(),
            triangles: 1,
            budget,
            surfels,
            read: 0.0,
            pre: PreTimings {
                tracer: 0.5,
                surfels: seconds,
                gathers: seconds * seconds,
                tree: seconds,
            },
            frame: 1.0,
            total: seconds,
            peak_bytes: None,
            tree_bytes_per_surfel: 100.0,
            stage_peaks: Vec::new(),
        }
    }

    #[test]
    fn growth_finds_n_log_n_and_a_square() {
        // The parts' costs: c·n·ln n, its square (gathers), and a constant
        // frame; a case below GROWTH_FROM that would bend the fit. The
        // case of budget GROWTH_FROM made fewer surfels and is fitted.
        let n_log_n = |n: f64| 1e-6 * n * n.ln();
        let mut rows: Vec<ScaleRow> = [100_000, 1_000_000, 10_000_000]
            .map(|b| case(b, n_log_n))
            .to_vec();
        rows.insert(0, case(10_000, |_| 5.0));
        let g = growth(&rows);
        let part = |name: &str| g.iter().find(|g| g.part == name).unwrap();
        let tree = part("tree");
        assert_eq!(tree.cases, 3);
        assert!((tree.n_log_n_off - 1.0).abs() < 1e-9, "{tree:?}");
        // d ln(n ln n)/d ln n = 1 + 1/ln n: 1.06–1.09 over 10⁵–10⁷.
        assert!(tree.exponent > 1.05 && tree.exponent < 1.09, "{tree:?}");
        let gathers = part("gathers at surfels");
        assert!(
            (gathers.exponent - 2.0 * tree.exponent).abs() < 1e-9,
            "{gathers:?}"
        );
        assert!(gathers.n_log_n_off > 10.0, "{gathers:?}");
        assert!(part("frame").exponent.abs() < 1e-12);
        assert!(g.iter().all(|g| g.part != "peak memory"), "no peak was measured");
        assert!(growth_markdown(&g).contains("| tree | 1.07 | 1.00× | 3 |"));
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn the_peak_is_measured_on_linux() {
        assert!(reset_peak(), "/proc/self/clear_refs is writable by the process");
        {
            let before = peak().expect("VmHWM after a reset");
            let big = vec![1u8; 64 << 20];
            std::hint::black_box(&big);
            assert!(
                peak().unwrap() >= before + (60 << 20),
                "a 64 MB buffer raised the peak"
            );
        }
    }
}
