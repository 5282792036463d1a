//! How a receiver's irradiance changes as it moves and turns, read off its
//! composed microbuffer: the gradients an irradiance cache extrapolates its
//! records by (Ward & Heckbert 1992), and the harmonic mean distance of
//! what the receiver sees, which bounds how far a record may serve
//! (Ward et al. 1988).
//!
//! **Translation**, in the boundary form of Ward & Heckbert's gradient: as
//! the receiver moves by `δ`, what a pixel sees at distance `d` slides
//! across the hemisphere by `−δ⊥/d`, so each edge between two pixels moves
//! and the brighter side gains what the darker loses:
//! `∇E = −Σ_edges (L_a − L_b) ∫cosθ m ds / min(d_a, d_b)`, `m` the unit
//! direction across the edge from `a` to `b` (the nearer side's edge is the
//! one that moves). A wall of one radiance has none, however near; the sky
//! (no distance) moves with the receiver.
//!
//! **Rotation**: turning the normal by `α` changes each pixel's cosine
//! weight by `α·∫ n × ω dω`, so `∇_r E = Σ L ∫ n × ω dω` and a record with
//! normal `n_i` serves normal `n` with `E + (n_i × n)·∇_r E`.

use glam::Vec3;

use super::compose::{self, Scratch, Site};
use super::fragments::Fragments;
use super::open::Sky;
use super::table::Table;
use crate::tree::Tree;

/// A receiver's irradiance gradients, per channel, in world space.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gradients {
    /// `∂E/∂x` per channel (red, green, blue): the change of `E` per unit
    /// of distance the receiver moves.
    pub translation: [Vec3; 3],
    /// Per channel, the change of `E` per radian the normal turns, about
    /// each axis: a receiver with normal `n_i` turned to `n` gains
    /// `(n_i × n)·rotation[c]`.
    pub rotation: [Vec3; 3],
    /// Harmonic mean distance to what the receiver sees, cosine-weighted
    /// (infinite where it sees only the sky).
    pub distance: f32,
}

impl Gradients {
    /// `e` (the receiver's irradiance) moved by `offset` and turned from
    /// normal `from` to normal `to`, per channel.
    #[inline]
    pub fn extrapolate(&self, e: Vec3, offset: Vec3, from: Vec3, to: Vec3) -> Vec3 {
        let turn = from.cross(to);
        let [t, r] = [self.translation, self.rotation];
        e + Vec3::new(
            t[0].dot(offset) + r[0].dot(turn),
            t[1].dot(offset) + r[1].dot(turn),
            t[2].dot(offset) + r[2].dot(turn),
        )
    }
}

/// The light pixel `p` of the composed `s` sends the receiver, the sky
/// through its open part included (the irradiance's sum), and the light it
/// shows: the same with its splats' coverage at most one. One surface's
/// splats overlap here and leave gaps there; the rotation follows the sum,
/// but the differences across the edges would follow the overlaps, not the
/// light.
#[inline]
fn light(t: &Table, s: &Scratch, site: &Site, sky: Option<&Sky>, p: usize) -> (Vec3, Vec3) {
    let (l, cover) = (s.radiance[p], s.cover[p]);
    let capped = if cover > 1.0 { l / cover } else { l };
    match (site.open, sky) {
        (Some(open), Some(sky)) if open[p] >= 1.0 => (sky.at(t, p), sky.at(t, p)),
        (Some(open), Some(sky)) => {
            let s = sky.at(t, p) * open[p];
            (l + s, capped * (1.0 - open[p]) + s)
        }
        (None, Some(sky)) => {
            let s = sky.at(t, p) * (1.0 - cover.clamp(0.0, 1.0));
            (l + s, capped + s)
        }
        _ => (l, capped),
    }
}

/// Local to world through the receiver's frame.
#[inline]
fn world(site: &Site, v: Vec3) -> Vec3 {
    site.frame[0] * v.x + site.frame[1] * v.y + site.frame[2] * v.z
}

/// The rotational gradient (per channel, world space) of the receiver
/// `site` whose pixels `s` holds composed with their radiance: what an
/// irradiance convolution leaves in its buffer, so the cache reads it
/// without composing again.
pub(super) fn rotation(t: &Table, s: &Scratch, site: &Site, sky: Option<&Sky>) -> [Vec3; 3] {
    let mut rotation = [Vec3::ZERO; 3];
    for p in 0..t.dir.len() {
        let sent = light(t, s, site, sky, p).0;
        for c in 0..3 {
            rotation[c] += t.turn[p] * sent[c];
        }
    }
    rotation.map(|v| world(site, v))
}

/// The gradients of the receiver `site` whose splats left `frags`, the
/// environment `sky` showing through its open pixels.
pub(super) fn gradients(
    t: &Table,
    frags: &Fragments,
    tree: &Tree,
    site: &Site,
    sky: Option<&Sky>,
    s: &mut Scratch,
) -> Gradients {
    compose::compose(t, frags, tree, site, true, true, s);
    let pixels = t.dir.len();
    let shown: Vec<Vec3> = (0..pixels).map(|p| light(t, s, site, sky, p).1).collect();
    // The inverse depth of what each pixel shows, where it shows anything.
    let inv: Vec<f32> = s
        .inverse
        .iter()
        .zip(&s.drawn)
        .map(|(i, d)| if *d > 0.0 { i / d } else { 0.0 })
        .collect();
    let n = t.n;
    let mut translation = [Vec3::ZERO; 3];
    let (mut weight, mut inverse) = (0.0f32, 0.0f32);
    for p in 0..pixels {
        let neighbours = [(p % n + 1 < n, p + 1), (p / n + 1 < n, p + n)];
        for ((inside, q), edge) in neighbours.into_iter().zip(t.edge[p]) {
            if !inside {
                continue;
            }
            let i = inv[p].max(inv[q]);
            if i > 0.0 {
                let step = (shown[p] - shown[q]) * i;
                for c in 0..3 {
                    translation[c] -= edge * step[c];
                }
            }
        }
        let w = t.cos_weight[p];
        weight += w;
        // As much of the pixel as its splats cover (their grown disks
        // reach sub-samples past their edges), unclamped as the
        // irradiance's sum is (one surface's disks overlap here and leave
        // gaps there).
        inverse += w * s.cover[p].max(0.0) * inv[p];
    }
    Gradients {
        translation: translation.map(|v| world(site, v)),
        rotation: rotation(t, s, site, sky),
        distance: if inverse > 0.0 {
            weight / inverse
        } else {
            f32::INFINITY
        },
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use crate::gather::{Gather, GatherOptions};
    use crate::points::{PointCloud, Surfel};
    use crate::polygon::projected_solid_angle;

    /// The wall `x = 1`, `y ∈ [−1, 1]`, `z ∈ [0.2, 1.2]`, facing −x, of
    /// radiance one, as surfels `s` apart whose disks tile it.
    fn wall(s: f32) -> PointCloud {
        let mut surfels = Vec::new();
        let (ny, nz) = ((2.0 / s).round() as usize, (1.0 / s).round() as usize);
        for i in 0..ny {
            for j in 0..nz {
                let position = glam::Vec3::new(1.0, -1.0 + (i as f32 + 0.5) * s, 0.2 + (j as f32 + 0.5) * s);
                surfels.push(Surfel {
                    position,
                    normal: -glam::Vec3::X,
                    radius: s / std::f32::consts::PI.sqrt(),
                    radiance: glam::Vec3::ONE,
                });
            }
        }
        PointCloud::new(surfels).unwrap()
    }

    /// The wall's exact irradiance at `p` with normal `n` (Lambert).
    fn exact(p: DVec3, n: DVec3) -> f64 {
        let corners = [(-1.0, 0.2), (1.0, 0.2), (1.0, 1.2), (-1.0, 1.2)];
        let poly: Vec<DVec3> = corners.iter().map(|&(y, z)| DVec3::new(1.0, y, z) - p).collect();
        projected_solid_angle(&poly, n)
    }

    /// `π / ∫ cosθ / r dω` over the wall (what sees nothing is infinitely
    /// far), by the midpoint rule.
    fn harmonic_distance(p: DVec3, n: DVec3) -> f64 {
        let (ny, nz) = (400, 200);
        let area = (2.0 / ny as f64) * (1.0 / nz as f64);
        let mut sum = 0.0;
        for i in 0..ny {
            for j in 0..nz {
                let q = DVec3::new(
                    1.0,
                    -1.0 + (i as f64 + 0.5) * 2.0 / ny as f64,
                    0.2 + (j as f64 + 0.5) / nz as f64,
                );
                let d = q - p;
                let r = d.length();
                let cos = (d.dot(n) / r).max(0.0);
                sum += cos / r * (d.x / r) / (r * r) * area;
            }
        }
        std::f64::consts::PI / sum
    }

    /// The exact gradient by central differences (f64).
    fn exact_gradient(p: DVec3, n: DVec3) -> (DVec3, DVec3) {
        let h = 1e-5;
        let axes = [DVec3::X, DVec3::Y, DVec3::Z];
        let t = axes.map(|a| (exact(p + a * h, n) - exact(p - a * h, n)) / (2.0 * h));
        // Turning `n` about axis `a` by ±h.
        let r = axes.map(|a| {
            let turn = |s: f64| (n + a.cross(n) * s).normalize();
            (exact(p, turn(h)) - exact(p, turn(-h))) / (2.0 * h)
        });
        (DVec3::from_array(t), DVec3::from_array(r))
    }

    /// Gathered gradients match the exact ones of a lit wall seen from a
    /// floor, moving toward it and along it, and turning, and the harmonic
    /// mean distance its quadrature; the gradients' error shrinks as the
    /// microbuffer and the surfels are refined.
    #[test]
    fn a_walls_gradients_match_lamberts_formula_and_converge() {
        let receivers = [
            (glam::Vec3::new(0.0, 0.0, 0.0), glam::Vec3::Z),
            (glam::Vec3::new(0.4, 0.3, 0.0), glam::Vec3::Z),
            (
                glam::Vec3::new(-0.5, -0.6, 0.1),
                glam::Vec3::new(0.3, 0.0, 1.0).normalize(),
            ),
        ];
        let mut errors = Vec::new();
        for (spacing, resolution) in [(0.04, 12), (0.02, 24), (0.01, 48)] {
            let tree = crate::Tree::build(&wall(spacing));
            let opts = GatherOptions {
                microbuffer: resolution,
                ..GatherOptions::default()
            };
            let gather = Gather::new(&tree, &opts).unwrap();
            let got = gather.irradiance_gradients(&receivers).unwrap();
            // Worst relative errors: E, distance, translation, rotation.
            let mut worst = [0.0f64; 4];
            for (&(p, n), (e, g)) in receivers.iter().zip(&got) {
                let (p, n) = (p.as_dvec3(), n.as_dvec3());
                let (t, r) = exact_gradient(p, n);
                // Only turns off the normal count.
                let tangent = |v: DVec3| v - n * v.dot(n);
                let rg = tangent(g.rotation[0].as_dvec3());
                let err = [
                    (f64::from(e.x) / exact(p, n) - 1.0).abs(),
                    (f64::from(g.distance) / harmonic_distance(p, n) - 1.0).abs(),
                    (g.translation[0].as_dvec3() - t).length() / t.length(),
                    (rg - tangent(r)).length() / tangent(r).length(),
                ];
                for (w, e) in worst.iter_mut().zip(err) {
                    *w = w.max(e);
                }
            }
            errors.push(worst);
        }
        eprintln!("worst errors (E, distance, translation, rotation), coarse to fine: {errors:?}");
        // E and the distance are within a percent at every level; the
        // rotation's error falls by about half as the pixels halve, the
        // translation's (the pixels' edges stand for the wall's) falls
        // toward the floor that capping each pixel's coverage at one leaves
        // (it lowers the overlaps of the wall's disks but not their gaps).
        for e in &errors {
            assert!(e[0] < 0.01 && e[1] < 0.01, "{errors:?}");
        }
        assert!(errors.windows(2).all(|w| w[1][3] < 0.7 * w[0][3]), "{errors:?}");
        assert!(errors.windows(2).all(|w| w[1][2] < 0.9 * w[0][2]), "{errors:?}");
        assert!(errors[2][2] < 0.1 && errors[2][3] < 0.01, "{errors:?}");
    }

    /// The rotational gradient the cache reads off a gather's own
    /// composition is the bits of the one a second composition gives.
    #[test]
    fn the_turning_read_after_a_gather_is_the_gradients_rotation() {
        let tree = crate::Tree::build(&wall(0.02));
        let gather = Gather::new(&tree, &GatherOptions::default()).unwrap();
        let receivers: Vec<_> = (0..16)
            .map(|k| {
                let p = glam::Vec3::new(-0.5 + 0.06 * k as f32, 0.3 - 0.04 * k as f32, 0.0);
                let n = glam::Vec3::new(0.02 * k as f32, 0.0, 1.0).normalize();
                crate::cut::Receiver::new(p, n).unwrap()
            })
            .collect();
        let mut g = gather.gatherer();
        g.cut(&receivers).unwrap();
        g.shade(crate::microbuffer::Convolution::Irradiance);
        for b in g.buffers().iter().take(receivers.len()) {
            let (read, again) = (b.turning(), b.gradients(&tree).rotation);
            assert_eq!(
                read.map(|v| v.to_array().map(f32::to_bits)),
                again.map(|v| v.to_array().map(f32::to_bits))
            );
            assert!(read[0].length() > 0.0);
        }
    }
}
