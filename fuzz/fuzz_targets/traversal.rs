//! Arbitrary surfels, receivers, Ω and light offset weight (structured: grids, ties, coincident
//! points, receivers on surfels, edge-case radii and thresholds, raw bits):
//! invalid input is a typed error; on valid input every scheme on every path
//! this CPU runs gives the scalar cut (with and without discard bookkeeping)
//! and tests the same (receiver, node) pairs, the cut invariants hold, the
//! tree is finite; nothing panics.
#![no_main]

mod shapes;

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use pbgi::{CutOptions, CutRecorder, Isa, NodeId, PointCloud, Receiver, Scheme, Traversal, Tree};
use shapes::{Dir, OMEGAS, Pos, Scalar, SurfelSpec};

#[derive(Arbitrary, Debug)]
struct Input {
    surfels: Vec<SurfelSpec>,
    receivers: Vec<(Pos, Dir)>,
    omega: Scalar,
    threshold: u8,
    /// The light offset's weight, `0, ¼, …, 8`.
    light_offset: u8,
}

/// Splats only: the kernels skip the discard bookkeeping for such a sink.
struct SplatsOnly(Vec<Vec<NodeId>>);

impl pbgi::CutSink for SplatsOnly {
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.0[receiver].push(node);
    }
}

fuzz_target!(|input: Input| {
    let surfels = shapes::surfels(&input.surfels, 2000);
    let Ok(cloud) = PointCloud::new(surfels) else {
        return;
    };
    let tree = Tree::build(&cloud);
    for k in 0..tree.len() as NodeId {
        let v = tree.node(k);
        assert!(
            v.center.is_finite() && v.radius.is_finite() && v.area.is_finite() && v.radiance.is_finite(),
            "node {k} is not finite: {v:?}"
        );
    }
    assert!(tree.depth() <= pbgi::tree::MAX_DEPTH);
    let pairs: Vec<_> = input
        .receivers
        .iter()
        .take(64)
        .map(|&(p, n)| {
            (
                shapes::position(p, cloud.surfels()),
                shapes::direction(n, cloud.surfels()),
            )
        })
        .collect();
    let Ok(receivers) = Receiver::from_pairs(pairs) else {
        return;
    };
    let omega = input.omega.value(&OMEGAS);
    let mut reference: Option<Vec<pbgi::Cut>> = None;
    let mut tests = None;
    for isa in Isa::available() {
        let opts = CutOptions {
            max_solid_angle: omega,
            light_offset: (input.light_offset % 33) as f32 / 4.0,
            hybrid_threshold: input.threshold as u32 % 18,
            isa: Some(isa),
        };
        let Ok(t) = Traversal::new(&tree, opts) else {
            return;
        };
        let scalar = t.cuts(Scheme::Scalar, &receivers);
        for c in &scalar {
            c.check(&tree).expect("cut invariants");
        }
        for scheme in Scheme::ALL {
            let mut rec = CutRecorder::new(receivers.len());
            let stats = t.run(scheme, &receivers, &mut rec);
            assert_eq!(rec.into_cuts(), scalar, "{scheme} on {isa} differs from scalar");
            assert_eq!(
                *tests.get_or_insert(stats.node_tests),
                stats.node_tests,
                "{scheme} on {isa}: node tests"
            );
            let mut only = SplatsOnly(vec![Vec::new(); receivers.len()]);
            t.run(scheme, &receivers, &mut only);
            for (i, mut s) in only.0.into_iter().enumerate() {
                s.sort_unstable();
                assert_eq!(
                    s, scalar[i].splats,
                    "{scheme} on {isa} without discards, receiver {i}"
                );
            }
        }
        match &reference {
            None => reference = Some(scalar),
            Some(r) => assert_eq!(r, &scalar, "scalar on {isa} differs from the first path"),
        }
    }
});
