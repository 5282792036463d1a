//! Criterion benchmarks of the four traversal schemes on one thread.
//!
//! ```text
//! cargo bench --bench traversal                        # 1e4 and 1e5 surfels, best ISA
//! PBGI_ISA=portable cargo bench --bench traversal      # force an instruction-set path
//! PBGI_BENCH_LARGE=1 cargo bench --bench traversal     # also 1e6 surfels (slow to set up)
//! cargo bench --bench traversal -- box-10000/coherent  # filter as usual
//! ```
//!
//! Each group is one (cloud, receiver set); its members are the schemes, named
//! `scheme/isa`, so a report compares schemes side by side. Throughput counts
//! receivers. Every run calls [`Traversal::run`] directly with a
//! [`SplatCounter`] sink (no rayon), so this measures the kernels alone.
//!
//! For a table with speedups, node counts and lane utilization across every
//! ISA, see `cargo run --release --example cut_bench`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use pbgi::{CutOptions, Isa, Receiver, Scheme, SplatCounter, Traversal, Tree, synthetic};

/// Packets of 16 receivers per measured run.
const TILES: usize = 32;
/// Seeds of the cloud and of the receivers (the same as `cut_bench`).
const CLOUD_SEED: u64 = 1;
const RECEIVER_SEED: u64 = 7;

fn sizes() -> Vec<usize> {
    let mut sizes = vec![10_000, 100_000];
    if std::env::var("PBGI_BENCH_LARGE").is_ok_and(|v| v == "1") {
        sizes.push(1_000_000);
    }
    sizes
}

fn isa() -> Isa {
    match Isa::from_env() {
        Ok(isa) => isa.unwrap_or_else(Isa::best),
        Err(e) => panic!("PBGI_ISA: {e}"),
    }
}

fn traversal(c: &mut Criterion) {
    let isa = isa();
    let available: Vec<&str> = Isa::available().into_iter().map(Isa::name).collect();
    println!(
        "pbgi traversal bench: isa {isa} (available: {}; set PBGI_ISA to choose), one thread, \
         {} receivers per run",
        available.join(", "),
        TILES * 16
    );
    for n in sizes() {
        let cloud = synthetic::box_with_blocks(n, CLOUD_SEED);
        let tree = Tree::build(&cloud);
        let options = CutOptions {
            isa: Some(isa),
            ..CutOptions::default()
        };
        let trav = Traversal::new(&tree, options).expect("valid options");
        for (set, jitter) in [("coherent", 0.0), ("incoherent", 1.0)] {
            let receivers: Vec<Receiver> = synthetic::receivers(TILES, 0.01, jitter, RECEIVER_SEED);
            let stats = trav.run(Scheme::Scalar, &receivers, &mut SplatCounter::default());
            println!(
                "box-{n} ({} surfels, {} nodes) {set}: {:.0} nodes tested per receiver, max_solid_angle {}",
                cloud.len(),
                tree.len(),
                stats.nodes_per_receiver(),
                trav.max_solid_angle()
            );

            let mut group = c.benchmark_group(format!("box-{n}/{set}"));
            group
                .throughput(Throughput::Elements(receivers.len() as u64))
                .sample_size(10)
                .warm_up_time(Duration::from_millis(500))
                .measurement_time(Duration::from_secs(if n >= 1_000_000 { 4 } else { 2 }));
            for scheme in Scheme::ALL {
                group.bench_with_input(
                    BenchmarkId::new(scheme.name(), isa.name()),
                    &receivers,
                    |b, receivers| {
                        b.iter(|| {
                            let mut sink = SplatCounter::default();
                            let stats = trav.run(scheme, black_box(receivers), &mut sink);
                            black_box((sink.splats, stats.node_tests))
                        })
                    },
                );
            }
            group.finish();
        }
    }
}

criterion_group!(benches, traversal);
criterion_main!(benches);
