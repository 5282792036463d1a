//! How a render grows with the scene: each part of `pre.` and the frame,
//! and the peak memory, over scenes of 10⁴ to 10⁷ triangles and budgets of
//! 10⁴ to 10⁷ surfels (`pbgi bench --scale`).
//!
//! A case's peak memory is the process's resident peak from just before the
//! case (Linux resets it through `/proc/self/clear_refs`; elsewhere it is
//! not measured), so it holds the scene, the BVH, the surfels, their trees
//! and the image: all a render needs at once.

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
    let frame = Frame::prepare_with_progress(scene, &opts, progress)?;
    let tree_bytes_per_surfel = frame.tree().bytes_per_surfel();
    let out = frame.render(&|_, _| {})?;
    let total = read + clock.elapsed().as_secs_f64();
    Ok(ScaleRow {
        label: label.to_string(),
        triangles: scene.triangle_count(),
        budget,
        surfels: out.surfels,
        read,
        pre: out.timings.pre_parts,
        frame: out.timings.total_wall - out.timings.pre,
        total,
        peak_bytes: if measured { peak() } else { None },
        tree_bytes_per_surfel,
    })
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
