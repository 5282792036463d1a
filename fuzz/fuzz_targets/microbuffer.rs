//! Splatting arbitrary cuts of arbitrary clouds: irradiance finite, ≥ 0, and
//! bounded by π times the largest radiance (plus coverage rounding).
#![no_main]

use arbitrary::Arbitrary;
use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use pbgi::microbuffer::MicroBuffer;
use pbgi::{PointCloud, Surfel, Tree};

#[derive(Arbitrary, Debug)]
struct Input {
    surfels: Vec<([f32; 3], [f32; 3], f32, f32)>,
    receiver: ([f32; 3], [f32; 3]),
    splats: Vec<u16>,
    resolution: u8,
}

fuzz_target!(|input: Input| {
    let surfels: Vec<Surfel> = input
        .surfels
        .iter()
        .take(500)
        .map(|&(p, n, r, l)| Surfel {
            position: Vec3::from(p),
            normal: Vec3::from(n).try_normalize().unwrap_or(Vec3::Z),
            radius: r,
            radiance: Vec3::splat(l),
        })
        .collect();
    let Ok(cloud) = PointCloud::new(surfels) else { return };
    let tree = Tree::build(&cloud);
    let Ok(mut mb) = MicroBuffer::new(input.resolution as usize % 33) else { return };
    let (p, n) = (Vec3::from(input.receiver.0), Vec3::from(input.receiver.1));
    let (Some(n), true) = (n.try_normalize(), p.is_finite()) else { return };
    mb.reset(p, n);
    if tree.is_empty() {
        return;
    }
    for &k in &input.splats {
        mb.splat(&tree, k as u32 % tree.len() as u32);
    }
    let e = mb.irradiance(&tree);
    let lmax = cloud.surfels().iter().map(|s| s.radiance.x).fold(0.0f32, f32::max);
    assert!(e.is_finite() && e.min_element() >= 0.0, "irradiance {e}");
    assert!(e.x <= std::f32::consts::PI * lmax * 1.01 + 1e-30, "irradiance {e} above π·{lmax}");
    let ao = mb.occlusion();
    assert!((0.0..=1.0).contains(&ao), "occlusion {ao}");
});
