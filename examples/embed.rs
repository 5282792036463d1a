//! Embedding pbgi: bring your own surfels, build the tree, cut it for some
//! receivers and consume the cuts with your own sink.
//!
//! `cargo run --release --example embed`
//!
//! The scene: a 0.5 × 0.5 glowing quad light 1 unit above a dark 2 × 2 floor.
//! For a row of receivers on the floor we estimate the irradiance crudely by
//! summing, over the splatted nodes, radiance × projected solid angle
//! (`area · cos_r · cos_e / d²`), with no visibility.

use glam::Vec3;
use pbgi::{CutOptions, CutSink, NodeId, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};

/// Surfels on an `m × m` grid over the square of side `size` centred at `center` in
/// the y = `center.y` plane, facing `normal`, one disk per cell.
fn grid(center: Vec3, size: f32, m: usize, normal: Vec3, radiance: Vec3) -> Vec<Surfel> {
    let cell = size / m as f32;
    let radius = cell / std::f32::consts::PI.sqrt(); // disk of the cell's area
    (0..m * m)
        .map(|i| {
            let (u, v) = ((i % m) as f32 + 0.5, (i / m) as f32 + 0.5);
            let position = center + Vec3::new(u * cell - size / 2.0, 0.0, v * cell - size / 2.0);
            Surfel {
                position,
                normal,
                radius,
                radiance,
            }
        })
        .collect()
}

/// A custom sink: accumulates radiance × projected solid angle of every splatted node.
struct Irradiance<'a> {
    tree: &'a Tree,
    receivers: &'a [Receiver],
    sum: Vec<Vec3>,
}

impl CutSink for Irradiance<'_> {
    // We do not need the culled nodes; leaving DISCARDS false lets the kernels skip them.

    fn splat(&mut self, receiver: usize, node: NodeId) {
        let r = &self.receivers[receiver];
        let k = self.tree.node(node); // area, area-weighted normal and radiance, bounding sphere
        let v = k.center - r.position();
        let d2 = v.length_squared().max(1e-8);
        let dir = v / d2.sqrt();
        let cos_r = r.normal().dot(dir).max(0.0); // at the receiver
        let cos_e = k.normal.dot(-dir).max(0.0); // at the emitter (k.normal is not unit: |n| ≤ 1)
        self.sum[receiver] += k.radiance * (k.area * cos_r * cos_e / d2);
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // 1. Surfels: the light (facing down) and the floor (facing up, faintly lit).
    let mut surfels = grid(Vec3::new(0.0, 1.0, 0.0), 0.5, 32, -Vec3::Y, Vec3::splat(10.0));
    surfels.extend(grid(Vec3::ZERO, 2.0, 128, Vec3::Y, Vec3::splat(0.05)));

    // 2. A PointCloud validates every surfel and names the first bad one.
    let mut bad = surfels.clone();
    bad[3].normal = Vec3::new(0.0, 2.0, 0.0); // not unit length: rejected, never renormalized
    match PointCloud::new(bad) {
        Ok(_) => unreachable!("a non-unit normal is rejected"),
        Err(e) => println!("rejected as expected: {e}"),
    }
    let cloud = PointCloud::new(surfels)?; // real code: propagate with `?`

    // 3. The hierarchy (built in parallel with rayon).
    let tree = Tree::build(&cloud);
    println!(
        "{} surfels, {} nodes, depth {}",
        cloud.len(),
        tree.len(),
        tree.depth()
    );

    // 4. The traversal: Ω, the hybrid switch, and the ISA (None = PBGI_ISA or the best).
    let options = CutOptions {
        max_solid_angle: 0.01,
        light_offset: 0.0,
        hybrid_threshold: 4,
        isa: None,
    };
    let traversal = Traversal::new(&tree, options)?;
    println!("kernels run on {}", traversal.isa());

    // 5. Receivers on the floor, facing up, in a row from under the light outwards.
    //    Packet and hybrid take them 16 at a time, so keep neighbours together.
    let receivers = Receiver::from_pairs((0..16).map(|i| (Vec3::new(i as f32 * 0.06, 1e-3, 0.0), Vec3::Y)))?;

    // 6a. Cuts as data (sorted node lists), computed in parallel.
    let cuts = traversal.cuts(Scheme::Hybrid, &receivers);
    for cut in &cuts {
        cut.check(&tree)?; // splats and discards partition the leaves
    }
    assert_eq!(cuts, traversal.cuts(Scheme::Scalar, &receivers)); // every scheme: same cut

    // 6b. Or stream the cut into your own sink on this thread.
    let mut sink = Irradiance {
        tree: &tree,
        receivers: &receivers,
        sum: vec![Vec3::ZERO; receivers.len()],
    };
    let stats = traversal.run(Scheme::Hybrid, &receivers, &mut sink);
    println!(
        "{:.0} nodes tested per receiver, lane utilization {:.0}%",
        stats.nodes_per_receiver(),
        100.0 * stats.lane_utilization().unwrap_or(0.0)
    );

    println!("{:>6} {:>7} {:>8}", "x", "splats", "E (red)");
    for ((r, cut), e) in receivers.iter().zip(&cuts).zip(&sink.sum) {
        println!("{:>6.2} {:>7} {:>8.3}", r.position().x, cut.splats.len(), e.x);
    }
    Ok(())
}
