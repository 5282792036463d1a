//! Splatting and convolution on structured clouds (see `shapes.rs`): the cut
//! of a real traversal, or an arbitrary list of nodes (parents and children
//! together, repeats), at resolutions 1 to 256. Irradiance finite, ≥ 0 and at
//! most π·max L per channel (coverage ≤ 1 per pixel, Σ∫cosθ dω = π; plus
//! rounding, absolute for subnormal radiance), ambient
//! occlusion in [0, 1], the glossy convolution finite and ≥ 0, and the
//! shading of a cut the same bit for bit on every scheme and path.
#![no_main]

mod shapes;

use arbitrary::Arbitrary;
use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use pbgi::brdf::GlossyLobe;
use pbgi::microbuffer::{MicroBuffer, MicroBufferSink};
use pbgi::{CutOptions, Isa, PointCloud, Receiver, Scheme, Traversal, Tree};
use shapes::{Dir, OMEGAS, Pos, Scalar, SurfelSpec};

#[derive(Arbitrary, Debug)]
enum Splats {
    /// The cut of a traversal with this Ω.
    Cut(Scalar),
    /// These nodes (modulo the tree size), in this order.
    Nodes(Vec<u16>),
}

#[derive(Arbitrary, Debug)]
struct Input {
    surfels: Vec<SurfelSpec>,
    receiver: (Pos, Dir),
    splats: Splats,
    resolution: u8,
    roughness: Scalar,
    wo: Dir,
}

const RESOLUTIONS: [usize; 10] = [1, 2, 3, 4, 5, 8, 16, 32, 64, 256];

fuzz_target!(|input: Input| {
    let res = RESOLUTIONS[input.resolution as usize % RESOLUTIONS.len()];
    // The largest rasters cost 10⁵ pixels a splat: fewer surfels there.
    let surfels = shapes::surfels(&input.surfels, if res >= 64 { 60 } else { 500 });
    let Ok(cloud) = PointCloud::new(surfels) else {
        return;
    };
    let tree = Tree::build(&cloud);
    let (p, n) = input.receiver;
    let Ok(receiver) = Receiver::new(
        shapes::position(p, cloud.surfels()),
        shapes::direction(n, cloud.surfels()),
    ) else {
        return;
    };
    let proto = MicroBuffer::new(res).expect("resolution in range");
    let mut mb = proto.clone();
    mb.reset(receiver.position(), receiver.normal());
    if !tree.is_empty() {
        match &input.splats {
            Splats::Cut(omega) => {
                let opts = CutOptions {
                    max_solid_angle: omega.value(&OMEGAS),
                    ..Default::default()
                };
                let Ok(t) = Traversal::new(&tree, opts) else {
                    return;
                };
                let mut shaded = None;
                for isa in Isa::available() {
                    let t = Traversal::new(
                        &tree,
                        CutOptions {
                            isa: Some(isa),
                            ..opts
                        },
                    )
                    .expect("path available");
                    for scheme in Scheme::ALL {
                        let mut buffers = [proto.clone()];
                        buffers[0].reset(receiver.position(), receiver.normal());
                        let sink = &mut MicroBufferSink {
                            tree: &tree,
                            buffers: &mut buffers,
                        };
                        t.run(scheme, &[receiver], sink);
                        let e = buffers[0].irradiance(&tree).to_array().map(f32::to_bits);
                        assert_eq!(
                            *shaded.get_or_insert(e),
                            e,
                            "{scheme} on {isa} shades differently"
                        );
                    }
                }
                t.run(
                    Scheme::Scalar,
                    &[receiver],
                    &mut MicroBufferSink {
                        tree: &tree,
                        buffers: std::slice::from_mut(&mut mb),
                    },
                );
            }
            Splats::Nodes(nodes) => {
                for &k in nodes.iter().take(256) {
                    mb.splat(&tree, k as u32 % tree.len() as u32);
                }
            }
        }
    }
    let e = mb.irradiance(&tree);
    let lmax = cloud.surfels().iter().fold(Vec3::ZERO, |m, s| m.max(s.radiance));
    // Relative slack for the f32 sums; absolute slack for subnormal radiance,
    // where rounding is absolute (≤ 2⁻¹⁴⁹ a term, at most 5·256² terms).
    let bound = lmax * std::f32::consts::PI * 1.0001 + Vec3::splat(f32::MIN_POSITIVE);
    assert!(e.is_finite() && e.min_element() >= 0.0, "irradiance {e}");
    assert!(!e.cmpgt(bound).any(), "irradiance {e} above π·max L = {bound}");
    let ao = mb.occlusion(&tree);
    assert!((0.0..=1.0).contains(&ao), "occlusion {ao}");
    // A lobe as a valid scene gives it (roughness in (0, 1]).
    let roughness = input.roughness.value(&[0.01, 0.1, 0.5, 1.0, 1e-3]);
    let lobe = GlossyLobe {
        specular: Vec3::splat(0.5),
        roughness: if roughness > 0.0 && roughness <= 1.0 {
            roughness
        } else {
            0.5
        },
    };
    let wo = shapes::direction(input.wo, &[]);
    if let Some(wo) = wo.try_normalize() {
        let g = mb.glossy(&tree, wo, &lobe);
        assert!(g.is_finite() && g.min_element() >= 0.0, "glossy {g}");
    }
});
