//! Arbitrary surfels, receivers and Ω: every scheme on every path this CPU
//! runs gives the scalar cut, the cut invariants hold, nothing panics.
#![no_main]

use arbitrary::Arbitrary;
use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use pbgi::{CutOptions, Isa, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};

#[derive(Arbitrary, Debug)]
struct Input {
    surfels: Vec<([f32; 3], [f32; 3], f32)>,
    receivers: Vec<([f32; 3], [f32; 3])>,
    omega: f32,
    threshold: u8,
}

fuzz_target!(|input: Input| {
    let surfels: Vec<Surfel> = input
        .surfels
        .iter()
        .take(2000)
        .map(|&(p, n, r)| Surfel {
            position: Vec3::from(p),
            normal: Vec3::from(n).try_normalize().unwrap_or(Vec3::Z),
            radius: r,
            radiance: Vec3::ONE,
        })
        .collect();
    // Invalid input must be an error, never a panic.
    let Ok(cloud) = PointCloud::new(surfels) else { return };
    let tree = Tree::build(&cloud);
    let pairs = input.receivers.iter().take(64).map(|&(p, n)| (Vec3::from(p), Vec3::from(n).try_normalize().unwrap_or(Vec3::Y)));
    let Ok(receivers) = Receiver::from_pairs(pairs) else { return };
    let mut reference = None;
    for isa in Isa::available() {
        let opts = CutOptions { max_solid_angle: input.omega, hybrid_threshold: input.threshold as u32 % 18, isa: Some(isa) };
        let Ok(t) = Traversal::new(&tree, opts) else { return };
        let scalar = t.cuts(Scheme::Scalar, &receivers);
        for c in &scalar {
            c.check(&tree).expect("cut invariants");
        }
        for scheme in [Scheme::Single, Scheme::Packet, Scheme::Hybrid] {
            assert_eq!(t.cuts(scheme, &receivers), scalar, "{scheme} on {isa} differs from scalar");
        }
        match &reference {
            None => reference = Some(scalar),
            Some(r) => assert_eq!(r, &scalar, "scalar on {isa} differs from the first path"),
        }
    }
});
