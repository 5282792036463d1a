//! The octree of cells the records live in: a cube around the tree's
//! bounding sphere, `2^(COARSE + level)` cells across at each level, each
//! cell named by its level and the Morton code of its coordinates, so that
//! sorted keys run through space as neighbours.

use glam::Vec3;

/// Level 0 has `2^COARSE` cells across the scene's cube.
pub(super) const COARSE: u32 = 3;

/// Bits of a cell coordinate at the finest resolution the codes keep.
const BITS: u32 = 20;

/// The deepest level: the key keeps it in four bits and its cell's Morton
/// code in 57.
pub(super) const MAX_LEVEL: u32 = 15;

/// A cell and a facing: the level in the top four bits, the facing (one of
/// six axis directions) in the next three, the Morton code of the cell's
/// coordinates below, so that sorted keys run facing by facing, through
/// space as neighbours.
pub(super) type Key = u64;

/// The cube, and how deep its cells go.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Grid {
    /// The cube's lowest corner.
    pub origin: Vec3,
    /// Its side.
    pub size: f32,
    /// Levels `0..levels`.
    pub levels: u32,
}

impl Grid {
    /// The cube of side `2·radius` about `centre`, with `levels` levels.
    pub fn new(centre: Vec3, radius: f32, levels: u32) -> Self {
        Grid {
            origin: centre - Vec3::splat(radius),
            size: 2.0 * radius,
            levels: levels.clamp(1, MAX_LEVEL + 1),
        }
    }

    /// Cells across at `level`.
    #[inline]
    pub fn across(level: u32) -> u32 {
        1 << (COARSE + level)
    }

    /// The side of a cell at `level`.
    #[inline]
    pub fn cell_size(&self, level: u32) -> f32 {
        self.size / Self::across(level) as f32
    }

    /// The coordinates of the cell at `level` holding `p`, or `None` outside
    /// the cube.
    #[inline]
    pub fn cell(&self, p: Vec3, level: u32) -> Option<[u32; 3]> {
        let n = Self::across(level);
        let q = (p - self.origin) / self.cell_size(level);
        let inside = |v: f32| v >= 0.0 && v < n as f32;
        (inside(q.x) && inside(q.y) && inside(q.z)).then_some([q.x as u32, q.y as u32, q.z as u32])
    }

    /// The centre of cell `c` at `level`.
    #[inline]
    pub fn centre(&self, c: [u32; 3], level: u32) -> Vec3 {
        let h = self.cell_size(level);
        self.origin + (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + 0.5) * h
    }

    /// The Morton code of `p` at the finest resolution (0 outside the
    /// cube, where no leaf lies: the cube holds the tree's sphere).
    pub fn code(&self, p: Vec3) -> u64 {
        let n = (1u32 << BITS) as f32;
        let q = ((p - self.origin) / self.size * n).clamp(Vec3::ZERO, Vec3::splat(n - 1.0));
        morton3([q.x as u32, q.y as u32, q.z as u32])
    }

    /// The range of finest codes inside cell `c` at `level`.
    pub fn codes(c: [u32; 3], level: u32) -> (u64, u64) {
        let shift = 3 * (BITS - COARSE - level);
        let m = morton3(c);
        (m << shift, (m + 1) << shift)
    }
}

/// The key of cell `c` at `level`, for facing `facing`.
#[inline]
pub(super) fn key(c: [u32; 3], level: u32, facing: u8) -> Key {
    u64::from(level) << 60 | u64::from(facing) << 57 | morton3(c)
}

/// The cell of `key`: its coordinates, level and facing.
pub(super) fn cell_of(key: Key) -> ([u32; 3], u32, u8) {
    let level = (key >> 60) as u32;
    let facing = (key >> 57 & 7) as u8;
    let m = key & ((1 << 57) - 1);
    ([compact(m), compact(m >> 1), compact(m >> 2)], level, facing)
}

/// Interleaves the low 20 bits of each coordinate: x in bit 0, y in bit 1,
/// z in bit 2.
#[inline]
pub(super) fn morton3(c: [u32; 3]) -> u64 {
    spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2
}

#[inline]
fn spread(v: u32) -> u64 {
    let mut v = u64::from(v) & 0xF_FFFF;
    v = (v | v << 32) & 0x001F_0000_0000_FFFF;
    v = (v | v << 16) & 0x001F_0000_FF00_00FF;
    v = (v | v << 8) & 0x100F_00F0_0F00_F00F;
    v = (v | v << 4) & 0x10C3_0C30_C30C_30C3;
    (v | v << 2) & 0x1249_2492_4924_9249
}

fn compact(m: u64) -> u32 {
    let mut v = m & 0x1249_2492_4924_9249;
    v = (v | v >> 2) & 0x10C3_0C30_C30C_30C3;
    v = (v | v >> 4) & 0x100F_00F0_0F00_F00F;
    v = (v | v >> 8) & 0x001F_0000_FF00_00FF;
    v = (v | v >> 16) & 0x001F_0000_0000_FFFF;
    v = (v | v >> 32) & 0xF_FFFF;
    v as u32
}

/// A hasher for keys (already well spread by Morton order): one multiply.
#[derive(Default, Clone, Copy)]
pub(super) struct KeyHasher(u64);

impl std::hash::Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x100_0000_01B3);
        }
    }
    fn write_u64(&mut self, k: u64) {
        self.0 = (k ^ k >> 29).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        self.0 ^= self.0 >> 32;
    }
}

pub(super) type KeyMap<V> = std::collections::HashMap<Key, V, std::hash::BuildHasherDefault<KeyHasher>>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_name_their_cell_and_codes_nest() {
        for c in [
            [0, 0, 0],
            [1, 2, 3],
            [1023, 5, 77],
            [(1 << 17) - 1, 9, (1 << 16) + 3],
        ] {
            for level in [0, 4, MAX_LEVEL] {
                let c = c.map(|v| v % Grid::across(level));
                for facing in [0, 5] {
                    assert_eq!(cell_of(key(c, level, facing)), (c, level, facing));
                }
            }
        }
        // A point's finest code lies in the range of its cell at every level.
        let g = Grid::new(Vec3::new(1.0, -2.0, 3.0), 5.0, 8);
        let p = Vec3::new(2.3, -4.1, 6.9);
        let code = g.code(p);
        for level in 0..8 {
            let c = g.cell(p, level).expect("inside");
            let (lo, hi) = Grid::codes(c, level);
            assert!(lo <= code && code < hi, "level {level}");
            let centre = g.centre(c, level);
            assert!((centre - p).abs().max_element() <= 0.5 * g.cell_size(level) * 1.0001);
        }
        assert_eq!(g.cell(Vec3::new(100.0, 0.0, 0.0), 0), None);
    }
}
