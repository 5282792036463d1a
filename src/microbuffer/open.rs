//! The sky by rays: through which part of each pixel a receiver sees the
//! environment, where the caller can tell by tracing the scene itself.
//!
//! The microbuffer's open part `1 − coverage` is a small difference of large
//! sums: a window's sky is a few per cent of the hemisphere, and any
//! coverage the cut gets wrong anywhere else (clusters behind a wall joining
//! its front layer, disks overhanging an opening's edge, gaps in a closed
//! wall) takes from it or adds to it. Sunlit rooms came out +11 % at the
//! defaults and −7 % at fine settings, an atrium's sky −46 %
//! (docs/lab/openings-exact.md). Whether a direction escapes is a question
//! about the scene's surfaces, not the surfels', so where a
//! [`NearField`] answers it, each pixel casts one ray through its centre,
//! and a pixel whose ray differs from a neighbour's (an opening's edge
//! crosses it), or whose ray escapes where a splat left a fragment (a jamb
//! seen edge-on, narrower than the pixel, or disks overhanging an edge),
//! casts one through each of its 16 sub-samples: the pixel's open part is
//! the fraction that escapes. A pixel open all through shows
//! the sky alone (the splats there are an opening's overhanging disks); one
//! open in part adds the sky through that part to its splats' light.

use glam::Vec3;

use super::fragments::Fragments;
use super::near::NearField;
use super::table::Table;
use crate::environment::Environment;

/// Per pixel of `t`, the fraction through which the environment shows from
/// the receiver at `position` with local frame `frame` (world space), into
/// `open`; left empty where `field` cannot tell. `frags`: the receiver's
/// fragments.
#[inline(always)]
pub(super) fn open(
    t: &Table,
    position: Vec3,
    frame: &[Vec3; 3],
    field: &dyn NearField,
    frags: &Fragments,
    open: &mut Vec<f32>,
) {
    let normal = frame[2];
    open.clear();
    for l in &t.dir {
        match field.escapes(position, normal, world(frame, l.x, l.y, l.z)) {
            Some(e) => open.push(if e { 1.0 } else { 0.0 }),
            None => {
                open.clear();
                return;
            }
        }
    }
    // Decided on the pixel-centre rays alone, then refined: a refined
    // pixel's fraction must not decide whether its neighbour is an edge.
    let mut refine = vec![false; open.len()];
    for &p in &frags.pixel {
        refine[p as usize] = open[p as usize] == 1.0;
    }
    for (p, r) in refine.iter_mut().enumerate() {
        *r |= edge(open, t.n, p);
    }
    for p in 0..open.len() {
        if !refine[p] {
            continue;
        }
        let [sx, sy, sz] = &t.sub[p];
        let mut escaped = 0u32;
        for k in 0..sx.len() {
            if field.escapes(position, normal, world(frame, sx[k], sy[k], sz[k])) == Some(true) {
                escaped += 1;
            }
        }
        open[p] = escaped as f32 / sx.len() as f32;
    }
}

/// The world direction of local `(x, y, z)` in `frame`, unit.
#[inline(always)]
fn world(frame: &[Vec3; 3], x: f32, y: f32, z: f32) -> Vec3 {
    (frame[0] * x + frame[1] * y + frame[2] * z).normalize()
}

/// Whether pixel `p` of the `n × n` grid differs from a 4-neighbour in `open`.
#[inline(always)]
fn edge(open: &[f32], n: usize, p: usize) -> bool {
    let (c, r, v) = (p % n, p / n, open[p]);
    (c > 0 && open[p - 1] != v)
        || (c + 1 < n && open[p + 1] != v)
        || (r > 0 && open[p - n] != v)
        || (r + 1 < n && open[p + n] != v)
}

/// `Σ f(p)·w(p)·(L(p) + sky(p)·open(p))` in pixel order, `L(p)` the
/// splats' light in pixel `p` where it is not open all through (a pixel
/// open all through shows the sky alone) and `w` its cosine weight.
#[inline(always)]
pub(super) fn light_and_sky(
    radiance: &[Vec3],
    weights: &[f32],
    open: &[f32],
    sky: &Sky,
    t: &Table,
    f: impl Fn(usize) -> Vec3,
) -> Vec3 {
    let mut e = Vec3::ZERO;
    for (p, ((l, w), o)) in radiance.iter().zip(weights).zip(open).enumerate() {
        if *o < 1.0 && *l != Vec3::ZERO {
            e += *l * f(p) * *w;
        }
        if *o > 0.0 {
            e += sky.at(t, p) * f(p) * (*o * *w);
        }
    }
    e
}

/// One for every pixel: irradiance's weight in [`light_and_sky`] (a
/// function, not a closure, so that it is inlined into the kernels' clones).
#[inline(always)]
pub(super) fn one(_: usize) -> Vec3 {
    Vec3::ONE
}

/// What a receiver's open pixels see: the environment, through the
/// receiver's frame (local x, y, z in world space).
pub(crate) struct Sky<'a> {
    pub environment: &'a Environment,
    pub frame: [Vec3; 3],
}

impl<'a> Sky<'a> {
    /// What a receiver with local frame `frame` sees through its open
    /// pixels: `environment`, or nothing (black).
    #[inline(always)]
    pub(crate) fn of(environment: Option<&'a Environment>, frame: [Vec3; 3]) -> Option<Self> {
        Some(Sky {
            environment: environment?,
            frame,
        })
    }

    /// The environment's radiance toward pixel `p`'s centre.
    #[inline(always)]
    pub(super) fn at(&self, t: &Table, p: usize) -> Vec3 {
        let l = t.dir[p];
        let d = self.frame[0] * l.x + self.frame[1] * l.y + self.frame[2] * l.z;
        self.environment.radiance(d)
    }
}
