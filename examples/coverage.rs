//! How much of each mesh's surface lies in no surfel disk: the gaps through
//! which what lies behind a surface shows in a gather. Samples points
//! uniformly over every triangle and finds, among the surfels whose normal
//! is within `--cos` of the triangle's (default 0.9995: its own plane only;
//! 0.85 lets a curved surface's neighbouring facets count), the nearest one
//! measured in its own radii; prints per mesh the share of area farther
//! than 1, √2 and √3 radii (a disk of its area, and the disks grown ×2 and
//! ×3 as the hiding grows them, `microbuffer/samples.rs`). docs/lab/BENCHMARKS.md,
//! "Both cores to the end, and surfels on a plane's lattice", used it.
//!
//! ```text
//! cargo run --release --example coverage -- SCENE [--density D] [--samples PER_UNIT_AREA] [--cos C]
//! ```

use std::collections::HashMap;

use glam::{IVec3, Vec3};
use pbgi::render::{BakeOptions, Lights, Tracer, bake};
use pbgi::rng::Rng;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut density, mut per_area, mut cos) = (2000.0f32, 200_000.0f32, 0.9995f32);
    let mut positional = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--density" => density = it.next().ok_or("--density needs a value")?.parse()?,
            "--cos" => cos = it.next().ok_or("--cos needs a value")?.parse()?,
            "--samples" => per_area = it.next().ok_or("--samples needs a value")?.parse()?,
            _ => positional.push(a.clone()),
        }
    }
    let [scene] = &positional[..] else {
        return Err("usage: coverage SCENE [--density D] [--samples PER_UNIT_AREA] [--cos C]".into());
    };
    // Normals that close: the triangle's own plane, so the surfel must lie on it.
    let own_plane = cos >= 0.999;
    let scene = pbgi::scene::catalogue::resolve(scene)?;
    let tracer = Tracer::new(&scene);
    let lights = Lights::new(&scene);
    let baked = bake(
        &scene,
        &tracer,
        &lights,
        &BakeOptions {
            density,
            light_samples: 1,
            ..Default::default()
        },
    )?;
    let surfels = baked.cloud.surfels();
    let cell = 3.0 * surfels.iter().map(|s| s.radius).fold(0.0, f32::max);
    let key = |p: Vec3| (p / cell).floor().as_ivec3();
    let mut grid: HashMap<IVec3, Vec<u32>> = HashMap::new();
    for (i, s) in surfels.iter().enumerate() {
        grid.entry(key(s.position)).or_default().push(i as u32);
    }
    let mut rng = Rng::new(3);
    println!("mesh | triangles | area | beyond 1 r | beyond √2 r | beyond √3 r (share of area)");
    for mesh in &scene.meshes {
        let (mut area, mut out) = (0.0f64, [0.0f64; 3]);
        for t in &mesh.triangles {
            let v = t.map(|i| mesh.positions[i as usize]);
            let c = (v[1] - v[0]).cross(v[2] - v[0]);
            let a = 0.5 * c.length();
            // A degenerate triangle makes no surfel and has no area to cover.
            let Some(n) = (a > 0.0).then(|| c / (2.0 * a)) else {
                continue;
            };
            let k = ((a * per_area) as u32).max(4);
            for _ in 0..k {
                let (u, w) = (rng.f32(), rng.f32());
                let su = u.sqrt();
                let p = v[0] * (1.0 - su) + v[1] * (w * su) + v[2] * ((1.0 - w) * su);
                // Nearest in radii among the surfels on this plane.
                let mut best = f32::INFINITY;
                let g = key(p);
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            for &i in grid.get(&(g + IVec3::new(dx, dy, dz))).into_iter().flatten() {
                                let s = &surfels[i as usize];
                                let d = p - s.position;
                                if s.normal.dot(n) > cos
                                    && (!own_plane || s.normal.dot(d).abs() < 1e-4 * cell)
                                {
                                    best = best.min(d.length() / s.radius);
                                }
                            }
                        }
                    }
                }
                let wgt = f64::from(a) / f64::from(k);
                area += wgt;
                for (o, f) in out.iter_mut().zip([1.0f32, 2f32.sqrt(), 3f32.sqrt()]) {
                    if best > f {
                        *o += wgt;
                    }
                }
            }
        }
        println!(
            "{} | {} | {:.4} | {:.2} % | {:.2} % | {:.3} %",
            mesh.name,
            mesh.triangles.len(),
            area,
            100.0 * out[0] / area,
            100.0 * out[1] / area,
            100.0 * out[2] / area
        );
    }
    Ok(())
}
