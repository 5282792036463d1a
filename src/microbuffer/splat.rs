//! Drawing one splat. A located splat ([`Located`](super::lanes::Located))
//! is drawn one of three ways:
//!
//! * smaller than the pixel its centre falls in (`Ω < ΔΩ`): spread over the
//!   2×2 pixels around the centre with bilinear weights, each covered by its
//!   weight times `Ω/ΔΩ` ([`plan_small`]);
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

use std::simd::prelude::*;
use std::simd::simd_swizzle;

use glam::Vec3;

use super::lanes::{FrameLanes, Located, NodeSplat};
use super::{COVER_CAP, COVER_ONE, MicroBuffer, NEAR, NO_KEY, Table, key};
use crate::cut::node_test::{F32s, LANES, M32s, Real};
use crate::tree::{NodeId, SplatRecord};

/// Leaf disks are rasterized this much larger than their radius, so that
/// the disks of a surface overlap instead of leaving holes between them.
const DISK_INFLATION: f32 = 1.2;

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
    fn splat(&self) -> PixelBox<F32s> {
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
    fn bounds(&self) -> (usize, usize, usize, usize) {
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

/// Spreads solid angle `omega` at `(x, y)` over the 2×2 pixels around it
/// (bilinear weights between pixel centres, clamped into the grid).
#[inline(always)]
pub(crate) fn plan_small<V: Real>(t: &Table, x: V, y: V, omega: V) -> SmallPlan<V> {
    let (zero, half, one) = (V::splat(0.0), V::splat(0.5), V::splat(1.0));
    let (n, last) = (V::splat(t.n as f32), V::splat((t.n - 1) as f32));
    let (gx, gy) = (x - half, y - half);
    let (x0, y0) = (gx.floor(), gy.floor());
    let (tx, ty) = (gx - x0, gy - y0);
    let (c0, c1) = (x0.max_of(zero).min_of(last), (x0 + one).max_of(zero).min_of(last));
    let (r0, r1) = (y0.max_of(zero).min_of(last), (y0 + one).max_of(zero).min_of(last));
    let p = [r0 * n + c0, r0 * n + c1, r1 * n + c0, r1 * n + c1];
    let w = [(one - tx) * (one - ty), tx * (one - ty), (one - tx) * ty, tx * ty];
    // Written out: a closure passed to `map` may be left out of line, and
    // then compiled for the baseline target rather than the caller's clone.
    let sa = &t.solid_angle;
    let cover = [
        w[0] * (omega / V::gather(sa, p[0])),
        w[1] * (omega / V::gather(sa, p[1])),
        w[2] * (omega / V::gather(sa, p[2])),
        w[3] * (omega / V::gather(sa, p[3])),
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

/// The disk of leaf `s` (radius inflated by [`DISK_INFLATION`]) seen from
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
    let r2 = s.area * V::splat(std::f32::consts::FRAC_1_PI) * V::splat(DISK_INFLATION * DISK_INFLATION);
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
    fn cover(&self, w: [V; 3], ux: V, uy: V, uz: V) -> (V::Mask, V) {
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
    /// `delta`) wide at the hit distance, so a disk over a few pixels still
    /// shows its true area on average.
    #[inline(always)]
    fn hit(&self, ux: V, uy: V, uz: V, delta: V) -> (V::Mask, V, V) {
        let [mx, my, mz] = self.m;
        let denom = mx * ux + my * uy + mz * uz;
        let t = self.mc / denom;
        let ex = ux * t - self.c[0];
        let ey = uy * t - self.c[1];
        let ez = uz * t - self.c[2];
        let e = (ex * ex + ey * ey + ez * ez).sqrt();
        let cover = (V::splat(0.5) + (self.r - e) / (delta * t)).min_of(V::splat(1.0));
        let zero = V::splat(0.0);
        (denom.lt(zero) & zero.lt(t) & zero.lt(cover), t, cover)
    }
}

impl DiskPlan<f32> {
    /// The same disk in every lane.
    #[inline(always)]
    fn splat(&self) -> DiskPlan<F32s> {
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
    fn splat(&self) -> ConePlan<F32s> {
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

/// A pixel box is swept 16 pixels at a time in tiles of `w` columns by
/// `16 / w` rows (`w` = 4, 8 or 16, the narrowest that spans the box), each
/// row of a tile one contiguous load from a pixel table. Lane `k` is column
/// `k % w`, row `k / w` of the tile.
#[derive(Clone, Copy)]
struct Tile {
    /// Pixel index of the tile's first lane.
    base: usize,
    /// Grid width (pixels from one row to the next).
    n: usize,
    /// Tile width, and its index in [`TILE_COL`] / [`TILE_ROW`].
    w: usize,
    shape: usize,
    /// Rows of the tile inside the box.
    rows: usize,
    /// Lanes inside the box.
    inside: M32s,
}

impl Tile {
    /// The tile's 16 entries of the pixel table `a` (padded by [`LANES`] past
    /// the last pixel, so that every row load stays inside); rows past
    /// `rows` repeat the last (their lanes are outside the box).
    #[inline(always)]
    fn load(&self, a: &[f32]) -> F32s {
        let row = |j: usize| self.base + j.min(self.rows - 1) * self.n;
        match self.w {
            4 => {
                let q = |j: usize| Simd::<f32, 4>::from_slice(&a[row(j)..row(j) + 4]);
                let lo: Simd<f32, 8> = simd_swizzle!(q(0), q(1), [0, 1, 2, 3, 4, 5, 6, 7]);
                let hi: Simd<f32, 8> = simd_swizzle!(q(2), q(3), [0, 1, 2, 3, 4, 5, 6, 7]);
                simd_swizzle!(lo, hi, [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15])
            }
            8 => {
                let h = |j: usize| Simd::<f32, 8>::from_slice(&a[row(j)..row(j) + 8]);
                simd_swizzle!(h(0), h(1), [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15])
            }
            _ => F32s::from_slice(&a[self.base..self.base + LANES]),
        }
    }

    /// The pixel of lane `k`.
    #[inline(always)]
    fn pixel(&self, k: usize) -> usize {
        self.base + TILE_ROW[self.shape][k] as usize * self.n + TILE_COL[self.shape][k] as usize
    }
}

/// Tile width for a box `cols` pixels wide.
#[inline(always)]
fn tile_width(cols: usize) -> usize {
    if cols <= 4 {
        4
    } else if cols <= 8 {
        8
    } else {
        16
    }
}

/// Column and row of each lane in a tile of width 4, 8 and 16.
const TILE_COL: [[i32; LANES]; 3] = [
    [0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3],
    [0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2, 3, 4, 5, 6, 7],
    [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15],
];
const TILE_ROW: [[i32; LANES]; 3] = [
    [0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3],
    [0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1],
    [0; LANES],
];

/// The tiles covering the pixel box `(c0, c1, r0, r1)` of an `n`-wide grid,
/// row by row of tiles.
struct Tiles {
    n: usize,
    c0: usize,
    c1: usize,
    r1: usize,
    w: usize,
    h: usize,
    shape: usize,
    r: usize,
    c: usize,
}

impl Tiles {
    #[inline(always)]
    fn new(n: usize, (c0, c1, r0, r1): (usize, usize, usize, usize)) -> Self {
        let w = tile_width(c1 + 1 - c0);
        Tiles {
            n,
            c0,
            c1,
            r1,
            w,
            h: LANES / w,
            shape: w.trailing_zeros() as usize - 2,
            r: r0,
            c: c0,
        }
    }
}

impl Iterator for Tiles {
    type Item = Tile;
    #[inline(always)]
    fn next(&mut self) -> Option<Tile> {
        if self.r > self.r1 {
            return None;
        }
        let (r, c) = (self.r, self.c);
        let cols = (self.c1 + 1 - c).min(self.w);
        let rows = (self.r1 + 1 - r).min(self.h);
        let inside = Simd::from_array(TILE_COL[self.shape]).simd_lt(Simd::splat(cols as i32))
            & Simd::from_array(TILE_ROW[self.shape]).simd_lt(Simd::splat(rows as i32));
        self.c += self.w;
        if self.c > self.c1 {
            self.c = self.c0;
            self.r += self.h;
        }
        Some(Tile {
            base: r * self.n + c,
            n: self.n,
            w: self.w,
            shape: self.shape,
            rows,
            inside,
        })
    }
}

/// [`MicroBuffer::write`] on the buffer's arrays (borrowed apart from its
/// pixel table).
#[inline(always)]
fn write_pixel(
    own: &mut [u64],
    any: &mut [u64],
    cover: &mut [u32],
    p: usize,
    key: u64,
    coverage: f32,
    owns: bool,
) {
    debug_assert!(coverage >= 0.0, "coverage {coverage}");
    let c = (coverage.min_of(1.0) * COVER_ONE) as u32;
    cover[p] = (cover[p] + c).min(COVER_CAP);
    any[p] = any[p].min(key);
    if owns {
        own[p] = own[p].min(key);
    }
}

impl MicroBuffer {
    /// Adds a splat of `key` covering the fraction `coverage` ∈ [0, 1] of pixel `p`.
    #[inline(always)]
    fn write(&mut self, p: usize, key: u64, coverage: f32, owns: bool) {
        write_pixel(
            &mut self.own,
            &mut self.any,
            &mut self.cover,
            p,
            key,
            coverage,
            owns,
        );
    }

    /// [`write`](Self::write) where `m`, else nothing, without a branch:
    /// whether a corner gets weight is data the branch predictor cannot learn.
    #[inline(always)]
    fn write_if(&mut self, m: bool, p: usize, key: u64, coverage: f32, owns: bool) {
        let c = (f32::select(m, coverage, 0.0).min_of(1.0) * COVER_ONE) as u32;
        self.cover[p] = (self.cover[p] + c).min(COVER_CAP);
        let key = if m { key } else { NO_KEY };
        self.any[p] = self.any[p].min(key);
        let own_key = if owns { key } else { NO_KEY };
        self.own[p] = self.own[p].min(own_key);
    }

    /// Draws a small splat; it owns the pixel its centre falls in.
    #[inline(always)]
    pub(crate) fn draw_small(&mut self, plan: &SmallPlan<f32>, key: u64, pixel: f32) {
        for k in 0..4 {
            let p = plan.p[k];
            self.write_if(plan.w[k] > 0.0, p as usize, key, plan.cover[k], p == pixel);
        }
    }

    /// Draws a cone around local direction `w`; it owns the pixels it covers
    /// by at least one half.
    #[inline(always)]
    pub(crate) fn draw_cone(&mut self, w: Vec3, plan: &ConePlan<f32>, key: u64) {
        let (c0, c1, r0, r1) = plan.bx.bounds();
        let n = self.table.n;
        for r in r0..=r1 {
            for c in c0..=c1 {
                let p = r * n + c;
                let t = &self.table;
                let (m, cover) = plan.cover([w.x, w.y, w.z], t.dir_x[p], t.dir_y[p], t.dir_z[p]);
                if m {
                    self.write(p, key, cover, 0.5 <= cover);
                }
            }
        }
    }

    /// Draws a leaf's disk (depth: the hit distance); false if it covers no
    /// pixel centre.
    #[inline(always)]
    pub(crate) fn draw_disk(&mut self, plan: &DiskPlan<f32>, node: NodeId) -> bool {
        if !plan.fronts {
            return false;
        }
        let (c0, c1, r0, r1) = plan.bx.bounds();
        let n = self.table.n;
        let mut any_hit = false;
        for row in r0..=r1 {
            for col in c0..=c1 {
                let p = row * n + col;
                let t = &self.table;
                let (hit, depth, cover) = plan.hit(t.dir_x[p], t.dir_y[p], t.dir_z[p], t.pixel_size[p]);
                if hit {
                    self.write(p, key(depth, node), cover, 0.5 <= cover);
                    any_hit = true;
                }
            }
        }
        any_hit
    }

    /// [`draw_cone`](Self::draw_cone) 16 pixels at a time (the 16-lane
    /// pipeline): the same coverage of each pixel, bit for bit.
    #[inline(always)]
    pub(crate) fn draw_cone_tiles(&mut self, w: Vec3, plan: &ConePlan<f32>, key: u64) {
        let (t, own, any, cov) = (&*self.table, &mut self.own, &mut self.any, &mut self.cover);
        let (lanes, wl) = (plan.splat(), [w.x, w.y, w.z].map(F32s::splat));
        for tile in Tiles::new(t.n, plan.bx.bounds()) {
            let (ux, uy, uz) = (tile.load(&t.dir_x), tile.load(&t.dir_y), tile.load(&t.dir_z));
            let (m, cover) = lanes.cover(wl, ux, uy, uz);
            let mut hits = (m & tile.inside).to_bitmask();
            if hits == 0 {
                continue;
            }
            let cover = cover.to_array();
            while hits != 0 {
                let k = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                let p = tile.pixel(k);
                write_pixel(own, any, cov, p, key, cover[k], 0.5 <= cover[k]);
            }
        }
    }

    /// [`draw_disk`](Self::draw_disk) 16 pixels at a time (the 16-lane
    /// pipeline): the same hits, depths and coverage, bit for bit.
    #[inline(always)]
    pub(crate) fn draw_disk_tiles(&mut self, plan: &DiskPlan<f32>, node: NodeId) -> bool {
        if !plan.fronts {
            return false;
        }
        let (t, own, any, cov) = (&*self.table, &mut self.own, &mut self.any, &mut self.cover);
        let lanes = plan.splat();
        let mut any_hit = false;
        for tile in Tiles::new(t.n, plan.bx.bounds()) {
            let (ux, uy, uz) = (tile.load(&t.dir_x), tile.load(&t.dir_y), tile.load(&t.dir_z));
            let (m, depth, cover) = lanes.hit(ux, uy, uz, tile.load(&t.pixel_size));
            let mut hits = (m & tile.inside).to_bitmask();
            if hits == 0 {
                continue;
            }
            any_hit = true;
            let (depth, cover) = (depth.to_array(), cover.to_array());
            while hits != 0 {
                let k = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                let p = tile.pixel(k);
                write_pixel(own, any, cov, p, key(depth[k], node), cover[k], 0.5 <= cover[k]);
            }
        }
        any_hit
    }

    /// Draws node `node` (record `rec`) located at `l`: the scalar pipeline,
    /// which works out only what the splat's class needs.
    #[inline(always)]
    pub(crate) fn apply(&mut self, rec: &SplatRecord, node: NodeId, l: &Located<f32>) {
        let t = &*self.table;
        let pixel = pixel_of(t, l.x, l.y);
        let visible = 0.0 < l.wz;
        let pixel_omega = f32::gather(&t.solid_angle, pixel);
        let key = key(l.d, node);
        if visible && l.omega < pixel_omega {
            let plan = plan_small(t, l.x, l.y, l.omega);
            self.draw_small(&plan, key, pixel);
        } else if rec.leaf != 0 {
            let plan = plan_disk(t, &self.frame_lanes(), &NodeSplat::of(rec), l.x, l.y, pixel, l.d);
            // `Ω` is a far-field estimate that blows up for a disk nearly in
            // the receiver's plane: a leaf missing every centre gets a pixel at most.
            if !self.draw_disk(&plan, node) && visible {
                let t = &*self.table;
                let plan = plan_small(t, l.x, l.y, pixel_omega);
                self.draw_small(&plan, key, pixel);
            }
        } else {
            let plan = plan_cone(t, l.x, l.y, pixel, l.omega, visible);
            self.draw_cone(Vec3::new(l.wx, l.wy, l.wz), &plan, key);
        }
    }
}
