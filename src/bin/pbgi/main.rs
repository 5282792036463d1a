//! `pbgi`: render scenes with point-based global illumination.
//!
//! With no arguments it renders the built-in Cornell box to `cornell-box.png`
//! and prints the timing summary in the paper's Table 1 columns.

mod args;
mod bake;
mod cache;
mod denoise;
mod exit;
mod farm;
mod flicker;
mod images;
mod overrides;
mod path;
mod progress;
mod report;
mod scale;
mod view;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use args::{
    BenchArgs, Cli, Command, CompareArgs, EnvironmentArgs, ReferenceArgs, RenderArgs, Res, options,
    parse_choices,
};
use clap::Parser;
pub(crate) use images::{read_exr, write_image};
use overrides::{print_notes, set_view};
use pbgi::SchemeChoice;
use pbgi::render::{
    Frame, Gathers, ReferenceOptions, RenderError, RenderOptions, RenderOutput, file_bounces, file_spp,
    render_reference,
};
use pbgi::report::{BenchOptions, BenchReceivers, BenchRow, bench};
use pbgi::scene::resolve;
use progress::{StageBars, progress_bar, tick};

fn main() -> ExitCode {
    default_sigpipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Render(args)) => cmd_render(&args),
        Some(Command::Bake(args)) => bake::cmd_bake(&args),
        Some(Command::Reference(args)) => cmd_reference(&args),
        Some(Command::Bench(args)) => cmd_bench(&args),
        Some(Command::Compare(args)) => cmd_compare(&args),
        Some(Command::Report(args)) => report::cmd_report(&args),
        Some(Command::Stitch(args)) => farm::cmd_stitch(&args),
        Some(Command::Scenes) => cmd_scenes(),
        None => cmd_render(&RenderArgs::default()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(exit::code(&*e))
        }
    }
}

/// A reader that closes the pipe early (`pbgi compare … | head -1`) ends
/// `pbgi` as it ends any Unix tool. Rust starts with SIGPIPE ignored, so
/// the write fails instead and `println!` panics ("failed printing to
/// stdout: Broken pipe").
fn default_sigpipe() {
    #[cfg(unix)]
    {
        const SIGPIPE: i32 = 13;
        const SIG_DFL: usize = 0;
        unsafe extern "C" {
            fn signal(signum: i32, handler: usize) -> usize;
        }
        // SAFETY: restores the default action of one signal, before any
        // thread starts; libc's `signal` is linked by std on every Unix.
        unsafe {
            signal(SIGPIPE, SIG_DFL);
        }
    }
}

pub(crate) fn thread_pool(threads: Option<usize>) -> Res<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err(exit::usage("--threads must be at least 1"));
        }
        b = b.num_threads(n);
    }
    Ok(b.build()?)
}

/// A built-in scene or a file, its warnings printed.
pub(crate) fn load_scene(name: &str) -> Res<pbgi::scene::Scene> {
    let scene = resolve(name)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// A scene with the environment the arguments give it.
pub(crate) fn load_lit_scene(name: &str, env: &EnvironmentArgs) -> Res<pbgi::scene::Scene> {
    use pbgi::environment::Environment;
    let mut scene = load_scene(name)?;
    if let Some(sky) = &env.sky {
        let v: Vec<f32> = sky
            .split(',')
            .map(|t| t.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|e| exit::usage(format!("--sky {sky:?}: {e} (expected R,G,B or one value)")))?;
        let l = match v[..] {
            [x] => glam::Vec3::splat(x),
            [r, g, b] => glam::Vec3::new(r, g, b),
            _ => return Err(exit::usage(format!("--sky {sky:?}: expected R,G,B or one value"))),
        };
        scene.environment =
            Some(Environment::uniform(l).map_err(|e| exit::usage(format!("--sky {sky:?}: {e}")))?);
    }
    if let Some(path) = &env.envmap {
        let map = pbgi::scene::formats::read_lat_long(path, env.envmap_scale)?;
        scene.environment = Some(Environment::LatLong(map));
    }
    Ok(scene)
}

fn cmd_render(a: &RenderArgs) -> Res<()> {
    let clock = std::time::Instant::now();
    let mut scene = load_lit_scene(&a.scene, &a.environment)?;
    let read = clock.elapsed().as_secs_f64();
    set_view(&mut scene, &a.view)?;
    let resolved = overrides::resolve(&scene, &a.scene, options(a)?, &a.settings, a.spp);
    let opts = farm::tile_crop(resolved.options, a, &scene)?;
    let out_path = match &a.camera_path {
        Some(_) => path::pattern(a.output.as_deref(), &scene.name)?,
        None => {
            let out = a
                .output
                .clone()
                .unwrap_or_else(|| PathBuf::from(format!("{}.png", scene.name)));
            check_output(&out)?;
            out
        }
    };
    if a.denoise {
        denoise::available()?;
    }
    let pool = thread_pool(a.threads)?;
    let loaded = match &a.tree {
        Some(path) => Some(bake::load_tree(path)?),
        None => None,
    };
    let mut from = None;
    let stages = StageBars::new(&scene.name);
    let frame = pool.install(|| match loaded {
        Some((tree, path, seconds)) => {
            from = Some((path, seconds));
            Frame::with_tree(&scene, &opts, tree).map_err(|e| match e {
                RenderError::TreeMismatch { .. } => format!("{}: {e}", path.display()).into(),
                e => Box::<dyn std::error::Error + Send + Sync>::from(e),
            })
        }
        None => Ok(Frame::prepare_with_progress(&scene, &opts, &|s, d, n| {
            stages.report(s, d, n)
        })?),
    });
    stages.finish();
    let mut frame = frame.map_err(|e| e as Box<dyn std::error::Error>)?;
    let cache = match &a.cache {
        Some(path) => Some(cache::CacheFile::open(path, a.frozen_cache, &opts, &mut frame)?),
        None => None,
    };
    if let Some(file) = &a.camera_path {
        path::render_path(&scene, &opts, &mut frame, (file, a.frames), &out_path, &pool)?;
        return cache.map_or(Ok(()), |c| c.close(&frame));
    }
    let bar = progress_bar("tiles", format!("rendering {}", scene.name));
    let out = pool.install(|| frame.render(&|done, total| tick(&bar, done, total)))?;
    bar.finish_and_clear();
    let clean = a
        .denoise
        .then(|| denoise::denoise(&frame, &out.image, &pool))
        .transpose()?;
    let image = clean.as_ref().map_or(&out.image, |c| &c.0);
    write_image(image, &out_path)?;
    if let Some(c) = &cache {
        c.close(&frame)?;
    }
    print_summary(&scene, &opts, &out, pool.current_num_threads());
    print_notes(&resolved.notes());
    println!("scene read in {read:.3} s (before the render's total)");
    if let Some((path, seconds)) = from {
        println!(
            "surfels + tree loaded from {} ({seconds:.3} s to read and check)",
            path.display()
        );
    }
    if let Some((_, said)) = &clean {
        println!("{said}");
    }
    println!(
        "wrote {} (image digest {:016x})",
        out_path.display(),
        image.digest()
    );
    Ok(())
}

fn cmd_scenes() -> Res<()> {
    use pbgi::scene::{builtin, catalogue};
    for name in builtin::NAMES {
        println!("{name:<20} built-in");
    }
    let dir = catalogue::scene_dir();
    for name in catalogue::FETCHED {
        let files = catalogue::files(name).unwrap_or_default();
        if catalogue::is_present_in(name, &dir) {
            println!("{name:<20} fetched: {}", dir.join(files[0]).display());
        } else {
            println!(
                "{name:<20} missing: {} (run scripts/fetch-scenes.sh)",
                files
                    .iter()
                    .map(|f| dir.join(f).display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    Ok(())
}

fn cmd_reference(a: &ReferenceArgs) -> Res<()> {
    let mut scene = load_scene(&a.scene)?;
    set_view(&mut scene, &a.view)?;
    // The path tracer's own: an unlimited max_depth stays unlimited.
    let (spp, spp_note) = file_spp(scene.file_settings, a.spp);
    let (bounces, bounces_note) = file_bounces(scene.file_settings, a.bounces, false);
    let (spp, bounces) = (spp.unwrap_or(256), bounces.unwrap_or(1));
    let out_path = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}-reference.exr", scene.name)));
    check_output(&out_path)?;
    let pool = thread_pool(a.threads)?;
    let bar = progress_bar("rows", format!("path tracing {}", scene.name));
    let opts = ReferenceOptions {
        spp,
        bounces,
        component: a.component.parse()?,
        seed: a.seed,
    };
    let out = pool.install(|| render_reference(&scene, &opts, &|done, total| tick(&bar, done, total)))?;
    bar.finish_and_clear();
    write_image(&out.image, &out_path)?;
    println!(
        "pbgi reference: {} {}×{}, {} spp, {} bounce(s), {} light, seed {}, {:.2} s on {} thread(s)",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        spp,
        bounces,
        opts.component,
        opts.seed,
        out.seconds,
        pool.current_num_threads()
    );
    print_notes(spp_note.iter().chain(&bounces_note));
    println!("wrote {}", out_path.display());
    Ok(())
}

fn cmd_compare(a: &CompareArgs) -> Res<()> {
    let mut scene = load_scene(&a.scene)?;
    set_view(&mut scene, &a.view)?;
    let image = read_exr(&a.image)?;
    let references = a.reference.iter().map(|p| read_exr(p)).collect::<Res<Vec<_>>>()?;
    // The emitter mask is the scene's camera's: an image of another scene
    // (the default is the Cornell box) is named here, not as a mask's length.
    let (w, h) = (scene.camera.width, scene.camera.height);
    let images = std::iter::once((&a.image, &image)).chain(a.reference.iter().zip(&references));
    for (path, i) in images {
        if (i.width, i.height) != (w, h) {
            return Err(exit::usage(format!(
                "{}: {}×{} pixels, but the scene {} renders {w}×{h}: name the scene the images show with --scene, and their view with --resolution and --camera-*",
                path.display(),
                i.width,
                i.height,
                a.scene
            )));
        }
    }
    let mask = pbgi::report::emitter_mask(&scene);
    let (reference, noise) = pbgi::report::mean_reference(&references, &mask)?;
    let e = pbgi::report::compare(&image, &reference, &mask)?;
    let against = match a.reference.as_slice() {
        [one] => one.display().to_string(),
        many => format!("the mean of {} references", many.len()),
    };
    println!(
        "{} against {against}: relative RMSE {:.4}, bias {:+.4} (mean {:.5} against {:.5}), over {} pixels ({} seeing an emitter left out)",
        a.image.display(),
        e.rel_rmse,
        e.bias,
        e.mean,
        e.reference_mean,
        e.pixels,
        mask.len() - e.pixels
    );
    if let Some(noise) = noise {
        println!(
            "the references' mean has noise {noise:.4} of its own; without it the image's relative RMSE is {:.4}",
            (e.rel_rmse * e.rel_rmse - noise * noise).max(0.0).sqrt()
        );
    }
    if let Some(path) = &a.error_image {
        let png = pbgi::report::error_image(&image, &reference, &mask);
        image::save_buffer(
            path,
            &png,
            image.width,
            image.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| exit::output(format!("{}: {e}", path.display())))?;
        println!(
            "wrote {} (red: too bright, blue: too dark, full at ±25 % of the mean)",
            path.display()
        );
    }
    if let Some(path) = &a.side_by_side {
        let (png, w, h) = pbgi::report::side_by_side(&image, &reference, &mask);
        image::save_buffer(path, &png, w, h, image::ExtendedColorType::Rgb8)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        println!("wrote {} (image, reference, signed error)", path.display());
    }
    Ok(())
}

pub(crate) fn check_output(path: &Path) -> Res<()> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("png") | Some("exr") => Ok(()),
        _ => Err(exit::usage(format!(
            "{}: output must end in .png or .exr",
            path.display()
        ))),
    }
}

pub(crate) fn print_summary(
    scene: &pbgi::scene::Scene,
    opts: &RenderOptions,
    out: &RenderOutput,
    threads: usize,
) {
    let c = &scene.camera;
    println!(
        "pbgi render: {} ({} triangles), {}{}×{}, {} spp, {} light sample(s) per camera sample ({}), {}, {} bounce(s){}",
        scene.name,
        scene.triangle_count(),
        opts.crop.map(|w| format!("crop {w} of ")).unwrap_or_default(),
        c.width,
        c.height,
        opts.spp,
        opts.light_samples(),
        opts.direct,
        match opts.gathers {
            Gathers::All => "a gather per camera sample".to_string(),
            g => format!("gathers {g}"),
        },
        opts.bounces,
        if opts.ao { ", ambient occlusion" } else { "" }
    );
    let glossy = if scene.has_glossy() && !opts.ao {
        format!(
            " (glossy: Ω {}, light offset {}, microbuffer {})",
            opts.glossy_max_solid_angle, opts.glossy_light_offset, opts.glossy_microbuffer
        )
    } else {
        String::new()
    };
    println!(
        "scheme {} on {}, Ω {}{}, microbuffer {}{glossy}, {} thread(s)",
        match out.choice {
            SchemeChoice::Auto => format!(
                "auto ({}; single for packets under {} receivers)",
                out.scheme,
                pbgi::AUTO_SINGLE_BELOW
            ),
            SchemeChoice::Fixed(s) => s.to_string(),
        },
        out.isa,
        opts.cut.max_solid_angle,
        if opts.cut.light_offset > 0.0 {
            format!(", light offset {}", opts.cut.light_offset)
        } else {
            String::new()
        },
        opts.microbuffer,
        threads
    );
    if out.surfels > 0 {
        println!(
            "{} surfels ({}), tree {:.0} bytes a surfel, {} receivers gathered{}, {:.0} nodes tested per receiver{}",
            out.surfels,
            match opts.surfel_budget {
                Some(b) => format!("budget {b}"),
                None => format!("density {}", opts.density),
            },
            out.tree_bytes_per_surfel,
            out.receivers,
            if let Gathers::Cache { .. } = opts.gathers {
                format!(" ({} of them cache records, {} held)", out.records, out.cached)
            } else {
                String::new()
            },
            out.stats.nodes_per_receiver(),
            out.stats
                .lane_utilization()
                .map(|u| format!(", lane utilization {:.1} %", 100.0 * u))
                .unwrap_or_default()
        );
    }
    let t = &out.timings;
    println!("times (s, summed over threads; total is wall clock):");
    println!(
        "  {:>8} {:>16} {:>8} {:>8} {:>12}",
        "pre.",
        format!("trav. ({})", out.scheme),
        "shading",
        "direct",
        "total (wall)"
    );
    println!(
        "  {:>8.3} {:>16.3} {:>8.3} {:>8.3} {:>12.3}",
        t.pre, t.trav, t.shading, t.direct, t.total_wall
    );
    let p = &t.pre_parts;
    if out.surfels > 0 {
        println!(
            "  pre. (wall): ray-tracing BVH {:.3}, surfels + direct light {:.3}, gathers at surfels {:.3}, tree {:.3}",
            p.tracer, p.surfels, p.gathers, p.tree
        );
    }
    println!("stages:");
    for s in &out.stages {
        match &s.skipped {
            None => println!("  ran      {}", s.name),
            Some(why) => println!("  skipped  {} ({why})", s.name),
        }
    }
}

fn cmd_bench(a: &BenchArgs) -> Res<()> {
    if a.scale {
        return scale::cmd_scale(a);
    }
    let scenes = if a.scenes.is_empty() {
        pbgi::scene::available_scenes()
    } else {
        a.scenes.clone()
    };
    let opts = BenchOptions {
        render: a.settings.options(a.spp)?,
        schemes: parse_choices(&a.schemes)?,
        rounds: a.rounds,
        receivers: match a.receivers.as_str() {
            "records" => BenchReceivers::Records,
            _ => BenchReceivers::Camera,
        },
    };
    let threads = a.threads.unwrap_or(1);
    let pool = thread_pool(Some(threads))?;
    let mut all = Vec::new();
    for name in &scenes {
        let scene = load_scene(name)?;
        let opts = BenchOptions {
            render: overrides::resolve(&scene, name, opts.render, &a.settings, Some(a.spp)).options,
            ..opts.clone()
        };
        let bar = progress_bar("passes", format!("bench {}", scene.name));
        let rows = pool.install(|| bench(&scene, &opts, &|done, total| tick(&bar, done, total)))?;
        bar.finish_and_clear();
        if a.json {
            for r in &rows {
                println!("{}", r.to_json());
            }
        } else {
            print_table1(&rows, &opts.render);
        }
        all.extend(rows);
    }
    if !a.json && all.len() > 1 {
        println!(
            "(times in seconds, {} thread(s); speed-ups are ratios from this one run)",
            threads
        );
    }
    Ok(())
}

fn print_table1(rows: &[BenchRow], o: &RenderOptions) {
    let Some(first) = rows.first() else { return };
    println!(
        "{}: {} surfels ({:.0} B/surfel in the tree), {} receivers ({}), {} on {}, {} thread(s), Ω {}, microbuffer {}",
        first.scene,
        first.surfels,
        first.bytes_per_surfel,
        first.receivers,
        match first.kind {
            BenchReceivers::Camera => "camera hits",
            BenchReceivers::Records => "cache records",
        },
        if o.spp == 1 {
            "1 spp".to_string()
        } else {
            format!("{} spp", o.spp)
        },
        first.isa,
        first.threads,
        o.cut.max_solid_angle,
        o.microbuffer
    );
    println!(
        "  {:<7} {:>8} {:>10} {:>9} {:>8} {:>7} {:>10} {:>11} {:>9}",
        "scheme", "pre.", "trav.", "speed-up", "shading", "lanes", "nodes/rec", "splats/rec", "frame"
    );
    for r in rows {
        println!(
            "  {:<7} {:>8.3} {:>10.3} {:>8.2}× {:>8.3} {:>7} {:>10.0} {:>11.0} {:>9.3}",
            r.scheme.to_string(),
            r.pre_s,
            r.trav_s,
            r.speedup_vs_scalar,
            r.shading_s,
            r.lane_utilization
                .map_or("–".to_string(), |u| format!("{:.1}%", 100.0 * u)),
            r.nodes_per_receiver,
            r.splats_per_receiver,
            r.frame_s()
        );
    }
}
