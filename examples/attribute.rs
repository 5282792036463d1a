//! Which nodes of a receiver's cut carry its error against the leaves: each
//! cluster of the cut is replaced by the leaves below it (the rest of the
//! cut kept) and the change in irradiance is its share. For the clusters
//! with the largest shares it also shows how much of their surface the
//! receiver really sees (rays to each leaf), and the radiance of what it
//! sees: a cluster shows the mean of all its surfels that face the
//! receiver, whether they are in view or not. And by irradiance: what the
//! cluster adds in the microbuffer (`shown`), what its leaves add to the
//! leaves' cut, what it would add with nothing in the way (`unoccluded`)
//! and what the rays find (`ray cast`), with the mesh that hides most of
//! its leaves.
//!
//! ```text
//! cargo run --release --example attribute -- SCENE "x,y,z[,nx,ny,nz]" [--omega 0.15] [--n 14] [--top 12] [--density 2000 | --budget 52000] [--keep-buried]
//! ```
//!
//! The normal defaults to +y; irradiance is the mean of the three channels.
//! docs/lab/BENCHMARKS.md, "The nave's indirect bias", used it on the nave's floor.

use std::collections::{HashMap, HashSet};

use glam::Vec3;
use pbgi::microbuffer::MicroBuffer;
use pbgi::render::{BakeOptions, Lights, Tracer, bake};
use pbgi::{CutOptions, CutRecorder, NodeId, PointCloud, Receiver, Scheme, Traversal, Tree};

const USAGE: &str = "usage: attribute SCENE \"x,y,z[,nx,ny,nz]\" [--omega 0.15] [--n 14] [--top 12] [--density 2000 | --budget 52000] [--keep-buried]";

fn mean(v: Vec3) -> f64 {
    f64::from(v.x + v.y + v.z) / 3.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut omega, mut n, mut top, mut density) = (0.15f32, 14usize, 12usize, 2000.0f32);
    let (mut budget, mut drop_buried) = (None, BakeOptions::default().drop_buried);
    let mut positional = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value\n{USAGE}"));
        match a.as_str() {
            "--omega" => omega = value()?.parse()?,
            "--n" => n = value()?.parse()?,
            "--top" => top = value()?.parse()?,
            "--density" => density = value()?.parse()?,
            "--budget" => budget = Some(value()?.parse()?),
            "--keep-buried" => drop_buried = false,
            _ => positional.push(a.clone()),
        }
    }
    let [scene, receiver] = &positional[..] else {
        return Err(USAGE.into());
    };
    let f = receiver
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<Vec<_>, _>>()?;
    let (p, normal) = match f[..] {
        [x, y, z] => (Vec3::new(x, y, z), Vec3::Y),
        [x, y, z, a, b, c] => (Vec3::new(x, y, z), Vec3::new(a, b, c).normalize()),
        _ => return Err(format!("receiver {receiver:?}: x,y,z or x,y,z,nx,ny,nz\n{USAGE}").into()),
    };

    let scene = pbgi::scene::catalogue::resolve(scene)?;
    let tracer = Tracer::new(&scene);
    let lights = Lights::new(&scene);
    if budget.is_some() {
        let by_budget = pbgi::render::RenderOptions {
            surfel_budget: budget,
            ..Default::default()
        };
        density = by_budget.surfel_density(&scene)?;
    }
    let opts = BakeOptions {
        density,
        drop_buried,
        ..Default::default()
    };
    let baked = bake(&scene, &tracer, &lights, &opts)?;
    let tree = Tree::build(&PointCloud::new(baked.cloud.surfels().to_vec())?);

    let cut = |max_solid_angle: f32| -> Result<Vec<NodeId>, pbgi::Error> {
        let opts = CutOptions {
            max_solid_angle,
            ..CutOptions::default()
        };
        let mut rec = CutRecorder::new(1);
        Traversal::new(&tree, opts)?.run(Scheme::Scalar, &[Receiver::new(p, normal)?], &mut rec);
        Ok(rec.into_cuts().swap_remove(0).splats)
    };
    let (coarse, leaves) = (cut(omega)?, cut(0.0)?);
    let mut mb = MicroBuffer::new(n)?;
    let mut irradiance = |nodes: &mut dyn Iterator<Item = NodeId>| {
        mb.reset(p, normal);
        for k in nodes {
            mb.splat(&tree, k);
        }
        mean(mb.irradiance(&tree))
    };
    let e = irradiance(&mut coarse.iter().copied());
    let e_leaves = irradiance(&mut leaves.iter().copied());
    println!(
        "Ω {omega}, N {n}: cut of {} nodes E {e:.5}; its {} leaves E {e_leaves:.5}; excess {:+.5} ({:+.1} %)",
        coarse.len(),
        leaves.len(),
        e - e_leaves,
        100.0 * (e / e_leaves - 1.0)
    );

    // The leaves of the leaves' cut below each node of the coarse one.
    let parents = tree.parents();
    let in_cut: HashSet<NodeId> = coarse.iter().copied().collect();
    let mut below: HashMap<NodeId, Vec<NodeId>> = HashMap::new();
    for &leaf in &leaves {
        let mut k = Some(leaf);
        while let Some(x) = k {
            if in_cut.contains(&x) {
                below.entry(x).or_default().push(leaf);
                break;
            }
            k = parents[x as usize];
        }
    }
    let mut shares: Vec<(f64, NodeId)> = coarse
        .iter()
        .enumerate()
        .filter(|&(_, &k)| !tree.is_leaf(k))
        .map(|(i, &k)| {
            let rest = coarse
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &x)| x);
            let refined = below.get(&k).into_iter().flatten().copied();
            (e - irradiance(&mut rest.chain(refined)), k)
        })
        .collect();
    shares.sort_by(|a, b| b.0.total_cmp(&a.0));
    let sum: f64 = shares.iter().map(|s| s.0).sum();
    println!("sum of the clusters' shares {sum:+.5}\n");
    println!(
        "| node | share | centre | R | distance | mean normal's length | radiance | not behind its own leaves | in view | radiance in view | shown | its leaves shown | unoccluded | ray cast | most hidden by |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let origin = p + normal * tracer.epsilon();
    for &(share, k) in shares.iter().take(top) {
        let mine: &[NodeId] = below.get(&k).map_or(&[], |b| &b[..]);
        // What the node adds to the irradiance in the microbuffer, and what
        // its leaves add to the leaves' cut.
        let rest: Vec<NodeId> = coarse.iter().copied().filter(|&x| x != k).collect();
        let shown = e - irradiance(&mut rest.iter().copied());
        let own: HashSet<NodeId> = mine.iter().copied().collect();
        let others: Vec<NodeId> = leaves.iter().copied().filter(|x| !own.contains(x)).collect();
        let leaves_shown = e_leaves - irradiance(&mut others.iter().copied());
        // Its leaves that face the receiver: by projected solid angle (`w`),
        // all of them, those no disk of the node's own leaves hides, those a
        // ray from the receiver reaches; by irradiance (`w·cos`, the mean
        // radiance), all of them and those a ray reaches; and what the rays
        // that do not reach them hit first.
        let disks: Vec<(Vec3, Vec3, f32, pbgi::NodeView)> = mine
            .iter()
            .map(|&l| {
                let v = tree.node(l);
                let n = v.normal.normalize_or_zero();
                (v.centroid, n, v.area / std::f32::consts::PI, v)
            })
            .collect();
        let (mut all, mut all_l, mut seen, mut seen_l, mut alone) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut unoccluded, mut cast) = (0.0, 0.0);
        let mut hiders: HashMap<&str, usize> = HashMap::new();
        for (j, (c, _, _, v)) in disks.iter().enumerate() {
            let to = *c - origin;
            let d = to.length();
            let u = to / d;
            let w = f64::from((-v.normal.dot(u)).max(0.0) * v.area / (d * d));
            if w == 0.0 {
                continue;
            }
            let l = mean(v.radiance);
            let e = w * f64::from(normal.dot(u).max(0.0)) * l;
            all += w;
            all_l += w * l;
            unoccluded += e;
            match tracer.closest(origin, u, d - 2.0 * tracer.epsilon()) {
                None => {
                    seen += w;
                    seen_l += w * l;
                    cast += e;
                }
                Some(h) => *hiders.entry(&scene.meshes[h.mesh as usize].name).or_default() += 1,
            }
            let hidden = disks.iter().enumerate().any(|(i, &(ci, ni, r2, _))| {
                let t = ni.dot(ci - origin) / ni.dot(u);
                i != j && t > 0.0 && t < d * (1.0 - 1e-4) && (origin + u * t).distance_squared(ci) < r2
            });
            if !hidden {
                alone += w;
            }
        }
        let most = hiders
            .iter()
            .max_by_key(|&(name, n)| (*n, std::cmp::Reverse(*name)))
            .map_or(String::from("—"), |(name, n)| format!("{name} ({n} leaves)"));
        let v = tree.node(k);
        println!(
            "| {k} | {share:+.5} | {:.2}, {:.2}, {:.2} | {:.3} | {:.2} | {:.2} | {:.4} | {:.0} % | {:.0} % | {:.4} | {shown:.5} | {leaves_shown:.5} | {unoccluded:.5} | {cast:.5} | {most} |",
            v.center.x,
            v.center.y,
            v.center.z,
            v.radius,
            v.center.distance(p),
            v.normal.length(),
            all_l / all,
            100.0 * alone / all,
            100.0 * seen / all,
            seen_l / seen
        );
    }
    Ok(())
}
