//! Gathers at the surfels: the environment's light (`--sky`, an envmap)
//! and extra bounces (`--bounces 2+`), each from the current cloud.

use glam::Vec3;

use super::surfel_groups::Groups;
use super::trace::Tracer;
use crate::error::Error;
use crate::gather::{Gather, GatherOptions};
use crate::microbuffer::{MicroBuffer, NearField, Sight};
use crate::points::{PointCloud, Surfel};
use crate::tree::Tree;
use rayon::prelude::*;

/// One more bounce at the surfels: each surfel's radiance becomes its direct
/// part plus `albedo/π · E`, with `E` gathered over `tree` (the current
/// cloud's) once per group of `groups`, with `rays` as the gather's near
/// field (the sky by rays) if given.
#[allow(clippy::too_many_arguments)]
pub(super) fn gather_bounce(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    tree: &Tree,
    groups: &Groups,
    opts: &GatherOptions,
    rays: Option<&dyn NearField>,
    tick: &(dyn Fn(usize, usize) + Sync),
) -> Result<PointCloud, Error> {
    let gather = Gather::new(tree, opts)?;
    let gather = match rays {
        Some(field) => gather.with_near_field(field),
        None => gather,
    };
    add_gathered(cloud, direct, albedo, groups, tick, |part| {
        gather.irradiance(part)
    })
}

/// The environment's light at the surfels, grouped as [`gather_bounce`]'s,
/// by rays alone (`rays` tells which directions leave the scene): with the
/// sky by rays, the surfels are no occluders the gather needs, so no cut
/// is taken and nothing is splatted (the same light as a gather over the
/// surfels made black, without its traversal and composition).
pub(super) fn gather_sky(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    groups: &Groups,
    opts: &GatherOptions,
    rays: &dyn NearField,
    tick: &(dyn Fn(usize, usize) + Sync),
) -> Result<PointCloud, Error> {
    let proto = MicroBuffer::new(opts.microbuffer)?.with_environment(opts.environment.clone());
    let empty = Tree::default();
    add_gathered(cloud, direct, albedo, groups, tick, |part| {
        Ok(part
            .par_chunks(64)
            .flat_map_iter(|chunk| {
                let mut mb = proto.clone();
                let empty = &empty;
                chunk.iter().map(move |&(p, n)| {
                    mb.reset(p, n);
                    mb.set_near_field(empty, rays);
                    mb.irradiance_inline(empty)
                })
            })
            .collect())
    })
}

/// Each surfel's radiance: its direct part plus `albedo/π · E`, `E` from
/// `gather` at its group's receiver (in runs of neighbours, the groups in
/// tree order, a progress report after each).
fn add_gathered(
    cloud: &PointCloud,
    direct: &[Vec3],
    albedo: &[Vec3],
    groups: &Groups,
    tick: &(dyn Fn(usize, usize) + Sync),
    gather: impl Fn(&[(Vec3, Vec3)]) -> Result<Vec<Vec3>, Error>,
) -> Result<PointCloud, Error> {
    let surfels = cloud.surfels();
    let (receivers, members) = (&groups.receivers, &groups.members);
    // A receiver's light is the same in any packet or run.
    let run = (receivers.len() / 64).max(4096);
    let mut gathered = Vec::with_capacity(receivers.len());
    tick(0, receivers.len());
    for part in receivers.chunks(run) {
        gathered.extend(gather(part)?);
        tick(gathered.len(), receivers.len());
    }
    let mut e = vec![Vec3::ZERO; surfels.len()];
    for (g, m) in gathered.iter().zip(members) {
        for &i in m {
            e[i as usize] = *g;
        }
    }
    let next: Vec<Surfel> = surfels
        .iter()
        .zip(&e)
        .zip(direct.iter().zip(albedo))
        .map(|((s, e), (d, a))| Surfel {
            radiance: (*d + *a * std::f32::consts::FRAC_1_PI * *e).max(Vec3::ZERO),
            ..*s
        })
        .collect();
    PointCloud::new(next)
}

/// The sky by rays alone, for the surfels' gathers (they have no near
/// field): which directions leave the scene.
#[derive(Clone, Copy)]
pub(super) struct SkyRays<'a>(pub &'a Tracer);

impl NearField for SkyRays<'_> {
    fn trace(&self, _: Vec3, _: Vec3, _: Vec3, _: f32) -> Option<Vec3> {
        None
    }

    fn near_leaves(&self) -> bool {
        false
    }

    fn escapes(&self, origin: Vec3, normal: Vec3, dir: Vec3) -> Option<bool> {
        Some(self.0.escapes(origin, normal, dir))
    }

    fn escapes_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<bool>) -> bool {
        self.0.escapes_each(origin, normal, dirs, out);
        true
    }

    fn sight_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<Sight>) -> bool {
        self.0.sight_each(origin, normal, dirs, out);
        true
    }
}
