//! Extra bounces at the surfels (`--bounces 2+`): each gathers at every
//! surfel from the current cloud and rebuilds the tree.

use glam::Vec3;
use rayon::prelude::*;

use super::options::RenderOptions;
use super::packets::PacketCuts;
use crate::cut::{Receiver, Scheme, Traversal};
use crate::error::Error;
use crate::microbuffer::{Convolution, MicroBuffer};
use crate::points::{PointCloud, Surfel};
use crate::simd::LANES;
use crate::tree::Tree;

/// One more bounce at the surfels: each surfel's radiance becomes its direct
/// part plus `albedo/π · E`, with `E` gathered from the current cloud.
pub(super) fn gather_bounce(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    tree: &Tree,
    scheme: Scheme,
    opts: &RenderOptions,
) -> Result<PointCloud, Error> {
    let traversal = Traversal::new(tree, opts.cut)?;
    let surfels = cloud.surfels();
    // The receivers sit a hair above their surfel so it does not see itself edge-on.
    let receivers: Vec<Receiver> = surfels
        .iter()
        .map(|s| Receiver::new(s.position + s.normal * (s.radius * 1e-3), s.normal))
        .collect::<Result<_, _>>()?;
    let proto = MicroBuffer::new(opts.microbuffer)?;
    // The surfels' packets (tree order: neighbours) through the scheme's
    // shading pipeline, as in `Frame::shade`.
    let isa = traversal.isa();
    let gathered: Vec<Vec3> = receivers
        .par_chunks(LANES)
        .map_init(
            || (PacketCuts::for_scheme(scheme, tree), vec![proto.clone(); LANES]),
            |(cuts, buffers), chunk| {
                cuts.run(&traversal, scheme, chunk);
                let buffers = &mut buffers[..chunk.len()];
                for (b, r) in buffers.iter_mut().zip(chunk) {
                    b.reset(r.position(), r.normal());
                }
                cuts.shade(isa, tree, buffers, Convolution::Irradiance)
            },
        )
        .flatten_iter()
        .collect();
    let next: Vec<Surfel> = surfels
        .iter()
        .zip(&gathered)
        .zip(direct.iter().zip(albedo))
        .map(|((s, e), (d, a))| Surfel {
            radiance: (*d + *a * std::f32::consts::FRAC_1_PI * *e).max(Vec3::ZERO),
            ..*s
        })
        .collect();
    PointCloud::new(next)
}
