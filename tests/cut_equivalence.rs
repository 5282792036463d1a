//! Property tests of the cut: single, packet and hybrid give exactly the scalar
//! cut (sorted splats and discards) on every instruction-set path this CPU
//! runs, for every hybrid threshold, on random and adversarial clouds
//! (duplicates, sheets, lines, mixed scales, wild radii, lattices, extreme
//! coordinates); the invariants of docs/design.md §2 hold (checked independently of
//! `Cut::check`); the cut follows the node test (re-derived in f64) and never
//! discards a visible disk, on full and compact trees alike; scaling the input by 2^k changes neither the
//! tree nor the cut.
//!
//! `PBGI_QC_TESTS` sets the number of cases per property (default 200).

use crate::common;

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use common::{
    Case, Shape, all_paths_agree, cases, first_difference, invariants, path_names, qc, reduced, semantics,
    surfels_below, traversal,
};
use pbgi::tree::Precision;
use pbgi::{Cut, CutRecorder, Isa, NodeId, PointCloud, Receiver, Scheme, Tree};
use quickcheck::{Arbitrary, Gen, TestResult};

static EQUIVALENCE_RECEIVERS: AtomicU64 = AtomicU64::new(0);

/// Both trees of a case's cloud: full precision and compact.
fn trees(surfels: &[pbgi::Surfel]) -> [Tree; 2] {
    let cloud = PointCloud::new(surfels.to_vec()).expect("generated surfels are valid");
    [Precision::Full, Precision::Compact].map(|p| Tree::build_with(&cloud, p))
}

fn prop_equivalence(case: Case) -> TestResult {
    let surfels = case.surfels();
    let receivers = case.receivers(&surfels);
    EQUIVALENCE_RECEIVERS.fetch_add(receivers.len() as u64, Relaxed);
    for tree in trees(&surfels) {
        let p = tree.precision();
        let cuts = match all_paths_agree(&tree, &receivers, case.omega, case.light_offset, case.threshold) {
            Ok(c) => c,
            Err(e) => return TestResult::error(format!("{p:?} tree: {e}")),
        };
        let parents = tree.parents();
        for (i, c) in cuts.iter().enumerate() {
            if let Err(e) = invariants(&tree, &parents, c) {
                return TestResult::error(format!("{p:?} tree, receiver {i} {:?}: {e}", receivers[i]));
            }
            if let Err(e) = c.check(&tree) {
                return TestResult::error(format!(
                    "{p:?} tree, receiver {i} {:?}: Cut::check: {e}",
                    receivers[i]
                ));
            }
        }
    }
    TestResult::passed()
}

#[test]
fn schemes_equal_scalar_on_every_path() {
    qc("cut equivalence", prop_equivalence as fn(Case) -> TestResult);
    let n = EQUIVALENCE_RECEIVERS.load(Relaxed);
    eprintln!(
        "cut equivalence: {n} receivers (+ shrinking) × 4 schemes × 4 sinks on paths {}",
        path_names()
    );
    assert!(n >= cases(), "too few receivers exercised: {n}");
}

fn prop_semantics(case: Case) -> TestResult {
    let surfels = case.surfels();
    let receivers = case.receivers(&surfels);
    for tree in trees(&surfels) {
        let t = traversal(&tree, case.omega, case.light_offset, case.threshold, Isa::best()).unwrap();
        let cuts = t.cuts(Scheme::Hybrid, &receivers);
        let (parents, below) = (tree.parents(), surfels_below(&tree));
        for (i, (r, c)) in receivers.iter().zip(&cuts).enumerate() {
            if let Err(e) = semantics(
                &tree,
                &parents,
                &below,
                &surfels,
                r,
                (case.omega, case.light_offset),
                c,
            ) {
                return TestResult::error(format!("{:?} tree, receiver {i} {r:?}: {e}", tree.precision()));
            }
        }
    }
    TestResult::passed()
}

#[test]
fn cuts_follow_the_node_test_and_discard_nothing_visible() {
    qc("cut semantics (f64)", prop_semantics as fn(Case) -> TestResult);
}

/// Breaks a valid cut in one of several ways: both checkers must notice.
/// Also refines a splat into its children, which stays valid: both must accept.
fn prop_broken_cuts_are_rejected(case: Case) -> TestResult {
    let surfels = case.surfels();
    let tree = Tree::build(&PointCloud::new(surfels.clone()).expect("generated surfels are valid"));
    let receivers = case.receivers(&surfels);
    let t = traversal(
        &tree,
        case.omega,
        case.light_offset,
        case.threshold,
        Isa::Portable,
    )
    .unwrap();
    let parents = tree.parents();
    let mut rng = common::Rng::new(case.receivers.seed);
    if tree.is_empty() {
        let c = Cut {
            splats: vec![0],
            discards: vec![],
        };
        return TestResult::from_bool(invariants(&tree, &parents, &c).is_err() && c.check(&tree).is_err());
    }
    let insert = |v: &mut Vec<NodeId>, k: NodeId| {
        let at = v.partition_point(|&x| x < k);
        v.insert(at, k);
    };
    for (i, cut) in t.cuts(Scheme::Scalar, &receivers).into_iter().enumerate().take(8) {
        let all: Vec<NodeId> = cut.splats.iter().chain(&cut.discards).copied().collect();
        let mut broken = Vec::new();
        // Drop one cut node: its leaves lose their cover.
        let mut c = cut.clone();
        let k = rng.pick(&all);
        c.splats.retain(|&x| x != k);
        c.discards.retain(|&x| x != k);
        broken.push(("dropped", k, c));
        // Add a child of an inner cut node: it lies below a cut node.
        if let Some(&k) = all.iter().find(|&&k| tree.node(k).children.is_some()) {
            let mut c = cut.clone();
            let child = tree.node(k).children.unwrap() + rng.below(2) as NodeId;
            insert(&mut c.splats, child);
            broken.push(("added child", child, c));
        }
        // Add the parent of a non-root cut node: its leaves are covered twice.
        let k = rng.pick(&all);
        if let Some(p) = parents[k as usize] {
            let mut c = cut.clone();
            insert(
                if rng.chance(0.5) {
                    &mut c.splats
                } else {
                    &mut c.discards
                },
                p,
            );
            broken.push(("added parent", p, c));
        }
        // Report a splat as a discard too.
        if let Some(&k) = cut.splats.first() {
            let mut c = cut.clone();
            insert(&mut c.discards, k);
            broken.push(("splat also discarded", k, c));
        }
        for (what, k, c) in broken {
            let mine = invariants(&tree, &parents, &c);
            let theirs = c.check(&tree);
            if mine.is_ok() || theirs.is_ok() {
                return TestResult::error(format!(
                    "receiver {i}: cut with {what} node {k} accepted (independent: {mine:?}, Cut::check: {theirs:?})"
                ));
            }
        }
        // Refining a splat into its two children keeps a valid cut.
        if let Some(&k) = cut.splats.iter().find(|&&k| tree.node(k).children.is_some()) {
            let mut c = cut.clone();
            c.splats.retain(|&x| x != k);
            let l = tree.node(k).children.unwrap();
            insert(&mut c.splats, l);
            insert(&mut c.splats, l + 1);
            if let Err(e) = invariants(&tree, &parents, &c).and(c.check(&tree)) {
                return TestResult::error(format!("receiver {i}: refined cut rejected: {e}"));
            }
        }
    }
    TestResult::passed()
}

#[test]
fn broken_cuts_are_rejected_by_both_checkers() {
    qc(
        "invariant checkers on broken cuts",
        prop_broken_cuts_are_rejected as fn(Case) -> TestResult,
    );
}

/// A case and a power of two to scale it by.
#[derive(Clone, Debug)]
struct Scaled {
    case: Case,
    k: i32,
}

impl Arbitrary for Scaled {
    fn arbitrary(g: &mut Gen) -> Self {
        Scaled {
            case: Case::arbitrary(g),
            k: (u32::arbitrary(g) % 41) as i32 - 20,
        }
    }
    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        let k = self.k;
        Box::new(self.case.shrink().map(move |case| Scaled { case, k }))
    }
}

fn prop_scale(input: Scaled) -> TestResult {
    let Scaled { case, k } = input;
    // Coordinates of 1e15 or radii of 1e-40 under- or overflow when scaled.
    if case.cloud.shape == Shape::Extreme {
        return TestResult::discard();
    }
    let s = 2f32.powi(k);
    let surfels = case.surfels();
    let scaled = common::scale_cloud(&surfels, s);
    let tree = Tree::build(&PointCloud::new(surfels.clone()).unwrap());
    let tree_s = Tree::build(&PointCloud::new(scaled).unwrap());
    if tree.len() != tree_s.len() || tree.depth() != tree_s.depth() {
        return TestResult::error(format!("tree shape changes under 2^{k}"));
    }
    for n in 0..tree.len() as NodeId {
        let (a, b) = (tree.node(n), tree_s.node(n));
        let want = pbgi::NodeView {
            center: a.center * s,
            radius: a.radius * s,
            area: a.area * s * s,
            centroid: a.centroid * s,
            light_centroid: a.light_centroid * s,
            light_offset: a.light_offset * s,
            ..a
        };
        if b != want {
            return TestResult::error(format!("node {n} under 2^{k}: {b:?}, expected {want:?}"));
        }
    }
    let receivers = case.receivers(&surfels);
    let receivers_s: Vec<Receiver> = receivers
        .iter()
        .map(|r| Receiver::new(r.position() * s, r.normal()).unwrap())
        .collect();
    let reference = traversal(
        &tree,
        case.omega,
        case.light_offset,
        case.threshold,
        Isa::Portable,
    )
    .unwrap()
    .cuts(Scheme::Scalar, &receivers);
    for isa in Isa::available() {
        let t = traversal(&tree_s, case.omega, case.light_offset, case.threshold, isa).unwrap();
        for scheme in Scheme::ALL {
            if let Some(d) = first_difference(&t.cuts(scheme, &receivers_s), &reference) {
                return TestResult::error(format!("{scheme} on {isa}: cut changes under 2^{k}: {d}"));
            }
        }
    }
    TestResult::passed()
}

#[test]
fn scaling_by_powers_of_two_keeps_tree_and_cut() {
    qc("scale equivariance", prop_scale as fn(Scaled) -> TestResult);
}

/// Every hybrid threshold on every path, on a box with incoherent packets and
/// a receiver count that is not a multiple of 16.
#[test]
fn every_hybrid_threshold_on_every_path() {
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(
        if reduced() { 500 } else { 3000 },
        21,
    ));
    let mut receivers = pbgi::synthetic::receivers(if reduced() { 3 } else { 20 }, 0.02, 0.7, 4);
    receivers.truncate(receivers.len() - 9);
    let parents = tree.parents();
    for omega in [0.0, 0.02, 0.2] {
        let t = traversal(&tree, omega, 0.0, 2, Isa::Portable).unwrap();
        let scalar = t.cuts(Scheme::Scalar, &receivers);
        for c in &scalar {
            invariants(&tree, &parents, c).unwrap();
        }
        for isa in Isa::available() {
            for threshold in 0..=17 {
                let t = traversal(&tree, omega, 0.0, threshold, isa).unwrap();
                let mut rec = CutRecorder::new(receivers.len());
                let stats = t.run(Scheme::Hybrid, &receivers, &mut rec);
                if let Some(d) = first_difference(&rec.into_cuts(), &scalar) {
                    panic!("hybrid threshold {threshold} on {isa}, Ω {omega}: {d}");
                }
                // 0 and 1 never switch (no entry has fewer than one active lane); 17
                // switches every packet at the root.
                match threshold {
                    0 | 1 => assert_eq!(stats.switches, 0, "threshold {threshold}"),
                    17 => assert_eq!(stats.switches, receivers.len().div_ceil(16) as u64),
                    _ => {}
                }
            }
        }
    }
    eprintln!(
        "hybrid thresholds 0..=17: {} receivers × 3 Ω on paths {}",
        receivers.len(),
        path_names()
    );
}

/// Thousands of receivers per scheme on a realistic cloud, coherent and not.
#[test]
fn thousands_of_receivers_on_the_box() {
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(
        if reduced() { 2000 } else { 20_000 },
        5,
    ));
    let tiles = if reduced() { 8 } else { 128 };
    let parents = tree.parents();
    for jitter in [0.0, 1.0] {
        let receivers = pbgi::synthetic::receivers(tiles, 0.01, jitter, 11);
        for omega in [0.0, 0.02, 0.2] {
            let cuts = all_paths_agree(&tree, &receivers, omega, 0.0, 2).unwrap();
            for (i, c) in cuts.iter().enumerate() {
                invariants(&tree, &parents, c).unwrap_or_else(|e| panic!("receiver {i}: {e}"));
            }
            let inner = cuts
                .iter()
                .flat_map(|c| &c.splats)
                .filter(|&&k| !tree.is_leaf(k))
                .count();
            assert!(
                cuts.iter().all(|c| !c.splats.is_empty()),
                "Ω {omega}: a receiver inside the box sees nothing"
            );
            assert_eq!(inner == 0, omega == 0.0, "Ω {omega}: {inner} inner splats");
        }
    }
    eprintln!(
        "box: {} receivers × 3 Ω × 2 sets × 4 schemes on paths {}",
        tiles * 16,
        path_names()
    );
}
