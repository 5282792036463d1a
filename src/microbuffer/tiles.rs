//! The tiled draw: a cone's or a disk's pixels tested 16 at a time (4×4,
//! 8×2 or 16×1 tiles of contiguous row loads), for the 16-lane pipeline;
//! the same coverage, hits and depths as the scalar draw, bit for bit.

use std::simd::prelude::*;
use std::simd::simd_swizzle;

use glam::Vec3;

use super::buffer::{MicroBuffer, key};
use super::draw::normalize_cone;
use super::plan::{ConePlan, DiskPlan};
use crate::simd::{F32s, LANES, M32s, Real, set_bits};
use crate::tree::NodeId;

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
    pub(super) fn load(&self, a: &[f32]) -> F32s {
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
    pub(super) fn pixel(&self, k: usize) -> usize {
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
    pub(super) fn new(n: usize, (c0, c1, r0, r1): (usize, usize, usize, usize)) -> Self {
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

impl MicroBuffer {
    /// [`draw_cone`](Self::draw_cone) 16 pixels at a time (the 16-lane
    /// pipeline): the same coverage of each pixel, bit for bit.
    #[inline(always)]
    pub(crate) fn draw_cone_tiles(
        &mut self,
        w: Vec3,
        plan: &ConePlan<f32>,
        key: u64,
        target: f32,
        radiance: [f32; 3],
    ) {
        let (t, frags) = (&*self.table, &mut self.frags);
        let start = frags.len();
        let (lanes, wl) = (plan.splat(), [w.x, w.y, w.z].map(F32s::splat));
        for tile in Tiles::new(t.n, plan.bx.bounds()) {
            let (ux, uy, uz) = (tile.load(&t.dir_x), tile.load(&t.dir_y), tile.load(&t.dir_z));
            let (m, cover) = lanes.cover(wl, ux, uy, uz);
            let hits = (m & tile.inside).to_bitmask();
            if hits == 0 {
                continue;
            }
            let cover = cover.to_array();
            for k in set_bits(hits) {
                frags.push(tile.pixel(k), key, cover[k].min_of(1.0), radiance);
            }
        }
        normalize_cone(frags, start, t, target);
    }

    /// [`draw_disk`](Self::draw_disk) 16 pixels at a time (the 16-lane
    /// pipeline): the same hits, depths and coverage, bit for bit.
    #[inline(always)]
    pub(crate) fn draw_disk_tiles(&mut self, plan: &DiskPlan<f32>, node: NodeId, radiance: [f32; 3]) -> bool {
        if !plan.fronts {
            return false;
        }
        let (t, frags) = (&*self.table, &mut self.frags);
        let lanes = plan.splat();
        let mut any_hit = false;
        for tile in Tiles::new(t.n, plan.bx.bounds()) {
            let (ux, uy, uz) = (tile.load(&t.dir_x), tile.load(&t.dir_y), tile.load(&t.dir_z));
            let (m, depth, cover) = lanes.hit(ux, uy, uz, tile.load(&t.pixel_size));
            let hits = (m & tile.inside).to_bitmask();
            if hits == 0 {
                continue;
            }
            any_hit = true;
            let (depth, cover) = (depth.to_array(), cover.to_array());
            for k in set_bits(hits) {
                frags.push(tile.pixel(k), key(depth[k], node), cover[k].min_of(1.0), radiance);
            }
        }
        any_hit
    }
}
