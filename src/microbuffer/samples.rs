//! Where in its pixel a fragment lies: its coverage spread over the pixel's
//! 4×4 sub-samples, with a depth interval at each, so that `compose` can
//! tell one surface's splats (same place in the pixel, same depth) from two
//! surfaces that only share a pixel or a depth range.

use std::simd::prelude::*;

use glam::Vec3;

use super::plan::chord2;
use crate::simd::{F32s, LANES, M32s, Real};
use crate::tree::{FACETS, LEAF, MIXED, NodeId, Tree, field};

/// Sub-samples per pixel: a 4×4 grid, one per lane.
pub(crate) const SAMPLES: usize = LANES;

/// How many sub-samples wide a footprint's placement may be off (the
/// nearest sub-sample for a small splat, a round cone for a cluster of
/// another shape): a plane's depth interval at a sub-sample spans its depth
/// over that width. Measured on the exact rooms (`examples/exact`): one
/// sub-sample loses 1.3 % of a wall's light at Ω 0.01, N 12; three, 0.3 %.
const PLACEMENT: f32 = 3.0;

/// Relative depth slack for rounding (`f32` plane depths of one surface).
const ROUNDING: f32 = 1e-4;

/// How many times its own area the disk is over which a splat hides what
/// lies behind it: a leaf's (one jittered surfel per cell: disks of the
/// cell's area leave gaps, which a sub-sample resolves once it is smaller
/// than a splat), a planar cluster's (disks of the clusters' areas tile a
/// wall no better than a square grid's disks, which need π/2). Measured on
/// the blocker (`examples/exact`, mid-wall, a light behind a slab): at Ω 0,
/// N 96, 16 % error with no hiding, 3.0 % at ×2, 1.0 % at ×3; at Ω 0.002
/// the clusters' ×2 takes N 24 / 48 / 96 from 5.6 / 6.5 / 11.4 % (leaves
/// hiding alone) to 5.6 / 1.8 / 1.4 % (`docs/lab/exact/findings.md`). The
/// grown disks also hide a band past an occluder's silhouette. The band
/// narrows with density and Ω, but slowly. It is all of the Cornell box's
/// indirect bias (−1.1 % at the defaults, about 0 without the blocks) and
/// all of Sponza's (−2.7 %). Shrinking or clipping the disks at a
/// surface's edges opens gaps through which the nave leaks
/// (docs/lab/BENCHMARKS.md, "What bounds Sponza at 2 %").
const HIDE_LEAF: f32 = 3.0;
const HIDE_PLANAR: f32 = 2.0;

/// A node as one receiver sees it, for the sub-sample tests: worked out
/// once per splat, read at every pixel it left a fragment in.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shape {
    kind: u32,
    /// The node's centre (its area centroid) in the receiver's frame, its distance and unit
    /// direction.
    v: Vec3,
    d: f32,
    w: Vec3,
    /// The node's plane (leaves and planar clusters): unit normal in the
    /// receiver's frame and `m·v`.
    m: Vec3,
    mv: f32,
    /// Leaf: the disk's radius². Cluster: the chord radius² of the cone of
    /// its projected solid angle (mixed: of its whole area; its cone is
    /// drawn only where its facets are not flat).
    r2: f32,
    /// The radius² `A/π` of the disk of the node's area (leaves and planar
    /// clusters: their footprint is that disk on their plane, an ellipse as
    /// the receiver sees it).
    disk2: f32,
    /// The centre's continuous pixel coordinates (octahedral map, as
    /// `locate` places it).
    x: f32,
    y: f32,
    /// Whether the footprint is narrower than half the smallest sub-sample
    /// (it covers one at most).
    small: bool,
    /// `tanθ`, θ between the centre's ray and the plane's normal (at most
    /// 10³).
    tan: f32,
    /// Bounding radius `R`: no plane's depth spreads further over the node.
    radius: f32,
    /// Depth slack beyond the plane: `R·sin β` (β the normal cone's
    /// half-angle: how far a planar cluster's surfels may leave its plane);
    /// for a mixed cluster, its bounding radius `R`.
    reach: f32,
    /// A mixed cluster's index in the receiver's [`Facets`] (`u32::MAX`:
    /// drawn as its cone).
    facets: u32,
}

/// Floats per facet in [`Facets`].
const FACET: usize = 11;

/// A mixed cluster's facets as one receiver sees them, `FACET` floats
/// each: the plane's unit normal (local frame), `m·v`, the centroid `v`
/// (local), the radius² `A/π` of the disk of its area (0: no facet), the
/// centroid's distance, `tanθ` (as [`Shape`]'s) and its reach.
pub(crate) type Facets = [f32; FACETS * FACET];

/// The facets of node `node` seen from `position` with local frame `frame`
/// (`Tree::planes`), if it is drawn as them: a mixed node whose facets are
/// flat (else it is one round cone at its centre, `±R` deep).
#[inline(always)]
pub(crate) fn facets(tree: &Tree, node: NodeId, position: Vec3, frame: &[Vec3; 3]) -> Option<Facets> {
    let planes = tree.planes_of(node)?;
    if !planes.flat {
        return None;
    }
    let mut out = [0.0; FACETS * FACET];
    for (f, o) in planes.facet.iter().zip(out.chunks_exact_mut(FACET)) {
        let n = Vec3::new(f[0], f[1], f[2]);
        let m = Vec3::new(n.dot(frame[0]), n.dot(frame[1]), n.dot(frame[2]));
        let x = Vec3::new(f[3], f[4], f[5]) - position;
        let v = Vec3::new(x.dot(frame[0]), x.dot(frame[1]), x.dot(frame[2]));
        let (d, mv) = (v.length(), m.dot(v));
        let c = if d > 0.0 { (mv / d).abs().max(1e-3) } else { 1.0 };
        // Seen from behind its plane it is hit on no sub-sample's front:
        // no disk to test.
        let area = if mv < 0.0 { f[6] } else { 0.0 };
        o.copy_from_slice(&[
            m.x,
            m.y,
            m.z,
            mv,
            v.x,
            v.y,
            v.z,
            area * std::f32::consts::FRAC_1_PI,
            d,
            (1.0 - c * c).max(0.0).sqrt() / c,
            f[7],
        ]);
    }
    Some(out)
}

impl Shape {
    /// Node `node` seen from `position` with local frame `frame`.
    #[inline(always)]
    pub(crate) fn of(
        tree: &Tree,
        node: NodeId,
        position: Vec3,
        frame: &[Vec3; 3],
        res: usize,
        half_sample: f32,
        facets: u32,
    ) -> Shape {
        let rec = tree.splat_record(node).expect("a splatted node");
        let r = tree.bounding_radius(node);
        let local = |x: Vec3| Vec3::new(x.dot(frame[0]), x.dot(frame[1]), x.dot(frame[2]));
        let v = local(Vec3::from_array(rec.centroid) - position);
        let d = v.length();
        let w = v / d;
        let n = local(Vec3::from_array(rec.normal));
        let m = n.normalize_or_zero();
        let r2 = if rec.kind == LEAF {
            rec.area * std::f32::consts::FRAC_1_PI
        } else {
            let facing = if rec.kind == MIXED {
                1.0
            } else {
                (-m.dot(w)).max(0.0)
            };
            (rec.area * facing / (d * d)).min(std::f32::consts::TAU) * std::f32::consts::FRAC_1_PI
        };
        let sum = w.x.abs() + w.y.abs() + w.z.max(0.0);
        let (px, py) = (w.x / sum, w.y / sum);
        let half = 0.5 * res as f32;
        let c = m.dot(w).abs().max(1e-3);
        // The footprint's chord radius² (a disk's at most `r²/(d − r)²`).
        let footprint = chord2(rec.kind == LEAF, r2, d);
        Shape {
            small: footprint < half_sample * half_sample,
            kind: rec.kind,
            tan: (1.0 - c * c).max(0.0).sqrt() / c,
            x: (px + py + 1.0) * half,
            y: (px - py + 1.0) * half,
            v,
            d,
            w,
            m,
            mv: m.dot(v),
            r2,
            disk2: rec.area * std::f32::consts::FRAC_1_PI,
            radius: r,
            reach: if rec.kind == MIXED {
                r
            } else {
                r * tree.nodes.get(node, field::SIN)
            },
            facets,
        }
    }
}

/// A [`Shape`] as plain floats, for storage: a `Vec` of the crate's own
/// type would grow through code compiled for the baseline target, outside
/// the kernel's clone (`scripts/check-asm.sh`).
pub(crate) type Packed = [f32; 21];

impl Shape {
    /// The shape as plain floats.
    #[inline(always)]
    pub(crate) fn pack(&self) -> Packed {
        [
            self.kind as f32,
            self.v.x,
            self.v.y,
            self.v.z,
            self.d,
            self.w.x,
            self.w.y,
            self.w.z,
            self.m.x,
            self.m.y,
            self.m.z,
            self.mv,
            self.r2,
            self.x,
            self.y,
            if self.small { 1.0 } else { 0.0 },
            self.tan,
            self.radius,
            self.reach,
            self.disk2,
            f32::from_bits(self.facets),
        ]
    }

    /// The shape [`pack`](Self::pack) stored.
    #[inline(always)]
    pub(crate) fn unpack(p: &Packed) -> Shape {
        Shape {
            kind: p[0] as u32,
            v: Vec3::new(p[1], p[2], p[3]),
            d: p[4],
            w: Vec3::new(p[5], p[6], p[7]),
            m: Vec3::new(p[8], p[9], p[10]),
            mv: p[11],
            r2: p[12],
            x: p[13],
            y: p[14],
            small: p[15] != 0.0,
            tan: p[16],
            radius: p[17],
            reach: p[18],
            disk2: p[19],
            facets: p[20].to_bits(),
        }
    }
}

impl Shape {
    /// Depth along the ray `u`: the plane's, or the centre's distance
    /// where the ray misses the plane's front (mixed: the centre's).
    #[inline(always)]
    fn depth(&self, u: Vec3) -> f32 {
        let denom = self.m.dot(u);
        let t = self.mv / denom;
        if self.kind != MIXED && denom < 0.0 && 0.0 < t {
            t
        } else {
            self.d
        }
    }

    /// The depth interval's half-width in a pixel whose sub-samples are
    /// `size` wide (radians): a plane's depth changes by `d·δ·tanθ` across
    /// a sub-sample (θ between the centre's ray and the plane's normal), so
    /// over `PLACEMENT` of them by `PLACEMENT` times that (`capped`: at most
    /// `R` a sub-sample, for a depth taken along each sub-sample's ray
    /// through the node's own footprint); plus rounding and `reach`.
    #[inline(always)]
    fn slack(&self, size: f32, capped: bool) -> f32 {
        if self.kind == MIXED {
            return self.reach;
        }
        let spread = self.d * size * self.tan;
        let spread = if capped { spread.min(self.radius) } else { spread };
        spread * PLACEMENT + self.d * ROUNDING + self.reach
    }
}

/// A fragment at the sub-samples: coverage (each sub-sample a sixteenth of
/// the pixel; they average to the fragment's coverage), depth interval, and
/// the sub-samples over which it hides what lies behind it.
#[derive(Clone, Copy)]
pub(crate) struct Lanes {
    pub cover: F32s,
    pub near: F32s,
    pub far: F32s,
    pub hide: M32s,
    /// At each sub-sample, the plane of the surface drawn there (the
    /// node's, or the facet's nearest hit) moved back by its reach, as
    /// `m` and `m·v − reach`: what lies at `x` with `m·x` below that is
    /// behind the surface (a cone: `(0, −∞)`, nothing behind it).
    pub plane: [F32s; 4],
    /// At each sub-sample, the centre of the surface drawn there and how
    /// far behind another surface's plane it may lie and still be part of
    /// it ([`wholly_behind`]).
    pub body: [F32s; 4],
}

/// The sub-sample directions of one pixel (local frame) and the angular
/// size of one sub-sample.
pub(crate) struct Pixel {
    /// Column and row in the grid.
    pub col: f32,
    pub row: f32,
    pub ux: F32s,
    pub uy: F32s,
    pub uz: F32s,
    pub size: f32,
}

/// How far behind another surface's plane a splat's centre may lie and
/// still be part of that surface: its reach, rounding, and half its disk's
/// radius (on a curved surface, splats of radius `r` lie `2r²/ρ` behind
/// their neighbours' tangent planes, within `r/2` while `r < ρ/4`).
#[inline(always)]
fn tolerance(reach: f32, disk2: f32, d: f32) -> f32 {
    reach + 0.5 * disk2.sqrt() + d * ROUNDING
}

/// A node's [`Lanes::plane`] and [`Lanes::body`], the same at every
/// sub-sample: its own plane and centre (a cone: no plane).
#[inline(always)]
fn surface(s: &Shape) -> ([F32s; 4], [F32s; 4]) {
    let sp = F32s::splat;
    let plane = if s.kind == MIXED {
        [sp(0.0), sp(0.0), sp(0.0), sp(f32::NEG_INFINITY)]
    } else {
        [sp(s.m.x), sp(s.m.y), sp(s.m.z), sp(s.mv - s.reach)]
    };
    let tol = tolerance(s.reach, s.disk2, s.d);
    (plane, [sp(s.v.x), sp(s.v.y), sp(s.v.z), sp(tol)])
}

/// Where a surface whose centre and tolerance are `body` lies wholly
/// behind `plane`: its centre further behind that plane than its tolerance.
#[inline(always)]
pub(crate) fn wholly_behind(plane: &[F32s; 4], body: &[F32s; 4]) -> M32s {
    let side = plane[0] * body[0] + plane[1] * body[1] + plane[2] * body[2] - plane[3];
    side.simd_lt(-body[3])
}

/// Where the fragment `(plane, body)` is hidden by `(near_plane,
/// near_body)`, another drawn at the same sub-sample: it lies wholly behind
/// that one's plane, and that one does not lie wholly behind its. Such a
/// fragment joins no front layer, however near its depth interval reaches:
/// the interval's placement spread (up to `3R`) joined a window's sunlit
/// jambs to the wall a few centimetres in front of them, and the nave's
/// floor saw them as if nothing hid them (`tests/hiding.rs`). Two faces of
/// a convex corner each lie behind the other's plane, and neither can hide
/// the other: a block's top, whose grown hiding disk reaches past its edge,
/// hid a band of its side (the Cornell box's ceiling 2–3 % dark). A disk
/// overhanging a convex corner, whose centre lies in front of the other
/// wall, still joins that wall's front layer (the closed-form rooms keep
/// their bits).
#[inline(always)]
pub(crate) fn hidden_by(
    near_plane: &[F32s; 4],
    near_body: &[F32s; 4],
    plane: &[F32s; 4],
    body: &[F32s; 4],
) -> M32s {
    wholly_behind(near_plane, body) & !wholly_behind(plane, near_body)
}

/// Fragment of coverage `cover` of shape `s` at the sub-samples of `px`.
///
/// Which sub-samples: the disk of its area on its plane (leaves and planar
/// clusters: the ray–disk hits), the disks of a mixed cluster's facets on
/// theirs, or, for a mixed cluster whose facets are not flat
/// ([`facets`]), its cone; where none is inside, or the footprint is
/// narrower than half the smallest sub-sample (so that it covers one at
/// most), the one its centre's map position falls in, or the nearest one
/// in this pixel (a small splat's neighbouring pixels). Depth: along each
/// sub-sample's ray, the plane (of the nearest facet hit) or the centre's
/// distance (a cone, whose interval is `±R`). Hidden behind it: the
/// sub-samples in its disks grown `HIDE_LEAF` / `HIDE_PLANAR` times (a
/// cone, a rough outline of curved faces, hides none).
#[inline(always)]
pub(crate) fn lanes(s: &Shape, px: &Pixel, cover: f32, facets: &[Facets]) -> Lanes {
    if s.small {
        return one(s, px, cover);
    }
    let sp = F32s::splat;
    let (ux, uy, uz) = (px.ux, px.uy, px.uz);
    if s.kind == MIXED && s.facets == u32::MAX {
        let (ex, ey, ez) = (ux - sp(s.w.x), uy - sp(s.w.y), uz - sp(s.w.z));
        let Some(cover) = spread((ex * ex + ey * ey + ez * ez).simd_le(sp(s.r2)), cover) else {
            return one(s, px, cover);
        };
        let (plane, body) = surface(s);
        return Lanes {
            cover,
            near: sp(s.d - s.reach),
            far: sp(s.d + s.reach),
            hide: M32s::splat(false),
            plane,
            body,
        };
    }
    if s.kind == MIXED {
        // Each facet as a planar cluster: the disk of its area on its
        // plane; the depth interval of the nearest facet hit.
        let (mut member, mut hide) = (M32s::splat(false), M32s::splat(false));
        let (mut near, mut far) = (sp(f32::INFINITY), sp(f32::NEG_INFINITY));
        let (mut plane, mut body) = surface(s);
        let mut first = sp(f32::INFINITY);
        for g in facets[s.facets as usize].chunks_exact(FACET) {
            if g[7] == 0.0 {
                continue;
            }
            let (t, front, e2) =
                plane_hit(px, Vec3::new(g[0], g[1], g[2]), g[3], Vec3::new(g[4], g[5], g[6]));
            member |= front & e2.simd_le(sp(g[7]));
            let hit = front & e2.simd_le(sp(g[7] * HIDE_PLANAR));
            hide |= hit;
            let spread = (g[8] * px.size * g[9]).min(s.radius);
            let slack = spread * PLACEMENT + g[8] * ROUNDING + g[10];
            near = F32s::select(hit, (t - sp(slack)).simd_min(near), near);
            far = F32s::select(hit, (t + sp(slack)).simd_max(far), far);
            let nearer = hit & t.simd_lt(first);
            first = F32s::select(nearer, t, first);
            let f = [g[0], g[1], g[2], g[3] - g[10]];
            let b = [g[4], g[5], g[6], tolerance(g[10], g[7], g[8])];
            for c in 0..4 {
                plane[c] = F32s::select(nearer, sp(f[c]), plane[c]);
                body[c] = F32s::select(nearer, sp(b[c]), body[c]);
            }
        }
        let Some(cover) = spread(member, cover) else {
            let l = hiding(one(s, px, cover), hide, near, far);
            return Lanes { plane, body, ..l };
        };
        return Lanes {
            cover,
            near,
            far,
            hide,
            plane,
            body,
        };
    }
    let (t, front, e2) = plane_hit(px, s.m, s.mv, s.v);
    let grow = if s.kind == LEAF { HIDE_LEAF } else { HIDE_PLANAR };
    let hide = front & e2.simd_le(sp(s.disk2 * grow));
    let depth = F32s::select(front, t, sp(s.d));
    let slack = sp(s.slack(px.size, true));
    let (near, far) = (depth - slack, depth + slack);
    let Some(cover) = spread(front & e2.simd_le(sp(s.disk2)), cover) else {
        return hiding(one(s, px, cover), hide, near, far);
    };
    let (plane, body) = surface(s);
    Lanes {
        cover,
        near,
        far,
        hide,
        plane,
        body,
    }
}

/// A fragment whose disk catches none of the pixel's sub-samples (it grazes
/// the pixel: its coverage goes to one of them), with what its grown disk
/// still hides, at the depths of its plane there: were the hiding dropped
/// until the disk caught a sub-sample, a move of 10⁻⁴ would hide a dozen
/// sub-samples at once (a receiver's occlusion jumped by 3 %).
#[inline(always)]
fn hiding(l: Lanes, hide: M32s, near: F32s, far: F32s) -> Lanes {
    Lanes {
        cover: l.cover,
        near: F32s::select(hide, near, l.near),
        far: F32s::select(hide, far, l.far),
        hide,
        ..l
    }
}

/// Along each sub-sample's ray of `px`: the distance `t` to the plane
/// `m·x = mv`, whether the ray meets its front there, and the squared
/// distance of that hit from `v`.
#[inline(always)]
fn plane_hit(px: &Pixel, m: Vec3, mv: f32, v: Vec3) -> (F32s, M32s, F32s) {
    let sp = F32s::splat;
    let zero = sp(0.0);
    let denom = sp(m.x) * px.ux + sp(m.y) * px.uy + sp(m.z) * px.uz;
    let t = sp(mv) / denom;
    let front = denom.simd_lt(zero) & zero.simd_lt(t);
    let (ex, ey, ez) = (px.ux * t - sp(v.x), px.uy * t - sp(v.y), px.uz * t - sp(v.z));
    (t, front, ex * ex + ey * ey + ez * ez)
}

/// The whole fragment at one sub-sample: the one its centre's map position
/// falls in, or the nearest one in this pixel.
#[inline(always)]
fn one(s: &Shape, px: &Pixel, cover: f32) -> Lanes {
    let col = ((s.x - px.col) * 4.0).floor().clamp(0.0, 3.0) as usize;
    let row = ((s.y - px.row) * 4.0).floor().clamp(0.0, 3.0) as usize;
    let k = col + 4 * row;
    // From its own depth to its plane's along the sub-sample's ray:
    // the ray may cross a corner onto another surface, nearer than
    // this splat's plane there, where the splat itself lies beside it.
    let plane = s.depth(Vec3::new(px.ux[k], px.uy[k], px.uz[k]));
    let slack = s.slack(px.size, true);
    let (own, body) = surface(s);
    Lanes {
        cover: F32s::select(
            M32s::from_bitmask(1 << k),
            F32s::splat(cover * SAMPLES as f32),
            F32s::splat(0.0),
        ),
        near: F32s::splat(plane.min(s.d) - slack),
        far: F32s::splat(plane.max(s.d) + slack),
        hide: M32s::splat(false),
        plane: own,
        body,
    }
}

/// Coverage `cover` spread evenly over the sub-samples in `member` (they
/// average to it); `None` where there are none.
#[inline(always)]
fn spread(member: M32s, cover: f32) -> Option<F32s> {
    let count = member.to_bitmask().count_ones();
    if count == 0 {
        return None;
    }
    Some(F32s::select(
        member,
        F32s::splat(cover * SHARE[count as usize]),
        F32s::splat(0.0),
    ))
}

/// `SAMPLES / count` for every count of sub-samples, the same IEEE
/// quotient as at run time (a division per fragment saved).
const SHARE: [f32; SAMPLES + 1] = {
    let mut s = [0.0; SAMPLES + 1];
    let mut k = 1;
    while k <= SAMPLES {
        s[k] = SAMPLES as f32 / k as f32;
        k += 1;
    }
    s
};
