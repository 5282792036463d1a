//! How much of the hemisphere a receiver's cut covers, splat by splat:
//! the open part a uniform sky shines through is `1 − Σ coverage`, so a
//! window's sky is a small difference of large sums, and an error of 0.5 %
//! of the hemisphere anywhere in the room takes a third of it.
//!
//! ```text
//! cargo run --release --no-default-features --features lab --example sky_coverage -- \
//!     [--scene window] [--k 4] [--omega 0.15] [--n 12,14,24,48] [--receiver 1] [--rows 8]
//! ```
//!
//! One mid-wall receiver of [`pbgi::exact::opening`]'s scene (`--receiver`
//! indexes them), the room black and the sky 1, surfels on a grid (`--k`
//! per cell side): the exact sky, the gathered one at each N, and each
//! splat of the cut drawn alone into the microbuffer — the coverage it
//! adds (`(π − E)/π`) against its first-order projected solid angle
//! `A·max(0, −n̄·ω)·(n·ω)/(π d²)` (planar clusters; leaves and mixed
//! clusters print NaN), as ratios per N; and per kind (leaf, planar,
//! mixed) the coverage drawn against its cells' exact `∫ cosθ dω / π`
//! (Lambert's formula over each leaf's square); the splats whose coverage
//! at the last N is furthest from their cells' first.

use std::sync::Arc;

use glam::{DVec3, Vec3};
use pbgi::environment::Environment;
use pbgi::exact::{ExactScene, opening};
use pbgi::microbuffer::MicroBuffer;
use pbgi::{CutOptions, CutRecorder, NodeId, Receiver, Scheme, Traversal};

/// `∫ cosθ dω / π` over the square a grid leaf stands for (side `√(π r²)`,
/// its edges along the two axes across its axis-aligned normal), clipped to
/// the receiver's horizon: Lambert's polygon formula.
fn leaf_exact(s: &pbgi::Surfel, x: DVec3, n: DVec3) -> f64 {
    let c = s.position.as_dvec3();
    let m = s.normal.as_dvec3();
    let h = 0.5 * (std::f64::consts::PI * (s.radius as f64).powi(2)).sqrt();
    let (e1, e2) = if m.x.abs() > 0.5 {
        (DVec3::Y, DVec3::Z)
    } else if m.y.abs() > 0.5 {
        (DVec3::Z, DVec3::X)
    } else {
        (DVec3::X, DVec3::Y)
    };
    let square = [
        c - h * e1 - h * e2,
        c + h * e1 - h * e2,
        c + h * e1 + h * e2,
        c - h * e1 + h * e2,
    ];
    // Clip to the half-space in front of the receiver's tangent plane.
    let mut poly: Vec<DVec3> = Vec::new();
    for i in 0..4 {
        let (a, b) = (square[i] - x, square[(i + 1) % 4] - x);
        let (da, db) = (a.dot(n), b.dot(n));
        if da > 0.0 {
            poly.push(a);
        }
        if (da > 0.0) != (db > 0.0) {
            poly.push(a + (b - a) * (da / (da - db)));
        }
    }
    if poly.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..poly.len() {
        let (a, b) = (poly[i].normalize(), poly[(i + 1) % poly.len()].normalize());
        let g = a.cross(b);
        let len = g.length();
        if len > 0.0 {
            sum += a.dot(b).clamp(-1.0, 1.0).acos() * n.dot(g / len);
        }
    }
    (0.5 * sum).abs() / std::f64::consts::PI
}

fn leaves(tree: &pbgi::Tree, node: NodeId, out: &mut Vec<NodeId>) {
    match tree.left_child(node) {
        None => out.push(node),
        Some(l) => {
            leaves(tree, l, out);
            leaves(tree, l + 1, out);
        }
    }
}

const USAGE: &str =
    "usage: sky_coverage [--scene window] [--k 4] [--omega 0.15] [--n 12,14,24,48] [--receiver 1] [--rows 8]";

fn main() -> Result<(), String> {
    let (mut name, mut k, mut omega, mut ns, mut which, mut rows) = (
        "window".to_string(),
        4usize,
        0.15f32,
        vec![12usize, 14, 24, 48],
        1usize,
        8usize,
    );
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value\n{USAGE}"));
        let bad = |e: &dyn std::fmt::Display| format!("{a}: {e}\n{USAGE}");
        match a.as_str() {
            "--scene" => name = value()?,
            "--k" => k = value()?.parse().map_err(|e| bad(&e))?,
            "--omega" => omega = value()?.parse().map_err(|e| bad(&e))?,
            "--n" => {
                ns = value()?
                    .split(',')
                    .map(|x| x.parse().map_err(|e| bad(&e)))
                    .collect::<Result<_, _>>()?
            }
            "--receiver" => which = value()?.parse().map_err(|e| bad(&e))?,
            "--rows" => rows = value()?.parse().map_err(|e| bad(&e))?,
            _ => return Err(format!("unknown argument {a}\n{USAGE}")),
        }
    }
    let spec = opening(&name).ok_or(format!("no scene {name} (window, sunroom, shell, thin-shell)"))?;
    let mut scene = ExactScene::room(&spec).dark_inside();
    scene.sky = 1.0;
    let surfels = scene.surfels(k, None);
    let tree = scene.tree(k, None).map_err(|e| e.to_string())?;
    let sky = Some(Arc::new(
        Environment::uniform(Vec3::ONE).map_err(|e| e.to_string())?,
    ));
    let cut_options = CutOptions {
        max_solid_angle: omega,
        ..Default::default()
    };
    let t = Traversal::new(&tree, cut_options).map_err(|e| e.to_string())?;
    let probes: Vec<_> = scene
        .probes(2e-5)
        .into_iter()
        .filter(|p| p.class == "mid")
        .collect();
    let p = probes
        .get(which)
        .ok_or(format!("--receiver {which}: {} mid receivers", probes.len()))?;
    let pi = std::f64::consts::PI;
    let exact = scene.exact(p.position, p.normal).0;
    let receivers = Receiver::from_pairs([(p.position, p.normal)]).map_err(|e| e.to_string())?;
    let mut recorder = CutRecorder::new(1);
    t.run(Scheme::Scalar, &receivers, &mut recorder);
    let cut = recorder.into_cuts().remove(0);
    println!(
        "{name}, grid k {k}, Ω {omega}: receiver on the {} at {:?}, {} splats; exact sky {exact:.5} (open {:.5} of the hemisphere)",
        p.face,
        p.position,
        cut.splats.len(),
        exact / pi
    );
    let mut buffers: Vec<MicroBuffer> = ns
        .iter()
        .map(|&n| MicroBuffer::new(n).map(|b| b.with_environment(sky.clone())))
        .collect::<Result<_, _>>()
        .map_err(|e| e.to_string())?;
    let sky_of = |b: &mut MicroBuffer, nodes: &[NodeId]| {
        b.reset(p.position, p.normal);
        for &n in nodes {
            b.splat(&tree, n);
        }
        b.irradiance(&tree).x as f64
    };
    for (b, n) in buffers.iter_mut().zip(&ns) {
        let e = sky_of(b, &cut.splats);
        println!(
            "N {n:>3}: sky {e:.5} ({:+.1} %), coverage over by {:+.5} of the hemisphere",
            100.0 * (e / exact - 1.0),
            (exact - e) / pi
        );
    }
    let mut total = vec![0.0f64; ns.len()];
    let (x, nx) = (p.position.as_dvec3(), p.normal.as_dvec3());
    let mut by_kind = std::collections::BTreeMap::<&str, (f64, Vec<f64>)>::new();
    let mut table = Vec::new();
    for &node in &cut.splats {
        let alone: Vec<f64> = buffers
            .iter_mut()
            .map(|b| (pi - sky_of(b, &[node])) / pi)
            .collect();
        for (t, c) in total.iter_mut().zip(&alone) {
            *t += c;
        }
        let v = tree.node(node);
        let to = v.centroid - p.position;
        let d = to.length();
        let w = to / d;
        let planar = !tree.is_leaf(node) && v.normal.length() >= 0.99;
        let first_order = if planar {
            (v.area * (-v.normal.normalize().dot(w)).max(0.0) * p.normal.dot(w).max(0.0) / (d * d)) as f64
                / pi
        } else {
            f64::NAN
        };
        let ratios: Vec<String> = alone.iter().map(|c| format!("{:.3}", c / first_order)).collect();
        let mut below = Vec::new();
        leaves(&tree, node, &mut below);
        let exact_node: f64 = below
            .iter()
            .filter_map(|&l| tree.node(l).surfel)
            .map(|i| leaf_exact(&surfels[i as usize], x, nx))
            .sum();
        let kind = if tree.is_leaf(node) {
            "leaf"
        } else if planar {
            "plane"
        } else {
            "mixed"
        };
        let e = by_kind.entry(kind).or_insert((0.0, vec![0.0; ns.len()]));
        e.0 += exact_node;
        for (t, c) in e.1.iter_mut().zip(&alone) {
            *t += c;
        }
        let last = alone.last().copied().unwrap_or(0.0);
        let dir = v.centroid - p.position;
        let elevation = (p.normal.dot(dir) / dir.length()).asin().to_degrees();
        table.push((
            (last - exact_node).abs(),
            format!(
                "node {node:>6} {kind:<5} R {:.3} d {d:.2} at {elevation:.0}°: its cells {exact_node:.5}, first order {first_order:.5}, alone / first order by N: {}",
                v.radius,
                ratios.join(" ")
            ),
        ));
    }
    let sums: Vec<String> = total.iter().map(|t| format!("{t:.5}")).collect();
    println!(
        "splats alone, summed, by N: {} (what the walls cover: {:.5})",
        sums.join(" "),
        1.0 - exact / pi
    );
    for (kind, (exact_sum, drawn)) in &by_kind {
        let d: Vec<String> = drawn.iter().map(|t| format!("{:+.5}", t - exact_sum)).collect();
        println!(
            "{kind:>5}: its cells cover {exact_sum:.5}; drawn alone minus that, by N: {}",
            d.join(" ")
        );
    }
    table.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, row) in table.iter().take(rows) {
        println!("  {row}");
    }
    Ok(())
}
