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

    /// A random digit scramble for [`sobol2`]: 64 random bits.
    pub(crate) fn scramble(&mut self) -> [u32; 2] {
        let h = self.next_u64();
        [h as u32, (h >> 32) as u32]
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

/// Camera sample `s` of pixel `(x, y)` on the film: point `s` of the
/// pixel's scrambled (0,2)-sequence ([`sobol2`]). A pixel's first 2^m
/// samples fall one in each elementary interval of area 2^-m: in columns
/// and rows of 2^m as well as in squares, so an edge along either axis
/// crosses as many strata as there are samples (a jittered grid of 4 × 2
/// gives a horizontal edge two). The first samples of an adaptive render
/// are stratified among themselves and with the rest. The renderer and the
/// path tracer sample pixels alike.
#[cfg(feature = "render")]
#[inline]
pub(crate) fn film_point(x: u32, y: u32, s: u32, scramble: [u32; 2]) -> (f32, f32) {
    let (u, v) = sobol2(s, scramble);
    (x as f32 + u, y as f32 + v)
}

#[cfg(test)]
mod tests {
    use super::sobol2;

    /// A pixel's first 2, 4, …, 32 camera samples lie in the pixel, one in
    /// each of as many columns and as many rows: an edge along either axis
    /// meets them all (a jittered 4 × 2 grid puts 8 samples in 2 rows).
    #[cfg(feature = "render")]
    #[test]
    fn a_pixels_first_samples_take_each_row_and_column_once() {
        for scramble in [[0, 0], [0x9E37_79B9, 0x7F4A_7C15]] {
            for n in [2u32, 4, 8, 16, 32] {
                let (mut columns, mut rows) = (vec![0; n as usize], vec![0; n as usize]);
                for s in 0..n {
                    let (fx, fy) = super::film_point(3, 5, s, scramble);
                    assert!((3.0..4.0).contains(&fx) && (5.0..6.0).contains(&fy), "{fx}, {fy}");
                    columns[((fx - 3.0) * n as f32) as usize] += 1;
                    rows[((fy - 5.0) * n as f32) as usize] += 1;
                }
                assert!(
                    columns.iter().chain(&rows).all(|&c| c == 1),
                    "{n}: {columns:?} {rows:?}"
                );
            }
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
