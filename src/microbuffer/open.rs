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
//! [`NearField`] answers it, each pixel casts one ray through its centre.
//! A pixel refines, casting one ray through each of its 16 sub-samples,
//! where its ray differs from one of its 8 neighbours' (an opening's edge
//! or corner crosses it), where its ray escapes past a splat's fragment (a
//! jamb seen edge-on, narrower than the pixel, or disks overhanging an
//! edge), and where its ray or a neighbour's meets a surface edge-on (an
//! opening in that surface may lie between the pixels' centres: from a
//! receiver 8 cm from a window's wall, the window is a band of directions
//! 4° wide, which no centre of a 10° pixel met). The pixel's open part is
//! the fraction that escapes. A pixel on a smooth surface's silhouette
//! against the sky, with no edged surface on it or on a neighbour that
//! differs from it, casts 4 of the
//! 16 ([`SILHOUETTE`]): an opening's sky is bounded by its edges, so its
//! edge pixels carry much of its light, but a smooth body's silhouette
//! bounds the body, and its pixels are a small share of the sky beside it.
//! A pixel open all through shows the sky alone
//! (the splats there are an opening's overhanging disks); one open in part
//! adds the sky through that part to its splats' light.
//!
//! A receiver's rays go to the field in two batches, the centres and then
//! the sub-samples ([`NearField::sight_each`], [`NearField::escapes_each`]),
//! so that the renderer's tracer can try the triangles that stopped the
//! last rays before its tree.

use glam::Vec3;

use super::fragments::Fragments;
use super::near::{NearField, Sight};
use super::table::{Table, unmap};
use crate::environment::Environment;
use crate::simd::LANES;

/// A pixel whose centre ray meets a surface within this cosine of edge-on
/// refines: its footprint there is over four times as long as face-on,
/// long enough to hold an opening that every pixel centre misses (a window
/// in the wall beside a receiver is a thin band of directions along that
/// wall).
const GRAZING: f32 = 0.25;

/// A pixel whose centre ray meets a surface within a quarter of
/// [`GRAZING`] refines on a `DEEP × DEEP` grid, not on its 16 sub-samples.
const DEEP: usize = 8;

/// The sub-samples a pixel on a smooth surface's silhouette casts (indices
/// into the 4×4 grid, row by row): one in each row, each column and each
/// quadrant, so a vertical or horizontal edge through the pixel is met at
/// four offsets and an edge of any other slope at two at least.
const SILHOUETTE: [usize; 4] = [1, 7, 8, 14];

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
    // Plain loops, not iterator adaptors: their closures would be compiled
    // out of line for the baseline target, outside the kernels' clones.
    let mut dirs = Vec::with_capacity(t.dir.len());
    for l in &t.dir {
        dirs.push(world(frame, l.x, l.y, l.z));
    }
    let mut sight = Vec::with_capacity(dirs.len());
    if !field.sight_each(position, normal, &dirs, &mut sight) {
        return;
    }
    // Decided on the pixel-centre rays alone, then refined: a refined
    // pixel's fraction must not decide whether its neighbour is an edge.
    // Pixels whose centre ray meets a surface edge-on, and their
    // neighbours (an opening seen edge-on may lie in a pixel whose own
    // centre ray passes beside the surface); the most edge-on more finely.
    let mut grazing = Vec::with_capacity(sight.len());
    let mut deep = Vec::with_capacity(sight.len());
    for s in &sight {
        let cos = match *s {
            Sight::Sky => {
                open.push(1.0f32);
                1.0
            }
            Sight::Surface { cos } => {
                open.push(0.0);
                cos
            }
            Sight::Smooth => {
                open.push(0.0);
                1.0
            }
        };
        grazing.push(if cos < GRAZING { 1.0f32 } else { 0.0 });
        deep.push(cos < GRAZING / 4.0);
    }
    let mut refine = Vec::with_capacity(open.len());
    for p in 0..open.len() {
        refine.push(grazing[p] == 1.0 || edge(&grazing, t.n, p));
    }
    let mut past = vec![false; open.len()];
    for &p in &frags.pixel {
        past[p as usize] |= open[p as usize] == 1.0;
    }
    // Pixels refined for a neighbour's sake or a fragment's, not for a
    // grazing hit, take the silhouette's 4 sub-samples where they lie on
    // a smooth surface's silhouette against the sky (a fragment there is
    // the body's own disks overhanging it); a fragment with no such
    // neighbour keeps 16.
    let mut silhouette = vec![false; open.len()];
    for (p, r) in refine.iter_mut().enumerate() {
        if *r {
            continue;
        }
        let beside = edge(open, t.n, p);
        if beside || past[p] {
            *r = true;
            silhouette[p] = beside && smooth(&sight, open, t.n, p);
        }
    }
    // Every refined pixel's sub-samples, in pixel order, as one batch.
    let mut refined = Vec::new();
    for (p, &r) in refine.iter().enumerate() {
        if r {
            refined.push(p);
        }
    }
    dirs.clear();
    let h = 2.0 / t.n as f64;
    for &p in &refined {
        if deep[p] {
            let (u0, v0) = (-1.0 + (p % t.n) as f64 * h, -1.0 + (p / t.n) as f64 * h);
            for j in 0..DEEP {
                for i in 0..DEEP {
                    let (u, v) = ((i as f64 + 0.5) / DEEP as f64, (j as f64 + 0.5) / DEEP as f64);
                    let l = unmap(u0 + u * h, v0 + v * h);
                    dirs.push(world(frame, l.x as f32, l.y as f32, l.z as f32));
                }
            }
            continue;
        }
        let [sx, sy, sz] = &t.sub[p];
        if silhouette[p] {
            for k in SILHOUETTE {
                dirs.push(world(frame, sx[k], sy[k], sz[k]));
            }
            continue;
        }
        for k in 0..LANES {
            dirs.push(world(frame, sx[k], sy[k], sz[k]));
        }
    }
    let mut escaped = Vec::with_capacity(dirs.len());
    if !field.escapes_each(position, normal, &dirs, &mut escaped) {
        open.clear();
        return;
    }
    let mut rest = escaped.as_slice();
    for &p in &refined {
        let k = if deep[p] {
            DEEP * DEEP
        } else if silhouette[p] {
            SILHOUETTE.len()
        } else {
            LANES
        };
        let (sub, more) = rest.split_at(k);
        rest = more;
        let mut n = 0u32;
        for &e in sub {
            n += e as u32;
        }
        open[p] = n as f32 / k as f32;
    }
    debug_assert!(rest.is_empty(), "every sub-sample ray is read");
}

/// The world direction of local `(x, y, z)` in `frame`, unit.
#[inline(always)]
fn world(frame: &[Vec3; 3], x: f32, y: f32, z: f32) -> Vec3 {
    (frame[0] * x + frame[1] * y + frame[2] * z).normalize()
}

/// Whether pixel `p` of the `n × n` grid differs from one of its 8
/// neighbours in `open` (a diagonal one too: an opening's corner may cut
/// a pixel whose 4 neighbours' centres it misses).
#[inline(always)]
fn edge(open: &[f32], n: usize, p: usize) -> bool {
    let ((rows, cols), v) = (around(n, p), open[p]);
    for rr in rows {
        for cc in cols.clone() {
            if open[rr * n + cc] != v {
                return true;
            }
        }
    }
    false
}

/// The rows and the columns of pixel `p` and its 8 neighbours in the
/// `n × n` grid.
#[inline(always)]
fn around(n: usize, p: usize) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let (c, r) = (p % n, p / n);
    (
        r.saturating_sub(1)..(r + 2).min(n),
        c.saturating_sub(1)..(c + 2).min(n),
    )
}

/// Whether pixel `p`, which differs from a neighbour in `open`, does so
/// only as the sky against a smooth surface: neither it nor any neighbour
/// that differs from it meets an edged surface ([`Sight::Surface`]), where
/// an opening may be.
#[inline(always)]
fn smooth(sight: &[Sight], open: &[f32], n: usize, p: usize) -> bool {
    if matches!(sight[p], Sight::Surface { .. }) {
        return false;
    }
    let ((rows, cols), v) = (around(n, p), open[p]);
    for rr in rows {
        for cc in cols.clone() {
            let q = rr * n + cc;
            if open[q] != v && matches!(sight[q], Sight::Surface { .. }) {
                return false;
            }
        }
    }
    true
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

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;

    /// Directions with local `x` above 0.3 meet a surface, smooth or edged;
    /// the others leave. Counts the sub-sample rays.
    struct Body {
        smooth: bool,
        rays: AtomicUsize,
    }

    impl NearField for Body {
        fn trace(&self, _: Vec3, _: Vec3, _: Vec3, _: f32) -> Option<Vec3> {
            None
        }

        fn escapes(&self, _: Vec3, _: Vec3, dir: Vec3) -> Option<bool> {
            Some(dir.x <= 0.3)
        }

        fn escapes_each(&self, _: Vec3, _: Vec3, dirs: &[Vec3], out: &mut Vec<bool>) -> bool {
            self.rays.fetch_add(dirs.len(), Ordering::Relaxed);
            out.clear();
            out.extend(dirs.iter().map(|d| d.x <= 0.3));
            true
        }

        fn sight_each(&self, _: Vec3, _: Vec3, dirs: &[Vec3], out: &mut Vec<Sight>) -> bool {
            out.clear();
            out.extend(dirs.iter().map(|d| match (d.x <= 0.3, self.smooth) {
                (true, _) => Sight::Sky,
                (false, true) => Sight::Smooth,
                (false, false) => Sight::Surface { cos: 1.0 },
            }));
            true
        }
    }

    /// The sub-sample rays the receiver at the origin facing +z casts, and
    /// its pixels' open parts.
    fn open_parts(t: &Table, smooth: bool, frags: &Fragments) -> (usize, Vec<f32>) {
        let body = Body {
            smooth,
            rays: AtomicUsize::new(0),
        };
        let mut parts = Vec::new();
        open(
            t,
            Vec3::ZERO,
            &[Vec3::X, Vec3::Y, Vec3::Z],
            &body,
            frags,
            &mut parts,
        );
        (body.rays.into_inner(), parts)
    }

    #[test]
    fn the_silhouettes_sub_samples_take_each_row_column_and_quadrant_once() {
        let cells = SILHOUETTE.map(|k| (k % 4, k / 4));
        for x in 0..4 {
            assert_eq!(
                cells.iter().filter(|c| c.0 == x).count(),
                1,
                "column {x}: {cells:?}"
            );
            assert_eq!(cells.iter().filter(|c| c.1 == x).count(), 1, "row {x}: {cells:?}");
            let quadrant = |c: &&(usize, usize)| (c.0 / 2) + 2 * (c.1 / 2) == x;
            assert_eq!(
                cells.iter().filter(quadrant).count(),
                1,
                "quadrant {x}: {cells:?}"
            );
        }
    }

    #[test]
    fn a_smooth_silhouette_casts_four_sub_samples_a_pixel_and_an_edged_one_sixteen() {
        let t = Table::new(14);
        let none = Fragments::default();
        let (edged_rays, edged) = open_parts(&t, false, &none);
        let (smooth_rays, smooth) = open_parts(&t, true, &none);
        // The same pixels refine, those beside the line x = 0.3: 16 rays
        // each against an edged surface, 4 against a smooth one.
        assert!(edged_rays > 0 && edged_rays % LANES == 0, "{edged_rays}");
        assert_eq!(smooth_rays, 4 * (edged_rays / LANES));
        let mut split = 0;
        for (p, (&e, &s)) in edged.iter().zip(&smooth).enumerate() {
            // The 4 are among the 16: a pixel all on one side is so in both.
            if e == 0.0 || e == 1.0 {
                assert_eq!(s, e, "pixel {p}");
            } else {
                split += 1;
                assert_eq!((s * 4.0).fract(), 0.0, "pixel {p}: {s} is no share of 4 rays");
            }
        }
        assert!(split > 0, "the line splits pixels");
    }

    #[test]
    fn a_fragment_beside_a_smooth_silhouette_takes_four_and_one_in_the_open_sky_sixteen() {
        let t = Table::new(14);
        let none = Fragments::default();
        let beside = open_parts(&t, false, &none).0 / LANES;
        // A fragment in every pixel: each open pixel refines, those beside
        // the line as before and the others for their fragment.
        let mut all = Fragments::default();
        for p in 0..t.n * t.n {
            all.push(p, 0, 0.5, [0.0; 3]);
        }
        let (edged, _) = open_parts(&t, false, &all);
        let (smooth, _) = open_parts(&t, true, &all);
        assert!(
            edged > beside * LANES,
            "fragments in the open sky refine: {edged}"
        );
        assert_eq!(smooth, edged - (LANES - SILHOUETTE.len()) * beside);
    }
}
