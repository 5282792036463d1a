//! How well a receiver's irradiance gradients predict the irradiance a
//! short step away along its surface, against predicting no change: the
//! measurement behind the cache's use of them (docs/lab/cache.md).
//!
//! ```text
//! cargo run --release --example gradients [box|light|uniform]
//! ```
//!
//! On the synthetic box with blocks: `box` as it is, `light` with only its
//! emitter lit (black walls), `uniform` with every surface of radiance ½
//! and no emitter (the exact irradiance is the same everywhere). Prints the
//! relative RMS error of both predictions against the gathers at the moved
//! points, for steps of 0.01, 0.03 and 0.1 (the box is 2 across).

use glam::Vec3;
use pbgi::gather::{Gather, GatherOptions};
use pbgi::synthetic::{box_with_blocks, receivers};

fn main() -> Result<(), pbgi::Error> {
    let mode = std::env::args().nth(1).unwrap_or_else(|| "box".into());
    let mut surfels = box_with_blocks(40_000, 1).surfels().to_vec();
    for s in &mut surfels {
        let emitter = s.radiance.max_element() > 1.0;
        match mode.as_str() {
            "light" if !emitter => s.radiance = Vec3::ZERO,
            "uniform" => s.radiance = Vec3::splat(0.5),
            "box" | "light" => {}
            other => {
                eprintln!("unknown mode {other}: box, light or uniform");
                std::process::exit(2);
            }
        }
    }
    let tree = pbgi::Tree::build(&pbgi::PointCloud::new(surfels)?);
    let gather = Gather::new(&tree, &GatherOptions::default())?;
    let base: Vec<(Vec3, Vec3)> = receivers(200, 0.0, 0.0, 3)
        .iter()
        .step_by(16)
        .map(|r| (r.position(), r.normal()))
        .collect();
    let at = gather.irradiance_gradients(&base)?;
    println!("{mode}: {} receivers", base.len());
    for step in [0.01f32, 0.03, 0.1] {
        let moved: Vec<(Vec3, Vec3)> = base
            .iter()
            .map(|&(p, n)| (p + n.any_orthonormal_pair().0 * step, n))
            .collect();
        let truth = gather.irradiance(&moved)?;
        let (mut flat, mut slope, mut sum) = (0.0f64, 0.0f64, 0.0f64);
        for (((p, n), (e, g)), (q, t)) in base.iter().zip(&at).zip(moved.iter().map(|m| m.0).zip(&truth)) {
            let predicted = g.extrapolate(*e, q - *p, *n, *n).max(Vec3::ZERO);
            flat += f64::from((*t - *e).length_squared());
            slope += f64::from((*t - predicted).length_squared());
            sum += f64::from(t.length_squared());
        }
        println!(
            "step {step}: relative RMS error {:.4} predicting no change, {:.4} by the gradients",
            (flat / sum).sqrt(),
            (slope / sum).sqrt()
        );
    }
    Ok(())
}
