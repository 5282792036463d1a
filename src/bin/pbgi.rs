//! `pbgi`: render scenes with point-based global illumination.
//!
//! With no arguments it renders the built-in Cornell box to `cornell-box.png`
//! and prints the timing summary in the paper's Table 1 columns.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use pbgi::render::{Image, RenderOptions, RenderOutput, SchemeChoice, render};
use pbgi::scene::load::resolve;
use pbgi::{Isa, Scheme};

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
    /// List the scene names: built-in, and fetched ones with whether their files are present.
    Scenes,
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
    /// Ω: largest solid angle (sr) of a splatted cluster.
    #[arg(long, default_value_t = RenderOptions::default().max_solid_angle)]
    max_solid_angle: f32,
    /// Microbuffer resolution N (hemicube top face N×N).
    #[arg(long, default_value_t = RenderOptions::default().microbuffer)]
    microbuffer: usize,
    /// Indirect bounces: 0 direct only, 1 = direct + one bounce (Mitsuba max_depth 3).
    #[arg(long, default_value_t = RenderOptions::default().bounces)]
    bounces: u32,
    /// Stratified camera samples per pixel (each a receiver); also direct-light samples.
    #[arg(long, default_value_t = RenderOptions::default().spp)]
    spp: u32,
    /// Ambient occlusion instead of radiance.
    #[arg(long)]
    ao: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Instruction-set path: auto, avx512, avx2, neon, portable (default: PBGI_ISA or auto).
    #[arg(long)]
    isa: Option<String>,
    /// Surfels per unit area.
    #[arg(long, default_value_t = RenderOptions::default().density)]
    density: f32,
    /// Hybrid: switch an entry to single below this many active lanes.
    #[arg(long, default_value_t = RenderOptions::default().hybrid_threshold)]
    hybrid_threshold: u32,
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
    let scheme = if a.scheme.eq_ignore_ascii_case("auto") {
        SchemeChoice::Auto
    } else {
        SchemeChoice::Fixed(a.scheme.parse::<Scheme>()?)
    };
    Ok(RenderOptions {
        scheme,
        max_solid_angle: a.max_solid_angle,
        hybrid_threshold: a.hybrid_threshold,
        microbuffer: a.microbuffer,
        bounces: a.bounces,
        spp: a.spp,
        ao: a.ao,
        density: a.density,
        isa: parse_isa(&a.isa)?,
        ..RenderOptions::default()
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
    use pbgi::scene::{builtin, fetched};
    for name in builtin::NAMES {
        println!("{name:<20} built-in");
    }
    let dir = fetched::scene_dir();
    for name in fetched::NAMES {
        let files = fetched::files(name).unwrap_or_default();
        if fetched::is_present_in(name, &dir) {
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
    let opts = pbgi::reference::ReferenceOptions {
        spp: a.spp,
        bounces: a.bounces,
        ..Default::default()
    };
    let out = pool.install(|| {
        pbgi::reference::render_reference(&scene, &opts, &|done, total| tick(&bar, done, total))
    })?;
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
        out.scheme, out.isa, opts.max_solid_angle, opts.microbuffer, threads
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
