//! Composing a pixel from its fragments, and the convolutions that read the
//! composed pixels: the one place both shading pipelines resolve a
//! microbuffer, so they give the same bits by construction.
//!
//! A splat leaves one fragment in each pixel it touches: its depth, its node
//! and the fraction of the pixel it covers. Composition works on the pixel's
//! 4×4 sub-samples, one per lane (`samples`): each fragment's coverage is
//! spread over the sub-samples its footprint covers, with a depth interval
//! at each (the node's plane along the sub-sample's ray, widened by how far
//! the footprint's placement may be off; a cluster that faces several ways
//! shows each facet's disk on its plane, or, curved, a cone `±R` deep).
//! At each sub-sample the *front layer* is every fragment
//! whose interval reaches the nearest fragment's, unless a fragment drawn
//! there hides it: its centre lies behind that one's plane, and not the
//! other way round (`samples::hidden_by`): one surface, seen through
//! several splats, whose coverage adds unclamped (the disks of a surface
//! tile it about once, so a clamp at one would lose the overlaps and keep
//! the gaps). Everything behind adds through `1 − κ·coverage` of the front
//! layer (opaque at half coverage: a surface's splats leave gaps that would
//! let light leak through), and not at all where a front splat's grown disk
//! hides it (`samples`: fine sub-samples resolve the gaps between splats,
//! where coverage alone let a light behind a slab through, more so as N
//! grew). A pixel is the mean of its sub-samples.
//!
//! Why sub-samples: a pixel's fragments swept into layers by chaining
//! overlapping `[d − R, d + R]` intervals merged a block's top with the lit
//! floor behind it (the Cornell box's indirect light +1.4 % too bright, the
//! nave's +7 %), and a half-covered layer hid a whole pixel of light at a
//! silhouette. Where in the pixel a fragment lies, and its plane's depth
//! there, separate both (`docs/lab/exact/findings.md`).
//!
//! The fragments of a pixel are taken in a canonical order, `(node,
//! coverage)`, so the `f32` sums depend on the set of splats only, not on
//! the order a traversal scheme reported them in; no depth sort is needed.

use glam::Vec3;
use std::simd::prelude::*;

use super::fragments::Fragments;
use super::near::{Near, coplanar};
use super::open::{self, Sky};
use super::samples::{Facets, Packed, Pixel, SAMPLES, Shape, facets, hidden_by, lanes, wholly_behind};
use super::table::Table;
use crate::simd::{F32s, M32s, Real, sum};
use crate::tree::Tree;

/// How much of what lies behind the front layer it hides per unit of
/// coverage.
const KAPPA: f32 = 2.0;

/// A fragment in the canonical order: `(node, coverage bits)` as one key
/// (equal keys are the same node twice in one pixel: the same fragment),
/// and the fragment's index.
type Sorted = (u64, u32);

/// Moves `v[root]` down the max-heap `v[..end]`.
#[inline(always)]
fn sift(v: &mut [Sorted], mut root: usize, end: usize) {
    loop {
        let mut child = 2 * root + 1;
        if child >= end {
            break;
        }
        if child + 1 < end && v[child].0 < v[child + 1].0 {
            child += 1;
        }
        if v[root].0 >= v[child].0 {
            break;
        }
        v.swap(root, child);
        root = child;
    }
}

/// Sorts a pixel's fragments by key: insertion sort for the usual few
/// dozen (mostly in order already: splats arrive about in node order), heap
/// sort for long buckets (written out: a sort taking a closure would be
/// compiled out of line, for the baseline target, not the kernel's clone).
#[inline(always)]
fn sort(v: &mut [Sorted]) {
    if v.len() <= 48 {
        for i in 1..v.len() {
            let x = v[i];
            let mut j = i;
            while j > 0 && x.0 < v[j - 1].0 {
                v[j] = v[j - 1];
                j -= 1;
            }
            v[j] = x;
        }
        return;
    }
    let n = v.len();
    for i in (0..n / 2).rev() {
        sift(v, i, n);
    }
    for end in (1..n).rev() {
        v.swap(0, end);
        sift(v, 0, end);
    }
}

/// The receiver a microbuffer belongs to: its position and local frame
/// (x, y, z = normal, in world space).
pub(crate) struct Site<'a> {
    pub position: Vec3,
    pub frame: [Vec3; 3],
    /// Leaves drawn by rays, and what each pixel's ray met (`near`).
    pub near: Option<&'a Near>,
    /// Per pixel, its open part by rays (`open`); `None`: `1 − coverage`.
    pub open: Option<&'a [f32]>,
    /// The normal irradiance is convolved about (local frame), if not +z.
    pub shading: Option<Vec3>,
}

/// The composition's working memory, kept by a microbuffer from one
/// receiver to the next: a receiver's composition allocated its nine arrays
/// anew each time (and grew three of them by doubling), a tenth of the
/// 16-lane pipeline's time in the allocator. Holds no state between
/// receivers: every array is cleared or overwritten before it is read.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    /// One shape per splat (its fragments are consecutive), and the
    /// facets of the mixed ones.
    shapes: Vec<Packed>,
    /// Per shape: left out for the near field's rays.
    skipped: Vec<bool>,
    /// Per shape, where depths are asked: on the receiver's own surface.
    own: Vec<bool>,
    mixed: Vec<Facets>,
    /// Per fragment: its splat's shape.
    shape_of: Vec<u32>,
    /// Per pixel: where its bucket starts (and the next free slot).
    start: Vec<u32>,
    next: Vec<u32>,
    /// The fragments bucketed by pixel.
    sorted: Vec<Sorted>,
    /// One pixel's fragments at its sub-samples.
    seen: Vec<Seen>,
    /// The fragments behind the front layer that the fragment nearest in
    /// depth cannot hide: their coverage there, and where they are in
    /// `seen`.
    backs: Vec<(F32s, u32)>,
    /// The composed pixels: per pixel the effective coverage and the
    /// radiance it lets through (empty when only coverage was asked for).
    pub cover: Vec<f32>,
    pub radiance: Vec<Vec3>,
    /// Per pixel `∫ max(0, n·ω) dω` about a tilted normal (`Site::shading`).
    tilted: Vec<f32>,
    /// Per pixel, where asked (`compose`'s `depths`): the sum of `1/d` over
    /// its sub-samples that show a fragment, `d` the nearest one's depth
    /// there, and how many do, both as fractions of the pixel.
    pub inverse: Vec<f32>,
    pub drawn: Vec<f32>,
}

/// A fragment at a pixel's sub-samples: its `Lanes` less the far depth
/// (coverage, near depth, plane, body), its index, and three masks as bits
/// (a pixel's fragments are copied once and read twice): where it is drawn
/// (covers or hides), where it hides, and where it hides what lies behind
/// the front layer (once that is known). A tuple of `std` types: a vector
/// of a type of ours would grow through a function named after it, out of
/// line, which `scripts/check-asm.sh` rightly cannot tell from kernel code.
type Seen = (F32s, F32s, [F32s; 4], [F32s; 4], u32, [u16; 3]);

/// [`Seen`]'s masks: drawn, hides, hides behind the front layer.
const DRAWN: usize = 0;
const HIDE: usize = 1;
const HIDES: usize = 2;

/// A mask from its bits.
#[inline(always)]
fn mask(bits: u16) -> M32s {
    M32s::from_bitmask(u64::from(bits))
}

/// A mask's bits.
#[inline(always)]
fn bits(m: M32s) -> u16 {
    m.to_bitmask() as u16
}

/// The lanes' mean, as a fraction of the pixel (`simd::sum`: summed one
/// lane after the other, the four means of each pixel were four chains of
/// sixteen dependent additions, a twentieth of the 16-lane pipeline's time).
#[inline(always)]
fn mean(v: F32s) -> f32 {
    sum(v) * (1.0 / SAMPLES as f32)
}

/// Composes every pixel of `t` from `frags` (in any order), seen from
/// `site`, into `s.cover` (and `s.radiance`); returns the brightest
/// radiance among the fragments, per channel. `radiance`: also sum the
/// nodes' radiance (occlusion needs none); `depths`: also the inverse
/// depths of what the pixels show (`Scratch::inverse`, the gradients').
#[inline(always)]
pub(crate) fn compose(
    t: &Table,
    frags: &Fragments,
    tree: &Tree,
    site: &Site,
    radiance: bool,
    depths: bool,
    s: &mut Scratch,
) -> Vec3 {
    let (pixels, n) = (t.dir.len(), frags.len());
    let Scratch {
        shapes,
        skipped,
        own,
        mixed,
        shape_of,
        start,
        next,
        sorted,
        seen,
        backs,
        cover: out_cover,
        radiance: out_radiance,
        tilted: _,
        inverse: out_inverse,
        drawn: out_drawn,
    } = s;
    // One shape per splat (its fragments are consecutive). With the
    // radiance, the brightest the nodes hold: their own radiance, not the
    // radiance they show (a cluster's light-centroid scale, `locate`, may
    // show more than its surfels send, which the irradiance's bound must
    // not follow).
    shapes.clear();
    skipped.clear();
    own.clear();
    mixed.clear();
    shape_of.clear();
    let mut brightest = Vec3::ZERO;
    let mut last = None;
    for &key in &frags.key {
        let node = (key & 0xFFFF_FFFF) as u32;
        if last != Some(node) {
            if radiance {
                brightest = brightest.max(brightest_of(tree, node));
            }
            let index = match facets(tree, node, site.position, &site.frame) {
                Some(f) => {
                    mixed.push(f);
                    mixed.len() as u32 - 1
                }
                None => u32::MAX,
            };
            let shape = Shape::of(tree, node, site.position, &site.frame, t.n, t.half_sample, index);
            shapes.push(shape.pack());
            skipped.push(site.near.is_some_and(|n| n.skips(node)));
            if depths {
                own.push(coplanar(tree, node, site.position, site.frame[2]));
            }
            last = Some(node);
        }
        shape_of.push(shapes.len() as u32 - 1);
    }
    if let (true, Some(near)) = (radiance, site.near) {
        for l in near.pixels.iter().flatten() {
            brightest = brightest.max(*l);
        }
    }
    // Bucket by pixel (a counting sort: O(n)).
    start.clear();
    start.resize(pixels + 1, 0);
    for &p in &frags.pixel {
        start[p as usize + 1] += 1;
    }
    for p in 0..pixels {
        start[p + 1] += start[p];
    }
    next.clear();
    next.extend_from_slice(start);
    sorted.clear();
    sorted.resize(n, (0, 0));
    for i in 0..n {
        let slot = &mut next[frags.pixel[i] as usize];
        let node = frags.key[i] & 0xFFFF_FFFF;
        sorted[*slot as usize] = (node << 32 | u64::from(frags.cover[i].to_bits()), i as u32);
        *slot += 1;
    }
    out_cover.clear();
    out_cover.resize(pixels, 0.0);
    out_radiance.clear();
    out_radiance.resize(if radiance { pixels } else { 0 }, Vec3::ZERO);
    if depths {
        out_inverse.clear();
        out_inverse.resize(pixels, 0.0);
        out_drawn.clear();
        out_drawn.resize(pixels, 0.0);
    }
    let zero = F32s::splat(0.0);
    for p in 0..pixels {
        // A near surface met by the pixel's ray hides everything else.
        if let Some(l) = site.near.and_then(|n| n.pixels[p]) {
            out_cover[p] = 1.0;
            if radiance {
                out_radiance[p] = l;
            }
            if let (true, Some(near)) = (depths, site.near) {
                // The hit lies within the rays' reach (its distance is not
                // kept): the nearest it can be seen as is the reach.
                out_inverse[p] = 1.0 / near.reach;
                out_drawn[p] = 1.0;
            }
            continue;
        }
        let bucket = &mut sorted[start[p] as usize..start[p + 1] as usize];
        if bucket.is_empty() {
            continue;
        }
        sort(bucket);
        let [sx, sy, sz] = &t.sub[p];
        let px = Pixel {
            col: (p % t.n) as f32,
            row: (p / t.n) as f32,
            ux: F32s::from_array(*sx),
            uy: F32s::from_array(*sy),
            uz: F32s::from_array(*sz),
            size: t.pixel_size[p] * 0.25,
        };
        // At each sub-sample: the far depth of the fragment whose interval
        // starts nearest, and the plane and body of the one whose depth is
        // nearest (a surface seen at a grazing angle has a wide interval,
        // whose start may come before the facing surface in front of it).
        seen.clear();
        let (mut nearest, mut reach) = (F32s::splat(f32::INFINITY), F32s::splat(f32::INFINITY));
        let mut plane = [zero, zero, zero, F32s::splat(f32::NEG_INFINITY)];
        let mut body = [zero; 4];
        let mut depth = F32s::splat(f32::INFINITY);
        // The same, without the receiver's own surface (its splats lie at
        // the horizon a few radii away, and move with it).
        let mut shown = depth;
        for &(_, i) in bucket.iter() {
            let k = shape_of[i as usize] as usize;
            if skipped[k] {
                continue;
            }
            let shape = Shape::unpack(&shapes[k]);
            let l = lanes(&shape, &px, frags.cover[i as usize], mixed);
            let drawn = zero.simd_lt(l.cover) | l.hide;
            let nearer = drawn & l.near.simd_lt(nearest);
            nearest = F32s::select(nearer, l.near, nearest);
            reach = F32s::select(nearer, l.far, reach);
            let mid = (l.near + l.far) * F32s::splat(0.5);
            let closer = drawn & mid.simd_lt(depth);
            depth = F32s::select(closer, mid, depth);
            if depths && !own[k] {
                shown = F32s::select(drawn & mid.simd_lt(shown), mid, shown);
            }
            for c in 0..4 {
                plane[c] = F32s::select(closer, l.plane[c], plane[c]);
                body[c] = F32s::select(closer, l.body[c], body[c]);
            }
            seen.push((
                l.cover,
                l.near,
                l.plane,
                l.body,
                i,
                [bits(drawn), bits(l.hide), 0],
            ));
        }
        // The front layer (what reaches that far depth and is not hidden),
        // what it hides outright, and what lies behind it. Hidden: by the
        // fragment nearest in depth; where that one is spared (two faces of
        // a convex corner, each behind the other's plane: rare, so the
        // search is), by any other fragment drawn there.
        let (mut front, mut behind) = (zero, zero);
        let (mut lf, mut lb) = ([zero; 3], [zero; 3]);
        let mut hidden = M32s::splat(false);
        backs.clear();
        for k in 0..seen.len() {
            let e = &seen[k];
            let (own, at) = (&e.2, &e.3);
            // Where the fragment nearest in depth lies wholly behind this
            // one's plane (it can hide none of it).
            let beside = wholly_behind(own, &body);
            let back = wholly_behind(&plane, at);
            let spared = back & beside;
            let mut hid = back & !beside;
            if spared.any() {
                for f in seen.iter() {
                    hid |= spared & mask(f.5[DRAWN]) & hidden_by(&f.2, &f.3, own, at);
                }
            }
            let in_front = e.1.simd_le(reach) & !hid;
            let h = mask(e.5[HIDE]) & in_front;
            hidden |= h;
            let a = F32s::select(in_front, e.0, zero);
            let b = e.0 - a;
            front += a;
            let odd = (b.simd_ne(zero) & beside).any();
            if odd {
                backs.push((b, k as u32));
            } else {
                behind += b;
            }
            if radiance {
                let r = frags.radiance[e.4 as usize];
                for c in 0..3 {
                    lf[c] += a * F32s::splat(r[c]);
                    if !odd {
                        lb[c] += b * F32s::splat(r[c]);
                    }
                }
            }
            seen[k].5[HIDES] = bits(h);
        }
        let open = (F32s::splat(1.0) - F32s::splat(KAPPA) * front).simd_max(zero);
        let through = F32s::select(hidden, zero, open);
        let mut cover = front + through * behind;
        let mut light = [
            lf[0] + through * lb[0],
            lf[1] + through * lb[1],
            lf[2] + through * lb[2],
        ];
        // What lies behind where the fragment nearest in depth lies wholly
        // behind its plane: hidden only where a front splat that can hide
        // it does (a block's top, whose grown disks reach past its edge,
        // cannot hide its side).
        for &(b, k) in backs.iter() {
            let e = &seen[k as usize];
            let mut hid = M32s::splat(false);
            for f in seen.iter() {
                hid |= mask(f.5[HIDES]) & !wholly_behind(&e.2, &f.3);
            }
            let t = F32s::select(hid, zero, open) * b;
            cover += t;
            if radiance {
                let r = frags.radiance[e.4 as usize];
                for c in 0..3 {
                    light[c] += t * F32s::splat(r[c]);
                }
            }
        }
        out_cover[p] = mean(cover);
        if depths {
            let some = shown.simd_lt(F32s::splat(f32::INFINITY));
            out_inverse[p] = mean(F32s::select(some, F32s::splat(1.0) / shown, zero));
            out_drawn[p] = mean(F32s::select(some, F32s::splat(1.0), zero));
        }
        if radiance {
            out_radiance[p] = Vec3::new(mean(light[0]), mean(light[1]), mean(light[2]));
        }
    }
    brightest
}
/// The brightest radiance node `node` holds: its mean, or a mixed
/// cluster's brightest facet.
#[inline(always)]
fn brightest_of(tree: &Tree, node: u32) -> Vec3 {
    let mut b = if (node as usize) < tree.len() {
        tree.radiance(node)
    } else {
        Vec3::ZERO
    };
    if let Some(f) = tree.cluster_of(node).map(|c| c.get()) {
        for g in &f.facet {
            b = b.max(Vec3::new(g[3], g[4], g[5]));
        }
    }
    b
}

/// Irradiance `Σ radiance·∫cos dω` over the pixels, in pixel order, plus
/// what `sky` (radiance toward pixel `p`, and its largest) sends through the
/// open part of the pixels (by rays, `open`, else `1 − coverage`); at most `π` times the brightest
/// radiance splatted or seen: the unclamped layers of a receiver enclosed by
/// surfaces whose splats overlap may cover a little more than the
/// hemisphere, and where that radiance is uniform the exact answer is the
/// bound itself.
#[inline(always)]
pub(crate) fn irradiance(
    t: &Table,
    frags: &Fragments,
    tree: &Tree,
    site: &Site,
    sky: Option<&Sky>,
    scratch: &mut Scratch,
) -> Vec3 {
    let mut brightest = compose(t, frags, tree, site, true, false, scratch);
    let weights = match site.shading {
        None => &t.cos_weight,
        Some(n) => {
            tilted_weights(t, n, &mut scratch.tilted);
            &scratch.tilted
        }
    };
    let (cover, radiance) = (&scratch.cover, &scratch.radiance);
    let mut e = Vec3::ZERO;
    if let (Some(open), Some(sky)) = (site.open, sky) {
        let e = open::light_and_sky(radiance, weights, open, sky, t, open::one);
        brightest = brightest.max(sky.environment.max_radiance());
        return at_most(e, brightest * std::f32::consts::PI);
    }
    for (l, w) in radiance.iter().zip(weights) {
        e += *l * *w;
    }
    if let Some(sky) = sky {
        // Unclamped per pixel: the layers' coverage overshoots one in some
        // pixels as it falls short in others (splats do not tile exactly),
        // and only the sum is right, as occlusion's is; an enclosed
        // receiver's sum may dip below zero, where no sky is seen.
        let mut open = Vec3::ZERO;
        for (p, (cover, w)) in cover.iter().zip(weights).enumerate() {
            open += sky.at(t, p) * ((1.0 - cover) * w);
        }
        e += at_least_zero(open);
        brightest = brightest.max(sky.environment.max_radiance());
    }
    at_most(e, brightest * std::f32::consts::PI)
}

/// Per pixel `∫ max(0, n·ω) dω` for local unit `n`, by the pixel's 4×4
/// sub-sample directions (each a sixteenth of its solid angle). Inlined
/// into the shading clones, as everything they run.
#[inline(always)]
pub(super) fn tilted_weights(t: &Table, n: Vec3, out: &mut Vec<f32>) {
    out.clear();
    for (sub, omega) in t.sub.iter().zip(&t.solid_angle) {
        let count = sub[0].len();
        let mut sum = 0.0f32;
        for ((x, y), z) in sub[0].iter().zip(&sub[1]).zip(&sub[2]) {
            sum += (n.x * x + n.y * y + n.z * z).max(0.0);
        }
        out.push(sum * (omega / count as f32));
    }
}

/// `v.max(0)`, but a NaN stays NaN: glam's `max` would return the zero and
/// hide a defect upstream from the renderer's finiteness checks.
#[inline(always)]
pub(super) fn at_least_zero(v: Vec3) -> Vec3 {
    if v.is_nan() { v } else { v.max(Vec3::ZERO) }
}

/// `v.min(bound)`, but a NaN or an infinity stays as it is (glam's `min`
/// would return the bound), so that the caller's check names the receiver.
#[inline(always)]
pub(super) fn at_most(v: Vec3, bound: Vec3) -> Vec3 {
    if v.is_finite() { v.min(bound) } else { v }
}

/// Ambient occlusion `Σ coverage·∫cos dω / π`, at most 1.
#[inline(always)]
pub(crate) fn occlusion(
    t: &Table,
    frags: &Fragments,
    tree: &Tree,
    site: &Site,
    scratch: &mut Scratch,
) -> f32 {
    compose(t, frags, tree, site, false, false, scratch);
    let mut o = 0.0f32;
    for (c, w) in scratch.cover.iter().zip(&t.cos_weight) {
        o += c * w;
    }
    let o = o * std::f32::consts::FRAC_1_PI;
    // `f32::min` would turn a NaN into 1.
    if o.is_nan() { o } else { o.min(1.0) }
}

/// `Σ radiance·f(ωi)·∫cos dω` with `f` evaluated at each pixel's centre
/// direction (`wi(p)`, world space), and `sky` through the open part of
/// each pixel as in [`irradiance`].
pub(crate) fn reflected(
    t: &Table,
    frags: &Fragments,
    tree: &Tree,
    site: &Site,
    f: impl Fn(usize) -> Vec3,
    sky: Option<&Sky>,
    c: &mut Scratch,
) -> Vec3 {
    compose(t, frags, tree, site, true, false, c);
    let mut e = Vec3::ZERO;
    if let (Some(open), Some(sky)) = (site.open, sky) {
        return open::light_and_sky(&c.radiance, &t.cos_weight, open, sky, t, f);
    }
    for (p, (l, w)) in c.radiance.iter().zip(&t.cos_weight).enumerate() {
        if *l != Vec3::ZERO {
            e += *l * f(p) * *w;
        }
    }
    if let Some(sky) = sky {
        // As in `irradiance`: unclamped per pixel, the sum at least zero.
        let mut open = Vec3::ZERO;
        for (p, (cover, w)) in c.cover.iter().zip(&t.cos_weight).enumerate() {
            open += sky.at(t, p) * f(p) * ((1.0 - cover) * w);
        }
        e += at_least_zero(open);
    }
    e
}
