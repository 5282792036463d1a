#![feature(portable_simd)]
use pbgi::*;
use std::time::Instant;
fn main() {
    let n: usize = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(100_000);
    let cloud = synthetic::box_with_blocks(n, 1);
    let t0 = Instant::now();
    let tree = Tree::build(&cloud);
    println!("surfels {} nodes {} depth {} build {:?}", cloud.len(), tree.len(), tree.depth(), t0.elapsed());
    for jitter in [0.0, 1.0] {
        let recs = synthetic::receivers(256, 0.01, jitter, 7);
        let trav = Traversal::new(&tree, CutOptions::default()).unwrap();
        let reference = trav.cuts(Scheme::Scalar, &recs);
        for s in Scheme::ALL {
            let mut sink = SplatCounter::default();
            let t0 = Instant::now();
            let st = trav.run(s, &recs, &mut sink);
            let dt = t0.elapsed();
            let same = trav.cuts(s, &recs) == reference;
            println!("jitter {jitter} {s:7} {:?} {:?} npr {:.1} util {:?} splats {} same {same}", trav.isa(), dt, st.nodes_per_receiver(), st.lane_utilization(), sink.splats);
        }
    }
}
