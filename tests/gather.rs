//! The gather in one call (`pbgi::gather`): the bits of the kernels it
//! wraps, in any receiver order, scheme, path and thread count; normals a
//! little off unit length normalised, bad receivers typed errors naming them.

use crate::common;

use common::{GLOSSY_PROBES, Pipeline, Rng, shade_with};
use glam::Vec3;
use pbgi::brdf::GlossyLobe;
use pbgi::gather::{Gather, GatherOptions, GlossyReceiver, ReceiverOrder};
use pbgi::synthetic::{box_with_blocks, receivers as box_receivers};
use pbgi::{CutOptions, Error, Invalid, Isa, Receiver, Scheme, SchemeChoice, Tree};

fn bits(v: &[Vec3]) -> Vec<[u32; 3]> {
    v.iter().map(|e| e.to_array().map(f32::to_bits)).collect()
}

fn options(scheme: Scheme, isa: Isa, order: ReceiverOrder) -> GatherOptions {
    GatherOptions {
        cut: CutOptions {
            isa: Some(isa),
            ..Default::default()
        },
        scheme: SchemeChoice::Fixed(scheme),
        order,
        ..Default::default()
    }
}

/// A box with blocks and receivers on its walls and blocks, shuffled (the
/// order a file might give them in).
fn scene() -> (Tree, Vec<Receiver>) {
    let tree = Tree::build(&box_with_blocks(if common::reduced() { 600 } else { 3000 }, 3));
    let mut receivers = box_receivers(13, 0.2, 0.3, 7);
    receivers.truncate(if common::reduced() { 40 } else { 200 });
    let mut rng = Rng::new(5);
    for i in (1..receivers.len()).rev() {
        receivers.swap(i, rng.below(i + 1));
    }
    (tree, receivers)
}

fn pairs(receivers: &[Receiver]) -> Vec<(Vec3, Vec3)> {
    receivers.iter().map(|r| (r.position(), r.normal())).collect()
}

#[test]
fn irradiance_occlusion_and_glossy_are_the_kernels_bits_in_any_order() {
    let (tree, receivers) = scene();
    let omega = CutOptions::default().max_solid_angle;
    let want = shade_with(
        &tree,
        &receivers,
        omega,
        24,
        Scheme::Scalar,
        Isa::Portable,
        Pipeline::Scalar,
    )
    .unwrap();
    let want_e: Vec<Vec3> = want.iter().map(|s| s.irradiance).collect();
    let want_ao: Vec<u32> = want.iter().map(|s| s.occlusion.to_bits()).collect();
    let want_g: Vec<Vec3> = want.iter().map(|s| s.glossy[0]).collect();
    let (roughness, [x, y, z]) = GLOSSY_PROBES[0];
    let glossy: Vec<GlossyReceiver> = receivers
        .iter()
        .map(|r| {
            let n = r.normal();
            let t = n.any_orthonormal_vector();
            GlossyReceiver {
                position: r.position(),
                normal: n,
                wo: (t * x + n.cross(t) * y + n * z).normalize(),
                lobe: GlossyLobe {
                    specular: Vec3::ONE,
                    roughness,
                },
            }
        })
        .collect();
    for isa in Isa::available() {
        for scheme in Scheme::ALL {
            for order in [ReceiverOrder::Unordered, ReceiverOrder::Coherent] {
                let g = Gather::new(&tree, &options(scheme, isa, order)).unwrap();
                let path = g.path();
                assert_eq!((path.isa, path.scheme, path.order), (isa, scheme, order));
                let e = g.irradiance(&pairs(&receivers)).unwrap();
                assert_eq!(bits(&e), bits(&want_e), "irradiance: {path}");
                let ao: Vec<u32> = g
                    .occlusion(&pairs(&receivers))
                    .unwrap()
                    .iter()
                    .map(|a| a.to_bits())
                    .collect();
                assert_eq!(ao, want_ao, "occlusion: {path}");
                assert_eq!(bits(&g.glossy(&glossy).unwrap()), bits(&want_g), "glossy: {path}");
            }
        }
    }
    assert!(
        want_e.iter().any(|e| e.x > 0.0),
        "no light: the check proves nothing"
    );
}

/// With an environment (a lat-long map: each open pixel reads its own
/// texel), both pipelines on every path still give the same bits, and the
/// open sky adds light.
#[test]
fn an_environment_keeps_the_pipelines_bitwise_equal() {
    use pbgi::environment::{Environment, LatLong};
    use std::sync::Arc;
    let (tree, receivers) = scene();
    let texels = (0..64 * 32)
        .map(|i| Vec3::new((i % 64) as f32 / 64.0, (i / 64) as f32 / 32.0, 0.5))
        .collect();
    let env = Arc::new(Environment::LatLong(LatLong::new(64, 32, texels).unwrap()));
    let with = |scheme, isa| GatherOptions {
        environment: Some(env.clone()),
        ..options(scheme, isa, ReceiverOrder::Unordered)
    };
    let dark = Gather::new(
        &tree,
        &options(Scheme::Scalar, Isa::Portable, ReceiverOrder::Unordered),
    )
    .unwrap();
    let dark = dark.irradiance(&pairs(&receivers)).unwrap();
    let want = Gather::new(&tree, &with(Scheme::Scalar, Isa::Portable)).unwrap();
    let want = want.irradiance(&pairs(&receivers)).unwrap();
    assert!(
        want.iter().zip(&dark).any(|(a, b)| a.z > b.z),
        "the environment adds nothing: the check proves nothing"
    );
    for isa in Isa::available() {
        for scheme in Scheme::ALL {
            let g = Gather::new(&tree, &with(scheme, isa)).unwrap();
            assert_eq!(
                bits(&g.irradiance(&pairs(&receivers)).unwrap()),
                bits(&want),
                "{}",
                g.path()
            );
        }
    }
}

/// The caller's rayon pool runs the packets, and the thread count changes
/// nothing.
#[test]
fn any_pool_gives_the_same_bits() {
    let (tree, receivers) = scene();
    let g = Gather::new(&tree, &GatherOptions::default()).unwrap();
    let want = bits(&g.irradiance(&pairs(&receivers)).unwrap());
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (got, in_pool) = pool.install(|| {
            let got = g.irradiance(&pairs(&receivers)).unwrap();
            (got, rayon::current_num_threads())
        });
        assert_eq!(in_pool, threads);
        assert_eq!(bits(&got), want, "{threads} thread(s)");
    }
    // `GatherOptions::threads`: a pool of the gather's own, with no rayon
    // in the caller's code, and the same bits; 0 threads is an error
    // naming the option.
    for threads in [1, 2] {
        let opts = GatherOptions {
            threads: Some(threads),
            ..Default::default()
        };
        let g = Gather::new(&tree, &opts).unwrap();
        assert_eq!(
            bits(&g.irradiance(&pairs(&receivers)).unwrap()),
            want,
            "threads {threads}"
        );
    }
    let zero = GatherOptions {
        threads: Some(0),
        ..Default::default()
    };
    match Gather::new(&tree, &zero) {
        Err(pbgi::Error::InvalidParameter { name, .. }) => assert_eq!(name, "threads"),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("0 threads accepted"),
    }
}

#[test]
fn normals_a_little_off_are_normalised_and_bad_receivers_named() {
    let (tree, receivers) = scene();
    let g = Gather::new(&tree, &GatherOptions::default()).unwrap();
    let mut r = pairs(&receivers[..20]);
    let want = g.irradiance(&r).unwrap();
    // 0.5 % long: accepted, and shaded as the unit normal (up to rounding).
    r[3].1 *= 1.005;
    let got = g.irradiance(&r).unwrap();
    assert!(
        (got[3] - want[3]).abs().max_element() <= 1e-5 * want[3].max_element().max(1e-6),
        "{} vs {}",
        got[3],
        want[3]
    );
    // 5 % long: refused, naming the receiver.
    r[3].1 *= 1.05;
    assert_eq!(
        g.irradiance(&r).unwrap_err(),
        Error::InvalidReceiver {
            index: 3,
            reason: Invalid::NonUnitNormal {
                length: r[3].1.length()
            }
        }
    );
    r[3].1 = Vec3::ZERO;
    assert!(matches!(
        g.irradiance(&r),
        Err(Error::InvalidReceiver {
            index: 3,
            reason: Invalid::ZeroNormal
        })
    ));
    r[3].1 = Vec3::Y;
    r[7].0.y = f32::NAN;
    assert!(matches!(
        g.occlusion(&r),
        Err(Error::InvalidReceiver {
            index: 7,
            reason: Invalid::NonFinite { field: "position" }
        })
    ));
    let bad_wo = GlossyReceiver {
        position: Vec3::ZERO,
        normal: Vec3::Y,
        wo: Vec3::new(0.0, 2.0, 0.0),
        lobe: GlossyLobe {
            specular: Vec3::ONE,
            roughness: 0.5,
        },
    };
    assert!(matches!(
        g.glossy(&[bad_wo]),
        Err(Error::InvalidReceiver {
            index: 0,
            reason: Invalid::NonUnitDirection {
                field: "outgoing direction",
                ..
            }
        })
    ));
    assert_eq!(g.irradiance(&[]).unwrap(), Vec::<Vec3>::new());
}
