//! Times the four traversal schemes on every instruction-set path, on one
//! thread, and checks that they all give the scalar reference's cuts.
//!
//! ```text
//! cargo run --release --example cut_bench -- [--json] [--surfels N[,N...]] [--tiles T]
//!     [--max_solid_angle W] [--isa all|NAME[,NAME...]] [--threshold H]
//! ```
//!
//! * `--surfels`: cloud sizes (`box_with_blocks`), e.g. `10000,1e5,1e6`; default `1e4,1e5`.
//! * `--tiles`: packets of 16 receivers per set (default 128); each cloud gets a
//!   coherent set (4×4 tiles, surface normals) and an incoherent one (the same
//!   kind of tiles with jittered normals).
//! * `--max_solid_angle`: Ω, the largest solid angle a splatted node may subtend (default 0.05).
//! * `--isa`: `all` (default: every path this CPU runs) or a list of names.
//! * `--threshold`: the hybrid scheme's switch threshold (default 4).
//! * `--json`: one JSON object per line per (cloud, receivers, scheme, isa)
//!   instead of the table.
//!
//! Each timing warms up, then repeats the run until at least 0.3 s have passed
//! and keeps the fastest run. The scalar scheme on the same cloud, receivers
//! and ISA is the baseline of `speedup_vs_scalar`. Before timing, every scheme's
//! cuts are compared with scalar's (and scalar's across ISAs); any difference
//! is reported and the program exits with status 1.

use std::fmt::Write as _;
use std::hint::black_box;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use pbgi::{
    Cut, CutOptions, Isa, Receiver, Scheme, SplatCounter, Traversal, TraversalStats, Tree, synthetic,
};

const CLOUD_SEED: u64 = 1;
const RECEIVER_SEED: u64 = 7;
const SPACING: f32 = 0.01;
const MIN_TIME: Duration = Duration::from_millis(300);
const WARM_UP: Duration = Duration::from_millis(50);

const USAGE: &str = "usage: cut_bench [--json] [--surfels N[,N...]] [--tiles T] [--max_solid_angle W] \
                     [--isa all|NAME[,NAME...]] [--threshold H]";

struct Args {
    json: bool,
    surfels: Vec<usize>,
    tiles: usize,
    max_solid_angle: f32,
    isas: Vec<Isa>,
    threshold: u32,
}

fn parse_count(s: &str) -> Result<usize, String> {
    let s = s.trim();
    let n = s
        .parse::<usize>()
        .ok()
        .or_else(|| {
            s.parse::<f64>()
                .ok()
                .filter(|x| x.fract() == 0.0 && *x >= 0.0 && *x < 1e12)
                .map(|x| x as usize)
        })
        .ok_or_else(|| format!("`{s}` is not a whole number"))?;
    if n == 0 {
        return Err("counts must be positive".into());
    }
    Ok(n)
}

fn parse_args() -> Result<Args, String> {
    let defaults = CutOptions::default();
    let mut args = Args {
        json: false,
        surfels: vec![10_000, 100_000],
        tiles: 128,
        max_solid_angle: defaults.max_solid_angle,
        isas: Isa::available(),
        threshold: defaults.hybrid_threshold,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        // Accept both `--flag value` and `--flag=value`.
        let (flag, inline) = match flag.split_once('=') {
            Some((f, v)) => (f.to_string(), Some(v.to_string())),
            None => (flag, None),
        };
        let mut value = || {
            inline
                .clone()
                .or_else(|| it.next())
                .ok_or(format!("{flag} needs a value"))
        };
        match flag.as_str() {
            "--json" => args.json = true,
            "--surfels" => args.surfels = value()?.split(',').map(parse_count).collect::<Result<_, _>>()?,
            "--tiles" => args.tiles = parse_count(&value()?)?,
            "--max_solid_angle" => {
                let v = value()?;
                args.max_solid_angle = v
                    .parse()
                    .map_err(|_| format!("--max_solid_angle: `{v}` is not a number"))?;
            }
            "--threshold" => {
                let v = value()?;
                args.threshold = v
                    .parse()
                    .map_err(|_| format!("--threshold: `{v}` is not 0 to 17"))?;
            }
            "--isa" => {
                let v = value()?;
                if !v.trim().eq_ignore_ascii_case("all") {
                    args.isas = v
                        .split(',')
                        .map(|name| {
                            name.parse::<Isa>()
                                .and_then(Isa::require)
                                .map_err(|e| e.to_string())
                        })
                        .collect::<Result<_, _>>()?;
                }
            }
            "-h" | "--help" => {
                println!("{USAGE}");
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    if args.surfels.iter().any(|&n| n > pbgi::PointCloud::MAX_SURFELS) {
        return Err(format!("--surfels: at most {}", pbgi::PointCloud::MAX_SURFELS));
    }
    Ok(args)
}

/// The fastest of repeated runs after a warm-up, and the counters of one run.
fn time(trav: &Traversal, scheme: Scheme, receivers: &[Receiver]) -> (f64, TraversalStats) {
    let run = || {
        let mut sink = SplatCounter::default();
        let stats = trav.run(scheme, black_box(receivers), &mut sink);
        black_box(sink.splats);
        stats
    };
    let start = Instant::now();
    let stats = run();
    while start.elapsed() < WARM_UP {
        run();
    }
    let (mut best, mut total) = (f64::INFINITY, Duration::ZERO);
    while total < MIN_TIME {
        let t = Instant::now();
        run();
        let dt = t.elapsed();
        total += dt;
        best = best.min(dt.as_secs_f64());
    }
    (best, stats)
}

/// `None` if equal, else a description of the first difference.
fn compare(got: &[Cut], want: &[Cut]) -> Option<String> {
    if got.len() != want.len() {
        return Some(format!("{} cuts instead of {}", got.len(), want.len()));
    }
    let i = got.iter().zip(want).position(|(g, w)| g != w)?;
    let bad = got.iter().zip(want).filter(|(g, w)| g != w).count();
    Some(format!(
        "{bad} of {} receivers differ; first is receiver {i}: {} splats / {} discards instead of {} / {}",
        got.len(),
        got[i].splats.len(),
        got[i].discards.len(),
        want[i].splats.len(),
        want[i].discards.len()
    ))
}

fn json_num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".into()
    }
}

/// `println!` that ends the program quietly when stdout is closed (`| head`).
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout(), $($t)*).is_err() {
            std::process::exit(0);
        }
    }};
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("cut_bench: {e}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    // Check the options once up front, before any cloud is built.
    let empty = Tree::build(&pbgi::PointCloud::default());
    for &isa in &args.isas {
        let options = CutOptions {
            max_solid_angle: args.max_solid_angle,
            light_offset: 0.0,
            hybrid_threshold: args.threshold,
            isa: Some(isa),
        };
        if let Err(e) = Traversal::new(&empty, options) {
            eprintln!("cut_bench: {e}\n{USAGE}");
            return ExitCode::from(2);
        }
    }
    let sets = [("coherent", 0.0f32), ("incoherent", 1.0f32)];
    let receiver_sets: Vec<(&str, Vec<Receiver>)> = sets
        .iter()
        .map(|&(name, jitter)| {
            (
                name,
                synthetic::receivers(args.tiles, SPACING, jitter, RECEIVER_SEED),
            )
        })
        .collect();

    if !args.json {
        let isas: Vec<&str> = args.isas.iter().map(|i| i.name()).collect();
        out!(
            "pbgi cut_bench: max_solid_angle {}, hybrid threshold {}, {} receivers per set ({} tiles of 16), \
             isa {}, traversal on one thread (min of repeats >= {:.1} s)",
            args.max_solid_angle,
            args.threshold,
            args.tiles * 16,
            args.tiles,
            isas.join(","),
            MIN_TIME.as_secs_f64()
        );
    }

    for &n in &args.surfels {
        let cloud_name = format!("box-{n}");
        let cloud = synthetic::box_with_blocks(n, CLOUD_SEED);
        let start = Instant::now();
        let tree = Tree::build(&cloud);
        let build = start.elapsed().as_secs_f64();
        if !args.json {
            out!(
                "\n{cloud_name}: {} surfels, {} nodes, depth {}, tree build {:.1} ms (rayon, {} threads), \
                 {:.1} bytes/surfel",
                cloud.len(),
                tree.len(),
                tree.depth(),
                build * 1e3,
                rayon::current_num_threads(),
                tree.bytes_per_surfel()
            );
            out!(
                "{:<11} {:<9} {:<7} {:>10} {:>9} {:>10} {:>9} {:>10}",
                "receivers",
                "isa",
                "scheme",
                "ms/run",
                "ns/recv",
                "vs scalar",
                "lane use",
                "nodes/recv"
            );
        }
        for (set, receivers) in &receiver_sets {
            let mut first_scalar: Option<(Isa, Vec<Cut>)> = None;
            for &isa in &args.isas {
                let options = CutOptions {
                    max_solid_angle: args.max_solid_angle,
                    light_offset: 0.0,
                    hybrid_threshold: args.threshold,
                    isa: Some(isa),
                };
                let trav = match Traversal::new(&tree, options) {
                    Ok(t) => t,
                    Err(e) => {
                        eprintln!("cut_bench: {e}");
                        return ExitCode::from(2);
                    }
                };

                // Verify: every scheme's cuts equal scalar's, and scalar's equal
                // scalar's on the first ISA.
                let reference = trav.cuts(Scheme::Scalar, receivers);
                let mut checks = Vec::new();
                if let Some((isa0, cuts0)) = &first_scalar {
                    checks.push((
                        format!("scalar on {isa} vs scalar on {isa0}"),
                        compare(&reference, cuts0),
                    ));
                }
                for scheme in Scheme::ALL.into_iter().skip(1) {
                    let what = format!("{scheme} vs scalar on {isa}");
                    checks.push((what, compare(&trav.cuts(scheme, receivers), &reference)));
                }
                for (what, diff) in checks {
                    if let Some(diff) = diff {
                        eprintln!("cut_bench: MISMATCH on {cloud_name}, {set} receivers: {what}: {diff}");
                        return ExitCode::FAILURE;
                    }
                }
                if first_scalar.is_none() {
                    first_scalar = Some((isa, reference));
                }

                let mut scalar: Option<(f64, TraversalStats)> = None;
                for scheme in Scheme::ALL {
                    let (seconds, stats) = time(&trav, scheme, receivers);
                    let (base, base_stats) = *scalar.get_or_insert((seconds, stats));
                    if stats.node_tests != base_stats.node_tests {
                        eprintln!(
                            "cut_bench: warning: {scheme} on {isa} tested {} nodes, scalar {}",
                            stats.node_tests, base_stats.node_tests
                        );
                    }
                    let speedup = base / seconds;
                    let util = stats.lane_utilization();
                    if args.json {
                        let mut line = String::new();
                        write!(
                            line,
                            "{{\"cloud\":\"{cloud_name}\",\"receiver_set\":\"{set}\",\"scheme\":\"{scheme}\",\
                             \"isa\":\"{isa}\",\"receivers\":{},\"seconds\":{},\"speedup_vs_scalar\":{},\
                             \"nodes_per_receiver\":{},\"lane_utilization\":{},\"surfels\":{},\"max_solid_angle\":{}}}",
                            receivers.len(),
                            json_num(seconds),
                            json_num(speedup),
                            json_num(stats.nodes_per_receiver()),
                            util.map_or("null".into(), json_num),
                            cloud.len(),
                            args.max_solid_angle, // f32: shortest form, e.g. 0.05
                        )
                        .unwrap();
                        out!("{line}");
                    } else {
                        out!(
                            "{:<11} {:<9} {:<7} {:>10.3} {:>9.0} {:>9.2}x {:>9} {:>10.1}",
                            set,
                            isa.name(),
                            scheme.name(),
                            seconds * 1e3,
                            seconds * 1e9 / receivers.len() as f64,
                            speedup,
                            util.map_or("-".into(), |u| format!("{:.1}%", u * 100.0)),
                            stats.nodes_per_receiver()
                        );
                    }
                }
            }
        }
    }
    if !args.json {
        out!("\nall schemes gave the scalar cuts on every isa");
    }
    ExitCode::SUCCESS
}
