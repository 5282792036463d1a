//! Gathering at the probes with the library's public pipelines, and the
//! error against the exact values.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;

use super::Probe;
use crate::brdf::GlossyLobe;
use crate::environment::Environment;
use crate::microbuffer::{
    Convolution, MicroBuffer, MicroBufferSink, NearField, PacketCut, Sight, shade_packet_near,
};
use crate::{CutOptions, Error, LANES, Receiver, Scheme, Traversal, Tree};

/// What a gather computes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Quantity {
    /// Irradiance (first channel).
    Irradiance,
    /// Ambient occlusion.
    Occlusion,
    /// Glossy reflection towards each probe's `wo` (scalar pipeline only:
    /// the 16-lane one has no glossy convolution).
    Glossy(GlossyLobe),
}

/// How to gather.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherSettings {
    /// Ω of the cut.
    pub max_solid_angle: f32,
    /// The weight of a node's light offset in the cut
    /// ([`CutOptions::light_offset`]).
    pub light_offset: f32,
    /// Microbuffer resolution N.
    pub resolution: usize,
    /// The 16-lane shading pipeline ([`shade_packet`](crate::microbuffer::shade_packet), what the renderer
    /// runs) rather than the scalar one ([`MicroBufferSink`]).
    pub lanes: bool,
    /// Traversal scheme.
    pub scheme: Scheme,
    /// The uniform sky the open pixels see (the scene's [`ExactScene::sky`](super::ExactScene::sky)).
    pub sky: f32,
}

/// Gathers `what` at every probe, on this thread; returns the values and
/// the time taken (traversal, splatting and convolution).
pub fn gather(
    tree: &Tree,
    probes: &[Probe],
    what: Quantity,
    g: &GatherSettings,
) -> Result<(Vec<f64>, Duration), Error> {
    gather_with_rays(tree, probes, what, g, None)
}

/// [`gather`], with `rays` as each receiver's near field: the scene itself
/// (an [`ExactScene`](super::ExactScene), which tells which rays escape)
/// shows where the sky is, rather than what the cut leaves open.
pub fn gather_with_rays(
    tree: &Tree,
    probes: &[Probe],
    what: Quantity,
    g: &GatherSettings,
    rays: Option<&dyn NearField>,
) -> Result<(Vec<f64>, Duration), Error> {
    let t = Traversal::new(
        tree,
        CutOptions {
            max_solid_angle: g.max_solid_angle,
            light_offset: g.light_offset,
            ..Default::default()
        },
    )?;
    let receivers = Receiver::from_pairs(probes.iter().map(|p| (p.position, p.normal)))?;
    let sky = (g.sky > 0.0)
        .then(|| Environment::uniform(Vec3::splat(g.sky)).map(Arc::new))
        .transpose()?;
    let mut bufs = vec![MicroBuffer::new(g.resolution)?.with_environment(sky); LANES];
    let mut cut = PacketCut::new(tree);
    let mut out = Vec::with_capacity(probes.len());
    let mut values = [Vec3::ZERO; LANES];
    let start = Instant::now();
    for (chunk, pr) in receivers.chunks(LANES).zip(probes.chunks(LANES)) {
        let bufs = &mut bufs[..chunk.len()];
        for (b, r) in bufs.iter_mut().zip(chunk) {
            b.reset(r.position(), r.normal());
        }
        let conv = match what {
            Quantity::Irradiance => Convolution::Irradiance,
            _ => Convolution::Occlusion,
        };
        if g.lanes && !matches!(what, Quantity::Glossy(_)) {
            t.run(g.scheme, chunk, &mut cut);
            shade_packet_near(t.isa(), bufs, tree, &mut cut, conv, rays, &mut values)?;
            out.extend(values[..chunk.len()].iter().map(|v| v.x as f64));
        } else {
            t.run(g.scheme, chunk, &mut MicroBufferSink { tree, buffers: bufs });
            if let Some(field) = rays {
                for b in bufs.iter_mut() {
                    b.set_near_field(tree, field);
                }
            }
            out.extend(bufs.iter().zip(pr).map(|(b, p)| match what {
                Quantity::Irradiance => b.irradiance(tree).x as f64,
                Quantity::Occlusion => b.occlusion(tree) as f64,
                Quantity::Glossy(lobe) => b.glossy(tree, p.wo, &lobe).x as f64,
            }));
        }
    }
    Ok((out, start.elapsed()))
}

/// Error of gathered values against exact ones, relative per receiver.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// `√ mean((g − e)/e)²`.
    pub rel_rmse: f64,
    /// `mean (g − e)/e`.
    pub bias: f64,
    /// `max |g − e|/e`.
    pub max: f64,
}

/// [`Stats`] of `gathered` against `exact` (receivers with `exact ≤ 0` are skipped).
pub fn stats(gathered: &[f64], exact: &[f64]) -> Stats {
    let (mut s2, mut s1, mut max, mut n) = (0.0, 0.0, 0.0f64, 0usize);
    for (&g, &e) in gathered.iter().zip(exact) {
        if e > 0.0 {
            let r = (g - e) / e;
            s2 += r * r;
            s1 += r;
            max = max.max(r.abs());
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    Stats {
        rel_rmse: (s2 / n).sqrt(),
        bias: s1 / n,
        max,
    }
}

/// The scene itself along a receiver's rays: which directions see the sky
/// (its cells, holes let through). No near field: the leaves stay drawn.
impl NearField for super::ExactScene {
    fn trace(&self, _: Vec3, _: Vec3, _: Vec3, _: f32) -> Option<Vec3> {
        None
    }

    fn near_leaves(&self) -> bool {
        false
    }

    fn escapes(&self, origin: Vec3, _normal: Vec3, dir: Vec3) -> Option<bool> {
        Some(self.escapes(origin, dir))
    }

    fn sight_each(&self, origin: Vec3, _normal: Vec3, dirs: &[Vec3], out: &mut Vec<Sight>) -> bool {
        out.clear();
        out.extend(dirs.iter().map(|&d| self.sight(origin, d)));
        true
    }
}
