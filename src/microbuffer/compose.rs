//! Composing a pixel from its fragments, and the convolutions that read the
//! composed pixels: the one place both shading pipelines resolve a
//! microbuffer, so they give the same bits by construction.
//!
//! A splat leaves one fragment in each pixel it touches: its depth, its node
//! and the fraction of the pixel it covers. A pixel's fragments are sorted by
//! `(depth − R, depth, node, coverage)`, `R` the node's bounding radius: a
//! canonical order, so the composition depends on the set of splats only and
//! plain `f32` sums are deterministic. The sorted fragments are swept into
//! *layers* (runs whose depth intervals `[depth − R, depth + R]` overlap: one
//! surface, seen through several splats); a layer adds its summed coverage
//! and radiance unclamped (the disks of a surface tile it about once, so
//! clamping each pixel at one would lose the overlaps and keep the gaps), and
//! hides what lies behind it in proportion `κ·coverage` (opaque at half
//! coverage: splats of a surface leave gaps that would let light leak
//! through).
//!
//! Measured on the closed-form references (`pbgi::exact`, BENCHMARKS.md):
//! this composition, with cos-exact small splats, normalised cones and
//! uninflated disks, converges as Ω → 0 and is flat in N, where one owner's
//! radiance per pixel with coverage clamped at one grew worse with both.

use glam::Vec3;

use super::fragments::Fragments;
use super::table::Table;
use crate::environment::Environment;
use crate::tree::Tree;

/// How much of what lies behind a layer it hides per unit of coverage.
const KAPPA: f32 = 2.0;

/// A fragment in sort order: `(near, node)` as one integer (the near depth's
/// bits mapped to an unsigned order), the coverage's bits (equal keys are
/// the same node twice in one pixel, showing the same radiance), the
/// fragment's index.
type Sorted = (u64, u32, u32);

/// `x`'s bits, ordered like `f32::total_cmp` orders `x`.
#[inline(always)]
fn ordered(x: f32) -> u32 {
    let b = x.to_bits();
    if b >> 31 == 1 { !b } else { b | 0x8000_0000 }
}

/// The inverse of [`ordered`].
#[inline(always)]
fn unordered(o: u32) -> f32 {
    f32::from_bits(if o >> 31 == 1 { o & 0x7FFF_FFFF } else { !o })
}

/// `a` before `b` in the canonical order (a total order on the fields).
#[inline(always)]
fn before(a: &Sorted, b: &Sorted) -> bool {
    (a.0, a.1) < (b.0, b.1)
}

/// Moves `v[root]` down the max-heap `v[..end]`.
#[inline(always)]
fn sift(v: &mut [Sorted], mut root: usize, end: usize) {
    loop {
        let mut child = 2 * root + 1;
        if child >= end {
            break;
        }
        if child + 1 < end && before(&v[child], &v[child + 1]) {
            child += 1;
        }
        if !before(&v[root], &v[child]) {
            break;
        }
        v.swap(root, child);
        root = child;
    }
}

/// Sorts a pixel's fragments: insertion sort for the usual few dozen, heap
/// sort for long buckets (written out: a sort taking a closure would be
/// compiled out of line, for the baseline target, not the kernel's clone).
#[inline(always)]
fn sort(v: &mut [Sorted]) {
    if v.len() <= 48 {
        for i in 1..v.len() {
            let x = v[i];
            let mut j = i;
            while j > 0 && before(&x, &v[j - 1]) {
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

/// The composed pixels of one receiver: per pixel the effective coverage
/// and the radiance it lets through (`Σ layers T·Σ coverage·L`).
pub(crate) struct Composed {
    pub cover: Vec<f32>,
    pub radiance: Vec<Vec3>,
    /// The brightest radiance among the fragments, per channel.
    pub brightest: Vec3,
}

/// Composes every pixel of `t` from `frags` (in any order). `radiance`:
/// also sum the nodes' radiance (occlusion needs none).
#[inline(always)]
pub(crate) fn compose(t: &Table, frags: &Fragments, tree: &Tree, radiance: bool) -> Composed {
    let pixels = t.dir.len();
    // Bucket by pixel (a counting sort: O(n)).
    let mut start = vec![0u32; pixels + 1];
    for &p in &frags.pixel {
        start[p as usize + 1] += 1;
    }
    for p in 0..pixels {
        start[p + 1] += start[p];
    }
    let mut next = start.clone();
    let mut sorted: Vec<Sorted> = vec![(0, 0, 0); frags.pixel.len()];
    let mut far = vec![0.0f32; frags.pixel.len()];
    for i in 0..frags.pixel.len() {
        let key = frags.key[i];
        let depth = f32::from_bits((key >> 32) as u32);
        let r = tree.bounding_radius((key & 0xFFFF_FFFF) as u32);
        let slot = &mut next[frags.pixel[i] as usize];
        let node = key & 0xFFFF_FFFF;
        sorted[*slot as usize] = (
            u64::from(ordered(depth - r)) << 32 | node,
            frags.cover[i].to_bits(),
            i as u32,
        );
        far[i] = depth + r;
        *slot += 1;
    }
    let mut out = Composed {
        cover: vec![0.0; pixels],
        radiance: vec![Vec3::ZERO; if radiance { pixels } else { 0 }],
        brightest: Vec3::ZERO,
    };
    for p in 0..pixels {
        let bucket = &mut sorted[start[p] as usize..start[p + 1] as usize];
        if bucket.is_empty() {
            continue;
        }
        sort(bucket);
        // Sweep into layers: `t_pass` passes through the layers closed so
        // far, `(c, l)` is what they showed, `(s, ls)` the open layer and
        // `end` its far depth.
        let (mut t_pass, mut c, mut l) = (1.0f32, 0.0f32, Vec3::ZERO);
        let (mut s, mut ls, mut end) = (0.0f32, Vec3::ZERO, f32::NEG_INFINITY);
        for &(near_node, cover, i) in bucket.iter() {
            let (near, cover, i) = (
                unordered((near_node >> 32) as u32),
                f32::from_bits(cover),
                i as usize,
            );
            if near > end && s > 0.0 {
                c += t_pass * s;
                l += ls * t_pass;
                t_pass *= (1.0 - KAPPA * s).max(0.0);
                (s, ls) = (0.0, Vec3::ZERO);
            }
            end = end.max(far[i]);
            s += cover;
            if radiance {
                let r = Vec3::from_array(frags.radiance[i]);
                ls += r * cover;
                out.brightest = out.brightest.max(r);
            }
        }
        out.cover[p] = c + t_pass * s;
        if radiance {
            out.radiance[p] = l + ls * t_pass;
        }
    }
    out
}
/// Irradiance `Σ radiance·∫cos dω` over the pixels, in pixel order, plus
/// what `sky` (radiance toward pixel `p`, and its largest) sends through the
/// open part `1 − coverage` of the pixels; at most `π` times the brightest
/// radiance splatted or seen: the unclamped layers of a receiver enclosed by
/// surfaces whose splats overlap may cover a little more than the
/// hemisphere, and where that radiance is uniform the exact answer is the
/// bound itself.
#[inline(always)]
pub(crate) fn irradiance(t: &Table, frags: &Fragments, tree: &Tree, sky: Option<&Sky>) -> Vec3 {
    // Taken apart: the drop of the whole would be out-of-line glue,
    // compiled for the baseline target (scripts/check-asm.sh).
    let Composed {
        cover,
        radiance,
        brightest,
    } = compose(t, frags, tree, true);
    let mut e = Vec3::ZERO;
    for (l, w) in radiance.iter().zip(&t.cos_weight) {
        e += *l * *w;
    }
    let mut brightest = brightest;
    if let Some(sky) = sky {
        // Unclamped per pixel: the layers' coverage overshoots one in some
        // pixels as it falls short in others (splats do not tile exactly),
        // and only the sum is right, as occlusion's is; an enclosed
        // receiver's sum may dip below zero, where no sky is seen.
        let mut open = Vec3::ZERO;
        for (p, (cover, w)) in cover.iter().zip(&t.cos_weight).enumerate() {
            open += sky.at(t, p) * ((1.0 - cover) * w);
        }
        e += open.max(Vec3::ZERO);
        brightest = brightest.max(sky.environment.max_radiance());
    }
    e.min(brightest * std::f32::consts::PI)
}

/// What a receiver's open pixels see: the environment, through the
/// receiver's frame (local x, y, z in world space).
pub(crate) struct Sky<'a> {
    pub environment: &'a Environment,
    pub frame: [Vec3; 3],
}

impl Sky<'_> {
    /// The environment's radiance toward pixel `p`'s centre.
    #[inline(always)]
    fn at(&self, t: &Table, p: usize) -> Vec3 {
        let l = t.dir[p];
        let d = self.frame[0] * l.x + self.frame[1] * l.y + self.frame[2] * l.z;
        self.environment.radiance(d)
    }
}

/// Ambient occlusion `Σ coverage·∫cos dω / π`, at most 1.
#[inline(always)]
pub(crate) fn occlusion(t: &Table, frags: &Fragments, tree: &Tree) -> f32 {
    let Composed { cover, radiance, .. } = compose(t, frags, tree, false);
    drop(radiance);
    let mut o = 0.0f32;
    for (c, w) in cover.iter().zip(&t.cos_weight) {
        o += c * w;
    }
    (o * std::f32::consts::FRAC_1_PI).min(1.0)
}

/// `Σ radiance·f(ωi)·∫cos dω` with `f` evaluated at each pixel's centre
/// direction (`wi(p)`, world space), and `sky` through the open part of
/// each pixel as in [`irradiance`].
pub(crate) fn reflected(
    t: &Table,
    frags: &Fragments,
    tree: &Tree,
    f: impl Fn(usize) -> Vec3,
    sky: Option<&Sky>,
) -> Vec3 {
    let c = compose(t, frags, tree, true);
    let mut e = Vec3::ZERO;
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
        e += open.max(Vec3::ZERO);
    }
    e
}
