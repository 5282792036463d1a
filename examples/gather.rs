//! The gather API on a baking workload: irradiance at every surfel of a box
//! with blocks (receivers a hair above their surfels), timed against a
//! hand-written loop over the kernels (traversal, packet cut, 16-lane
//! shading: what the renderer ran before it used the API), and in three
//! receiver orders: the tree's (coherent), shuffled as a file might give
//! them (taken as coherent: packets of strangers), and shuffled but
//! declared unordered (the API sorts them in Morton order).
//!
//! ```text
//! cargo run --release --example gather [SURFELS]
//! ```
//! Best of 5 runs each, on all of rayon's threads; the ratios come from one run.

use std::time::Instant;

use glam::Vec3;
use pbgi::gather::{Gather, GatherOptions, ReceiverOrder};
use pbgi::microbuffer::{Convolution, MicroBuffer, PacketCut, shade_packet};
use pbgi::rng::Rng;
use pbgi::synthetic::box_with_blocks;
use pbgi::{CutOptions, LANES, Receiver, Scheme, Traversal, Tree};
use rayon::prelude::*;

fn best_of<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..runs {
        let t = Instant::now();
        let v = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(v);
    }
    (best, out.expect("at least one run"))
}

/// The loop an embedder wrote before the API: packets of 16 as given.
fn hand_loop(tree: &Tree, receivers: &[(Vec3, Vec3)]) -> Vec<Vec3> {
    let t = Traversal::new(tree, CutOptions::default()).expect("default options");
    let proto = MicroBuffer::new(24).expect("N 24");
    let receivers = Receiver::from_pairs(receivers.iter().copied()).expect("valid receivers");
    receivers
        .par_chunks(LANES)
        .map_init(
            || {
                (
                    PacketCut::new(tree),
                    vec![proto.clone(); LANES],
                    vec![Vec3::ZERO; LANES],
                )
            },
            |(cut, bufs, out), chunk| {
                cut.clear();
                t.run(Scheme::Packet, chunk, cut);
                let bufs = &mut bufs[..chunk.len()];
                for (b, r) in bufs.iter_mut().zip(chunk) {
                    b.reset(r.position(), r.normal());
                }
                shade_packet(t.isa(), bufs, tree, cut, Convolution::Irradiance, out).expect("one packet");
                out[..chunk.len()].to_vec()
            },
        )
        .flatten_iter()
        .collect()
}

/// The surfels of the tree's leaves, depth first: neighbours together.
fn leaves_in_order(tree: &Tree) -> Vec<u32> {
    let mut out = Vec::with_capacity(tree.len() / 2 + 1);
    let mut stack = vec![0];
    while let Some(k) = stack.pop() {
        let v = tree.node(k);
        match (v.children, v.surfel) {
            (Some(left), _) => stack.extend([left + 1, left]),
            (None, Some(s)) => out.push(s),
            (None, None) => {}
        }
    }
    out
}

fn main() -> Result<(), pbgi::Error> {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(60_000);
    let cloud = box_with_blocks(n, 1);
    let tree = Tree::build(&cloud);
    // Tree order: the surfels as the tree sorted them (neighbours together).
    let mut in_tree_order: Vec<(Vec3, Vec3)> = leaves_in_order(&tree)
        .iter()
        .map(|&i| {
            let s = &cloud.surfels()[i as usize];
            (s.position + s.normal * (s.radius * 1e-3), s.normal)
        })
        .collect();
    in_tree_order.truncate(20_000.min(in_tree_order.len()));
    let mut shuffled = in_tree_order.clone();
    let mut rng = Rng::new(3);
    for i in (1..shuffled.len()).rev() {
        shuffled.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    let coherent = Gather::new(
        &tree,
        &GatherOptions {
            order: ReceiverOrder::Coherent,
            ..Default::default()
        },
    )?;
    let unordered = Gather::new(&tree, &GatherOptions::default())?;
    println!(
        "{} surfels, {} receivers, {} thread(s); path: {}",
        cloud.len(),
        in_tree_order.len(),
        rayon::current_num_threads(),
        unordered.path()
    );
    let runs = 5;
    let (t_hand, hand) = best_of(runs, || hand_loop(&tree, &in_tree_order));
    let (t_api, api) = best_of(runs, || coherent.irradiance(&in_tree_order));
    let (t_file, _) = best_of(runs, || coherent.irradiance(&shuffled));
    let (t_morton, morton) = best_of(runs, || unordered.irradiance(&shuffled));
    let api = api?;
    let same = hand
        .iter()
        .zip(&api)
        .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits));
    let rate = |t: f64| in_tree_order.len() as f64 / t / 1e3;
    println!(
        "hand-written loop, tree order      {:8.1} k receivers/s",
        rate(t_hand)
    );
    println!(
        "Gather, tree order (coherent)      {:8.1} k receivers/s  ({:.3}× the hand loop's time; same bits: {same})",
        rate(t_api),
        t_api / t_hand
    );
    println!(
        "Gather, file order as coherent     {:8.1} k receivers/s  ({:.2}× tree order's time)",
        rate(t_file),
        t_file / t_api
    );
    println!(
        "Gather, file order, Morton-sorted  {:8.1} k receivers/s  ({:.2}× tree order's time)",
        rate(t_morton),
        t_morton / t_api
    );
    // The same receivers, the same results, whatever their order.
    let morton = morton?;
    let mut back = vec![Vec3::ZERO; shuffled.len()];
    let index: std::collections::HashMap<[u32; 6], usize> = in_tree_order
        .iter()
        .enumerate()
        .map(|(i, (p, n))| ([p.x, p.y, p.z, n.x, n.y, n.z].map(f32::to_bits), i))
        .collect();
    for ((p, n), e) in shuffled.iter().zip(&morton) {
        back[index[&[p.x, p.y, p.z, n.x, n.y, n.z].map(f32::to_bits)]] = *e;
    }
    let same_morton = back
        .iter()
        .zip(&api)
        .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits));
    println!("Morton-sorted results equal tree order's bit for bit: {same_morton}");
    Ok(())
}
