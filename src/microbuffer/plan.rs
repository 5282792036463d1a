//! Planning one splat: a located splat ([`Located`](super::locate::Located))
//! is drawn one of three ways:
//!
//! * smaller than the pixel its centre falls in (`Ω < ΔΩ`): spread over the
//!   pixels its footprint overlaps (up to 2×2), each covered by its share
//!   times `Ω/ΔΩ` ([`plan_small`]); never a leaf within two of its radii,
//!   where the far-field `Ω` is no bound ([`small`]);
//! * a larger cluster: a soft cone ([`plan_cone`]);
//! * a larger leaf: its disk, ray-traced at the pixel centres of a box
//!   ([`plan_disk`]; a disk whose front no pixel's ray can face is known to
//!   miss them all without a test); a leaf covering no pixel centre is
//!   spread like a small splat with `Ω` capped at `ΔΩ`.
//!
//! Everything up to the pixel loop — class, bilinear corners and weights,
//! cone and disk parameters, footprint boxes — is written once over lanes
//! ([`Real`]), so the 16-lane pipeline computes it for a whole packet in
//! vector code and the scalar pipeline for one receiver, with the same
//! operations. So are the per-pixel cone and disk tests: the scalar pipeline
//! runs them pixel by pixel, the 16-lane one 16 pixels of one receiver at a
//! time ([`Tiles`]); only the read-modify-write of pixels is per receiver
//! and pixel.

use super::locate::{FrameLanes, NodeSplat};
use super::table::{NEAR, Table};
use crate::simd::{F32s, M32s, Real};

/// Width of a cluster's coverage ramp, relative to its radius.
const CONE_SOFTNESS: f32 = 1.0;

/// An upper bound of `asin(x)` for `x ∈ [0, 1]` (footprint boxes need a
/// bound, not the angle): `asin` is convex there, so below the chord
/// through `(0, 0)` and `(½, π/6)` up to ½, and through `(½, π/6)` and `(1, π/2)` above.
#[inline(always)]
fn sine_angle_bound<V: Real>(x: V) -> V {
    const A: f32 = std::f32::consts::FRAC_PI_3 * 1.0001; // (π/6)/½
    const B: f32 = (std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_6) * 2.0 * 1.0001;
    let half = V::splat(0.5);
    let above = V::splat(std::f32::consts::FRAC_PI_6 * 1.0001) + V::splat(B) * (x - half);
    V::select(x.le(half), V::splat(A) * x, above)
}

/// An upper bound of the angle `2·asin(c/2)` of chord `c ∈ [0, 2]`.
#[inline(always)]
fn chord_angle_bound<V: Real>(c: V) -> V {
    V::splat(2.0) * sine_angle_bound((V::splat(0.5) * c).min_of(V::splat(1.0)))
}

/// The pixel `r·N + c` that continuous coordinates `(x, y)` fall in, as a
/// whole-number float (a NaN or negative coordinate goes to 0).
#[inline(always)]
pub(crate) fn pixel_of<V: Real>(t: &Table, x: V, y: V) -> V {
    let (zero, last) = (V::splat(0.0), V::splat((t.n - 1) as f32));
    let c = x.max_of(zero).floor().min_of(last);
    let r = y.max_of(zero).floor().min_of(last);
    r * V::splat(t.n as f32) + c
}

/// Columns `c0..=c1` and rows `r0..=r1` of pixels, as whole-number floats.
#[derive(Clone, Copy)]
pub(crate) struct PixelBox<V> {
    pub c0: V,
    pub c1: V,
    pub r0: V,
    pub r1: V,
}

impl PixelBox<f32> {
    /// The same box in every lane.
    #[inline(always)]
    pub(super) fn splat(&self) -> PixelBox<F32s> {
        let s = F32s::splat;
        PixelBox {
            c0: s(self.c0),
            c1: s(self.c1),
            r0: s(self.r0),
            r1: s(self.r1),
        }
    }

    /// Pixel indices `(c0, c1, r0, r1)`.
    #[inline(always)]
    pub(super) fn bounds(&self) -> (usize, usize, usize, usize) {
        (
            self.c0 as usize,
            self.c1 as usize,
            self.r0 as usize,
            self.r1 as usize,
        )
    }
}

/// The pixels whose centres may lie within angle `angle` of the direction
/// at `(x, y)` in pixel `pixel`: `angle` times the map's reach there (or
/// anywhere, for a wide footprint), clamped to the grid.
#[inline(always)]
pub(crate) fn footprint<V: Real>(t: &Table, x: V, y: V, pixel: V, angle: V) -> PixelBox<V> {
    let near = angle * V::gather(&t.reach, pixel);
    let h = V::select(
        near.le(V::splat(NEAR as f32)),
        near,
        angle * V::splat(t.reach_max),
    ) + V::splat(0.01);
    let (zero, half, last) = (V::splat(0.0), V::splat(0.5), V::splat((t.n - 1) as f32));
    // Pixel c's centre is c + ½.
    PixelBox {
        c0: (x - h - half).ceil().max_of(zero).min_of(last),
        c1: (x + h - half).floor().max_of(zero).min_of(last),
        r0: (y - h - half).ceil().max_of(zero).min_of(last),
        r1: (y + h - half).floor().max_of(zero).min_of(last),
    }
}

/// A splat spread over the 2×2 pixels around its centre: pixels, bilinear
/// weights, and the coverage of each.
#[derive(Clone, Copy)]
pub(crate) struct SmallPlan<V> {
    pub p: [V; 4],
    pub w: [V; 4],
    pub cover: [V; 4],
}

/// The share `½ + (t − ½)/width` of a box `width` wide in the second of two
/// pixels, `t` its centre's bilinear weight there, clamped to `[0, 1]`.
#[inline(always)]
fn box_share<V: Real>(t: V, width: V) -> V {
    let half = V::splat(0.5);
    (half + (t - half) / width)
        .max_of(V::splat(0.0))
        .min_of(V::splat(1.0))
}

/// Coverage `w·Ω·cosθ / ∫cos` of one corner (none where `∫cos` is 0).
#[inline(always)]
fn share_of<V: Real>(w: V, omega_cos: V, cos_weight: V) -> V {
    V::select(
        V::splat(0.0).lt(cos_weight),
        w * (omega_cos / cos_weight),
        V::splat(0.0),
    )
}

/// The chord radius² of a splat's footprint: a leaf's disk of radius² `r2`
/// at distance `d` spans at most `r2 / (d − r)²`; a cluster's cone, of
/// projected solid angle `π·r2`, `r2`.
#[inline(always)]
pub(crate) fn chord2<V: Real>(leaf: bool, r2: V, d: V) -> V {
    if leaf {
        let near = (d - r2.sqrt()).max_of(V::splat(0.0));
        r2 / (near * near)
    } else {
        r2
    }
}

/// Whether a splat of solid angle `omega` at distance `d` is drawn small
/// (`omega` below the solid angle `pixel_omega` of the pixel its centre
/// falls in): never a leaf of `area` within two of its radii, whose
/// far-field `Ω = A·cos/d²` is no bound there. A receiver 10⁻⁶ above a
/// disk of radius 11, 0.3 from its centre, sees it fill the hemisphere
/// below, but at `cos ≈ 3·10⁻⁶` its `Ω` is 0.01, and as a small splat at
/// the horizon it left the receiver dark at N 8 and 16.
#[inline(always)]
pub(crate) fn small<V: Real>(leaf: bool, area: V, omega: V, d: V, pixel_omega: V) -> V::Mask {
    let below = omega.lt(pixel_omega);
    if leaf {
        below & (area * V::splat(4.0 * std::f32::consts::FRAC_1_PI)).lt(d * d)
    } else {
        below
    }
}

/// How far past its centre the footprint of a splat of `area` and
/// projected solid angle `omega` at distance `d` reaches, in pixels
/// ([`chord2`] of a leaf's disk, of a cluster's cone, over the angular
/// size of pixel `pixel`), at most ½: for [`plan_small`].
#[inline(always)]
pub(crate) fn reach<V: Real>(t: &Table, leaf: bool, area: V, omega: V, d: V, pixel: V) -> V {
    let r2 = if leaf { area } else { omega } * V::splat(std::f32::consts::FRAC_1_PI);
    (chord2(leaf, r2, d).sqrt() / V::gather(&t.pixel_size, pixel)).min_of(V::splat(0.5))
}

/// Spreads projected solid angle `omega_cos` (`Ω·cosθ`) at `(x, y)` over
/// the pixels its footprint, `reach` pixels across each way (at most ½),
/// overlaps: the one it falls in and up to three beside it, each covered
/// by `w_k·Ω·cosθ / ∫_k cos`, `w_k` the share of the footprint's box in
/// pixel `k` (clamped into the grid). The splat adds exactly its projected
/// solid angle to the convolution. At a reach of ½ the shares are the
/// bilinear weights between pixel centres; a footprint within its pixel
/// leaves one fragment.
///
/// Spread by bilinear weights whatever its size, a splat's part in a
/// neighbouring pixel its footprint did not reach went to the sub-sample
/// there nearest its centre, up to a pixel from where it is; where a
/// nearer surface begins that close (a room's corner seen from inside, a
/// silhouette), that part lay behind it and was lost: a closed room's
/// mid-wall occlusion, leaves only, N 14, −0.53 % (−0.14 % with footprints
/// under half a sub-sample whole in their pixel).
#[inline(always)]
pub(crate) fn plan_small<V: Real>(t: &Table, x: V, y: V, omega_cos: V, reach: V) -> SmallPlan<V> {
    let (zero, half, one) = (V::splat(0.0), V::splat(0.5), V::splat(1.0));
    let (n, last) = (V::splat(t.n as f32), V::splat((t.n - 1) as f32));
    let (gx, gy) = (x - half, y - half);
    let (x0, y0) = (gx.floor(), gy.floor());
    // Bilinear weight `t` of the second column, as the share of a box
    // `reach` wide each way: `½ + (t − ½)/(2·reach)`, clamped (the second
    // column is the centre's from `t = ½` on).
    let width = (reach + reach).max_of(V::splat(1e-6));
    let (tx, ty) = (box_share(gx - x0, width), box_share(gy - y0, width));
    let (c0, c1) = (x0.max_of(zero).min_of(last), (x0 + one).max_of(zero).min_of(last));
    let (r0, r1) = (y0.max_of(zero).min_of(last), (y0 + one).max_of(zero).min_of(last));
    let p = [r0 * n + c0, r0 * n + c1, r1 * n + c0, r1 * n + c1];
    let w = [(one - tx) * (one - ty), tx * (one - ty), (one - tx) * ty, tx * ty];
    // Written out: a closure passed to `map` may be left out of line, and
    // then compiled for the baseline target rather than the caller's clone.
    let cw = &t.cos_weight;
    let cover = [
        share_of(w[0], omega_cos, V::gather(cw, p[0])),
        share_of(w[1], omega_cos, V::gather(cw, p[1])),
        share_of(w[2], omega_cos, V::gather(cw, p[2])),
        share_of(w[3], omega_cos, V::gather(cw, p[3])),
    ];
    SmallPlan { p, w, cover }
}

/// A cluster's soft cone: chord radius `a` where coverage is ½, ramp `1/s`,
/// full inside chord² `inner2`, none from `outer2`, over the box `bx`.
#[derive(Clone, Copy)]
pub(crate) struct ConePlan<V> {
    pub a: V,
    pub inv_s: V,
    pub inner2: V,
    pub outer2: V,
    pub bx: PixelBox<V>,
}

/// A soft cone of solid angle `omega` around the direction at `(x, y)`:
/// coverage 1 in the middle, falling linearly across a rim as wide as the
/// cone's radius (at least a pixel: `delta`, the angular size of the pixel
/// there, or the largest pixel's for a centre below the horizon), scaled so
/// that it integrates to `Ω`. Radii are chords `|u − ω|`, for which a cap's
/// solid angle is exactly `π·chord²`.
#[inline(always)]
pub(crate) fn plan_cone<V: Real>(t: &Table, x: V, y: V, pixel: V, omega: V, visible: V::Mask) -> ConePlan<V> {
    let (zero, half, one) = (V::splat(0.0), V::splat(0.5), V::splat(1.0));
    let delta = V::select(visible, V::gather(&t.pixel_size, pixel), V::splat(t.pixel_angle));
    // With chord radius `a` and rim width `s` (coverage ½ at `a`), the
    // coverage integrates to `π(a² + s²/12)`; solve for `a`.
    let cap = omega * V::splat(std::f32::consts::FRAC_1_PI);
    let k = CONE_SOFTNESS;
    let a2 = cap / V::splat(1.0 + k * k / 12.0);
    let s = V::splat(k) * a2.sqrt();
    let narrow = s.lt(delta);
    let s = V::select(narrow, delta, s);
    let a2 = V::select(narrow, (cap - delta * delta / V::splat(12.0)).max_of(zero), a2);
    let a = a2.min_of(V::splat(4.0)).sqrt();
    let (inner, outer) = ((a - half * s).max_of(zero), a + half * s);
    ConePlan {
        a,
        inv_s: one / s,
        inner2: inner * inner,
        outer2: outer * outer,
        bx: footprint(t, x, y, pixel, chord_angle_bound(outer)),
    }
}

/// A leaf's disk in the receiver's frame: normal `m`, centre `c`, `m·c`,
/// radius `r`, and the box of pixels it may cover.
#[derive(Clone, Copy)]
pub(crate) struct DiskPlan<V: Real> {
    /// Whether the disk's front can face some pixel's ray at all.
    pub fronts: V::Mask,
    pub m: [V; 3],
    pub c: [V; 3],
    pub mc: V,
    pub r: V,
    pub bx: PixelBox<V>,
}

/// The disk of leaf `s` (area `A`, radius `√(A/π)`) seen from
/// receiver `f`, its centre at `(x, y)` in pixel `pixel` and distance `d`.
#[inline(always)]
pub(crate) fn plan_disk<V: Real>(
    t: &Table,
    f: &FrameLanes<V>,
    s: &NodeSplat<V>,
    x: V,
    y: V,
    pixel: V,
    d: V,
) -> DiskPlan<V> {
    let r2 = s.area * V::splat(std::f32::consts::FRAC_1_PI);
    let r = r2.sqrt();
    let m = [
        s.nx * f.tx + s.ny * f.ty + s.nz * f.tz,
        s.nx * f.bx + s.ny * f.by + s.nz * f.bz,
        s.nx * f.nx + s.ny * f.ny + s.nz * f.nz,
    ];
    let (vx, vy, vz) = (s.cx - f.px, s.cy - f.py, s.cz - f.pz);
    let c = [
        vx * f.tx + vy * f.ty + vz * f.tz,
        vx * f.bx + vy * f.by + vz * f.bz,
        vx * f.nx + vy * f.ny + vz * f.nz,
    ];
    let mc = m[0] * c[0] + m[1] * c[1] + m[2] * c[2];
    // A ray `u` hits the front only where `m·u < 0`. Over the pixel centres
    // (`u_z ≥ z₀`, `|u_xy| ≤ √(1 − z₀²)`) `m·u ≥ m_z·z₀ − |m_xy|·√(1 − z₀²)`
    // (Cauchy–Schwarz); where that is clearly positive no pixel can be hit.
    // This drops the leaves coplanar with the receiver that rounding puts
    // just below its horizon, facing it by a hair (most leaves drawn as
    // disks): the bound holds with a margin far above the rounding of the
    // dot products, so it never drops a hit.
    let m_xy = (m[0] * m[0] + m[1] * m[1]).sqrt();
    let fronts = (m[2] * V::splat(t.lowest_z) - m_xy * V::splat(t.lowest_sin)).le(V::splat(1e-4));
    // The edge ramp reaches half a pixel past the rim; a disk reaching the
    // receiver may cover any pixel.
    let angle = sine_angle_bound(r / d) + V::splat(0.5 * t.pixel_angle + 1e-3);
    let near = footprint(t, x, y, pixel, angle);
    let whole = d.le(r);
    let (zero, last) = (V::splat(0.0), V::splat((t.n - 1) as f32));
    DiskPlan {
        fronts,
        m,
        c,
        mc,
        r,
        bx: PixelBox {
            c0: V::select(whole, zero, near.c0),
            c1: V::select(whole, last, near.c1),
            r0: V::select(whole, zero, near.r0),
            r1: V::select(whole, last, near.r1),
        },
    }
}

impl<V: Real> ConePlan<V> {
    /// Whether the cone around `w` covers the pixels of centre directions
    /// `u` (one pixel, or sixteen in the lanes), and by how much.
    #[inline(always)]
    pub(super) fn cover(&self, w: [V; 3], ux: V, uy: V, uz: V) -> (V::Mask, V) {
        let (ex, ey, ez) = (ux - w[0], uy - w[1], uz - w[2]);
        let c2 = ex * ex + ey * ey + ez * ez;
        let ramp = (V::splat(0.5) + (self.a - c2.sqrt()) * self.inv_s).min_of(V::splat(1.0));
        let cover = V::select(c2.le(self.inner2), V::splat(1.0), ramp);
        (c2.lt(self.outer2) & V::splat(0.0).lt(cover), cover)
    }
}

impl<V: Real> DiskPlan<V> {
    /// Whether the rays of directions `u` from the receiver (one pixel's, or
    /// sixteen in the lanes) hit the disk's front, at what distance, and the
    /// pixels' coverage: the disk's edge is a ramp one pixel (angular size
    /// `delta`) wide at the hit distance, centred where it integrates to the
    /// disk's area, so a disk over a few pixels still shows its true area on
    /// average.
    #[inline(always)]
    pub(super) fn hit(&self, ux: V, uy: V, uz: V, delta: V) -> (V::Mask, V, V) {
        let [mx, my, mz] = self.m;
        let denom = mx * ux + my * uy + mz * uz;
        let t = self.mc / denom;
        let ex = ux * t - self.c[0];
        let ey = uy * t - self.c[1];
        let ez = uz * t - self.c[2];
        let e = (ex * ex + ey * ey + ez * ez).sqrt();
        // A ramp of width `w` centred on radius `a` integrates to
        // `π(a² + w²/12)`: solved for the disk's area `πr²`, as the cone's
        // is (the rim `r` itself overstated a disk of a pixel or two by up
        // to 10 %: a square of coarse surfels in front of the receiver came
        // out 8 % too bright at N 24).
        let w = delta * t;
        let a = (self.r * self.r - w * w * V::splat(1.0 / 12.0))
            .max_of(V::splat(0.0))
            .sqrt();
        let cover = (V::splat(0.5) + (a - e) / w).min_of(V::splat(1.0));
        let zero = V::splat(0.0);
        (denom.lt(zero) & zero.lt(t) & zero.lt(cover), t, cover)
    }
}

impl DiskPlan<f32> {
    /// The same disk in every lane.
    #[inline(always)]
    pub(super) fn splat(&self) -> DiskPlan<F32s> {
        let s = F32s::splat;
        DiskPlan {
            fronts: M32s::splat(self.fronts),
            m: [s(self.m[0]), s(self.m[1]), s(self.m[2])],
            c: [s(self.c[0]), s(self.c[1]), s(self.c[2])],
            mc: s(self.mc),
            r: s(self.r),
            bx: self.bx.splat(),
        }
    }
}

impl ConePlan<f32> {
    /// The same cone in every lane.
    #[inline(always)]
    pub(super) fn splat(&self) -> ConePlan<F32s> {
        let s = F32s::splat;
        ConePlan {
            a: s(self.a),
            inv_s: s(self.inv_s),
            inner2: s(self.inner2),
            outer2: s(self.outer2),
            bx: self.bx.splat(),
        }
    }
}
