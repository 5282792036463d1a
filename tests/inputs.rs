//! Bad input gets a typed error naming the offending item (checked on random
//! clouds with one or two random defects at random places); valid edge cases
//! (empty cloud, one surfel, zero receivers, Ω at the float limits) work on
//! every path and scheme.
//!
//! `PBGI_QC_TESTS` sets the number of cases per property (default 200).

use crate::common;

use common::{CloudSpec, Rng, path_names, qc};
use glam::Vec3;
use pbgi::{
    CutOptions, Error, Invalid, Isa, IsaError, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree,
};
use quickcheck::{Arbitrary, Gen, TestResult};

fn ok() -> Surfel {
    Surfel {
        position: Vec3::ZERO,
        normal: Vec3::Z,
        radius: 0.1,
        radiance: Vec3::ONE,
    }
}

/// The defects a surfel or receiver can have, with the reason they must give.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Defect {
    NanPosition,
    InfPosition,
    NanRadius,
    InfRadius,
    ZeroRadius,
    NegativeZeroRadius,
    NegativeRadius,
    ZeroNormal,
    NanNormal,
    LongNormal,
    ShortNormal,
    NegativeRadiance,
    NanRadiance,
    InfRadiance,
}

const DEFECTS: [Defect; 14] = [
    Defect::NanPosition,
    Defect::InfPosition,
    Defect::NanRadius,
    Defect::InfRadius,
    Defect::ZeroRadius,
    Defect::NegativeZeroRadius,
    Defect::NegativeRadius,
    Defect::ZeroNormal,
    Defect::NanNormal,
    Defect::LongNormal,
    Defect::ShortNormal,
    Defect::NegativeRadiance,
    Defect::NanRadiance,
    Defect::InfRadiance,
];

impl Defect {
    /// Applies to a surfel; the expected reason (`None` for a receiver-only check).
    fn apply(self, s: &mut Surfel, rng: &mut Rng) -> Invalid {
        let c = rng.below(3);
        match self {
            Defect::NanPosition => {
                s.position[c] = f32::NAN;
                Invalid::NonFinite { field: "position" }
            }
            Defect::InfPosition => {
                s.position[c] = if rng.chance(0.5) {
                    f32::INFINITY
                } else {
                    f32::NEG_INFINITY
                };
                Invalid::NonFinite { field: "position" }
            }
            Defect::NanRadius => {
                s.radius = f32::NAN;
                Invalid::NonFinite { field: "radius" }
            }
            Defect::InfRadius => {
                s.radius = f32::INFINITY;
                Invalid::NonFinite { field: "radius" }
            }
            Defect::ZeroRadius => {
                s.radius = 0.0;
                Invalid::NonPositiveRadius(0.0)
            }
            Defect::NegativeZeroRadius => {
                s.radius = -0.0;
                Invalid::NonPositiveRadius(-0.0)
            }
            Defect::NegativeRadius => {
                s.radius = -rng.log_range(1e-30, 1e30);
                Invalid::NonPositiveRadius(s.radius)
            }
            Defect::ZeroNormal => {
                s.normal = Vec3::ZERO;
                Invalid::ZeroNormal
            }
            Defect::NanNormal => {
                s.normal[c] = f32::NAN;
                Invalid::NonFinite { field: "normal" }
            }
            Defect::LongNormal | Defect::ShortNormal => {
                // Off by more than the tolerance (|len² − 1| ≤ 1e-4).
                let f = rng.log_range(1e-3, 0.5);
                s.normal *= if self == Defect::LongNormal {
                    1.0 + f
                } else {
                    1.0 - f
                };
                Invalid::NonUnitNormal {
                    length: s.normal.length(),
                }
            }
            Defect::NegativeRadiance => {
                s.radiance[c] = -rng.log_range(1e-30, 10.0);
                Invalid::NegativeRadiance
            }
            Defect::NanRadiance => {
                s.radiance[c] = f32::NAN;
                Invalid::NonFinite { field: "radiance" }
            }
            Defect::InfRadiance => {
                s.radiance[c] = f32::INFINITY;
                Invalid::NonFinite { field: "radiance" }
            }
        }
    }

    fn receiver_applicable(self) -> bool {
        matches!(
            self,
            Defect::NanPosition
                | Defect::InfPosition
                | Defect::ZeroNormal
                | Defect::NanNormal
                | Defect::LongNormal
                | Defect::ShortNormal
        )
    }
}

/// Same reason; the normal's length only approximately (it is computed).
fn same_reason(got: &Invalid, want: &Invalid) -> bool {
    match (got, want) {
        (Invalid::NonUnitNormal { length: a }, Invalid::NonUnitNormal { length: b }) => {
            (a - b).abs() <= 1e-5 * b
        }
        (Invalid::NonPositiveRadius(a), Invalid::NonPositiveRadius(b)) => a.to_bits() == b.to_bits(),
        _ => got == want,
    }
}

/// A valid cloud with one defect at `index` (and maybe a second one later).
#[derive(Clone, Debug)]
struct Defective {
    cloud: CloudSpec,
    index: usize,
    defect: Defect,
    second: Option<(usize, Defect)>,
    seed: u64,
}

impl Arbitrary for Defective {
    fn arbitrary(g: &mut Gen) -> Self {
        let mut cloud = CloudSpec::arbitrary_sized(g, 300);
        if cloud.shape == common::Shape::Box {
            cloud.shape = common::Shape::Uniform;
        }
        cloud.n = cloud.n.max(1);
        let index = usize::arbitrary(g) % cloud.n;
        let later = index + 1 + usize::arbitrary(g) % cloud.n;
        Defective {
            cloud,
            index,
            defect: *g.choose(&DEFECTS).unwrap(),
            second: (later < cloud.n && bool::arbitrary(g)).then(|| (later, *g.choose(&DEFECTS).unwrap())),
            seed: u64::arbitrary(g),
        }
    }
}

fn prop_surfel_defect(d: Defective) -> TestResult {
    let mut rng = Rng::new(d.seed);
    let mut surfels = common::cloud(&d.cloud);
    if PointCloud::new(surfels.clone()).is_err() {
        return TestResult::error("the generated cloud itself is invalid");
    }
    let want = d.defect.apply(&mut surfels[d.index], &mut rng);
    if let Some((j, e)) = d.second {
        e.apply(&mut surfels[j], &mut rng);
    }
    match PointCloud::new(surfels.clone()) {
        Err(Error::InvalidSurfel { index, ref reason }) if index == d.index && same_reason(reason, &want) => {
            let e = PointCloud::new(surfels).unwrap_err();
            let text = e.to_string();
            if !text.starts_with(&format!("surfel {index}: ")) {
                return TestResult::error(format!("message does not name the surfel: {text:?}"));
            }
            // `validate` agrees, and names what it is told.
            match surfels_validate(&d, &want) {
                Ok(()) => TestResult::passed(),
                Err(e) => TestResult::error(e),
            }
        }
        other => TestResult::error(format!("expected surfel {} {want:?}, got {other:?}", d.index)),
    }
}

fn surfels_validate(d: &Defective, want: &Invalid) -> Result<(), String> {
    let mut rng = Rng::new(d.seed);
    let mut s = common::cloud(&d.cloud)[d.index];
    d.defect.apply(&mut s, &mut rng);
    match s.validate(12345) {
        Err(Error::InvalidSurfel { index: 12345, reason }) if same_reason(&reason, want) => Ok(()),
        other => Err(format!("Surfel::validate: {other:?}")),
    }
}

#[test]
fn invalid_surfels_are_named_by_index() {
    qc(
        "surfel validation",
        prop_surfel_defect as fn(Defective) -> TestResult,
    );
}

fn prop_receiver_defect(d: Defective) -> TestResult {
    if !d.defect.receiver_applicable() {
        return TestResult::discard();
    }
    let mut rng = Rng::new(d.seed);
    let surfels = common::cloud(&d.cloud);
    let mut pairs = common::receivers(
        &common::ReceiverSpec {
            count: surfels.len(),
            seed: d.seed,
        },
        &surfels,
    );
    if Receiver::from_pairs(pairs.iter().copied()).is_err() {
        return TestResult::error("the generated receivers themselves are invalid");
    }
    let mut s = Surfel {
        position: pairs[d.index].0,
        normal: pairs[d.index].1,
        ..ok()
    };
    let want = d.defect.apply(&mut s, &mut rng);
    pairs[d.index] = (s.position, s.normal);
    if let Some((j, e)) = d.second.filter(|(_, e)| e.receiver_applicable()) {
        let mut s = Surfel {
            position: pairs[j].0,
            normal: pairs[j].1,
            ..ok()
        };
        e.apply(&mut s, &mut rng);
        pairs[j] = (s.position, s.normal);
    }
    match Receiver::from_pairs(pairs.iter().copied()) {
        Err(Error::InvalidReceiver { index, ref reason })
            if index == d.index && same_reason(reason, &want) => {}
        other => {
            return TestResult::error(format!(
                "from_pairs: expected {} {want:?}, got {other:?}",
                d.index
            ));
        }
    }
    let e = Receiver::from_pairs(pairs.iter().copied()).unwrap_err();
    if !e.to_string().starts_with(&format!("receiver {}: ", d.index)) {
        return TestResult::error(format!("message does not name the receiver: {e}"));
    }
    // Built alone, the receiver is number 0.
    let (p, n) = pairs[d.index];
    match Receiver::new(p, n) {
        Err(Error::InvalidReceiver { index: 0, ref reason }) if same_reason(reason, &want) => {
            TestResult::passed()
        }
        other => TestResult::error(format!("Receiver::new: expected {want:?}, got {other:?}")),
    }
}

#[test]
fn invalid_receivers_are_named_by_index() {
    qc(
        "receiver validation",
        prop_receiver_defect as fn(Defective) -> TestResult,
    );
}

#[test]
fn surfel_errors_fixed_cases() {
    let e = PointCloud::new(vec![ok(), Surfel { radius: -1.0, ..ok() }]).unwrap_err();
    assert_eq!(e.to_string(), "surfel 1: radius -1 is not positive");
    let e = PointCloud::new(vec![
        ok(),
        ok(),
        ok(),
        Surfel {
            position: Vec3::new(0.0, f32::NAN, 0.0),
            ..ok()
        },
    ])
    .unwrap_err();
    assert_eq!(
        e,
        Error::InvalidSurfel {
            index: 3,
            reason: Invalid::NonFinite { field: "position" }
        }
    );
    assert_eq!(e.to_string(), "surfel 3: position is not finite");
    // The tolerance on normals: |len² − 1| ≤ 1e-4 passes, more does not.
    for (len2, good) in [
        (1.0 + 5e-5f32, true),
        (1.0 - 5e-5, true),
        (1.0 + 3e-4, false),
        (1.0 - 3e-4, false),
    ] {
        let s = Surfel {
            normal: Vec3::new(0.0, 0.0, len2.sqrt()),
            ..ok()
        };
        assert_eq!(PointCloud::new(vec![s]).is_ok(), good, "normal length² {len2}");
    }
    // Tiny but positive radii (subnormal included) are valid.
    for r in [1e-40f32, f32::MIN_POSITIVE, 1e-30] {
        let cloud = PointCloud::new(vec![Surfel { radius: r, ..ok() }; 3]).unwrap();
        assert_eq!(Tree::build(&cloud).len(), 5);
    }
    let surfels = vec![
        ok(),
        Surfel {
            position: Vec3::X,
            normal: Vec3::new(0.6, 0.8, 0.0),
            ..ok()
        },
    ];
    assert_eq!(PointCloud::new(surfels.clone()).unwrap().surfels(), &surfels[..]);
}

#[test]
fn receiver_errors_fixed_cases() {
    let e = Receiver::from_pairs([(Vec3::ZERO, Vec3::Z), (Vec3::ZERO, Vec3::Z), (Vec3::NAN, Vec3::Z)])
        .unwrap_err();
    assert_eq!(
        e,
        Error::InvalidReceiver {
            index: 2,
            reason: Invalid::NonFinite { field: "position" }
        }
    );
    assert_eq!(e.to_string(), "receiver 2: position is not finite");
    let e = Receiver::new(Vec3::ZERO, Vec3::ZERO).unwrap_err();
    assert_eq!(
        e,
        Error::InvalidReceiver {
            index: 0,
            reason: Invalid::ZeroNormal
        }
    );
    let e =
        Receiver::from_pairs([(Vec3::ZERO, Vec3::Z), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0))]).unwrap_err();
    assert!(
        e.to_string().starts_with("receiver 1: normal has length 1.414"),
        "{e}"
    );
    assert_eq!(Receiver::from_pairs(std::iter::empty()).unwrap(), vec![]);
    let r = Receiver::new(Vec3::new(1.0, 2.0, 3.0), Vec3::Y).unwrap();
    assert_eq!((r.position(), r.normal()), (Vec3::new(1.0, 2.0, 3.0), Vec3::Y));
}

fn options(omega: f32, threshold: u32) -> CutOptions {
    CutOptions {
        max_solid_angle: omega,
        hybrid_threshold: threshold,
        ..CutOptions::default()
    }
}

#[test]
fn traversal_options_are_validated() {
    let tree = Tree::build(&PointCloud::new(vec![ok()]).unwrap());
    for omega in [f32::NAN, -1.0, -1e-30, f32::INFINITY, f32::NEG_INFINITY] {
        let e = Traversal::new(&tree, options(omega, 2)).unwrap_err();
        assert!(
            matches!(
                &e,
                Error::InvalidParameter {
                    name: "max_solid_angle",
                    ..
                }
            ),
            "Ω {omega}: {e:?}"
        );
        assert!(e.to_string().contains("max_solid_angle"), "{e}");
    }
    for threshold in [18, 19, u32::MAX] {
        let e = Traversal::new(&tree, options(0.05, threshold)).unwrap_err();
        assert!(
            matches!(&e, Error::InvalidParameter { name: "hybrid_threshold", value, .. } if *value == threshold.to_string()),
            "{e:?}"
        );
        assert!(e.to_string().contains("hybrid_threshold"), "{e}");
    }
    for (omega, threshold) in [
        (0.0, 0),
        (f32::MAX, 17),
        (1e-40, 1),
        (4.0 * std::f32::consts::PI, 16),
    ] {
        let t = Traversal::new(&tree, options(omega, threshold)).unwrap();
        assert_eq!(t.max_solid_angle(), omega);
        assert_eq!(t.tree().len(), 1);
    }
    // −0 is accepted and is the same threshold as 0.
    let recs = Receiver::from_pairs([(Vec3::Z, -Vec3::Z), (Vec3::new(0.0, 0.0, 0.05), -Vec3::Z)]).unwrap();
    let zero = Traversal::new(&tree, options(0.0, 2)).unwrap();
    let minus_zero = Traversal::new(&tree, options(-0.0, 2)).unwrap();
    for s in Scheme::ALL {
        assert_eq!(zero.cuts(s, &recs), minus_zero.cuts(s, &recs), "{s}");
    }
}

#[test]
fn isa_names_and_availability() {
    for bad in ["avx9", "", "sse", "neon2", "avx 2"] {
        let e = bad.parse::<Isa>().unwrap_err();
        assert_eq!(
            e,
            IsaError::Unknown {
                value: bad.to_string()
            }
        );
        assert!(e.to_string().contains(&format!("{bad:?}")), "{e}");
    }
    for isa in Isa::ALL {
        assert_eq!(isa.name().parse::<Isa>().unwrap(), isa);
        assert_eq!(isa.to_string().to_uppercase().parse::<Isa>().unwrap(), isa);
        assert_eq!(format!(" {isa} ").parse::<Isa>().unwrap(), isa);
    }
    assert_eq!("AVX-512".parse::<Isa>().unwrap(), Isa::Avx512);
    assert_eq!("scalar".parse::<Isa>().unwrap(), Isa::Portable);
    for s in Scheme::ALL {
        assert_eq!(s.name().parse::<Scheme>().unwrap(), s);
    }
    assert!(matches!(
        "quadtree".parse::<Scheme>(),
        Err(Error::UnknownScheme { .. })
    ));

    let available = Isa::available();
    assert_eq!(available.last(), Some(&Isa::Portable));
    assert_eq!(available[0], Isa::best());
    let tree = Tree::build(&PointCloud::new(vec![ok()]).unwrap());
    for isa in Isa::ALL {
        let r = Traversal::new(
            &tree,
            CutOptions {
                isa: Some(isa),
                ..Default::default()
            },
        );
        assert_eq!(isa.is_available(), available.contains(&isa));
        if isa.is_available() {
            assert_eq!(r.unwrap().isa(), isa);
            assert_eq!(isa.require(), Ok(isa));
        } else {
            // Asking for a path this CPU lacks is an error, never an illegal instruction.
            let e = r.unwrap_err();
            let expected = IsaError::Unavailable {
                requested: isa,
                available: available.clone(),
            };
            assert_eq!(e, Error::Isa(expected.clone()));
            assert!(e.to_string().contains(isa.name()), "{e}");
            assert_eq!(isa.require(), Err(expected));
        }
    }
    #[cfg(target_arch = "x86_64")]
    assert!(matches!(
        Isa::Neon.require(),
        Err(IsaError::Unavailable {
            requested: Isa::Neon,
            ..
        })
    ));
    #[cfg(target_arch = "aarch64")]
    for isa in [Isa::Avx2, Isa::Avx512] {
        assert!(matches!(isa.require(), Err(IsaError::Unavailable { .. })));
    }
    eprintln!("isa: paths {}", path_names());
}

#[test]
fn empty_cloud_gives_empty_cuts_everywhere() {
    let empty = Tree::build(&PointCloud::new(vec![]).unwrap());
    assert!(empty.is_empty());
    assert_eq!((empty.len(), empty.depth()), (0, 0));
    for count in [0usize, 1, 16, 17, 33] {
        let recs =
            Receiver::from_pairs((0..count).map(|i| (Vec3::new(i as f32, 1.0, 0.0), -Vec3::Y))).unwrap();
        for isa in Isa::available() {
            let t = Traversal::new(
                &empty,
                CutOptions {
                    isa: Some(isa),
                    hybrid_threshold: 17,
                    ..Default::default()
                },
            )
            .unwrap();
            for s in Scheme::ALL {
                let cuts = t.cuts(s, &recs);
                assert_eq!(cuts.len(), count, "{s} on {isa}");
                assert!(cuts.iter().all(|c| c.splats.is_empty() && c.discards.is_empty()));
                assert!(cuts.iter().all(|c| c.check(&empty).is_ok()));
                let mut rec = pbgi::CutRecorder::new(count);
                let stats = t.run(s, &recs, &mut rec);
                assert_eq!(
                    (stats.receivers, stats.node_tests),
                    (count as u64, 0),
                    "{s} on {isa}"
                );
            }
        }
    }
    eprintln!("empty cloud: paths {}", path_names());
}

#[test]
fn one_surfel_on_every_path() {
    let one = Tree::build(&PointCloud::new(vec![ok()]).unwrap());
    assert_eq!((one.len(), one.depth()), (1, 0));
    // (receiver, normal, splatted?) — the surfel sits at the origin facing +z.
    let cases = [
        (Vec3::Z, -Vec3::Z, true),                   // in front, facing it
        (-Vec3::Z, Vec3::Z, false),                  // behind it: faces away
        (Vec3::Z, Vec3::Z, false),                   // in front, looking away: below the horizon
        (Vec3::ZERO, Vec3::Z, true),                 // at its centre: d = 0
        (Vec3::new(5.0, 0.0, 0.0), -Vec3::X, true),  // edge on, in its plane
        (Vec3::new(0.0, 0.0, 1e6), -Vec3::Z, true),  // far away
        (Vec3::new(0.0, 0.0, -1e6), Vec3::Z, false), // far behind
    ];
    let recs = Receiver::from_pairs(cases.iter().map(|&(p, n, _)| (p, n))).unwrap();
    for isa in Isa::available() {
        for omega in [0.0, 0.05, 1e3] {
            let t = Traversal::new(
                &one,
                CutOptions {
                    isa: Some(isa),
                    max_solid_angle: omega,
                    ..Default::default()
                },
            )
            .unwrap();
            for s in Scheme::ALL {
                let cuts = t.cuts(s, &recs);
                for (i, (c, &(_, _, splat))) in cuts.iter().zip(&cases).enumerate() {
                    let want = if splat {
                        (vec![0], vec![])
                    } else {
                        (vec![], vec![0])
                    };
                    assert_eq!(
                        (c.splats.clone(), c.discards.clone()),
                        want,
                        "{s} on {isa}, case {i}"
                    );
                }
            }
        }
    }
    eprintln!("one surfel: paths {}", path_names());
}

#[test]
fn zero_receivers() {
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(500, 1));
    for isa in Isa::available() {
        let t = Traversal::new(
            &tree,
            CutOptions {
                isa: Some(isa),
                ..Default::default()
            },
        )
        .unwrap();
        for s in Scheme::ALL {
            assert!(t.cuts(s, &[]).is_empty());
            let stats = t.run(s, &[], &mut pbgi::SplatCounter::default());
            assert_eq!(stats, Default::default(), "{s} on {isa}");
        }
    }
}

/// A packet's cut holds 16 receivers (one bit each): a traversal of 32 into
/// one is refused, in release builds too, where it once folded receivers
/// 16–31 into lanes 0–15 and shaded them wrong without a word.
#[test]
fn a_packet_cut_refuses_more_than_sixteen_receivers() {
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(500, 1));
    let t = Traversal::new(&tree, CutOptions::default()).unwrap();
    let receivers: Vec<pbgi::Receiver> = (0..32)
        .map(|i| pbgi::Receiver::new(Vec3::new(0.5, 0.01 * i as f32, 0.5), Vec3::Y).unwrap())
        .collect();
    let mut cut = pbgi::microbuffer::PacketCut::new(&tree);
    t.run(Scheme::Packet, &receivers[..16], &mut cut);
    let refused = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        t.run(Scheme::Packet, &receivers, &mut cut);
    }));
    let message = refused.expect_err("32 receivers into one packet's cut");
    let message = message.downcast_ref::<String>().expect("a formatted message");
    assert!(
        message.contains("32 receivers for one call that takes at most 16"),
        "{message}"
    );
    // The same as an error, for embedders.
    assert_eq!(
        t.try_run(Scheme::Packet, &receivers, &mut cut).unwrap_err(),
        pbgi::Error::TooManyReceivers { given: 32, most: 16 }
    );
    // A receiver index past the packet is refused, not wrapped into lane 0.
    use pbgi::CutSink;
    let wrapped = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| cut.splat(16, 0)));
    assert!(wrapped.is_err(), "receiver 16 splatted into a packet's cut");
}

/// The shading entry points reject misuse with a typed error: a path this
/// CPU does not run (entering its clone would be undefined behaviour), more
/// than 16 buffers for one packet, fewer outputs or cuts than buffers.
#[test]
fn shading_calls_reject_misuse_with_errors() {
    use pbgi::microbuffer::{Convolution, MicroBuffer, PacketCut, shade_cuts, shade_packet};
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(500, 1));
    let absent = pbgi::Isa::ALL
        .into_iter()
        .find(|i| !i.is_available())
        .expect("no CPU runs all of AVX-512, AVX2 and NEON");
    let mut bufs = vec![MicroBuffer::new(8).unwrap(); 17];
    let mut out = vec![Vec3::ZERO; 17];
    let cuts = vec![vec![0]; 17];
    let mut cut = PacketCut::new(&tree);
    let isa = pbgi::Isa::best();
    let conv = Convolution::Irradiance;
    assert!(matches!(
        shade_cuts(absent, &mut bufs[..1], &tree, &cuts, conv, &mut out),
        Err(pbgi::Error::Isa(pbgi::IsaError::Unavailable { .. }))
    ));
    assert!(matches!(
        shade_packet(absent, &mut bufs[..1], &tree, &mut cut, conv, &mut out),
        Err(pbgi::Error::Isa(pbgi::IsaError::Unavailable { .. }))
    ));
    assert_eq!(
        shade_packet(isa, &mut bufs, &tree, &mut cut, conv, &mut out),
        Err(pbgi::Error::TooManyReceivers { given: 17, most: 16 })
    );
    assert!(matches!(
        shade_packet(isa, &mut bufs[..4], &tree, &mut cut, conv, &mut out[..3]),
        Err(pbgi::Error::InvalidParameter { name: "out", .. })
    ));
    assert!(matches!(
        shade_cuts(isa, &mut bufs[..4], &tree, &cuts[..3], conv, &mut out),
        Err(pbgi::Error::InvalidParameter { .. })
    ));
    assert_eq!(shade_cuts(isa, &mut bufs, &tree, &cuts, conv, &mut out), Ok(()));
}
