//! The gather at chosen receivers of a scene against its ground truth: the
//! one-bounce irradiance ray cast from the receiver (cosine-weighted rays,
//! direct light reflected at each hit: what the gather's surfels carry),
//! for several Ω and microbuffer sizes. It finds where the gather leaks or
//! loses light, which an image-wide error only averages.
//!
//! ```text
//! cargo run --release --example leak -- SCENE "x,y,z[,nx,ny,nz];px:X,Y;…" \
//!     [--omega 0.15,0.01,0.001] [--n 14,32,48] [--rays 200000] [--lit X0,Y0,Z0,X1,Y1,Z1] [--light-offset K] [--density D]
//! ```
//!
//! The normal defaults to +y; `px:X,Y` is where pixel (X, Y)'s camera ray
//! through its centre hits, facing the camera. `--lit` keeps the light of the surfels (and
//! of the ray hits) inside that box alone, so one source's share is
//! measured with every occluder still in place. Irradiance is the mean of
//! the three channels. Each Ω and N is gathered with the surfels alone and
//! with the renderer's near field (rays within three surfel radii; not with
//! `--lit`). docs/lab/BENCHMARKS.md, "The nave's indirect bias", used it on the
//! nave's window jambs, and "Sponza's error floor" on receivers just above
//! a sunlit ledge.

use glam::Vec3;
use pbgi::brdf::lambert_sample;
use pbgi::gather::{Gather, GatherOptions};
use pbgi::render::{BakeOptions, Brdf, LightSamples, Lights, NearRays, Tracer, bake};
use pbgi::rng::Rng;
use pbgi::{PointCloud, Surfel, Tree};

const USAGE: &str = "usage: leak SCENE \"x,y,z[,nx,ny,nz];px:X,Y;…\" [--omega 0.15,0.01,0.001] [--n 14,32,48] [--rays N] [--lit X0,Y0,Z0,X1,Y1,Z1] [--light-offset K] [--density D]";

fn floats(s: &str) -> Result<Vec<f32>, String> {
    s.split(',')
        .map(|x| x.trim().parse::<f32>().map_err(|e| format!("{x:?}: {e}")))
        .collect()
}

fn mean(v: Vec3) -> f64 {
    f64::from(v.x + v.y + v.z) / 3.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut omegas, mut sizes, mut rays, mut lit) =
        (vec![0.15, 0.01, 0.001], vec![14, 32, 48], 200_000u32, None);
    let (mut light_offset, mut density) = (0.0, 2000.0);
    let mut positional = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value\n{USAGE}"));
        match a.as_str() {
            "--omega" => omegas = floats(value()?)?,
            "--n" => sizes = value()?.split(',').map(str::parse).collect::<Result<_, _>>()?,
            "--rays" => rays = value()?.parse()?,
            "--light-offset" => light_offset = value()?.parse()?,
            "--density" => density = value()?.parse()?,
            "--lit" => match floats(value()?)?[..] {
                [a, b, c, d, e, f] => lit = Some((Vec3::new(a, b, c), Vec3::new(d, e, f))),
                _ => return Err(format!("--lit takes six numbers\n{USAGE}").into()),
            },
            _ => positional.push(a.clone()),
        }
    }
    let [scene, receivers] = &positional[..] else {
        return Err(USAGE.into());
    };
    if omegas.len() != sizes.len() {
        return Err(format!("--omega and --n need as many values\n{USAGE}").into());
    }
    let inside = |p: Vec3| lit.is_none_or(|(lo, hi): (Vec3, Vec3)| p.cmpge(lo).all() && p.cmple(hi).all());

    let scene = pbgi::scene::catalogue::resolve(scene)?;
    let tracer = Tracer::new(&scene);
    let cam = &scene.camera;
    let receivers = receivers
        .split(';')
        .map(
            |r| match (r.strip_prefix("px:"), &floats(r.trim_start_matches("px:"))?[..]) {
                // A pixel's centre: where its camera ray hits, the normal
                // turned toward the camera.
                (Some(_), &[x, y]) => {
                    let d = cam.ray_direction(x + 0.5, y + 0.5);
                    let hit = tracer
                        .closest(cam.origin, d, f32::INFINITY)
                        .ok_or_else(|| format!("pixel {r:?}: its camera ray leaves the scene"))?;
                    let n = hit.geometric_normal;
                    let n = if n.dot(d) > 0.0 { -n } else { n };
                    let p = cam.origin + d * hit.t;
                    println!(
                        "{r}: position {:.4},{:.4},{:.4} normal {:.3},{:.3},{:.3}",
                        p.x, p.y, p.z, n.x, n.y, n.z
                    );
                    Ok((p, n))
                }
                (None, &[x, y, z]) => Ok((Vec3::new(x, y, z), Vec3::Y)),
                (None, &[x, y, z, a, b, c]) => Ok((Vec3::new(x, y, z), Vec3::new(a, b, c).normalize())),
                _ => Err(format!(
                    "receiver {r:?}: x,y,z, x,y,z,nx,ny,nz or px:X,Y (a pixel)"
                )),
            },
        )
        .collect::<Result<Vec<_>, _>>()?;
    let lights = Lights::new(&scene);
    let baked = bake(
        &scene,
        &tracer,
        &lights,
        &BakeOptions {
            density,
            ..Default::default()
        },
    )?;
    let surfels: Vec<Surfel> = baked
        .cloud
        .surfels()
        .iter()
        .map(|&s| Surfel {
            radiance: if inside(s.position) {
                s.radiance
            } else {
                Vec3::ZERO
            },
            ..s
        })
        .collect();
    let tree = Tree::build(&PointCloud::new(surfels)?);

    // A surfel's radius at this density: how near is near.
    let radius = (1.0 / (std::f32::consts::PI * density)).sqrt();
    let mut rows = vec![String::from("ray cast")];
    let mut truth = Vec::new();
    let mut near = Vec::new();
    for &(p, n) in &receivers {
        let origin = p + n * tracer.epsilon();
        let mut rng = Rng::new(9);
        let (mut sum, mut within) = (0.0, [0.0; 2]);
        for i in 0..rays {
            let d = lambert_sample(n, rng.f32(), rng.f32());
            let Some(hit) = tracer.closest(origin, d, f32::INFINITY) else {
                continue;
            };
            // Flat normals, as the surfels have; a one-sided back face is black.
            let material = &scene.materials[scene.meshes[hit.mesh as usize].material];
            let mut ng = hit.geometric_normal;
            if ng.dot(d) > 0.0 {
                if !material.two_sided {
                    continue;
                }
                ng = -ng;
            }
            let q = origin + d * hit.t;
            if !inside(q) {
                continue;
            }
            // One area-light sample per ray, each its own point of the sequence.
            let samples = LightSamples {
                count: 1,
                first: i,
                scramble: [rng.f32().to_bits(), rng.f32().to_bits()],
                ratio: false,
            };
            let l = mean(lights.reflected(
                &tracer,
                q + ng * tracer.epsilon(),
                ng,
                samples,
                Brdf::lambert(material.albedo),
            ));
            sum += l;
            for (w, k) in within.iter_mut().zip([2.0, 4.0]) {
                if hit.t < k * radius {
                    *w += l;
                }
            }
        }
        truth.push(std::f64::consts::PI * sum / f64::from(rays));
        near.push(within.map(|w| w / sum));
    }
    rows[0] += &truth.iter().map(|e| format!(" | {e:.5}")).collect::<String>();
    // The share of that light from surfaces within two and four surfel
    // radii: where disks stand for the surface worst (docs/lab/BENCHMARKS.md,
    // "Sponza's error floor").
    rows.push(format!(
        "from within 2r / 4r ({:.1} / {:.1} mm)",
        2e3 * radius,
        4e3 * radius
    ));
    rows[1] += &near
        .iter()
        .map(|w| format!(" | {:.0} / {:.0} %", 100.0 * w[0], 100.0 * w[1]))
        .collect::<String>();
    for (&omega, &n) in omegas.iter().zip(&sizes) {
        let mut opts = GatherOptions::default();
        opts.cut.max_solid_angle = omega;
        opts.microbuffer = n;
        opts.cut.light_offset = light_offset;
        let cells = |e: Vec<Vec3>| -> String {
            e.iter()
                .zip(&truth)
                .map(|(&e, &t)| format!(" | {:.5} ({:+.0} %)", mean(e), 100.0 * (mean(e) / t - 1.0)))
                .collect()
        };
        let gather = Gather::new(&tree, &opts)?;
        rows.push(format!(
            "Ω {omega}, N {n}{}",
            cells(gather.irradiance(&receivers)?)
        ));
        // With the renderer's near field (not with `--lit`: its rays' hits
        // would keep every light).
        if lit.is_none() {
            let rays = NearRays {
                scene: &scene,
                tracer: &tracer,
                lights: &lights,
                light_samples: 16,
                seed: 1,
            };
            let e = gather.with_near_field(&rays).irradiance(&receivers)?;
            rows.push(format!("Ω {omega}, N {n}, near field by rays{}", cells(e)));
        }
    }
    let head: String = receivers.iter().map(|(p, n)| format!(" | {p} n {n}")).collect();
    println!("| irradiance{head} |\n|---{} |", " | ---".repeat(receivers.len()));
    for r in rows {
        println!("| {r} |");
    }
    Ok(())
}
