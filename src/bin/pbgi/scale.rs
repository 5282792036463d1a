//! `pbgi bench --scale`: how each part of a default render grows with the
//! triangles and with the surfels, and its peak memory.

use std::path::PathBuf;
use std::time::Instant;

use pbgi::render::DEFAULT_SURFEL_BUDGET;
use pbgi::report::{
    GROWTH_FROM, ScaleRow, copies, growth, growth_markdown, scale_csv, scale_markdown, scale_row,
    stage_peaks_markdown,
};

use crate::args::{BenchArgs, Res, options};
use crate::{StageBars, load_scene, thread_pool};

/// The meshes `--scale` uses without SCENES: the fetched dragon at three
/// resolutions, smallest first.
const DRAGONS: [&str; 3] = [
    "dragon/dragon_vrip_res3.ply",
    "dragon/dragon_vrip_res2.ply",
    "dragon/dragon_vrip.ply",
];

pub fn cmd_scale(a: &BenchArgs) -> Res<()> {
    let meshes: Vec<String> = if a.scenes.is_empty() {
        let dir = pbgi::scene::catalogue::scene_dir();
        let paths: Vec<PathBuf> = DRAGONS.iter().map(|f| dir.join(f)).collect();
        if let Some(missing) = paths.iter().find(|p| !p.is_file()) {
            return Err(crate::exit::input(format!(
                "{} not found: run scripts/fetch-scenes.sh (the dragon comes from npm), or name the meshes",
                missing.display()
            )));
        }
        paths.iter().map(|p| p.display().to_string()).collect()
    } else {
        a.scenes.clone()
    };
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let pool = thread_pool(a.threads)?;
    let threads = pool.current_num_threads();
    // A default render of a file: the defaults of `pbgi render` (4 spp).
    let opts = options(&Default::default())?;
    let run = |label: &str, scene: &pbgi::scene::Scene, budget: u32, read: f64| -> Res<ScaleRow> {
        let bars = StageBars::new(label);
        let row =
            pool.install(|| scale_row(label, scene, &opts, budget, read, &|s, d, n| bars.report(s, d, n)));
        bars.finish();
        let row = row?;
        eprintln!(
            "{label}: {} triangles, {} surfels, {:.2} s, peak {}",
            row.triangles,
            row.surfels,
            row.total,
            row.peak_bytes
                .map_or("not measured".into(), |b| format!("{:.0} MB", b as f64 / 1e6))
        );
        Ok(row)
    };
    let name = |m: &str| {
        std::path::Path::new(m)
            .file_name()
            .map_or(m.to_string(), |f| f.to_string_lossy().into_owned())
    };
    let mut by_triangles = Vec::new();
    let mut last = None;
    for m in &meshes {
        let clock = Instant::now();
        let scene = load_scene(m)?;
        let read = clock.elapsed().as_secs_f64();
        by_triangles.push(run(&name(m), &scene, DEFAULT_SURFEL_BUDGET, read)?);
        last = Some((scene, read));
    }
    let (scene, read) = last.ok_or("no mesh to scale")?;
    let label = name(meshes.last().map_or("", |m| m.as_str()));
    if a.copies > 1 {
        let clock = Instant::now();
        let big = copies(&scene, a.copies as usize);
        let read = read + clock.elapsed().as_secs_f64();
        by_triangles.push(run(
            &format!("{label} ×{}", a.copies),
            &big,
            DEFAULT_SURFEL_BUDGET,
            read,
        )?);
    }
    let mut by_surfels = Vec::new();
    let mut budget = 10_000u32;
    while budget <= a.max_surfels {
        by_surfels.push(run(&label, &scene, budget, read)?);
        budget = budget.saturating_mul(10);
    }
    let rows: Vec<ScaleRow> = by_triangles.iter().chain(&by_surfels).cloned().collect();
    let mut table = format!(
        "{}\n(wall-clock seconds, {threads} thread(s), {}, one run; peak memory: the process's resident peak over the case)\n",
        scale_markdown(&rows),
        pbgi::Isa::best(),
    );
    let peaks = stage_peaks_markdown(&rows);
    if !peaks.is_empty() {
        table += &format!(
            "\nEach stage's resident peak (from the stage's start, so with what earlier stages, and memory \
             freed but kept by the allocator, left resident):\n\n{peaks}"
        );
    }
    let growth = growth(&by_surfels);
    let fitted = growth.iter().map(|g| g.surfels);
    if let (Some(lo), Some(hi)) = (fitted.clone().map(|s| s.0).min(), fitted.map(|s| s.1).max()) {
        let (lo, hi) = (lo as f64, hi as f64);
        // d ln(n ln n) / d ln n = 1 + 1/ln n.
        table += &format!(
            "\nHow each part grows with the surfels of {label}, fitted over the budgets from {GROWTH_FROM} up \
             (least squares of ln cost against ln n; n ln n alone grows as n^{:.2}–{:.2} there):\n\n{}",
            1.0 + 1.0 / hi.ln(),
            1.0 + 1.0 / lo.ln(),
            growth_markdown(&growth)
        );
    }
    print!("{table}");
    let write = |file: &str, text: &str| {
        let p = a.out.join(file);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
    };
    write("scale.md", &table)?;
    write("scale.csv", &scale_csv(&rows))?;
    pbgi::report::plot::write_scale_plot(
        &by_triangles,
        &by_surfels,
        &a.out.join("scale.png"),
        &a.out.join("scale.svg"),
    )?;
    println!("wrote {}/scale.{{md,csv,png,svg}}", a.out.display());
    Ok(())
}
