//! Bad input gets a typed error naming the offending item; valid edge cases work.

use glam::Vec3;
use pbgi::{CutOptions, Error, Invalid, Isa, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};

fn ok() -> Surfel {
    Surfel {
        position: Vec3::ZERO,
        normal: Vec3::Z,
        radius: 0.1,
        radiance: Vec3::ONE,
    }
}

fn surfel_error(bad: Surfel) -> (usize, Invalid) {
    match PointCloud::new(vec![ok(), ok(), bad, ok()]) {
        Err(Error::InvalidSurfel { index, reason }) => (index, reason),
        other => panic!("expected InvalidSurfel, got {other:?}"),
    }
}

#[test]
fn surfels_are_validated_by_index() {
    let cases = [
        (
            Surfel {
                position: Vec3::new(f32::NAN, 0.0, 0.0),
                ..ok()
            },
            Invalid::NonFinite { field: "position" },
        ),
        (
            Surfel {
                position: Vec3::new(0.0, f32::INFINITY, 0.0),
                ..ok()
            },
            Invalid::NonFinite { field: "position" },
        ),
        (
            Surfel {
                radius: f32::NAN,
                ..ok()
            },
            Invalid::NonFinite { field: "radius" },
        ),
        (Surfel { radius: 0.0, ..ok() }, Invalid::NonPositiveRadius(0.0)),
        (Surfel { radius: -2.0, ..ok() }, Invalid::NonPositiveRadius(-2.0)),
        (
            Surfel {
                normal: Vec3::ZERO,
                ..ok()
            },
            Invalid::ZeroNormal,
        ),
        (
            Surfel {
                radiance: Vec3::new(0.0, -1.0, 0.0),
                ..ok()
            },
            Invalid::NegativeRadiance,
        ),
        (
            Surfel {
                radiance: Vec3::splat(f32::NAN),
                ..ok()
            },
            Invalid::NonFinite { field: "radiance" },
        ),
    ];
    for (bad, want) in cases {
        assert_eq!(surfel_error(bad), (2, want));
    }
    let (index, reason) = surfel_error(Surfel {
        normal: Vec3::new(0.0, 0.0, 2.0),
        ..ok()
    });
    assert_eq!(index, 2);
    assert!(matches!(reason, Invalid::NonUnitNormal { length } if (length - 2.0).abs() < 1e-6));
    let e = PointCloud::new(vec![ok(), Surfel { radius: -1.0, ..ok() }]).unwrap_err();
    assert_eq!(e.to_string(), "surfel 1: radius -1 is not positive");
}

#[test]
fn the_cloud_keeps_the_callers_data() {
    let surfels = vec![
        ok(),
        Surfel {
            position: Vec3::X,
            normal: Vec3::new(0.6, 0.8, 0.0),
            ..ok()
        },
    ];
    let cloud = PointCloud::new(surfels.clone()).unwrap();
    assert_eq!(cloud.surfels(), &surfels[..]);
}

#[test]
fn receivers_are_validated_by_index() {
    let e = Receiver::from_pairs([(Vec3::ZERO, Vec3::Z), (Vec3::ZERO, Vec3::Z), (Vec3::NAN, Vec3::Z)])
        .unwrap_err();
    assert_eq!(
        e,
        Error::InvalidReceiver {
            index: 2,
            reason: Invalid::NonFinite { field: "position" }
        }
    );
    let e =
        Receiver::from_pairs([(Vec3::ZERO, Vec3::Z), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0))]).unwrap_err();
    assert!(
        matches!(
            e,
            Error::InvalidReceiver {
                index: 1,
                reason: Invalid::NonUnitNormal { .. }
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().starts_with("receiver 1: normal has length"), "{e}");
}

#[test]
fn traversal_options_are_validated() {
    let tree = Tree::build(&PointCloud::new(vec![ok()]).unwrap());
    for omega in [f32::NAN, -1.0, f32::INFINITY] {
        let e = Traversal::new(
            &tree,
            CutOptions {
                max_solid_angle: omega,
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                Error::InvalidParameter {
                    name: "max_solid_angle",
                    ..
                }
            ),
            "{e:?}"
        );
    }
    let e = Traversal::new(
        &tree,
        CutOptions {
            hybrid_threshold: 18,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(
        e,
        Error::InvalidParameter {
            name: "hybrid_threshold",
            ..
        }
    ));
    assert!(matches!("avx9".parse::<Isa>(), Err(Error::UnknownIsa { .. })));
    assert!(matches!(
        "quadtree".parse::<Scheme>(),
        Err(Error::UnknownScheme { .. })
    ));
    for isa in Isa::ALL {
        let r = Traversal::new(
            &tree,
            CutOptions {
                isa: Some(isa),
                ..Default::default()
            },
        );
        if isa.is_available() {
            assert_eq!(r.unwrap().isa(), isa);
        } else {
            // Asking for a path this CPU lacks is an error, never an illegal instruction.
            assert!(matches!(r, Err(Error::IsaUnavailable { requested, .. }) if requested == isa));
        }
    }
    assert!(Isa::available().contains(&Isa::Portable));
}

#[test]
fn empty_cloud_and_single_surfel() {
    let empty = Tree::build(&PointCloud::new(vec![]).unwrap());
    assert!(empty.is_empty());
    let recs = Receiver::from_pairs([(Vec3::Z, -Vec3::Z)]).unwrap();
    let t = Traversal::new(&empty, CutOptions::default()).unwrap();
    for s in Scheme::ALL {
        let cuts = t.cuts(s, &recs);
        assert!(cuts[0].splats.is_empty() && cuts[0].discards.is_empty());
    }
    let one = Tree::build(&PointCloud::new(vec![ok()]).unwrap());
    let t = Traversal::new(&one, CutOptions::default()).unwrap();
    for s in Scheme::ALL {
        assert_eq!(t.cuts(s, &recs)[0].splats, vec![0], "{s}");
        // Behind the surfel: discarded.
        let behind = Receiver::from_pairs([(-Vec3::Z, Vec3::Z)]).unwrap();
        assert_eq!(t.cuts(s, &behind)[0].discards, vec![0], "{s}");
    }
}

#[test]
fn every_node_sphere_holds_its_disks() {
    let cloud = pbgi::synthetic::box_with_blocks(5_000, 3);
    let tree = Tree::build(&cloud);
    assert_eq!(tree.len(), 2 * cloud.len() - 1);
    let mut leaves = vec![Vec::new(); tree.len()];
    // Collect the surfels under each node by walking down.
    fn collect(tree: &Tree, k: u32, out: &mut Vec<Vec<u32>>) -> Vec<u32> {
        let v = tree.node(k);
        let s = match v.children {
            Some(l) => {
                let mut a = collect(tree, l, out);
                a.extend(collect(tree, l + 1, out));
                a
            }
            None => vec![v.surfel.unwrap()],
        };
        out[k as usize] = s.clone();
        s
    }
    let all = collect(&tree, 0, &mut leaves);
    let mut sorted = all.clone();
    sorted.sort();
    assert_eq!(
        sorted,
        (0..cloud.len() as u32).collect::<Vec<_>>(),
        "leaves are a permutation of the surfels"
    );
    for k in 0..tree.len() as u32 {
        let v = tree.node(k);
        let mut area = 0.0f64;
        for &i in &leaves[k as usize] {
            let s = cloud.surfels()[i as usize];
            let reach = s.position.as_dvec3().distance(v.center.as_dvec3()) + s.radius as f64;
            assert!(
                reach <= v.radius as f64,
                "node {k}: surfel {i} reaches {reach} > {}",
                v.radius
            );
            area += std::f64::consts::PI * (s.radius as f64).powi(2);
        }
        assert!(
            (v.area as f64 - area).abs() <= 1e-4 * area,
            "node {k} area {} vs {area}",
            v.area
        );
    }
}

#[test]
fn build_is_deterministic() {
    let cloud = pbgi::synthetic::box_with_blocks(20_000, 9);
    let (a, b) = (Tree::build(&cloud), Tree::build(&cloud));
    assert!((0..a.len() as u32).all(|k| a.node(k) == b.node(k)));
}
