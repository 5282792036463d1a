//! Property tests of the bounding-sphere hierarchy on random and adversarial
//! clouds: shape (2n − 1 nodes, depth ⌈log₂ n⌉ plus at most `EXTRA_DEPTH`
//! where a hollow solid's two sides split apart, parent links), the leaves a
//! permutation of the surfels, every sphere holding its disks, areas, normal
//! cones and means matching the surfels below, and a deterministic build.
//!
//! `PBGI_QC_TESTS` sets the number of cases per property (default 200).

use crate::common;

use common::{TreeCase, parents_from_nodes, path_names, qc, reduced, surfels_below};
use glam::{DVec3, Vec3};
use pbgi::tree::{EXTRA_DEPTH, MAX_DEPTH, Precision};
use pbgi::{NodeId, PointCloud, Surfel, Tree, TreeFile};
use quickcheck::TestResult;

fn ceil_log2(n: usize) -> usize {
    (usize::BITS - (n - 1).leading_zeros()) as usize
}

/// Levels below the root, walked.
fn walked_depth(tree: &Tree) -> usize {
    let mut depth = vec![0usize; tree.len()];
    let mut max = 0;
    for k in 0..tree.len() as NodeId {
        if let Some(l) = tree.node(k).children {
            for c in [l, l + 1] {
                depth[c as usize] = depth[k as usize] + 1;
                max = max.max(depth[c as usize]);
            }
        }
    }
    max
}

/// Everything the tree promises about itself, or the first broken promise.
#[allow(clippy::len_zero)] // `len` and `is_empty` are both under test
fn check_tree(surfels: &[Surfel], tree: &Tree) -> Result<(), String> {
    let n = surfels.len();
    if n == 0 {
        return if tree.is_empty() && tree.len() == 0 && tree.depth() == 0 && tree.parents().is_empty() {
            Ok(())
        } else {
            Err(format!(
                "empty cloud: {} nodes, depth {}",
                tree.len(),
                tree.depth()
            ))
        };
    }
    if tree.len() != 2 * n - 1 {
        return Err(format!("{} nodes for {n} surfels", tree.len()));
    }
    let depth = walked_depth(tree);
    // The median split's ⌈log₂ n⌉, plus what splits by orientation (both
    // sides of a hollow solid, unequal in number) may add, within MAX_DEPTH.
    let bound = (ceil_log2(n) + EXTRA_DEPTH).min(MAX_DEPTH);
    if tree.depth() != depth || depth < ceil_log2(n) || depth > bound {
        return Err(format!(
            "depth(): {}, walked: {depth}, ⌈log₂ {n}⌉ = {}, bound {bound}",
            tree.depth(),
            ceil_log2(n)
        ));
    }
    let parents = tree.parents();
    if parents != parents_from_nodes(tree) {
        return Err("parents() disagrees with node(k).children".into());
    }
    if parents[0].is_some() || parents[1..].iter().any(Option::is_none) {
        return Err("the root must be the only node without a parent".into());
    }
    let below = surfels_below(tree);
    let mut all = below[0].clone();
    all.sort_unstable();
    if all != (0..n as u32).collect::<Vec<_>>() {
        return Err("the leaves' surfels are not a permutation of 0..n".into());
    }
    for k in 0..tree.len() as NodeId {
        let v = tree.node(k);
        let list = &below[k as usize];
        match v.children {
            Some(l) if l <= k || l as usize + 1 >= tree.len() || tree.is_leaf(k) || v.surfel.is_some() => {
                return Err(format!("node {k}: bad children {l}"));
            }
            None if !tree.is_leaf(k) || v.surfel.is_none() => return Err(format!("node {k}: bad leaf")),
            _ => {}
        }
        if tree.left_child(k) != v.children
            || tree.sphere(k) != (v.center, v.radius)
            || tree.area(k) != v.area
            || tree.mean_normal(k) != v.normal
            || tree.radiance(k) != v.radiance
        {
            return Err(format!("node {k}: accessors disagree with node()"));
        }
        let (mut area, mut normal, mut radiance) = (0.0f64, DVec3::ZERO, DVec3::ZERO);
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &i in list {
            let s = &surfels[i as usize];
            let r = s.radius as f64;
            let a = std::f64::consts::PI * r * r;
            area += a;
            normal += s.normal.as_dvec3() * a;
            radiance += s.radiance.as_dvec3() * a;
            lo = lo.min(s.radiance.as_dvec3());
            hi = hi.max(s.radiance.as_dvec3());
        }
        if (v.area as f64 - area).abs() > 1e-4 * area + 1e-37 {
            return Err(format!(
                "node {k}: area {:e}, surfels below sum to {area:e}",
                v.area
            ));
        }
        let (normal, radiance) = (normal / area, radiance / area);
        if (v.normal.as_dvec3() - normal).abs().max_element() > 1e-5
            || v.normal.length() > 1.0 + 1e-5
            || (v.radiance.as_dvec3() - radiance).abs().max_element() > 1e-5 * (1.0 + hi.max_element())
            || v.radiance.as_dvec3().cmplt(lo - 1e-5).any()
            || v.radiance.as_dvec3().cmpgt(hi + 1e-5).any()
        {
            return Err(format!(
                "node {k}: mean normal {} / radiance {} vs {normal} / {radiance}",
                v.normal, v.radiance
            ));
        }
    }
    check_bounds(surfels, tree)
}

/// Every node's sphere holds the disks below it, and its normal cone their
/// normals (rounded outwards), as a render reads them.
fn check_bounds(surfels: &[Surfel], tree: &Tree) -> Result<(), String> {
    let below = surfels_below(tree);
    for k in 0..tree.len() as NodeId {
        let v = tree.node(k);
        let (c, big_r) = (v.center.as_dvec3(), v.radius as f64);
        for &i in &below[k as usize] {
            let s = &surfels[i as usize];
            // The sphere holds the whole ball around each disk (so the disk too).
            let reach = (s.position.as_dvec3() - c).length() + s.radius as f64;
            if reach > big_r {
                return Err(format!(
                    "node {k}: surfel {i} reaches {reach:e} from the centre, radius {big_r:e}"
                ));
            }
        }
        // The node test's bound holds for a cone whose cosine is at most
        // each normal's cosine to the axis and whose sine is at least each
        // normal's sine (a wide cone, cosine 0 and sine 1, never culls).
        let (cos, sin) = (v.cone_cos as f64, v.cone_sin as f64);
        if !(0.0..=1.0).contains(&cos) || !(0.0..=1.0).contains(&sin) || (cos == 0.0 && sin < 1.0) {
            return Err(format!("node {k}: cone cos {cos} sin {sin}"));
        }
        if cos > 0.0 {
            let a = v.cone_axis.as_dvec3();
            if (a.length() - 1.0).abs() > 1e-5 {
                return Err(format!("node {k}: cone axis {a} is not unit"));
            }
            for &i in &below[k as usize] {
                let m = surfels[i as usize].normal.as_dvec3();
                let c = a.dot(m) / (a.length() * m.length());
                if c < cos || (1.0 - c * c).max(0.0).sqrt() > sin {
                    return Err(format!(
                        "node {k}: normal of surfel {i} at cos {c} from the axis, cone cos {cos} sin {sin}"
                    ));
                }
            }
        }
    }
    Ok(())
}

fn prop_tree(case: TreeCase) -> TestResult {
    let surfels = common::cloud(&case.0);
    let cloud = PointCloud::new(surfels.clone()).expect("generated surfels are valid");
    let tree = Tree::build(&cloud);
    if let Err(e) = check_tree(&surfels, &tree) {
        return TestResult::error(e);
    }
    // Deterministic: a second build is identical, node for node.
    let again = Tree::build(&cloud);
    if again.len() != tree.len() || again.depth() != tree.depth() {
        return TestResult::error("second build differs in shape");
    }
    if let Some(k) = (0..tree.len() as NodeId).find(|&k| tree.node(k) != again.node(k)) {
        return TestResult::error(format!("second build differs at node {k}"));
    }
    TestResult::passed()
}

#[test]
fn tree_properties_on_random_clouds() {
    qc("tree properties", prop_tree as fn(TreeCase) -> TestResult);
}

/// The compact tree against the full tree, node by node: its spheres and
/// cones still bound the surfels below and are barely larger, each payload
/// value is within half a quantization step of the full one (plus the
/// decoding's `f32` rounding), the links and areas are unchanged, and a file
/// reads back the decoded values.
fn prop_compact(case: TreeCase) -> TestResult {
    let surfels = common::cloud(&case.0);
    let cloud = PointCloud::new(surfels.clone()).expect("generated surfels are valid");
    let full = Tree::build(&cloud);
    let compact = Tree::build_with(&cloud, Precision::Compact);
    if compact.precision() != Precision::Compact || compact.len() != full.len() {
        return TestResult::error("not compact");
    }
    // Bounds stay bounds, on the decoded values.
    if let Err(e) = check_bounds(&surfels, &compact) {
        return TestResult::error(format!("compact: {e}"));
    }
    // Tight: a sphere grows by at most its centre's and its radius's steps
    // (`(√3/2)/32767 + 1/16384` of its parent's radius, and its centre's
    // `f32` rounding), a cone by the axis's step and the cosine's.
    let parents = full.parents();
    let half = 0.5 / 32767.0;
    for k in 0..full.len() as NodeId {
        let (a, b) = (full.node(k), compact.node(k));
        // The steps are of the parent's decoded radius, however much larger
        // than the node it is (an outlier's sibling); the root's of its own.
        let parent = parents[k as usize].map_or(a.radius as f64, |p| compact.node(p).radius as f64);
        let angle = |c: f32| (c as f64).clamp(-1.0, 1.0).acos();
        let round = 4.0 * f32::EPSILON as f64 * (b.center.abs().max_element() + b.radius) as f64;
        let off = |x: Vec3, y: Vec3| (x.as_dvec3() - y.as_dvec3()).abs().max_element();
        // A leaf's centroid is its decoded centre, and its normal its
        // decoded axis (its pair record holds its surfel's disk): within
        // half a step of the parent's radius, and the axis's half step plus
        // what normalizing it moves, `√3` half steps.
        let leaf = b.surfel.is_some();
        // Decoded from the parent's base, a leaf's centre rounds as that does.
        let base_round = parents[k as usize].map_or(round, |p| {
            let q = compact.node(p);
            4.0 * f32::EPSILON as f64 * (q.center.abs().max_element() + q.radius) as f64
        });
        let step = if leaf {
            half * parent + round + base_round
        } else {
            half * b.radius as f64 + round
        };
        // Where the two largest components of a leaf's normal round to one
        // step, its dominant one is stepped once more, so that the leaf
        // faces as its surfel does (the cache files records by it).
        let stepped =
            leaf && dominant((a.normal.as_dvec3() * 32767.0).round().as_vec3()) != dominant(a.normal);
        let normal_step = if leaf { (1.0 + 3f64.sqrt()) * half } else { half }
            + if stepped { 2.0 * half } else { 0.0 }
            + 1e-7;
        let top = a.radiance.max_element() as f64;
        let problem = if (a.area, a.children, a.surfel) != (b.area, b.children, b.surfel) {
            Some("the area or the links changed".to_string())
        } else if b.radius as f64 > a.radius as f64 * (1.0 + 1e-6) + 1e-4 * parent + round {
            Some(format!(
                "radius {} for {} (parent {parent}), centre {} for {}, parent {:?}",
                b.radius,
                a.radius,
                b.center,
                a.center,
                parents[k as usize].map(|p| compact.sphere(p))
            ))
        } else if a.cone_cos > 0.0 && angle(b.cone_cos) > angle(a.cone_cos) + 0.01 {
            Some(format!("cone cos {} for {}", b.cone_cos, a.cone_cos))
        } else if off(a.centroid, b.centroid) > step || off(a.light_centroid, b.light_centroid) > step {
            Some(format!(
                "centroids {} {} against {} {}",
                b.centroid, b.light_centroid, a.centroid, a.light_centroid
            ))
        } else if !(b.light_offset >= b.light_centroid.distance(b.centroid)
            && b.light_offset as f64
                <= b.light_centroid.distance(b.centroid) as f64 + b.radius as f64 / 16384.0 + round)
        {
            Some(format!(
                "light offset {} for centroids {} apart",
                b.light_offset,
                b.light_centroid.distance(b.centroid)
            ))
        } else if leaf && dominant(b.normal) != dominant(a.normal) {
            Some(format!("normal {} faces another way than {}", b.normal, a.normal))
        } else if off(a.normal, b.normal) > normal_step {
            Some(format!("normal {} against {}", b.normal, a.normal))
        } else if off(a.radiance, b.radiance) > top / 65535.0 * (1.0 + 1e-6) || b.radiance.min_element() < 0.0
        {
            Some(format!("radiance {} against {}", b.radiance, a.radiance))
        } else {
            None
        };
        if let Some(p) = problem {
            return TestResult::error(format!("node {k}: {p}"));
        }
    }
    // A file holds the compact tree as it lies in memory, and reads back to
    // the same nodes, bit for bit.
    let file = TreeFile::new(cloud, compact.clone(), Default::default()).expect("a built tree");
    let back = TreeFile::from_bytes(&file.to_bytes()).expect("the file reads back");
    if back.tree().precision() != Precision::Compact {
        return TestResult::error("a compact tree read back at another precision");
    }
    let bits = |t: &Tree, k| format!("{:?}", t.node(k));
    match (0..full.len() as NodeId).find(|&k| bits(back.tree(), k) != bits(&compact, k)) {
        Some(k) => TestResult::error(format!(
            "node {k}: {:?} read back, {:?} written",
            back.tree().node(k),
            compact.node(k)
        )),
        None => TestResult::passed(),
    }
}

/// The axis of `v`'s largest magnitude, the first among equals (as the
/// cache's facing picks it).
fn dominant(v: Vec3) -> usize {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    }
}

#[test]
fn compact_tree_bounds_hold_and_values_within_half_a_step() {
    qc("compact tree", prop_compact as fn(TreeCase) -> TestResult);
}

#[test]
fn hundred_thousand_surfels_at_one_position() {
    let n = 100_000;
    let s = Surfel {
        position: Vec3::new(0.25, -3.0, 7.5),
        normal: Vec3::Y,
        radius: 0.01,
        radiance: Vec3::ONE,
    };
    let surfels = vec![s; n];
    let tree = Tree::build(&PointCloud::new(surfels.clone()).unwrap());
    assert_eq!(tree.len(), 2 * n - 1);
    assert!(tree.depth() <= 17, "depth {}", tree.depth());
    let root = tree.node(0);
    assert_eq!(root.center, s.position);
    assert!(
        root.radius >= s.radius && root.radius <= s.radius * (1.0 + 1e-5),
        "{root:?}"
    );
    check_tree(&surfels, &tree).unwrap();
    eprintln!("coincident build: depth {}", tree.depth());
}

#[test]
fn parallel_builds_are_deterministic() {
    // Above the crate's parallel cut-off, with ties everywhere and without.
    let n = if reduced() { 5_000 } else { 20_000 };
    let boxed = pbgi::synthetic::box_with_blocks(n, 9);
    let lattice = PointCloud::new(common::cloud(&common::CloudSpec {
        shape: common::Shape::Lattice,
        n,
        seed: 3,
    }))
    .unwrap();
    for cloud in [boxed, lattice] {
        let (a, b) = (Tree::build(&cloud), Tree::build(&cloud));
        assert_eq!(a.len(), b.len());
        assert!((0..a.len() as NodeId).all(|k| a.node(k) == b.node(k)));
        check_tree(cloud.surfels(), &a).unwrap();
    }
    eprintln!("parallel builds: deterministic ({} threads)", rayon_threads());
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[test]
fn small_sizes_have_minimal_depth() {
    for n in 1..=70 {
        let surfels = common::cloud(&common::CloudSpec {
            shape: common::Shape::Uniform,
            n,
            seed: n as u64,
        });
        let tree = Tree::build(&PointCloud::new(surfels.clone()).unwrap());
        check_tree(&surfels, &tree).unwrap_or_else(|e| panic!("n = {n}: {e}"));
    }
    eprintln!("small trees: n = 1..=70 (paths {})", path_names());
}

#[test]
fn a_hollow_solid_splits_by_orientation_within_the_depth_budget() {
    // The closed thick-walled box: its walls' insides and outsides part by
    // orientation (unequal halves), so the tree is deeper than the median
    // split's ⌈log₂ n⌉, and still within the budget.
    let scene = pbgi::exact::ExactScene::room(&pbgi::exact::opening("shell").expect("a scene"));
    for seed in [None, Some(3)] {
        let surfels = scene.surfels(2, seed);
        let n = surfels.len();
        let tree = Tree::build(&PointCloud::new(surfels.clone()).unwrap());
        check_tree(&surfels, &tree).unwrap_or_else(|e| panic!("{seed:?}: {e}"));
        assert!(
            tree.depth() > ceil_log2(n),
            "{seed:?}: depth {} for {n} surfels",
            tree.depth()
        );
    }
}
