//! The command line: subcommands and the one `Settings` they share.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use pbgi::gather::MAX_THREADS;
use pbgi::render::{Crop, Direct, Gathers, ReferenceOptions, RenderOptions, Tiles};
use pbgi::tree::Precision;
use pbgi::{CutOptions, Isa, SchemeChoice};

use crate::farm::{Frames, StitchArgs};
use crate::view::ViewArgs;

#[derive(Parser)]
#[command(
    name = "pbgi",
    version,
    about = "Point-based global illumination renderer",
    after_help = "Exit status: 0 done; 1 the work failed (a self-check, a value that is not finite); \
                  2 a bad command line; 3 a scene, mesh, image or tree file missing or invalid; \
                  4 the output could not be written."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene (a name, see `pbgi scenes`, or a Mitsuba XML / OBJ / PLY / OFF / glTF / GLB file).
    Render(RenderArgs),
    /// Bake a scene's surfels and tree into a file that `pbgi render --tree` reads.
    Bake(BakeArgs),
    /// Render the ground truth with the path tracer (same scene, camera, bounces).
    Reference(ReferenceArgs),
    /// The paper's Table 1: pre., trav. per scheme, others, speed-ups over scalar.
    Bench(BenchArgs),
    /// Relative RMSE and bias of an image against a reference, emitters left out.
    Compare(CompareArgs),
    /// Point-based GI against the path tracer at equal error: curves of error against run time.
    Report(ReportArgs),
    /// Join a frame's tiles (render --tiles, one farm task each) into the frame.
    Stitch(StitchArgs),
    /// List the scene names: built-in, and fetched ones with whether their files are present.
    Scenes,
}

#[derive(Args, Clone)]
pub struct BenchArgs {
    /// Scenes (built-in names or files); default: every scene available here.
    pub scenes: Vec<String>,
    /// One JSON object per (scene, scheme) on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Schemes to time (comma-separated; auto: the renderer's per-packet choice); the scalar reference always runs.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "scalar,single,packet,hybrid,auto"
    )]
    pub schemes: Vec<String>,
    /// Rounds over the schemes; each time is the fastest of its rounds.
    #[arg(long, default_value_t = 1, value_parser = bounded_u32(1, 100), allow_negative_numbers = true)]
    pub rounds: u32,
    /// Worker threads (default 1: the paper's per-core figures; with
    /// `--scale`, all cores).
    #[arg(long, value_parser = threads, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Camera samples per pixel (each a receiver).
    #[arg(long, default_value_t = 1, value_parser = bounded_u32(1, MAX_SPP), allow_negative_numbers = true)]
    pub spp: u32,
    /// Whose receivers are cut: `camera` (the primary hits, 4×4-pixel
    /// packets) or `records` (the world-space cache's records of a
    /// `--gathers cache` render of the frame, made first, in the packets it
    /// gathers them in).
    #[arg(long, default_value = "camera", value_parser = ["camera", "records"])]
    pub receivers: String,
    /// The scale benchmark instead: each part's time, each stage's peak
    /// memory and the tree's bytes a surfel of a default render of the
    /// meshes given as SCENES (default: the three fetched dragons,
    /// scripts/fetch-scenes.sh), of `--copies` copies of the last, and of
    /// the last at budgets of 10⁴ surfels up to `--max-surfels`, with how
    /// each part grows with the surfels (the exponent of a power law, and
    /// how far n log n is). Writes scale.md, scale.csv and scale.png/.svg
    /// to `--out`.
    #[arg(long)]
    pub scale: bool,
    /// `--scale`: copies of the last mesh for the largest scene.
    #[arg(long, default_value_t = 12, value_parser = bounded_u32(1, 4096), allow_negative_numbers = true)]
    pub copies: u32,
    /// `--scale`: the largest surfel budget (powers of ten from 10⁴ up to it).
    #[arg(long, default_value_t = 10_000_000, value_parser = bounded_u32(10_000, MAX_SURFELS), allow_negative_numbers = true)]
    pub max_surfels: u32,
    /// `--scale`: the folder for the table, CSV and plot.
    #[arg(long, default_value = "scale")]
    pub out: PathBuf,
    #[command(flatten)]
    pub settings: Settings,
}

#[derive(Args, Clone)]
pub struct ReportArgs {
    /// Built-in scene or scene file.
    #[arg(default_value = "cornell-box")]
    pub scene: String,
    /// The ground truth (.exr); default: OUT/reference.exr, path traced first if missing.
    /// Several (`pbgi reference` with other `--seed`s) are averaged: a
    /// reference's own noise is in every curve's error.
    #[arg(long)]
    pub reference: Vec<PathBuf>,
    /// Paths per pixel of the reference when it is path traced here.
    #[arg(long, default_value_t = 4096, value_parser = bounded_u32(1, MAX_REFERENCE_SPP), allow_negative_numbers = true)]
    pub reference_spp: u32,
    /// Output folder for error.csv, error.md, error.png, error.svg.
    #[arg(long, default_value = "report")]
    pub out: PathBuf,
    /// Camera samples per pixel along each point-based curve (comma-separated;
    /// default 1,2,4,8,16, the default curves of Ω 0.4× and dense gathers a part of it;
    /// the coarse curve, Ω 0.5 and N 8, all of it and 2× and 4× its last; N 10 and
    /// 2 direct samples from 8 spp on).
    #[arg(long, value_delimiter = ',')]
    pub spp: Option<Vec<u32>>,
    /// Paths per pixel along the path tracer's curve (comma-separated; default
    /// 16,64,256,1024, with --full 1,4,16,64,256,1024).
    #[arg(long, value_delimiter = ',')]
    pub path_tracer_spp: Option<Vec<u32>>,
    /// Relative RMSE of the equal-error table, in percent (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "5,3,2")]
    pub targets: Vec<f64>,
    /// The old, long sweep: Ω 0.3 … 0.001 × microbuffer 8, 16 and the default's, each a curve.
    #[arg(long)]
    pub full: bool,
    /// Curves at these Ω (comma-separated; with the other lists, one curve per combination).
    #[arg(long, value_delimiter = ',')]
    pub max_solid_angles: Vec<f32>,
    /// Curves at these microbuffer resolutions (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub microbuffers: Vec<usize>,
    /// Curves at these gathers: "sparse", a sparse spacing in pixels, "cache" or "cache:THRESHOLD" for the world-space cache, or "all" for dense (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub gathers: Vec<String>,
    /// Curves for these schemes (comma-separated; same images, other times).
    #[arg(long, value_delimiter = ',')]
    pub schemes: Vec<String>,
    /// Redraw error.png and error.svg from OUT/error.csv (a finished sweep) and print its table, without rendering.
    #[arg(long)]
    pub replot: bool,
    /// Curves at these area-light samples per camera sample (comma-separated;
    /// default: as `pbgi render`, and 2 from 8 spp on where the scene has area lights).
    #[arg(long, value_delimiter = ',')]
    pub direct_samples: Vec<u32>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = threads, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Denoised path tracing rendered beforehand, to measure beside the
    /// sweep: a CSV `label,spp,seconds,image` as `scripts/denoised.sh`
    /// writes (Mitsuba 3 and pbgi's path tracer, each through Intel OIDN);
    /// image paths relative to the CSV's folder. May be given several times.
    #[arg(long)]
    pub denoised: Vec<PathBuf>,
    /// Also each point-based curve through Intel OIDN, guided by albedo and
    /// normals: a curve of its own, "… + OIDN" (the `denoise` feature); with
    /// --camera-path, each frame, as rows of their own.
    #[arg(long)]
    pub denoise: bool,
    /// The scene's name in OUT/summary.md, a row of the README's table
    /// (`scripts/expect.sh`); default: the scene's name and image size.
    #[arg(long)]
    pub title: Option<String>,
    /// Measure a shot instead of one image: each frame's error and the
    /// flicker (each frame-to-frame change against the true change) of
    /// point-based GI (--spp, default 4,16,64) and the path tracer
    /// (--path-tracer-spp, default 16,256); --denoised lists frames as
    /// patterns with {}. Writes OUT/flicker.md and flicker.csv.
    #[arg(long, value_name = "PATH.json")]
    pub camera_path: Option<PathBuf>,
    /// The references of a --camera-path's frames, reference-0000.exr …,
    /// path traced there at --reference-spp where missing (default OUT/references).
    #[arg(long, value_name = "DIR", requires = "camera_path")]
    pub reference_dir: Option<PathBuf>,
    /// The view of every image (the references' too), where not the scene's.
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub settings: Settings,
}

/// Point-based settings shared by `render`, `bench` and `report`: each
/// option once, its default from [`RenderOptions::default`].
#[derive(Args, Clone)]
pub struct Settings {
    /// Adaptive camera samples: N in every pixel first, the rest of --spp
    /// only where a pixel's first samples disagree (an edge).
    #[arg(long, value_name = "N")]
    pub first_samples: Option<u32>,
    /// How the area-light samples make the direct light: "ratio" (the
    /// unshadowed light in closed form, where the scene has at most 64
    /// emissive triangles, times the share of the samples' light that is
    /// not shadowed) or "sampled" (their mean).
    #[arg(long, default_value = "ratio", value_parser = ["ratio", "sampled"])]
    pub direct: String,
    /// Ω: largest solid angle (sr) of a splatted cluster.
    #[arg(long, default_value_t = RenderOptions::default().cut.max_solid_angle)]
    pub max_solid_angle: f32,
    /// Microbuffer resolution N (an N×N octahedral grid over the hemisphere).
    #[arg(long, default_value_t = RenderOptions::default().microbuffer)]
    pub microbuffer: usize,
    /// How much a cluster's light offset (its light centroid's distance
    /// from its area centroid) adds to its radius in the cut's test.
    #[arg(long, default_value_t = RenderOptions::default().cut.light_offset, help_heading = DEVELOPER)]
    pub light_offset: f32,
    /// Ω of the gathers at receivers with a glossy lobe (which reads where
    /// each cluster's light is drawn, so needs finer clusters).
    #[arg(long, default_value_t = RenderOptions::default().glossy_max_solid_angle)]
    pub glossy_max_solid_angle: f32,
    /// The light offset's weight in the cut of the gathers at receivers
    /// with a glossy lobe.
    #[arg(long, default_value_t = RenderOptions::default().glossy_light_offset, help_heading = DEVELOPER)]
    pub glossy_light_offset: f32,
    /// Microbuffer resolution of the gathers at receivers with a glossy lobe.
    #[arg(long, default_value_t = RenderOptions::default().glossy_microbuffer)]
    pub glossy_microbuffer: usize,
    /// With --gathers cache: lobes at least this rough take their light
    /// from the cache's records; smoother ones gather at each camera sample.
    #[arg(long, default_value_t = RenderOptions::default().glossy_cache_roughness)]
    pub glossy_cache_roughness: f32,
    /// Indirect bounces: 0 direct only, 1 = direct + one bounce (Mitsuba
    /// max_depth 3). Default: the scene file's max_depth, else 1.
    #[arg(long, value_parser = bounded_u32(0, MAX_BOUNCES), allow_negative_numbers = true)]
    pub bounces: Option<u32>,
    /// Surfels per unit area, instead of a budget (default for the named
    /// scenes, built for it: 2000).
    #[arg(long, conflicts_with = "surfels")]
    pub density: Option<f32>,
    /// Surfel budget: about N surfels whatever the scene's units (default for
    /// a file: 52000; the named scenes keep density 2000).
    #[arg(long, value_name = "N", value_parser = bounded_u32(1, MAX_SURFELS), allow_negative_numbers = true)]
    pub surfels: Option<u32>,
    /// About this many gathers of the sky and of each extra bounce at the
    /// surfels, whatever their number (flat groups of at least 8 share one;
    /// 0: groups of 8).
    #[arg(long, value_name = "N", default_value_t = RenderOptions::default().surfel_gathers)]
    pub surfel_gathers: u32,
    /// How the tree stores what splatting reads: full (f32) or compact
    /// (quantized against each node's sphere, 32 bytes a node).
    #[arg(long, value_parser = ["full", "compact"], default_value = "compact")]
    pub tree_precision: String,
    /// Surfels inside solids (a face against another, as a wall on its slab): kept, or dropped and their share given to the surfaces in the open.
    #[arg(long, value_parser = ["keep", "drop"], default_value = "drop")]
    pub buried_surfels: String,
    /// Hybrid: switch an entry to single below this many active lanes.
    #[arg(long, default_value_t = CutOptions::default().hybrid_threshold, help_heading = DEVELOPER)]
    pub hybrid_threshold: u32,
    /// Instruction-set path: auto, avx512, avx2, neon, portable (default: PBGI_ISA or auto).
    #[arg(long, help_heading = DEVELOPER)]
    pub isa: Option<String>,
}

impl Settings {
    pub fn options(&self, spp: u32) -> Res<RenderOptions> {
        Ok(RenderOptions {
            cut: CutOptions {
                max_solid_angle: self.max_solid_angle,
                light_offset: self.light_offset,
                hybrid_threshold: self.hybrid_threshold,
                isa: parse_isa(&self.isa)?,
            },
            microbuffer: self.microbuffer,
            glossy_max_solid_angle: self.glossy_max_solid_angle,
            glossy_microbuffer: self.glossy_microbuffer,
            glossy_light_offset: self.glossy_light_offset,
            glossy_cache_roughness: self.glossy_cache_roughness,
            bounces: self.bounces.unwrap_or(RenderOptions::default().bounces),
            spp,
            first_samples: self.first_samples,
            direct: if self.direct == "ratio" {
                Direct::Ratio
            } else {
                Direct::Sampled
            },
            density: self.density.unwrap_or(RenderOptions::default().density),
            surfel_budget: self.surfels,
            surfel_gathers: self.surfel_gathers,
            tree_precision: if self.tree_precision == "full" {
                Precision::Full
            } else {
                Precision::Compact
            },
            drop_buried: self.buried_surfels == "drop",
            ..RenderOptions::default()
        })
    }
}

/// `--gathers`: "all" (every camera sample gathers), "cache" (world-space
/// records, the default; "cache:T" at threshold T), "sparse" (the screen
/// lattice), or a number: sparse gathers that many pixels apart.
pub fn parse_gathers(g: &str) -> Res<Gathers> {
    match g.trim() {
        "all" => Ok(Gathers::All),
        "sparse" => Ok(Gathers::SPARSE),
        "cache" => Ok(Gathers::CACHE),
        g if g.starts_with("cache:") => match g["cache:".len()..].parse::<f32>() {
            Ok(threshold) if threshold.is_finite() && threshold > 0.0 => Ok(Gathers::Cache { threshold }),
            _ => Err(crate::exit::usage(format!(
                "--gathers {g:?}: the cache's threshold is a number above 0"
            ))),
        },
        g => match (g.parse(), Gathers::SPARSE) {
            (Ok(spacing), Gathers::Sparse { threshold, .. }) => Ok(Gathers::Sparse { spacing, threshold }),
            _ => Err(crate::exit::usage(format!(
                "--gathers: {g:?} is neither \"sparse\", \"cache\", \"all\" nor a spacing in pixels"
            ))),
        },
    }
}

/// Scheme names, `auto` included.
pub fn parse_choices(names: &[String]) -> Res<Vec<SchemeChoice>> {
    names.iter().map(|n| Ok(n.parse::<SchemeChoice>()?)).collect()
}

/// SCENE's help: the names (see `pbgi scenes` for which are present).
const SCENE_HELP: &str = "Scene: built-in cornell-box, cornell-box-glossy, nave (procedural, stands in for Sibenik); \
after scripts/fetch-scenes.sh also bunny, bunny-glossy, sponza, sponza-bump, cornell-box-embree \
(read from $PBGI_SCENE_DIR, else scenes/ in the repository, else ~/.local/share/pbgi/scenes); or a Mitsuba XML / OBJ / PLY / OFF / glTF (.gltf, .glb) file";

#[derive(Args, Clone)]
pub struct ReferenceArgs {
    #[arg(default_value = "cornell-box", help = SCENE_HELP)]
    pub scene: String,
    /// Output image (.exr keeps linear radiance; .png is tonemapped). Default: SCENE-reference.exr.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Paths per pixel. Default: the scene file's sample_count, else 256.
    #[arg(long, value_parser = bounded_u32(1, MAX_REFERENCE_SPP), allow_negative_numbers = true)]
    pub spp: Option<u32>,
    /// Indirect bounces: 0 direct only, 1 one bounce (as `pbgi render`), -1
    /// unlimited. Default: the scene file's max_depth, else 1.
    #[arg(long, allow_hyphen_values = true,
          value_parser = clap::value_parser!(i32).range(-1..=i64::from(MAX_BOUNCES)))]
    pub bounces: Option<i32>,
    /// Which light the image holds: all, direct, or indirect (what the gather computes).
    #[arg(long, default_value = "all")]
    pub component: String,
    /// Seed of every random choice (two seeds give independent images: their difference is the noise).
    #[arg(long, default_value_t = ReferenceOptions::default().seed)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = threads, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub view: ViewArgs,
}

#[derive(Args, Clone)]
pub struct CompareArgs {
    /// The image to measure (.exr).
    pub image: PathBuf,
    /// The ground truth (.exr), e.g. from `pbgi reference`; several (other
    /// `--seed`s) are averaged, and their own noise is estimated and taken out.
    #[arg(required = true)]
    pub reference: Vec<PathBuf>,
    /// The scene both show: pixels that see its emitters are left out of the error.
    #[arg(long, default_value = "cornell-box")]
    pub scene: String,
    /// Also write the signed error (image − reference) as a false-colour PNG: red too bright, blue too dark.
    #[arg(long)]
    pub error_image: Option<PathBuf>,
    /// Also write the image, the reference and the signed error side by side as one PNG, the two exposed alike.
    #[arg(long)]
    pub side_by_side: Option<PathBuf>,
    /// The view the images were rendered from, where not the scene's
    /// (the `--resolution` and `--camera-*` given to render and reference).
    #[command(flatten)]
    pub view: ViewArgs,
}

#[derive(Args, Clone)]
pub struct RenderArgs {
    #[arg(default_value = "cornell-box", help = SCENE_HELP)]
    pub scene: String,
    /// Output image: .png (tonemapped sRGB) or .exr (linear radiance). Default: SCENE.png.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Denoise the image with Intel OIDN, guided by its albedo and normals
    /// (a pbgi built with the `denoise` feature: docs/options.md, "Denoising").
    #[arg(long, conflicts_with = "camera_path")]
    pub denoise: bool,
    /// Traversal scheme: auto, scalar, single, packet or hybrid.
    #[arg(long, default_value = "auto", help_heading = DEVELOPER)]
    pub scheme: String,
    /// Stratified camera samples per pixel (antialiasing; each gets direct
    /// light). Default: the scene file's sample_count, else 4.
    #[arg(long, value_parser = bounded_u32(1, MAX_SPP), allow_negative_numbers = true)]
    pub spp: Option<u32>,
    /// Where the indirect light is gathered: "cache" (records on the
    /// surfaces in world space, shared by the pixels, tiles and frames that
    /// see them), "sparse" (a lattice of pixels, refined at edges and where
    /// the light changes, interpolated at each camera sample) or "all" (at
    /// every camera sample: the dense render, for validation).
    #[arg(long, default_value = "cache")]
    pub gathers: String,
    /// Pixels between sparse gathers on smooth surfaces (a power of two, 1 to 64).
    #[arg(long, default_value_t = 4)]
    pub gather_spacing: u32,
    /// Relative difference between the cache records a point blends, or
    /// change of the gathered light across a lattice cell, that refines it
    /// (smaller: more gathers, closer to the dense render). Default: 0.4
    /// for the cache, 0.1 for the lattice.
    #[arg(long)]
    pub gather_threshold: Option<f32>,
    /// Area-light samples at each camera sample's receiver for direct light
    /// (default 8), stratified over the lights and over the pixel's camera samples.
    #[arg(long, value_parser = bounded_u32(0, MAX_DIRECT_SAMPLES), allow_negative_numbers = true)]
    pub direct_samples: Option<u32>,
    /// Ambient occlusion instead of radiance.
    #[arg(long)]
    pub ao: bool,
    /// Which light the image holds: all, direct, or indirect (the gather's part alone).
    #[arg(long, default_value = "all")]
    pub component: String,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = threads, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
    /// Surfels and tree from this file (`pbgi bake`) instead of building them.
    #[arg(long, value_name = "FILE")]
    pub tree: Option<PathBuf>,
    /// With `--gathers cache`: take up the cache's records from this file
    /// where it exists (made by an earlier render of this scene with these
    /// settings), and write them back, with those this render gathered,
    /// when it ends.
    #[arg(long, value_name = "FILE")]
    pub cache: Option<PathBuf>,
    /// Read the `--cache` file, which must exist, and leave it as it is
    /// (the frames of a farm reading one cache made beforehand): records it
    /// lacks are gathered for this run alone, and the summary counts them.
    #[arg(long, requires = "cache")]
    pub frozen_cache: bool,
    /// Render every frame of a camera path from one bake (the surfels, their
    /// light and the tree built once, or read with --tree): a JSON file
    /// `{"frames": [{"origin": [x,y,z], "target": [x,y,z], "up": [x,y,z],
    /// "fov": degrees}, …]}` (up and fov optional). `{}` in -o becomes the
    /// frame number, 4 digits from 0000.
    #[arg(long, value_name = "PATH.json")]
    pub camera_path: Option<PathBuf>,
    /// Render only pixels x0..x1, y0..y1 of the frame (an image of that size).
    #[arg(long, value_name = "X0,Y0,X1,Y1")]
    pub crop: Option<Crop>,
    /// Render only these frames of --camera-path, K or A-B (inclusive,
    /// numbered from 0 as the files are): one task of a farm.
    #[arg(long, value_name = "K|A-B", requires = "camera_path")]
    pub frames: Option<Frames>,
    /// Cut the frame into COLUMNS,ROWS tiles and render tile --tile alone
    /// (numbered row by row from the top left); `pbgi stitch` joins them.
    #[arg(long, value_name = "COLUMNS,ROWS", requires = "tile", conflicts_with = "crop")]
    pub tiles: Option<Tiles>,
    /// The tile of --tiles to render.
    #[arg(long, value_name = "K", requires = "tiles")]
    pub tile: Option<u32>,
    /// Seed of every random choice: surfel placement, light and camera
    /// samples (two seeds give independent images; the same seed, the same
    /// image bit for bit on any machine and thread count).
    #[arg(long, default_value_t = RenderOptions::default().seed)]
    pub seed: u64,
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub settings: Settings,
}

/// Light from outside the scene, for `render` and `bake`.
#[derive(Args, Clone)]
pub struct EnvironmentArgs {
    /// A uniform sky of this radiance ("R,G,B" or one value) for what the
    /// scene leaves open; replaces the scene's environment.
    #[arg(long, value_name = "RADIANCE")]
    pub sky: Option<String>,
    /// An equirectangular HDR environment map (.exr, +Y up) instead;
    /// replaces the scene's environment.
    #[arg(long, value_name = "FILE", conflicts_with = "sky")]
    pub envmap: Option<PathBuf>,
    /// Factor on the environment map's radiance.
    #[arg(long, default_value_t = 1.0, requires = "envmap")]
    pub envmap_scale: f32,
}

#[derive(Args, Clone)]
pub struct BakeArgs {
    #[arg(default_value = "cornell-box", help = SCENE_HELP)]
    pub scene: String,
    /// Output tree file. Default: SCENE.pbgi.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Ambient-occlusion surfels (no radiance), for `render --ao`.
    #[arg(long)]
    pub ao: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = threads, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
    #[command(flatten)]
    pub settings: Settings,
}

impl Default for RenderArgs {
    fn default() -> Self {
        match Cli::parse_from(["pbgi", "render"]).command {
            Some(Command::Render(a)) => a,
            _ => unreachable!("`pbgi render` parses as the render command"),
        }
    }
}

pub type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// The heading of the options that tune the kernels rather than the image.
const DEVELOPER: &str = "Developer options";
/// Upper bounds of the numeric options: far above any use, below what
/// exhausts memory or time (4·10⁹ spp allocated 768 GB and aborted).
const MAX_SPP: u32 = 65_536;
const MAX_REFERENCE_SPP: u32 = 1 << 24;
const MAX_DIRECT_SAMPLES: u32 = 4_096;
const MAX_BOUNCES: u32 = 64;
const MAX_SURFELS: u32 = 200_000_000;

/// A `u32` option within `lo..=hi`: clap names the bound on a value
/// outside it (a negative one included).
fn bounded_u32(lo: u32, hi: u32) -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(i64::from(lo)..=i64::from(hi))
}

/// `--threads`: 1 to [`MAX_THREADS`], the gather's own bound.
fn threads(s: &str) -> Result<usize, String> {
    match s.trim().parse::<i64>() {
        Ok(n) if (1..=MAX_THREADS as i64).contains(&n) => Ok(n as usize),
        Ok(n) => Err(format!("{n} threads: expected 1 to {MAX_THREADS}")),
        Err(_) => Err(format!("{s:?} is not a whole number of threads")),
    }
}

pub fn parse_isa(s: &Option<String>) -> Res<Option<Isa>> {
    match s.as_deref().map(str::trim) {
        None => Ok(None),
        Some(s) if s.eq_ignore_ascii_case("auto") => Ok(Some(Isa::best())),
        Some(s) => Ok(Some(s.parse::<Isa>()?.require()?)),
    }
}

pub fn options(a: &RenderArgs) -> Res<RenderOptions> {
    Ok(RenderOptions {
        scheme: a.scheme.parse()?,
        ao: a.ao,
        component: a.component.parse()?,
        gathers: match parse_gathers(&a.gathers)? {
            // `--gathers 8` is `--gathers sparse --gather-spacing 8`.
            Gathers::Sparse { spacing, threshold } => Gathers::Sparse {
                spacing: if a.gathers.trim() == "sparse" {
                    a.gather_spacing
                } else {
                    spacing
                },
                threshold: a.gather_threshold.unwrap_or(threshold),
            },
            // `--gathers cache:0.4` is `--gathers cache --gather-threshold 0.4`.
            Gathers::Cache { threshold } => Gathers::Cache {
                threshold: if a.gathers.trim() == "cache" {
                    a.gather_threshold.unwrap_or(threshold)
                } else {
                    threshold
                },
            },
            g => g,
        },
        direct_samples: a.direct_samples,
        crop: a.crop,
        seed: a.seed,
        ..a.settings
            .options(a.spp.unwrap_or(RenderOptions::default().spp))?
    })
}

/// What a bake needs of the render options (the camera samples do not matter).
pub fn bake_options(a: &BakeArgs) -> Res<RenderOptions> {
    Ok(RenderOptions {
        ao: a.ao,
        ..a.settings.options(1)?
    })
}
