//! `pbgi report`: point-based GI against the path tracer at equal error.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};
use pbgi::render::{ReferenceOptions, RenderOptions, render_reference};
use pbgi::report::plot::write_plots;
use pbgi::report::{
    Curve, DEFAULT_PATH_TRACER_SPP, DEFAULT_SPP, ErrorPoint, External, Grid, Method, OIDN_SUFFIX,
    SweepOptions, SweepProgress, check_reference, compare, default_curves, describe, emitter_mask,
    equal_error_markdown, error_sweep, external_points, from_csv, mean_reference, summary_header,
    summary_row, to_csv, to_markdown,
};
use pbgi::scene::Scene;

use crate::args::{ReportArgs, Res, parse_choices, parse_gathers};
use crate::{load_scene, progress_bar, read_exr, thread_pool, tick, write_image};

/// The path tracer's curve of `--full`: the old sweep's.
const FULL_PATH_TRACER_SPP: [u32; 6] = [1, 4, 16, 64, 256, 1024];

/// `m:ss`.
fn clock(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    format!("{}:{:02}", s / 60, s % 60)
}

fn targets(a: &ReportArgs) -> Res<Vec<f64>> {
    if let Some(t) = a
        .targets
        .iter()
        .find(|t| !(t.is_finite() && **t > 0.0 && **t < 100.0))
    {
        return Err(crate::exit::usage(format!(
            "--targets: {t} is not a percentage between 0 and 100"
        )));
    }
    Ok(a.targets.iter().map(|t| t / 100.0).collect())
}

fn replot(a: &ReportArgs) -> Res<()> {
    let csv = a.out.join("error.csv");
    let text = std::fs::read_to_string(&csv).map_err(|e| format!("{}: {e}", csv.display()))?;
    let (scene, points) = from_csv(&text).map_err(|e| format!("{}: {e}", csv.display()))?;
    let targets = targets(a)?;
    let (png, svg) = (a.out.join("error.png"), a.out.join("error.svg"));
    let title = format!("{scene}: relative RMSE against time");
    write_plots(&points, &targets, &title, &png, &svg)?;
    print!("{}", equal_error_markdown(&points, &targets));
    println!("wrote {}, {}", png.display(), svg.display());
    Ok(())
}

/// The sweep `a` asks for: the default curves, or one per combination of
/// the lists given (`--full` fills those not given with the old sweep's),
/// for a scene with or without area lights (`emitters`).
fn sweep_options(a: &ReportArgs, scene: &pbgi::scene::Scene) -> Res<SweepOptions> {
    let emitters = scene.has_emitters();
    // The render `pbgi render` would make of it (the file's max_depth
    // included); the sweep sets the camera samples.
    let base = crate::overrides::resolve(scene, &a.scene, a.settings.options(1)?, &a.settings, None).options;
    let mut grid = if a.full {
        Grid::full(&base)
    } else {
        Grid::default()
    };
    if !a.max_solid_angles.is_empty() {
        grid.max_solid_angles.clone_from(&a.max_solid_angles);
    }
    if !a.microbuffers.is_empty() {
        grid.microbuffers.clone_from(&a.microbuffers);
    }
    if !a.gathers.is_empty() {
        grid.gathers = a.gathers.iter().map(|g| parse_gathers(g)).collect::<Res<_>>()?;
    }
    if !a.schemes.is_empty() {
        grid.schemes = parse_choices(&a.schemes)?;
    }
    grid.direct_samples.clone_from(&a.direct_samples);
    let spp = a.spp.clone().unwrap_or_else(|| DEFAULT_SPP.to_vec());
    let mut curves = if grid.is_empty() {
        default_curves(&base, &spp, emitters)
    } else {
        grid.curves(&base, &spp)
    };
    if a.denoise {
        crate::denoise::available()?;
        let denoised: Vec<Curve> = curves
            .iter()
            .map(|c| Curve {
                label: format!("{}{OIDN_SUFFIX}", c.label),
                denoised: true,
                ..c.clone()
            })
            .collect();
        curves.extend(denoised);
    }
    let path_tracer_spp = a.path_tracer_spp.clone().unwrap_or_else(|| {
        if a.full {
            FULL_PATH_TRACER_SPP.to_vec()
        } else {
            DEFAULT_PATH_TRACER_SPP.to_vec()
        }
    });
    Ok(SweepOptions {
        curves,
        path_tracer_spp,
        bounces: base.bounces,
    })
}

/// The images of each `--denoised` list, their paths resolved against the
/// list's folder and checked to exist (before the sweep, so a typo does not
/// wait for it).
fn denoised_lists(a: &ReportArgs) -> Res<Vec<(std::path::PathBuf, External)>> {
    let mut out = Vec::new();
    for csv in &a.denoised {
        let text = std::fs::read_to_string(csv)
            .map_err(|e| crate::exit::input(format!("{}: {e}", csv.display())))?;
        let dir = csv.parent().unwrap_or(std::path::Path::new("."));
        for e in external_points(&text).map_err(|e| crate::exit::input(format!("{}: {e}", csv.display())))? {
            let path = dir.join(&e.image);
            if !path.exists() {
                return Err(crate::exit::input(format!(
                    "{}: {}: no such image",
                    csv.display(),
                    path.display()
                )));
            }
            out.push((path, e));
        }
    }
    Ok(out)
}

/// Each denoised image measured against `reference` as the sweep's are.
fn measure_denoised(
    scene: &Scene,
    reference: &pbgi::render::Image,
    images: &[(std::path::PathBuf, External)],
) -> Res<Vec<ErrorPoint>> {
    let mask = emitter_mask(scene);
    images
        .iter()
        .map(|(path, e)| {
            let image = read_exr(path)?;
            check_reference(scene, &image).map_err(|err| format!("{}: {err}", path.display()))?;
            let c = compare(&image, reference, &mask).map_err(|err| format!("{}: {err}", path.display()))?;
            Ok(ErrorPoint {
                method: Method::Denoised,
                label: e.label.clone(),
                spp: e.spp,
                pre_s: 0.0,
                trav_s: 0.0,
                shading_s: 0.0,
                total_s: e.seconds,
                rel_rmse: c.rel_rmse,
                floor: c.floor,
            })
        })
        .collect()
}

fn list(spp: &[u32]) -> String {
    spp.iter().map(u32::to_string).collect::<Vec<_>>().join(", ")
}

pub fn cmd_report(a: &ReportArgs) -> Res<()> {
    if a.replot {
        return replot(a);
    }
    if let Some(path) = &a.camera_path {
        return crate::flicker::cmd_flicker(a, path);
    }
    let targets = targets(a)?;
    let mut scene = load_scene(&a.scene)?;
    crate::overrides::set_view(&mut scene, &a.view)?;
    let sweep = sweep_options(a, &scene)?;
    let denoised = denoised_lists(a)?;
    let pool = thread_pool(a.threads)?;
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let reference_note;
    let reference = if !a.reference.is_empty() {
        let mut images = Vec::new();
        for path in &a.reference {
            if !path.exists() {
                return Err(crate::exit::input(format!(
                    "{}: no such reference image",
                    path.display()
                )));
            }
            println!("reference: {}", path.display());
            let image = read_exr(path)?;
            check_reference(&scene, &image).map_err(|e| format!("{}: {e}", path.display()))?;
            images.push(image);
        }
        let names: Vec<String> = a.reference.iter().map(|p| format!("`{}`", p.display())).collect();
        let (mean, noise) = mean_reference(&images, &emitter_mask(&scene))?;
        reference_note = match noise {
            Some(noise) => format!(
                "Reference: the mean of {} (its own noise about {:.2} % relative RMSE).",
                names.join(", "),
                100.0 * noise
            ),
            None => format!("Reference: {}.", names[0]),
        };
        mean
    } else {
        let ref_path = a.out.join("reference.exr");
        if ref_path.exists() {
            println!("reference: {}", ref_path.display());
            reference_note = format!("Reference: `{}`.", ref_path.display());
            read_exr(&ref_path)?
        } else {
            let bar = progress_bar(
                "rows",
                format!("path tracing the reference, {} spp", a.reference_spp),
            );
            let opts = ReferenceOptions {
                spp: a.reference_spp,
                bounces: sweep.bounces as i32,
                ..Default::default()
            };
            let out =
                pool.install(|| render_reference(&scene, &opts, &|done, total| tick(&bar, done, total)))?;
            bar.finish_and_clear();
            write_image(&out.image, &ref_path)?;
            println!(
                "reference: path traced at {} spp in {:.1} s, wrote {}",
                a.reference_spp,
                out.seconds,
                ref_path.display()
            );
            reference_note = format!(
                "Reference: the path tracer at {} spp (`{}`).",
                a.reference_spp,
                ref_path.display()
            );
            out.image
        }
    };
    check_reference(&scene, &reference).map_err(|e| format!("the reference: {e}"))?;
    for c in &sweep.curves {
        println!("point-based curve \"{}\": {} spp", c.label, list(&c.spp));
    }
    println!("path tracer: {} spp", list(&sweep.path_tracer_spp));
    let bar = ProgressBar::new(1000).with_style(
        ProgressStyle::with_template("{spinner} [{bar:30}] {percent:>3}% in {elapsed}, {msg}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.enable_steady_tick(Duration::from_millis(250));
    let on_progress = |p: &SweepProgress| {
        let left = match p.remaining_s {
            Some(r) => {
                bar.set_position((1000.0 * p.elapsed_s / (p.elapsed_s + r).max(1e-9)) as u64);
                format!("about {} left", clock(r))
            }
            None => "estimating the time left".into(),
        };
        let image = (p.done + 1).min(p.images);
        bar.set_message(format!("{left}; image {image}/{}: {}", p.images, p.what));
    };
    let mut points = pool.install(|| error_sweep(&scene, &reference, &sweep, &on_progress))?;
    points.extend(measure_denoised(&scene, &reference, &denoised)?);
    let took = bar.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let threads = pool.current_num_threads();
    let base = sweep.curves.first().map(|c| &c.options);
    let context = format!(
        "{reference_note} Relative RMSE over the pixels that see no emitter; wall-clock \
         seconds on {threads} thread(s); the sweep took {}. Each point-based curve holds its \
         settings while the camera samples per pixel (spp) rise{}; the path tracer's raises its \
         paths per pixel.{}",
        clock(took),
        base.map_or(String::new(), |o| format!(" (the first: {})", describe(o))),
        if denoised.is_empty() {
            ""
        } else {
            " Denoised path tracing was rendered beforehand (`scripts/denoised.sh`: Intel OIDN's RT \
             filter, HDR, colour only); its seconds run from the scene file to the denoised image, \
             the scene's load included, Mitsuba's JIT warm."
        }
    );
    let row_title = a.title.clone().unwrap_or_else(|| {
        let c = &scene.camera;
        format!("{}, {} × {}", scene.name, c.width, c.height)
    });
    // The library's default camera samples, whatever a scene file asks
    // for: the rows of the README's table compare alike.
    let spp = RenderOptions::default().spp;
    let summary = format!(
        "{}\n{}\n",
        summary_header(spp, &targets),
        summary_row(&row_title, &points, &targets, spp)
    );
    let files = [
        ("error.csv", to_csv(&scene.name, &points)),
        ("error.md", to_markdown(&scene.name, &points, &targets, &context)),
        ("summary.md", summary),
    ];
    for (name, text) in &files {
        let p = a.out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    let (png, svg) = (a.out.join("error.png"), a.out.join("error.svg"));
    let title = format!("{}: relative RMSE against time ({threads} thread(s))", scene.name);
    write_plots(&points, &targets, &title, &png, &svg)?;
    println!("sweep: {} images in {}", points.len(), clock(took));
    print!("{}", equal_error_markdown(&points, &targets));
    let written = ["error.csv", "error.md", "summary.md", "error.png", "error.svg"]
        .map(|n| a.out.join(n).display().to_string());
    println!("wrote {}", written.join(", "));
    Ok(())
}
