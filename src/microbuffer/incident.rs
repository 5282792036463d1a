//! The light a receiver's buffer composed, kept per pixel in the
//! receiver's frame: what a radiance record of the world-space cache holds,
//! so that a glossy lobe near it is convolved without a gather of its own
//! (the radiance cache of Křivánek et al. 2005, with the microbuffer itself
//! as the compact form).

use glam::Vec3;

use super::compose::{Scratch, Site, tilted_weights};
use super::open::Sky;
use super::table::Table;
use crate::brdf::GlossyLobe;

/// The receiver's tangent frame: local x, y, z (= `n`, unit) in world
/// space (Duff et al., "Building an orthonormal basis, revisited"). A
/// function of the normal alone, so a record's pixels keep their
/// directions without storing the frame.
#[inline(always)]
pub(crate) fn basis(n: Vec3) -> [Vec3; 3] {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    [t, bt, n]
}

/// Per pixel the radiance the composition `s` lets through to the receiver
/// `site`, the sky through its open part included: the terms `reflected`
/// weighs by a lobe, in its order (so a record convolved at its own place
/// gives the gather's glossy light, but for the sky's sum being held at
/// least zero there).
pub(super) fn incident(s: &Scratch, site: &Site, sky: Option<&Sky>, t: &Table, out: &mut Vec<Vec3>) {
    out.clear();
    out.extend((0..t.dir.len()).map(|p| {
        let l = s.radiance[p];
        match (site.open, sky) {
            (Some(open), Some(sky)) => {
                let o = open[p];
                let seen = if o < 1.0 { l } else { Vec3::ZERO };
                if o > 0.0 { seen + sky.at(t, p) * o } else { seen }
            }
            (None, Some(sky)) => l + sky.at(t, p) * (1.0 - s.cover[p]),
            _ => l,
        }
    }));
}

/// `Σ L·f_s(ωi, ωo)·∫cosθ dω` over the pixels `light` of a receiver facing
/// `normal` (its [`incident`] light, table `t`), for a lobe at a point with
/// shading normal `n` seen from `wo` (world, unit): the light a glossy
/// surface near the receiver reflects, none of it negative.
pub(crate) fn reflect(t: &Table, normal: Vec3, light: &[Vec3], lobe: &GlossyLobe, n: Vec3, wo: Vec3) -> Vec3 {
    let [x, y, z] = basis(normal);
    let mut e = Vec3::ZERO;
    for ((l, d), w) in light.iter().zip(&t.dir).zip(&t.cos_weight) {
        if *l != Vec3::ZERO {
            let wi = x * d.x + y * d.y + z * d.z;
            e += *l * lobe.eval(n, wo, wi) * *w;
        }
    }
    if e.is_nan() { e } else { e.max(Vec3::ZERO) }
}

/// `Σ L·∫max(0, s·ω) dω` over the pixels `light` of a receiver facing
/// `normal` (its [`incident`] light, table `t`): the irradiance about a
/// shading normal `s` (world, unit) that a bump or normal map tilts, the
/// pixels weighed as a gather tilted to `s` weighs them, none of it
/// negative.
pub(crate) fn tilted(t: &Table, normal: Vec3, light: &[Vec3], s: Vec3) -> Vec3 {
    let [x, y, z] = basis(normal);
    let local = Vec3::new(s.dot(x), s.dot(y), s.dot(z));
    let mut weights = Vec::with_capacity(light.len());
    tilted_weights(t, local, &mut weights);
    let mut e = Vec3::ZERO;
    for (l, w) in light.iter().zip(&weights) {
        e += *l * *w;
    }
    if e.is_nan() { e } else { e.max(Vec3::ZERO) }
}
