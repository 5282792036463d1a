//! `pbgi`: render scenes with point-based global illumination.
//!
//! With no arguments it renders the built-in Cornell box to `cornell-box.png`
//! and prints the timing summary in the paper's Table 1 columns.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use pbgi::render::{Image, ReferenceOptions, RenderOptions, RenderOutput, render, render_reference};
use pbgi::report::plot::write_plots;
use pbgi::report::{BenchOptions, BenchRow, SweepOptions, bench, error_sweep, to_csv, to_markdown};
use pbgi::scene::resolve;
use pbgi::{CutOptions, Isa, Scheme, SchemeChoice};

#[derive(Parser)]
#[command(name = "pbgi", version, about = "Point-based global illumination renderer")]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (a name, see `pbgi scenes`, or a Mitsuba XML / OBJ / PLY file).
    Render(RenderArgs),
    /// Render the ground truth with the path tracer (same scene, camera, bounces).
    Reference(ReferenceArgs),
    /// The paper's Table 1: pre., trav. per scheme, others, speed-ups over scalar.
    Bench(BenchArgs),
    /// Error against run time: sweeps Ω, microbuffer and schemes against a path-traced reference.
    Report(ReportArgs),
    /// List the scene names: built-in, and fetched ones with whether their files are present.
    Scenes,
}

#[derive(Args, Clone)]
struct BenchArgs {
    /// Scenes (built-in names or files); default: every scene available here.
    scenes: Vec<String>,
    /// One JSON object per (scene, scheme) on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Schemes to time (comma-separated; auto: the renderer's per-packet choice); the scalar reference always runs.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "scalar,single,packet,hybrid,auto"
    )]
    schemes: Vec<String>,
    /// Rounds over the schemes; each time is the fastest of its rounds.
    #[arg(long, default_value_t = 1)]
    rounds: u32,
    /// Worker threads (default 1: the paper's per-core figures).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Camera samples per pixel (each a receiver).
    #[arg(long, default_value_t = 1)]
    spp: u32,
    #[command(flatten)]
    settings: Settings,
}

#[derive(Args, Clone)]
struct ReportArgs {
    /// Built-in scene or scene file.
    #[arg(default_value = "cornell-box")]
    scene: String,
    /// The ground truth (.exr); default: OUT/reference.exr, path traced first if missing.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Paths per pixel of the reference when it is path traced here.
    #[arg(long, default_value_t = 4096)]
    reference_spp: u32,
    /// Output folder for error.csv, error.md, error.png, error.svg.
    #[arg(long, default_value = "report")]
    out: PathBuf,
    /// Ω values to sweep (comma-separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0.3,0.1,0.05,0.02,0.01,0.005,0.002,0.001"
    )]
    max_solid_angles: Vec<f32>,
    /// Microbuffer resolutions swept besides the default (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "8,16")]
    microbuffers: Vec<usize>,
    /// Schemes to time (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "scalar,single,packet,hybrid")]
    schemes: Vec<String>,
    /// Path tracer's spp sweep (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "1,4,16,64,256")]
    path_tracer_spp: Vec<u32>,
    /// Redraw error.png and error.svg from OUT/error.csv (a finished sweep) without rendering.
    #[arg(long)]
    replot: bool,
    /// Leave out the Ω = 0 image (every leaf splatted; the slowest point).
    #[arg(long)]
    no_max_solid_angle_zero: bool,
    /// Camera samples per pixel of the point-based images.
    #[arg(long, default_value_t = RenderOptions::default().spp)]
    spp: u32,
    /// Light samples per receiver for direct light.
    #[arg(long, default_value_t = 16)]
    direct_samples: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    settings: Settings,
}

/// Point-based settings shared by `render`, `bench` and `report`: each
/// option once, its default from [`RenderOptions::default`].
#[derive(Args, Clone)]
struct Settings {
    /// Ω: largest solid angle (sr) of a splatted cluster.
    #[arg(long, default_value_t = CutOptions::default().max_solid_angle)]
    max_solid_angle: f32,
    /// Microbuffer resolution N (an N×N octahedral grid over the hemisphere).
    #[arg(long, default_value_t = RenderOptions::default().microbuffer)]
    microbuffer: usize,
    /// Indirect bounces: 0 direct only, 1 = direct + one bounce (Mitsuba max_depth 3).
    #[arg(long, default_value_t = RenderOptions::default().bounces)]
    bounces: u32,
    /// Surfels per unit area.
    #[arg(long, default_value_t = RenderOptions::default().density)]
    density: f32,
    /// Hybrid: switch an entry to single below this many active lanes.
    #[arg(long, default_value_t = CutOptions::default().hybrid_threshold)]
    hybrid_threshold: u32,
    /// Instruction-set path: auto, avx512, avx2, neon, portable (default: PBGI_ISA or auto).
    #[arg(long)]
    isa: Option<String>,
}

impl Settings {
    fn options(&self, spp: u32) -> Res<RenderOptions> {
        Ok(RenderOptions {
            cut: CutOptions {
                max_solid_angle: self.max_solid_angle,
                hybrid_threshold: self.hybrid_threshold,
                isa: parse_isa(&self.isa)?,
            },
            microbuffer: self.microbuffer,
            bounces: self.bounces,
            spp,
            density: self.density,
            ..RenderOptions::default()
        })
    }
}

fn parse_schemes(names: &[String]) -> Res<Vec<Scheme>> {
    names.iter().map(|n| Ok(n.trim().parse::<Scheme>()?)).collect()
}

/// Scheme names, `auto` included.
fn parse_choices(names: &[String]) -> Res<Vec<SchemeChoice>> {
    names.iter().map(|n| Ok(n.parse::<SchemeChoice>()?)).collect()
}

/// SCENE's help: the names (see `pbgi scenes` for which are present).
const SCENE_HELP: &str = "Scene: built-in cornell-box, cornell-box-glossy, nave (procedural, stands in for Sibenik); \
after scripts/fetch-scenes.sh also bunny, bunny-glossy, sponza, sponza-bump, cornell-box-embree \
(read from $PBGI_SCENE_DIR, default scenes/ in the repository); or a Mitsuba XML / OBJ / PLY file";

#[derive(Args, Clone)]
struct ReferenceArgs {
    #[arg(default_value = "cornell-box", help = SCENE_HELP)]
    scene: String,
    /// Output image (.exr keeps linear radiance; .png is tonemapped). Default: SCENE-reference.exr.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Paths per pixel.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Indirect bounces: 0 direct only, 1 one bounce (as `pbgi render`), -1 unlimited.
    #[arg(long, default_value_t = 1, allow_hyphen_values = true)]
    bounces: i32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(Args, Clone)]
struct RenderArgs {
    #[arg(default_value = "cornell-box", help = SCENE_HELP)]
    scene: String,
    /// Output image: .png (tonemapped sRGB) or .exr (linear radiance). Default: SCENE.png.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Traversal scheme: auto, scalar, single, packet or hybrid.
    #[arg(long, default_value = "auto")]
    scheme: String,
    /// Stratified camera samples per pixel (each a receiver); also direct-light samples.
    #[arg(long, default_value_t = RenderOptions::default().spp)]
    spp: u32,
    /// Ambient occlusion instead of radiance.
    #[arg(long)]
    ao: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    settings: Settings,
}

impl Default for RenderArgs {
    fn default() -> Self {
        match Cli::parse_from(["pbgi", "render"]).command {
            Some(Command::Render(a)) => a,
            _ => unreachable!("`pbgi render` parses as the render command"),
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Render(args)) => cmd_render(&args),
        Some(Command::Reference(args)) => cmd_reference(&args),
        Some(Command::Bench(args)) => cmd_bench(&args),
        Some(Command::Report(args)) => cmd_report(&args),
        Some(Command::Scenes) => cmd_scenes(),
        None => cmd_render(&RenderArgs::default()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

type Res<T> = Result<T, Box<dyn std::error::Error>>;

fn parse_isa(s: &Option<String>) -> Res<Option<Isa>> {
    match s.as_deref().map(str::trim) {
        None => Ok(None),
        Some(s) if s.eq_ignore_ascii_case("auto") => Ok(Some(Isa::best())),
        Some(s) => Ok(Some(s.parse::<Isa>()?.require()?)),
    }
}

fn options(a: &RenderArgs) -> Res<RenderOptions> {
    Ok(RenderOptions {
        scheme: a.scheme.parse()?,
        ao: a.ao,
        ..a.settings.options(a.spp)?
    })
}

fn thread_pool(threads: Option<usize>) -> Res<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err("--threads must be at least 1".into());
        }
        b = b.num_threads(n);
    }
    Ok(b.build()?)
}

/// A built-in scene or a file, its warnings printed.
fn load_scene(name: &str) -> Res<pbgi::scene::Scene> {
    let scene = resolve(name)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// A progress bar counting `unit`s; `tick(done, total)` is the library's callback shape.
fn progress_bar(unit: &str, message: String) -> ProgressBar {
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} {{msg}} [{{bar:30}}] {{pos}}/{{len}} {unit}, {{eta}} left"
        ))
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_message(message);
    bar
}

fn tick(bar: &ProgressBar, done: usize, total: usize) {
    if done == 0 {
        bar.set_length(total as u64);
    } else {
        bar.inc(1);
    }
}

fn cmd_render(a: &RenderArgs) -> Res<()> {
    let scene = load_scene(&a.scene)?;
    let opts = options(a)?;
    let out_path = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}.png", scene.name)));
    check_output(&out_path)?;
    let pool = thread_pool(a.threads)?;
    let bar = progress_bar("tiles", format!("rendering {}", scene.name));
    let out = pool.install(|| render(&scene, &opts, &|done, total| tick(&bar, done, total)))?;
    bar.finish_and_clear();
    write_image(&out.image, &out_path)?;
    print_summary(&scene, &opts, &out, pool.current_num_threads());
    println!("wrote {}", out_path.display());
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
    let scene = load_scene(&a.scene)?;
    let out_path = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}-reference.exr", scene.name)));
    check_output(&out_path)?;
    let pool = thread_pool(a.threads)?;
    let bar = progress_bar("rows", format!("path tracing {}", scene.name));
    let opts = ReferenceOptions {
        spp: a.spp,
        bounces: a.bounces,
        ..Default::default()
    };
    let out = pool.install(|| render_reference(&scene, &opts, &|done, total| tick(&bar, done, total)))?;
    bar.finish_and_clear();
    write_image(&out.image, &out_path)?;
    println!(
        "pbgi reference: {} {}×{}, {} spp, {} bounce(s), {:.2} s on {} thread(s)",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        a.spp,
        a.bounces,
        out.seconds,
        pool.current_num_threads()
    );
    println!("wrote {}", out_path.display());
    Ok(())
}

fn check_output(path: &Path) -> Res<()> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("png") | Some("exr") => Ok(()),
        _ => Err(format!("{}: output must end in .png or .exr", path.display()).into()),
    }
}

fn write_image(img: &Image, path: &Path) -> Res<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext == "exr" {
        let (w, h) = (img.width as usize, img.height as usize);
        exr::prelude::write_rgb_file(path, w, h, |x, y| {
            let p = img.pixels[y * w + x];
            (p.x, p.y, p.z)
        })
        .map_err(|e| format!("{}: {e}", path.display()))?;
    } else {
        image::save_buffer(
            path,
            &img.to_srgb8(),
            img.width,
            img.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

fn print_summary(scene: &pbgi::scene::Scene, opts: &RenderOptions, out: &RenderOutput, threads: usize) {
    let c = &scene.camera;
    println!(
        "pbgi render: {} ({} triangles), {}×{}, {} spp, {} bounce(s){}",
        scene.name,
        scene.triangle_count(),
        c.width,
        c.height,
        opts.spp,
        opts.bounces,
        if opts.ao { ", ambient occlusion" } else { "" }
    );
    println!(
        "scheme {} on {}, Ω {}, microbuffer {}, {} thread(s)",
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
        opts.microbuffer,
        threads
    );
    if out.surfels > 0 {
        println!(
            "{} surfels, {} receivers, {:.0} nodes tested per receiver{}",
            out.surfels,
            out.receivers,
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
        "others",
        "direct",
        "total (wall)"
    );
    println!(
        "  {:>8.3} {:>16.3} {:>8.3} {:>8.3} {:>12.3}",
        t.pre, t.trav, t.others, t.direct, t.total_wall
    );
    println!("stages:");
    for s in &out.stages {
        match &s.skipped {
            None => println!("  ran      {}", s.name),
            Some(why) => println!("  skipped  {} ({why})", s.name),
        }
    }
}

fn cmd_bench(a: &BenchArgs) -> Res<()> {
    let scenes = if a.scenes.is_empty() {
        pbgi::scene::available_scenes()
    } else {
        a.scenes.clone()
    };
    let opts = BenchOptions {
        render: a.settings.options(a.spp)?,
        schemes: parse_choices(&a.schemes)?,
        rounds: a.rounds,
    };
    let pool = thread_pool(Some(a.threads))?;
    let mut all = Vec::new();
    for name in &scenes {
        let scene = load_scene(name)?;
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
            a.threads
        );
    }
    Ok(())
}

fn print_table1(rows: &[BenchRow], o: &RenderOptions) {
    let Some(first) = rows.first() else { return };
    println!(
        "{}: {} surfels ({:.0} B/surfel in the tree), {} receivers, {} on {}, {} thread(s), Ω {}, microbuffer {}",
        first.scene,
        first.surfels,
        first.bytes_per_surfel,
        first.receivers,
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
        "scheme", "pre.", "trav.", "speed-up", "others", "lanes", "nodes/rec", "splats/rec", "frame"
    );
    for r in rows {
        println!(
            "  {:<7} {:>8.3} {:>10.3} {:>8.2}× {:>8.3} {:>7} {:>10.0} {:>11.0} {:>9.3}",
            r.scheme.to_string(),
            r.pre_s,
            r.trav_s,
            r.speedup_vs_scalar,
            r.others_s,
            r.lane_utilization
                .map_or("–".to_string(), |u| format!("{:.1}%", 100.0 * u)),
            r.nodes_per_receiver,
            r.splats_per_receiver,
            r.frame_s()
        );
    }
}

fn read_exr(path: &Path) -> Res<pbgi::render::Image> {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![glam::Vec3::ZERO; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<glam::Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = glam::Vec3::new(r, g, b);
        },
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    let size = img.layer_data.size;
    let (_, pixels) = img.layer_data.channel_data.pixels;
    Ok(pbgi::render::Image {
        width: size.width() as u32,
        height: size.height() as u32,
        pixels,
    })
}

fn cmd_report(a: &ReportArgs) -> Res<()> {
    if a.replot {
        let csv = a.out.join("error.csv");
        let text = std::fs::read_to_string(&csv).map_err(|e| format!("{}: {e}", csv.display()))?;
        let (scene, points) = pbgi::report::from_csv(&text).map_err(|e| format!("{}: {e}", csv.display()))?;
        let (png, svg) = (a.out.join("error.png"), a.out.join("error.svg"));
        write_plots(
            &points,
            a.settings.microbuffer,
            &format!("{scene}: relative RMSE against time"),
            &png,
            &svg,
        )?;
        println!("wrote {}, {}", png.display(), svg.display());
        return Ok(());
    }
    let scene = load_scene(&a.scene)?;
    let pool = thread_pool(a.threads)?;
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let (ref_path, given) = match &a.reference {
        Some(p) => (p.clone(), true),
        None => (a.out.join("reference.exr"), false),
    };
    let mut reference_spp = None;
    let reference = if ref_path.exists() {
        println!("reference: {}", ref_path.display());
        read_exr(&ref_path)?
    } else if given {
        return Err(format!("{}: no such reference image", ref_path.display()).into());
    } else {
        let bar = progress_bar(
            "rows",
            format!("path tracing the reference, {} spp", a.reference_spp),
        );
        let opts = ReferenceOptions {
            spp: a.reference_spp,
            bounces: a.settings.bounces as i32,
            ..Default::default()
        };
        let out = pool.install(|| render_reference(&scene, &opts, &|done, total| tick(&bar, done, total)))?;
        bar.finish_and_clear();
        write_image(&out.image, &ref_path)?;
        println!(
            "reference: path traced at {} spp in {:.1} s, wrote {}",
            a.reference_spp,
            out.seconds,
            ref_path.display()
        );
        reference_spp = Some(a.reference_spp);
        out.image
    };
    let (cw, ch) = (scene.camera.width, scene.camera.height);
    if (reference.width, reference.height) != (cw, ch) {
        return Err(format!(
            "{}: the reference is {}×{}, the scene's camera {cw}×{ch}",
            ref_path.display(),
            reference.width,
            reference.height
        )
        .into());
    }
    let mut render_opts = a.settings.options(a.spp)?;
    render_opts.direct_samples = Some(a.direct_samples);
    let sweep = SweepOptions {
        render: render_opts,
        max_solid_angles: a.max_solid_angles.clone(),
        microbuffers: a.microbuffers.clone(),
        schemes: parse_schemes(&a.schemes)?,
        max_solid_angle_zero: !a.no_max_solid_angle_zero,
        path_tracer_spp: a.path_tracer_spp.clone(),
        bounces: a.settings.bounces,
    };
    let bar = progress_bar("images", format!("error sweep of {}", scene.name));
    bar.set_length(sweep.len() as u64);
    let points = pool.install(|| {
        error_sweep(&scene, &reference, &sweep, &|done, _, what| {
            bar.set_position(done as u64);
            bar.set_message(what.to_string());
        })
    })?;
    bar.finish_and_clear();
    let files = [
        ("error.csv", to_csv(&scene.name, &points)),
        (
            "error.md",
            to_markdown(&scene.name, &points, &render_opts, reference_spp),
        ),
    ];
    for (name, text) in &files {
        let p = a.out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    let (png, svg) = (a.out.join("error.png"), a.out.join("error.svg"));
    write_plots(
        &points,
        render_opts.microbuffer,
        &format!(
            "{}: relative RMSE against time ({} thread(s))",
            scene.name,
            pool.current_num_threads()
        ),
        &png,
        &svg,
    )?;
    print!("{}", files[1].1);
    println!(
        "wrote {}, {}, {}, {}",
        a.out.join("error.csv").display(),
        a.out.join("error.md").display(),
        png.display(),
        svg.display()
    );
    Ok(())
}
