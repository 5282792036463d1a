//! Extra bounces at the surfels (`--bounces 2+`): each gathers at every
//! surfel from the current cloud and rebuilds the tree.

use glam::Vec3;

use crate::error::Error;
use crate::gather::{Gather, GatherOptions};
use crate::points::{PointCloud, Surfel};
use crate::tree::Tree;

/// One more bounce at the surfels: each surfel's radiance becomes its direct
/// part plus `albedo/π · E`, with `E` gathered from the current cloud.
pub(super) fn gather_bounce(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    tree: &Tree,
    opts: &GatherOptions,
) -> Result<PointCloud, Error> {
    let gather = Gather::new(tree, opts)?;
    let surfels = cloud.surfels();
    // The receivers sit a hair above their surfel so it does not see itself edge-on.
    let receivers: Vec<(Vec3, Vec3)> = surfels
        .iter()
        .map(|s| (s.position + s.normal * (s.radius * 1e-3), s.normal))
        .collect();
    let gathered = gather.irradiance(&receivers)?;
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
