//! Property tests: single, packet and hybrid give exactly the scalar cut (same
//! splats, same discards) on every instruction-set path this CPU runs, on
//! random and adversarial clouds; the cut invariants hold; scaling the input
//! by 2^k leaves the cut unchanged.
//!
//! `PBGI_QC_TESTS` sets the number of cases per property (default 150).

use glam::Vec3;
use pbgi::{Cut, CutOptions, Isa, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};
use quickcheck::{Arbitrary, Gen, QuickCheck, TestResult};

fn cases() -> u64 {
    std::env::var("PBGI_QC_TESTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(150)
}

fn check(name: &str, prop: fn(Input) -> TestResult) {
    let paths: Vec<_> = Isa::available().iter().map(|i| i.name()).collect();
    eprintln!("{name}: {} cases on paths {}", cases(), paths.join(", "));
    QuickCheck::new()
        .tests(cases())
        .max_tests(cases() * 10)
        .quickcheck(prop);
}

/// Kinds of cloud, from benign to adversarial.
#[derive(Clone, Copy, Debug)]
enum Shape {
    Uniform,
    Duplicates,
    Coplanar,
    Collinear,
    MixedScales,
    WildRadii,
    Box,
}

#[derive(Clone, Debug)]
struct Input {
    shape: Shape,
    surfels: Vec<Surfel>,
    receivers: Vec<(Vec3, Vec3)>,
    omega: f32,
    threshold: u32,
}

fn f(g: &mut Gen, lo: f32, hi: f32) -> f32 {
    let u = (u32::arbitrary(g) >> 8) as f32 / (1u32 << 24) as f32;
    lo + (hi - lo) * u
}

fn unit(g: &mut Gen) -> Vec3 {
    loop {
        let v = Vec3::new(f(g, -1.0, 1.0), f(g, -1.0, 1.0), f(g, -1.0, 1.0));
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

impl Arbitrary for Input {
    fn arbitrary(g: &mut Gen) -> Self {
        let shapes = [
            Shape::Uniform,
            Shape::Duplicates,
            Shape::Coplanar,
            Shape::Collinear,
            Shape::MixedScales,
            Shape::WildRadii,
            Shape::Box,
        ];
        let shape = *g.choose(&shapes).unwrap();
        let n = 1 + usize::arbitrary(g) % 400;
        let radiance = Vec3::ONE;
        let mut surfels = Vec::with_capacity(n);
        match shape {
            Shape::Box => {
                let cloud = pbgi::synthetic::box_with_blocks(n.max(30), u64::arbitrary(g));
                surfels = cloud.into_surfels();
            }
            _ => {
                let p0 = Vec3::new(f(g, -1.0, 1.0), f(g, -1.0, 1.0), f(g, -1.0, 1.0));
                let axis = unit(g);
                for i in 0..n {
                    let (position, normal, radius) = match shape {
                        Shape::Uniform => (
                            Vec3::new(f(g, -1.0, 1.0), f(g, -1.0, 1.0), f(g, -1.0, 1.0)),
                            unit(g),
                            f(g, 0.01, 0.1),
                        ),
                        Shape::Duplicates => (p0, if i % 3 == 0 { axis } else { unit(g) }, 0.05),
                        Shape::Coplanar => {
                            let (t, b) = axis.any_orthonormal_pair();
                            (
                                p0 + t * f(g, -1.0, 1.0) + b * f(g, -1.0, 1.0),
                                axis,
                                f(g, 0.01, 0.1),
                            )
                        }
                        Shape::Collinear => (p0 + axis * (i as f32 * 0.01), unit(g), 0.02),
                        Shape::MixedScales => {
                            let s = if i % 2 == 0 { 1e-3 } else { 1e3 };
                            (
                                Vec3::new(f(g, -1.0, 1.0), f(g, -1.0, 1.0), f(g, -1.0, 1.0)) * s,
                                unit(g),
                                0.05 * s,
                            )
                        }
                        Shape::WildRadii => {
                            let r = if i % 2 == 0 { 1e-6 } else { 10.0 };
                            (
                                Vec3::new(f(g, -1.0, 1.0), f(g, -1.0, 1.0), f(g, -1.0, 1.0)),
                                unit(g),
                                r,
                            )
                        }
                        Shape::Box => unreachable!(),
                    };
                    surfels.push(Surfel {
                        position,
                        normal,
                        radius,
                        radiance,
                    });
                }
            }
        }
        // Receivers: near the cloud, some on surfels, some at its centre.
        let m = 1 + usize::arbitrary(g) % 40;
        let receivers = (0..m)
            .map(|i| {
                let p = match i % 3 {
                    0 => surfels[usize::arbitrary(g) % surfels.len()].position,
                    1 => surfels[0].position * 0.5,
                    _ => Vec3::new(f(g, -2.0, 2.0), f(g, -2.0, 2.0), f(g, -2.0, 2.0)),
                };
                (p, unit(g))
            })
            .collect();
        let omegas = [0.0, 1e-6, 0.01, 0.05, 0.3, 1e3];
        let omega = if bool::arbitrary(g) {
            *g.choose(&omegas).unwrap()
        } else {
            f(g, 0.0, 1.0)
        };
        let threshold = u32::arbitrary(g) % 18;
        Input {
            shape,
            surfels,
            receivers,
            omega,
            threshold,
        }
    }
}

/// Independent check of DESIGN §2's invariants from parent links.
fn invariants(tree: &Tree, cut: &Cut) -> Result<(), String> {
    let parents = tree.parents();
    let mut marked = vec![false; tree.len()];
    for &k in cut.splats.iter().chain(&cut.discards) {
        if std::mem::replace(&mut marked[k as usize], true) {
            return Err(format!("node {k} reported twice"));
        }
    }
    for k in 0..tree.len() as u32 {
        // Marked ancestors-or-self of every leaf: exactly one.
        if tree.is_leaf(k) {
            let (mut n, mut count) = (Some(k), 0);
            while let Some(x) = n {
                count += marked[x as usize] as u32;
                n = parents[x as usize];
            }
            if count != 1 {
                return Err(format!("leaf {k} has {count} cut ancestors"));
            }
        }
    }
    for &k in &cut.splats {
        let mut n = parents[k as usize];
        while let Some(x) = n {
            if marked[x as usize] {
                return Err(format!("splatted node {k} lies below cut node {x}"));
            }
            n = parents[x as usize];
        }
    }
    Ok(())
}

fn cuts_on_every_path(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    threshold: u32,
) -> Result<Vec<Cut>, String> {
    let mut reference: Option<Vec<Cut>> = None;
    for isa in Isa::available() {
        let t = Traversal::new(
            tree,
            CutOptions {
                max_solid_angle: omega,
                hybrid_threshold: threshold,
                isa: Some(isa),
            },
        )
        .map_err(|e| e.to_string())?;
        let scalar = t.cuts(Scheme::Scalar, receivers);
        if let Some(r) = &reference
            && *r != scalar
        {
            return Err(format!("scalar on {isa} differs from the first path"));
        }
        for scheme in [Scheme::Single, Scheme::Packet, Scheme::Hybrid] {
            let c = t.cuts(scheme, receivers);
            if let Some(i) = (0..c.len()).find(|&i| c[i] != scalar[i]) {
                return Err(format!(
                    "{scheme} on {isa} differs at receiver {i}: {} splats / {} discards vs scalar {} / {}",
                    c[i].splats.len(),
                    c[i].discards.len(),
                    scalar[i].splats.len(),
                    scalar[i].discards.len()
                ));
            }
        }
        reference.get_or_insert(scalar);
    }
    Ok(reference.unwrap_or_default())
}

fn prop_equivalence(input: Input) -> TestResult {
    let tree = Tree::build(&PointCloud::new(input.surfels.clone()).expect("valid surfels"));
    let receivers = Receiver::from_pairs(input.receivers.iter().copied()).expect("valid receivers");
    match cuts_on_every_path(&tree, &receivers, input.omega, input.threshold) {
        Err(e) => TestResult::error(format!("{:?} Ω {}: {e}", input.shape, input.omega)),
        Ok(cuts) => {
            for (i, c) in cuts.iter().enumerate() {
                if let Err(e) = invariants(&tree, c).and(c.check(&tree)) {
                    return TestResult::error(format!("{:?} receiver {i}: {e}", input.shape));
                }
            }
            TestResult::passed()
        }
    }
}

#[test]
fn schemes_equal_scalar_on_every_path() {
    check("cut equivalence", prop_equivalence);
}

fn prop_scale(input: Input) -> TestResult {
    let k = (input.receivers.len() as i32 % 41) - 20; // 2^-20 .. 2^20
    let s = 2f32.powi(k);
    let scaled: Vec<Surfel> = input
        .surfels
        .iter()
        .map(|x| Surfel {
            position: x.position * s,
            radius: x.radius * s,
            ..*x
        })
        .collect();
    let tree = Tree::build(&PointCloud::new(input.surfels.clone()).unwrap());
    let tree_s = Tree::build(&PointCloud::new(scaled).unwrap());
    let recs = Receiver::from_pairs(input.receivers.iter().copied()).unwrap();
    let recs_s = Receiver::from_pairs(input.receivers.iter().map(|&(p, n)| (p * s, n))).unwrap();
    let opts = CutOptions {
        max_solid_angle: input.omega,
        ..Default::default()
    };
    let a = Traversal::new(&tree, opts).unwrap().cuts(Scheme::Packet, &recs);
    let b = Traversal::new(&tree_s, opts)
        .unwrap()
        .cuts(Scheme::Packet, &recs_s);
    if a == b {
        TestResult::passed()
    } else {
        TestResult::error(format!("{:?}: cut changes under scale 2^{k}", input.shape))
    }
}

#[test]
fn scaling_by_powers_of_two_keeps_the_cut() {
    check("scale invariance", prop_scale);
}

/// Thousands of receivers per scheme on a realistic cloud, coherent and not.
#[test]
fn thousands_of_receivers_on_the_box() {
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(20_000, 5));
    let tiles = if cases() < 50 { 16 } else { 128 };
    for jitter in [0.0, 1.0] {
        let receivers = pbgi::synthetic::receivers(tiles, 0.01, jitter, 11);
        for omega in [0.0, 0.02, 0.2] {
            let cuts = cuts_on_every_path(&tree, &receivers, omega, 2).unwrap();
            for c in cuts.iter().take(64) {
                invariants(&tree, c).unwrap();
            }
            assert!(
                cuts.iter().any(|c| !c.splats.is_empty()),
                "Ω {omega}: empty cuts prove nothing"
            );
        }
    }
    eprintln!(
        "box: {} receivers × 3 Ω × 2 sets on paths {:?}",
        tiles * 16,
        Isa::available()
    );
}

#[test]
fn hundred_thousand_coincident_surfels() {
    let s = Surfel {
        position: Vec3::splat(0.5),
        normal: Vec3::Z,
        radius: 0.01,
        radiance: Vec3::ONE,
    };
    let tree = Tree::build(&PointCloud::new(vec![s; 100_000]).unwrap());
    assert_eq!(tree.len(), 199_999);
    assert!(tree.depth() <= 17, "depth {}", tree.depth());
    let r = Receiver::from_pairs([
        (Vec3::new(0.5, 0.5, 1.0), -Vec3::Z),
        (Vec3::new(0.5, 0.5, 0.5), Vec3::Z),
    ])
    .unwrap();
    let cuts = cuts_on_every_path(&tree, &r, 0.05, 2).unwrap();
    invariants(&tree, &cuts[0]).unwrap();
    // From above, the whole cluster is one small splat... of solid angle π(0.01)²/0.25 < Ω: the root.
    assert_eq!(cuts[0].splats, vec![0]);
}

#[test]
fn deep_chain_does_not_overflow() {
    // Surfels along a line at doubling distances: median splits keep depth ⌈log₂ n⌉.
    let surfels: Vec<_> = (0..4096)
        .map(|i| Surfel {
            position: Vec3::new(1.001f32.powi(i), 0.0, 0.0),
            normal: Vec3::Y,
            radius: 1e-4,
            radiance: Vec3::ONE,
        })
        .collect();
    let tree = Tree::build(&PointCloud::new(surfels).unwrap());
    assert_eq!(tree.depth(), 12);
    let r = Receiver::from_pairs([(Vec3::new(1.0, 1.0, 0.0), -Vec3::Y)]).unwrap();
    cuts_on_every_path(&tree, &r, 0.0, 2).unwrap();
}
