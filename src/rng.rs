//! The one random-number generator of the crate: SplitMix64, so sampling
//! depends on the seed alone, not on a crate's version.

/// SplitMix64's increment (the golden ratio in 64 bits).
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's step as a hash: spreads `x` over 64 bits.
#[inline]
pub fn mix(x: u64) -> u64 {
    let mut z = x.wrapping_add(GOLDEN);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A small deterministic generator (SplitMix64), so inputs do not depend on a
/// random-number crate's version.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// Seeded generator.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ GOLDEN)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let z = mix(self.0);
        self.0 = self.0.wrapping_add(GOLDEN);
        z
    }

    /// Uniform in `[0, 1)`.
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform unit vector.
    #[cfg(any(test, feature = "lab"))]
    pub fn unit_vector(&mut self) -> glam::Vec3 {
        let z = 2.0 * self.f32() - 1.0;
        let phi = std::f32::consts::TAU * self.f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        glam::Vec3::new(s * phi.cos(), s * phi.sin(), z).normalize()
    }
}

/// Point `i` of the first two dimensions of Sobol's sequence, a
/// (0,2)-sequence: every aligned block of 2^m points is stratified in each
/// elementary interval of area 2^-m, so a receiver's light samples, and a
/// pixel's over its camera samples, cover a light evenly. `scramble` XORs
/// the digits (random digit scrambling, which keeps the stratification).
/// Both coordinates in `[0, 1)`.
pub(crate) fn sobol2(i: u32, scramble: [u32; 2]) -> (f32, f32) {
    let (mut x, mut y, mut v, mut bits) = (0u32, 0u32, 1u32 << 31, i);
    let mut k = 0;
    while bits != 0 {
        if bits & 1 != 0 {
            x ^= 1 << (31 - k);
            y ^= v;
        }
        bits >>= 1;
        v ^= v >> 1;
        k += 1;
    }
    let unit = |b: u32| (b >> 8) as f32 * (1.0 / 16_777_216.0);
    (unit(x ^ scramble[0]), unit(y ^ scramble[1]))
}

/// The strata of `n` camera samples over a pixel: `(columns, rows)` with
/// `columns × rows = n`, rows the largest divisor of `n` not above √n, so
/// every stratum holds one sample (a √n grid rounded up left the last row
/// short: at 2 spp both samples fell in the pixel's top half, at 32 the
/// bottom sixth got a third of its share).
pub(crate) fn strata(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let rows = (1..=n.isqrt()).rev().find(|&r| n.is_multiple_of(r)).unwrap_or(1);
    (n / rows, rows)
}

/// Camera sample `s` of `spp` in pixel `(x, y)`: a point jittered by `rng`
/// within its stratum ([`strata`]), on the film. The renderer and the path
/// tracer sample pixels alike.
#[cfg(feature = "render")]
pub(crate) fn film_point(x: u32, y: u32, s: u32, spp: u32, rng: &mut Rng) -> (f32, f32) {
    let (across, down) = strata(spp);
    let fx = x as f32 + ((s % across) as f32 + rng.f32()) / across as f32;
    let fy = y as f32 + ((s / across) as f32 + rng.f32()) / down as f32;
    (fx, fy)
}

#[cfg(test)]
mod tests {
    use super::{sobol2, strata};

    /// Every sample count tiles the pixel exactly, square where it can.
    #[test]
    fn strata_tile_the_pixel() {
        assert_eq!(strata(1), (1, 1));
        assert_eq!(strata(2), (2, 1));
        assert_eq!(strata(16), (4, 4));
        assert_eq!(strata(32), (8, 4));
        assert_eq!(strata(7), (7, 1));
        for n in 1..300 {
            let (c, r) = strata(n);
            assert_eq!(c * r, n);
            assert!(r <= c);
        }
    }

    /// Each block of 16 points puts one point in each of the 4×4 cells, and
    /// in each 16×1 and 1×16 strip (the elementary intervals of a (0,4,2)-net).
    #[test]
    fn sobol_blocks_are_nets() {
        for scramble in [[0, 0], [0xDEAD_BEEF, 0x1234_5678]] {
            for block in 0..4 {
                let pts: Vec<(f32, f32)> = (0..16).map(|i| sobol2(block * 16 + i, scramble)).collect();
                for (cx, cy) in [(4usize, 4usize), (16, 1), (1, 16), (8, 2), (2, 8)] {
                    let mut cells = vec![0; cx * cy];
                    for &(x, y) in &pts {
                        assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                        cells[(x * cx as f32) as usize * cy + (y * cy as f32) as usize] += 1;
                    }
                    assert!(cells.iter().all(|&c| c == 1), "{cx}×{cy} cells {cells:?}");
                }
            }
        }
    }
}
