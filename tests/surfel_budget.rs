//! The surfel budget: about N surfels whatever the scene's units (a model in
//! millimetres gets as many as in metres); `--density` overrides it, giving
//! both is an error, and the summary line says which was used.

use std::path::PathBuf;

use crate::common;

use pbgi::render::{RenderError, RenderOptions, render};
use pbgi::scene::builtin::cornell_box;
use pbgi::scene::{Light, Scene};

/// The scene scaled by `k` about the origin: geometry, camera and lights.
fn scaled(mut s: Scene, k: f32) -> Scene {
    for m in &mut s.meshes {
        m.positions.iter_mut().for_each(|p| *p *= k);
    }
    s.camera.origin *= k;
    s.camera.target *= k;
    for l in &mut s.lights {
        if let Light::Point { position, .. } = l {
            *position *= k;
        }
    }
    s
}

/// Surfels the render made for `scene` (a 4×4 image: the bake is what counts).
fn surfels(scene: &Scene, opts: &RenderOptions) -> usize {
    let mut s = scene.clone();
    s.camera.width = 4;
    s.camera.height = 4;
    render(&s, &RenderOptions { spp: 1, ..*opts }, &|_, _| {})
        .unwrap()
        .surfels
}

#[test]
fn the_budget_holds_in_any_units() {
    let budget = 8000;
    let opts = RenderOptions {
        surfel_budget: Some(budget),
        ..RenderOptions::default()
    };
    let metres = cornell_box();
    for k in [1.0, 1000.0, 0.001] {
        let n = surfels(&scaled(metres.clone(), k), &opts);
        let off = n as f64 / budget as f64 - 1.0;
        assert!(
            off.abs() < 0.03,
            "scale {k}: {n} surfels for a budget of {budget}"
        );
    }
    // A density is per unit area: millimetres multiply it by 10⁶ (capped
    // by the surfel limit, an error), metres keep it.
    let density = RenderOptions {
        density: 300.0,
        ..RenderOptions::default()
    };
    let n = surfels(&metres, &density);
    assert!(
        (n as f64 / (300.0 * metres.surface_area()) - 1.0).abs() < 0.05,
        "{n}"
    );
    let mm = scaled(metres, 1000.0);
    let mut tiny = mm.clone();
    tiny.camera.width = 4;
    tiny.camera.height = 4;
    match render(&tiny, &density, &|_, _| {}) {
        Err(RenderError::Kernel(pbgi::Error::TooManySurfels { count, max })) => {
            assert!(
                count > max && max == pbgi::PointCloud::MAX_SURFELS,
                "{count} > {max}"
            )
        }
        other => panic!("8·10⁹ surfels: {:?}", other.map(|_| "an image")),
    }
    let zero = RenderOptions {
        surfel_budget: Some(0),
        ..RenderOptions::default()
    };
    let e = render(&tiny, &zero, &|_, _| {}).unwrap_err().to_string();
    assert!(e.contains("surfels"), "{e}");
}

#[test]
fn the_cli_uses_a_budget_for_files_and_says_so() {
    let dir =
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("pbgi-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A quad 2 km on a side, in millimetres: a density would ask for 10¹³ surfels.
    let quad = "OFF\n4 2 0\n-1e6 0 -1e6\n1e6 0 -1e6\n1e6 0 1e6\n-1e6 0 1e6\n3 0 2 1\n3 0 3 2\n";
    let file = dir.join("quad.off");
    std::fs::write(&file, quad).unwrap();
    let out: PathBuf = dir.join("quad.png");
    let run = |extra: &[&str]| {
        let o = common::pbgi_command()
            .args(["render", "--spp", "1", "-o"])
            .arg(&out)
            .arg(&file)
            .args(extra)
            .output()
            .unwrap();
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr),
        )
    };
    let (ok, text) = run(&["--surfels", "3000"]);
    assert!(ok, "{text}");
    let line = text
        .lines()
        .find(|l| l.contains(" surfels ("))
        .unwrap_or_else(|| panic!("{text}"));
    let n: f64 = line.split_whitespace().next().unwrap().parse().unwrap();
    assert!(
        line.contains("(budget 3000)") && (n / 3000.0 - 1.0).abs() < 0.03,
        "{line}"
    );
    let (ok, text) = run(&["--density", "1e-9"]);
    assert!(ok && text.contains(" surfels (density 0.000000001)"), "{text}");
    let (ok, text) = run(&["--density", "1", "--surfels", "10"]);
    assert!(!ok && text.contains("cannot be used with"), "{text}");
}

#[test]
fn a_file_gets_the_default_budget() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("pbgi-budget-default-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("small.off");
    // Tiny: 1 mm on a side in metres, 10⁻⁶ m²: density 2000 would make 2 surfels.
    std::fs::write(&file, "OFF\n3 1 0\n0 0 0\n0.001 0 0\n0 0.001 0\n3 0 1 2\n").unwrap();
    let o = common::pbgi_command()
        .args(["render", "--spp", "1", "-o"])
        .arg(dir.join("small.png"))
        .arg(&file)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    let want = format!(" surfels (budget {})", pbgi::render::DEFAULT_SURFEL_BUDGET);
    assert!(text.contains(&want), "{text}");
}

/// `scene` with every triangle of its non-emitting meshes cut into `k²`
/// (a `k`×`k` lattice of sub-triangles): the same surfaces in far more
/// triangles.
fn subdivided(mut scene: Scene, k: u32) -> Scene {
    for m in scene.meshes.iter_mut().filter(|m| m.emission.is_none()) {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            // Lattice points (i, j), i + j ≤ k; `rows[i]` indexes (i, 0).
            let mut rows = Vec::new();
            for i in 0..=k {
                rows.push(positions.len() as u32);
                for j in 0..=k - i {
                    positions.push(a + (b - a) * (i as f32 / k as f32) + (c - a) * (j as f32 / k as f32));
                }
            }
            for i in 0..k as usize {
                for j in 0..k - i as u32 {
                    let (p, q, r) = (rows[i] + j, rows[i + 1] + j, rows[i] + j + 1);
                    triangles.push([p, q, r]);
                    if j + 1 < k - i as u32 {
                        triangles.push([q, rows[i + 1] + j + 1, r]);
                    }
                }
            }
        }
        m.positions = positions;
        m.triangles = triangles;
        m.normals = None;
    }
    scene
}

/// The indirect light of `scene` at 48×48 (the gather reads the surfels).
fn indirect(scene: &Scene, budget: u32, seed: u64) -> (usize, Vec<glam::Vec3>) {
    let mut s = scene.clone();
    (s.camera.width, s.camera.height) = (48, 48);
    let opts = RenderOptions {
        surfel_budget: Some(budget),
        spp: 4,
        seed,
        component: pbgi::render::Component::Indirect,
        ..RenderOptions::default()
    };
    let out = render(&s, &opts, &|_, _| {}).unwrap();
    (out.surfels, out.image.pixels)
}

#[test]
fn the_budget_holds_however_finely_surfaces_are_cut() {
    let coarse = cornell_box();
    let fine = subdivided(coarse.clone(), 40);
    let triangles = |s: &Scene| s.meshes.iter().map(|m| m.triangles.len()).sum::<usize>();
    let budget = 3000;
    assert!(triangles(&fine) > 15 * budget as usize && triangles(&coarse) < budget as usize / 50);
    let (n_fine, fine_image) = indirect(&fine, budget, 1);
    let (n_coarse, coarse_image) = indirect(&coarse, budget, 1);
    for (what, n) in [("fine", n_fine), ("coarse", n_coarse)] {
        assert!(
            (n as f64 / budget as f64 - 1.0).abs() < 0.03,
            "{what}: {n} surfels for a budget of {budget} ({} triangles)",
            triangles(if what == "fine" { &fine } else { &coarse })
        );
    }
    // Equal surfel counts, equal light: the fine mesh's indirect light
    // differs from the coarse one's as little as two seeds of the coarse
    // one differ (2.6 % RMS at 48×48, 4 spp), and its mean over four seeds
    // by under 1 %. One seed's mean is not enough: the fine mesh's moves by
    // up to 1.1 % from seed to seed (the coarse one's by 0.5 %), and over
    // six seeds the fine mesh is 0.7–0.8 % darker, keeping or dropping the
    // surfels inside solids: a small dependence on the mesh, not yet found.
    let (_, other_seed) = indirect(&coarse, budget, 2);
    let mean = |p: &[glam::Vec3]| p.iter().map(|c| c.element_sum() as f64).sum::<f64>() / p.len() as f64;
    let seeds = |s: &Scene, first: &[glam::Vec3], second: &[glam::Vec3]| {
        let more: f64 = (3..=4).map(|seed| mean(&indirect(s, budget, seed).1)).sum();
        (mean(first) + mean(second) + more) / 4.0
    };
    let rms = |a: &[glam::Vec3], b: &[glam::Vec3]| {
        let d2 = a
            .iter()
            .zip(b)
            .map(|(x, y)| (*x - *y).length_squared() as f64)
            .sum::<f64>();
        let n2 = b.iter().map(|y| y.length_squared() as f64).sum::<f64>();
        (d2 / n2).sqrt()
    };
    let (_, fine_second) = indirect(&fine, budget, 2);
    let bias = seeds(&fine, &fine_image, &fine_second) / seeds(&coarse, &coarse_image, &other_seed) - 1.0;
    let (spread, noise) = (rms(&fine_image, &coarse_image), rms(&other_seed, &coarse_image));
    eprintln!(
        "bias {bias:+.4}, rms {spread:.4}, seeds {:+.4} rms {noise:.4}",
        mean(&other_seed) / mean(&coarse_image) - 1.0
    );
    assert!(
        bias.abs() < 0.01 && spread < 1.5 * noise,
        "bias {bias:+.4}, RMS {spread:.4} (seed to seed {noise:.4})"
    );
}

/// A slab with two equal boxes stacked on it: the slab's top under the
/// boxes and both faces where the boxes meet lie inside a solid, and the
/// scene's surface area (12.96) is 1.44 more than its area in the open.
fn stacked_boxes() -> Scene {
    // Faces outward, counter-clockwise seen from outside.
    let cuboid = |lo: glam::Vec3, hi: glam::Vec3| {
        let mut m = pbgi::scene::Mesh::default();
        let (c, h) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let n = glam::Vec3::AXES[axis] * sign;
                let (u, v) = (glam::Vec3::AXES[(axis + 1) % 3], glam::Vec3::AXES[(axis + 2) % 3]);
                let base = m.positions.len() as u32;
                for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    m.positions.push(c + (n + u * a + v * b) * h);
                }
                let [i, j] = if sign > 0.0 { [1, 2] } else { [2, 1] };
                let [k, l] = if sign > 0.0 { [2, 3] } else { [3, 2] };
                m.triangles
                    .extend([[base, base + i, base + j], [base, base + k, base + l]]);
            }
        }
        m
    };
    let mut s = cornell_box();
    let v = glam::Vec3::new;
    s.meshes = vec![
        cuboid(v(-1.0, -0.2, -1.0), v(1.0, 0.0, 1.0)),
        cuboid(v(-0.3, 0.0, -0.3), v(0.3, 0.4, 0.3)),
        cuboid(v(-0.3, 0.4, -0.3), v(0.3, 0.8, 0.3)),
    ];
    s.lights = vec![Light::Directional {
        direction: v(-0.3, -1.0, -0.2).normalize(),
        irradiance: glam::Vec3::splat(3.0),
    }];
    s.validate().unwrap();
    s
}

/// With `drop_buried`, no surfel lies inside a solid: none on the slab
/// under the boxes, none where the boxes meet (where the upper box's bottom is tested, rays
/// through the lower box leave it where its bottom lies on the slab's top,
/// a front and a back face at one distance). Their share goes to the
/// surfaces in the open, so the density's count over the whole scene, and
/// a budget, still hold.
#[test]
fn no_surfel_lies_inside_a_solid_and_the_budget_holds() {
    use pbgi::render::{BakeOptions, Lights, Tracer, bake};
    let s = stacked_boxes();
    let (tracer, lights) = (Tracer::new(&s), Lights::new(&s));
    let density = 2000.0;
    let meets = |drop_buried| {
        let o = BakeOptions {
            density,
            drop_buried,
            ..Default::default()
        };
        let baked = bake(&s, &tracer, &lights, &o).unwrap();
        let mut meets = [0; 2];
        for p in baked.cloud.surfels().iter().map(|s| s.position) {
            let inside = p.x.abs() < 0.299 && p.z.abs() < 0.299;
            for (m, y) in meets.iter_mut().zip([0.0, 0.4]) {
                if inside && (p.y - y).abs() < 1e-4 {
                    *m += 1;
                }
            }
        }
        (meets, baked)
    };
    let (kept, _) = meets(false);
    assert!(kept.iter().all(|&m| m > 500), "kept: {kept:?}");
    let (meets, baked) = meets(true);
    assert_eq!(
        meets,
        [0, 0],
        "surfels on the slab under the boxes, and where the boxes meet"
    );
    let baked_surfels = baked.cloud.surfels();
    let (n, want) = (baked_surfels.len() as f64, density as f64 * 12.96);
    assert!((n / want - 1.0).abs() < 0.02, "{n} surfels, {want} expected");
    // Placed again at a density raised by 12.96/11.52, its sites on the
    // 1.44 inside were left out.
    let buried = baked.buried as f64 / (want / 11.52 * 1.44);
    assert!((buried - 1.0).abs() < 0.05, "{} buried", baked.buried);
    let budget = 3000;
    let opts = RenderOptions {
        surfel_budget: Some(budget),
        drop_buried: true,
        ..RenderOptions::default()
    };
    let n = surfels(&s, &opts);
    assert!(
        (n as f64 / budget as f64 - 1.0).abs() < 0.03,
        "{n} surfels for a budget of {budget}"
    );
}
