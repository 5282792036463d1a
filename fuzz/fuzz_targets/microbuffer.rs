//! Splatting and convolution on structured clouds (see `shapes.rs`): the cut
//! of a real traversal, or an arbitrary list of nodes (parents and children
//! together, repeats), at resolutions 1 to 256. Irradiance finite, ≥ 0 and at
//! most π·max L per channel (coverage ≤ 1 per pixel, Σ∫cosθ dω = π; plus
//! rounding, absolute for subnormal radiance), ambient
//! occlusion in [0, 1], the glossy convolution finite and ≥ 0, and the
//! shading of a cut the same bit for bit (irradiance, occlusion, glossy) on
//! every scheme and path through both shading pipelines: the scalar one
//! (`shade_cuts`) and the 16-lane one (`shade_packet`).
#![no_main]

mod shapes;

use arbitrary::Arbitrary;
use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use pbgi::brdf::GlossyLobe;
use pbgi::microbuffer::{Convolution, MicroBuffer, MicroBufferSink, PacketCut, shade_cuts, shade_packet};
use pbgi::{CutOptions, CutSink, Isa, NodeId, PointCloud, Receiver, Scheme, Traversal, Tree};
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

/// One receiver's cut in traversal order, as the scalar pipeline takes it.
struct List(Vec<NodeId>);

impl CutSink for List {
    fn splat(&mut self, _receiver: usize, node: NodeId) {
        self.0.push(node);
    }
}

/// What both pipelines are compared on: irradiance and occlusion from the
/// pipeline's convolution, glossy from the buffer it splatted.
type Bits = [u32; 7];

struct Probe<'a> {
    tree: &'a Tree,
    proto: &'a MicroBuffer,
    receiver: Receiver,
    lobe: GlossyLobe,
    wo: Vec3,
}

impl Probe<'_> {
    fn fresh(&self) -> [MicroBuffer; 1] {
        let mut b = [self.proto.clone()];
        b[0].reset(self.receiver.position(), self.receiver.normal());
        b
    }

    fn bits(&self, e: Vec3, ao: Vec3, b: &MicroBuffer) -> Bits {
        let g = b.glossy(self.tree, self.wo, &self.lobe);
        [e.x, e.y, e.z, ao.x, g.x, g.y, g.z].map(f32::to_bits)
    }

    /// The scalar pipeline on `cut`.
    fn scalar(&self, isa: Isa, cut: &[NodeId]) -> Bits {
        let cuts = [cut.to_vec()];
        let (mut e, mut ao) = ([Vec3::ZERO], [Vec3::ZERO]);
        let mut b = self.fresh();
        shade_cuts(isa, &mut b, self.tree, &cuts, Convolution::Occlusion, &mut ao).unwrap();
        let mut b = self.fresh();
        shade_cuts(isa, &mut b, self.tree, &cuts, Convolution::Irradiance, &mut e).unwrap();
        self.bits(e[0], ao[0], &b[0])
    }

    /// The 16-lane pipeline on `cut` (the receiver in lane 0).
    fn lanes(&self, isa: Isa, cut: &PacketCut) -> Bits {
        let (mut e, mut ao) = ([Vec3::ZERO], [Vec3::ZERO]);
        let mut b = self.fresh();
        shade_packet(isa, &mut b, self.tree, &mut cut.clone(), Convolution::Occlusion, &mut ao).unwrap();
        let mut b = self.fresh();
        shade_packet(isa, &mut b, self.tree, &mut cut.clone(), Convolution::Irradiance, &mut e).unwrap();
        self.bits(e[0], ao[0], &b[0])
    }
}

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
    let wo = shapes::direction(input.wo, &[]).try_normalize().unwrap_or(receiver.normal());
    let proto = MicroBuffer::new(res).expect("resolution in range");
    let probe = Probe {
        tree: &tree,
        proto: &proto,
        receiver,
        lobe,
        wo,
    };
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
                // Every scheme's cut on every path is compared as a list (the
                // traversal target checks cuts in depth); each path shades
                // through both pipelines, and the best path shades every
                // scheme's packet cut (how the schemes fill a packet's cut
                // differs). Fewer shadings than all of them keep N 256
                // within the unit timeout.
                let mut shaded = None;
                let mut reference: Option<Vec<NodeId>> = None;
                let best = Isa::best();
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
                        let mut list = List(Vec::new());
                        t.run(scheme, &[receiver], &mut list);
                        let mut sorted = list.0.clone();
                        sorted.sort_unstable();
                        assert_eq!(
                            reference.get_or_insert(sorted.clone()),
                            &sorted,
                            "{scheme} on {isa}: another cut"
                        );
                        let mut shadings = Vec::new();
                        if scheme == Scheme::Scalar {
                            shadings.push(("scalar", probe.scalar(isa, &list.0)));
                        }
                        if scheme == Scheme::Packet || isa == best {
                            let mut packet = PacketCut::new(&tree);
                            t.run(scheme, &[receiver], &mut packet);
                            shadings.push(("16-lane", probe.lanes(isa, &packet)));
                        }
                        for (pipeline, got) in shadings {
                            assert_eq!(
                                *shaded.get_or_insert(got),
                                got,
                                "{scheme} on {isa}, {pipeline} pipeline, shades differently"
                            );
                        }
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
                // A node near the receiver covers every pixel: at most 2¹⁹
                // fragments a composition (128 splats at N 64, 8 at N 256;
                // 256 repeats of one node at N 256 took 25 s a unit under
                // the sanitizer, past libFuzzer's timeout, and 16 took 10 s).
                let most = (128 * 64 * 64 / (res * res)).clamp(1, 256);
                let nodes: Vec<NodeId> = nodes.iter().take(most).map(|&k| k as u32 % tree.len() as u32).collect();
                for &k in &nodes {
                    mb.splat(&tree, k);
                }
                // Both pipelines on the list without repeats (a packet's cut
                // holds a node once), on every path.
                let mut once = Vec::new();
                let mut packet = PacketCut::new(&tree);
                for &k in &nodes {
                    if !once.contains(&k) {
                        once.push(k);
                        packet.splat(0, k);
                    }
                }
                let want = probe.scalar(Isa::Portable, &once);
                for isa in Isa::available() {
                    for (pipeline, got) in [("scalar", probe.scalar(isa, &once)), ("16-lane", probe.lanes(isa, &packet))] {
                        assert_eq!(got, want, "nodes {once:?} on {isa}, {pipeline} pipeline, shade differently");
                    }
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
    let g = mb.glossy(&tree, wo, &probe.lobe);
    assert!(g.is_finite() && g.min_element() >= 0.0, "glossy {g}");
});
