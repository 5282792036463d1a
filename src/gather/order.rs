//! Packet order for receivers given in any order: Morton (Z-order) of their
//! positions, so the 16 receivers of a packet are neighbours and share most
//! of their traversal.

use glam::Vec3;

/// Spreads the low 21 bits of `x` to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1F_FFFF;
    x = (x | x << 32) & 0x1F_0000_0000_FFFF;
    x = (x | x << 16) & 0x1F_0000_FF00_00FF;
    x = (x | x << 8) & 0x100F_00F0_0F00_F00F;
    x = (x | x << 4) & 0x10C3_0C30_C30C_30C3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// The receivers' indices in Morton order of their positions over the
/// positions' bounding box (21 bits an axis); ties keep input order, so the
/// order is a function of the positions alone.
pub(super) fn morton(positions: impl ExactSizeIterator<Item = Vec3> + Clone) -> Vec<u32> {
    let mut keys: Vec<(u64, u32)> = morton_codes(positions).zip(0..).collect();
    keys.sort_unstable();
    keys.into_iter().map(|(_, i)| i).collect()
}

/// The Morton (Z-order) code of each of `positions` over their bounding box,
/// 21 bits an axis.
pub(crate) fn morton_codes(
    positions: impl ExactSizeIterator<Item = Vec3> + Clone,
) -> impl ExactSizeIterator<Item = u64> {
    let (lo, hi) = positions
        .clone()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    let scale = ((1u32 << 21) - 1) as f32 / (hi - lo).max_element().max(f32::MIN_POSITIVE);
    positions.map(move |p| {
        // In [0, 2²¹): the cast saturates, so rounding cannot overflow.
        let q = ((p - lo) * scale).to_array().map(|c| c as u64);
        spread(q[0]) | spread(q[1]) << 1 | spread(q[2]) << 2
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_puts_each_bit_three_apart() {
        assert_eq!(spread(0b1011), 0b001_000_001_001);
        assert_eq!(spread(0x1F_FFFF), 0x1249_2492_4924_9249);
    }

    #[test]
    fn neighbours_come_together() {
        // Two clusters far apart, interleaved in the input.
        let p: Vec<Vec3> = (0..32)
            .map(|i| Vec3::new(if i % 2 == 0 { 0.0 } else { 100.0 }, i as f32 * 1e-3, 0.0))
            .collect();
        let order = morton(p.iter().copied());
        let (first, second) = order.split_at(16);
        assert!(first.iter().all(|&i| i % 2 == 0), "{order:?}");
        assert!(second.iter().all(|&i| i % 2 == 1), "{order:?}");
    }
}
