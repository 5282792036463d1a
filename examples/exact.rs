//! The gather against closed-form references (`pbgi::exact`): relative
//! RMSE and mean bias of irradiance, occlusion and a glossy lobe, for every
//! Ω × N × surfel density, with the time per receiver on one thread.
//!
//! ```text
//! cargo run --release --no-default-features --features lab --example exact -- \
//!     [--scenes light,bounce,open,blocker,window,sunroom,shell,thin-shell] [--omega 0.1,0.05,…] [--n 8,12,…]
//!     [--density 2,4,8] [--what irr,occ,glossy] [--scalar] [--grid]
//!     [--offset 2e-5] [--min-ms 30] [--dump] [--class mid|edge|corner|window]
//!     [--light-offset K] [--dark-inside] [--sky-rays]
//! ```
//!
//! Scenes: `light`, the closed room with a small bright ceiling light;
//! `bounce`, the same without the light's surfels (a hole); `open`, the room
//! without its ceiling; `blocker`, the lit room with a slab under the light;
//! the openings of [`pbgi::exact::opening`]: `window` (a window in a single
//! sheet under a uniform sky), `sunroom` (the window through a wall 0.075
//! thick, a sunlit floor patch, sky, the outside lit), `shell` and
//! `thin-shell` (closed walls 0.075 and 0.02 thick, the outside lit and a
//! sky: no light of the outside's arrives inside). `--dark-inside` makes
//! the room's own walls black: only what comes through the window lights it.
//! `--sky-rays` takes the sky from rays against the scene itself
//! (`exact::gather_with_rays`, as the renderer does), not from the part of
//! each pixel the cut leaves open.
//! Density `k` samples each 1/8-wide cell with k×k surfels (2: 6k surfels,
//! 4: 25k, 8: 98k). Errors are in percent, relative per receiver; `µs` is
//! the irradiance gather (traversal, splatting, convolution) per receiver,
//! 16-lane pipeline unless `--scalar`. Each error is given over all
//! receivers and over the `mid` ones alone (≥ 0.4 from every edge: over
//! jittered surfels the near edges and corners add the cloud's own
//! discretization error, where the few surfels beside a receiver happen to
//! lie, which only density reduces). `--grid` puts the surfels on a grid,
//! each standing for its own cell, so the exact answer is the cloud's own
//! at every receiver.

use std::time::Instant;

use glam::Vec3;
use pbgi::Scheme;
use pbgi::brdf::GlossyLobe;
use pbgi::exact::{ExactScene, GatherSettings, Quantity, RoomSpec, gather_with_rays, stats};
use pbgi::microbuffer::NearField;

const USAGE: &str = "usage: exact [--scenes light,bounce,open,blocker,window,sunroom,shell,thin-shell] [--omega 0.1,0.05,…] [--n 8,12,…]
    [--density 2,4,8] [--what irr,occ,glossy] [--scalar] [--grid] [--offset 2e-5]
    [--min-ms 30] [--dump] [--class mid|edge|corner|window] [--light-offset K] [--dark-inside] [--sky-rays]";

fn list<T: std::str::FromStr>(s: &str) -> Vec<T> {
    s.split(',').filter_map(|x| x.trim().parse().ok()).collect()
}

fn main() {
    let mut scenes = vec!["light".to_string(), "bounce".to_string()];
    let mut omegas = vec![0.1f32, 0.05, 0.02, 0.01, 0.005, 0.001, 0.0];
    let mut ns = vec![8usize, 12, 16, 32, 64];
    let mut densities = vec![2usize, 4, 8];
    let mut what = vec!["irr".to_string(), "occ".to_string(), "glossy".to_string()];
    let (mut lanes, mut jitter, mut offset, mut min_ms, mut dump) = (true, true, 2e-5f32, 30.0f64, false);
    let mut class = String::new();
    let mut dark = false;
    let mut sky_rays = false;
    let mut light_offset = 0.0f32;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        let v = args.get(i + 1).cloned().unwrap_or_default();
        match args[i].as_str() {
            "--scenes" => scenes = list(&v),
            "--omega" => omegas = list(&v),
            "--n" => ns = list(&v),
            "--density" => densities = list(&v),
            "--what" => what = list(&v),
            "--offset" => offset = v.parse().expect("--offset"),
            "--min-ms" => min_ms = v.parse().expect("--min-ms"),
            "--class" => class = v,
            "--light-offset" => light_offset = v.parse().expect("--light-offset"),
            "--scalar" => {
                lanes = false;
                i += 1;
                continue;
            }
            "--dump" => {
                dump = true;
                i += 1;
                continue;
            }
            "--sky-rays" => {
                sky_rays = true;
                i += 1;
                continue;
            }
            "--dark-inside" => {
                dark = true;
                i += 1;
                continue;
            }
            "--grid" => {
                jitter = false;
                i += 1;
                continue;
            }
            "--help" | "-h" => {
                println!("{USAGE}");
                return;
            }
            other => {
                eprintln!("unknown argument {other}\n{USAGE}");
                std::process::exit(2);
            }
        }
        i += 2;
    }
    let lobe = GlossyLobe {
        specular: Vec3::ONE,
        roughness: 0.3,
    };
    let has = |w: &str| what.iter().any(|x| x == w);
    println!(
        "pipeline {}, surfels {}, sky {}, receivers offset {offset}, light offset weight {light_offset}, glossy roughness {}; errors in % (rel. RMSE / mean bias)",
        if lanes { "16-lane" } else { "scalar" },
        if sky_rays {
            "by rays"
        } else {
            "what the cut leaves open"
        },
        if jitter { "jittered" } else { "grid" },
        lobe.roughness
    );
    for name in &scenes {
        let spec = match name.as_str() {
            "light" | "bounce" => RoomSpec::default(),
            "open" => RoomSpec {
                open_ceiling: true,
                ..Default::default()
            },
            "blocker" => RoomSpec {
                blocker: true,
                ..Default::default()
            },
            other => match pbgi::exact::opening(other) {
                Some(spec) => spec,
                None => panic!("unknown scene {other}"),
            },
        };
        let mut scene = ExactScene::room(&spec);
        if name == "bounce" {
            scene = scene.without_emitter();
        }
        if dark {
            scene = scene.dark_inside();
        }
        let mut probes = scene.probes(offset);
        if !class.is_empty() {
            probes.retain(|p| p.class == class);
        }
        let t0 = Instant::now();
        let exact: Vec<(f64, f64)> = probes.iter().map(|p| scene.exact(p.position, p.normal)).collect();
        let (e_irr, e_occ): (Vec<f64>, Vec<f64>) = exact.into_iter().unzip();
        let e_glossy: Vec<f64> = if has("glossy") {
            probes
                .iter()
                .map(|p| scene.glossy(p.position, p.normal, p.wo, &lobe, 500))
                .collect()
        } else {
            Vec::new()
        };
        println!(
            "\n== scene {name}: {} receivers, exact in {:.1} s; mean E {:.3}, occlusion {:.3}",
            probes.len(),
            t0.elapsed().as_secs_f64(),
            e_irr.iter().sum::<f64>() / e_irr.len() as f64,
            e_occ.iter().sum::<f64>() / e_occ.len() as f64
        );
        println!(
            "{:>3} {:>7} {:>6} {:>3} | {:^26} | {:^26} | {:^26} | {:>8}",
            "k", "surfels", "Ω", "N", "irradiance", "occlusion", "glossy", "µs/recv"
        );
        let h = format!("{:>5} {:>6} {:>6} {:>6}", "rmse", "bias", "mid", "bias");
        println!("{:22} | {h} | {h} | {h} |", "");
        for &k in &densities {
            let tree = scene.tree(k, jitter.then_some(7)).expect("valid surfels");
            let rays = sky_rays.then_some(&scene as &dyn NearField);
            let count = scene.surfels(k, None).len();
            for &omega in &omegas {
                for &n in &ns {
                    let g = GatherSettings {
                        max_solid_angle: omega,
                        light_offset,
                        resolution: n,
                        lanes,
                        scheme: Scheme::Packet,
                        sky: scene.sky as f32,
                    };
                    let cell = |q: Quantity, exact: &[f64]| {
                        let (v, _) = gather_with_rays(&tree, &probes, q, &g, rays).expect("gather");
                        if dump {
                            for ((p, e), v) in probes.iter().zip(exact).zip(&v) {
                                let x = p.position;
                                println!(
                                    "    {:<8} ({:>6.3} {:>6.3} {:>6.3}) exact {e:>8.4} got {v:>8.4} {:>+7.2} %",
                                    p.face,
                                    x.x,
                                    x.y,
                                    x.z,
                                    100.0 * (v / e - 1.0)
                                );
                            }
                        }
                        let s = stats(&v, exact);
                        let pick = |c: &str| -> (Vec<f64>, Vec<f64>) {
                            probes
                                .iter()
                                .zip(v.iter().zip(exact))
                                .filter(|(p, _)| p.class == c)
                                .map(|(_, (a, b))| (*a, *b))
                                .unzip()
                        };
                        let (vm, em) = pick("mid");
                        let m = stats(&vm, &em);
                        format!(
                            "{:>5.2} {:>+6.2} {:>6.2} {:>+6.2}",
                            100.0 * s.rel_rmse,
                            100.0 * s.bias,
                            100.0 * m.rel_rmse,
                            100.0 * m.bias
                        )
                    };
                    let irr = if has("irr") {
                        cell(Quantity::Irradiance, &e_irr)
                    } else {
                        "-".into()
                    };
                    let occ = if has("occ") {
                        cell(Quantity::Occlusion, &e_occ)
                    } else {
                        "-".into()
                    };
                    let glo = if has("glossy") {
                        cell(Quantity::Glossy(lobe), &e_glossy)
                    } else {
                        "-".into()
                    };
                    let (irr, occ, glo) = (irr.as_str(), occ.as_str(), glo.as_str());
                    // Time: repeat the irradiance gather for at least `min_ms`.
                    let (mut runs, mut total) = (0usize, 0.0f64);
                    while runs == 0 || total * 1e3 < min_ms {
                        let (_, t) =
                            gather_with_rays(&tree, &probes, Quantity::Irradiance, &g, rays).expect("gather");
                        total += t.as_secs_f64();
                        runs += 1;
                    }
                    let us = total * 1e6 / (runs * probes.len()) as f64;
                    println!(
                        "{k:>3} {count:>7} {omega:>6} {n:>3} | {irr:>26} | {occ:>26} | {glo:>26} | {us:>8.1}"
                    );
                }
            }
        }
    }
}
