//! What a splat leaves in a pixel: a fragment (pixel, depth and node,
//! coverage). Drawn by `draw`, `tiles` and `shade`; composed by `compose`.

/// The fragments of one receiver, one per (splat, pixel) it covers, as
/// parallel arrays (of plain integers and floats: their growth code is not
/// the crate's, so the kernels' clones call nothing of the crate's own).
#[derive(Clone, Debug, Default)]
pub(crate) struct Fragments {
    /// Pixel index.
    pub pixel: Vec<u32>,
    /// `(depth, node)` (`buffer::key`).
    pub key: Vec<u64>,
    /// Fraction of the pixel covered (≥ 0; at most 1 but for a normalised
    /// cone's scaled coverage).
    pub cover: Vec<f32>,
    /// The radiance the node shows this receiver.
    pub radiance: Vec<[f32; 3]>,
}

impl Fragments {
    /// Adds a fragment if it covers anything.
    #[inline(always)]
    pub fn push(&mut self, pixel: usize, key: u64, cover: f32, radiance: [f32; 3]) {
        if 0.0 < cover {
            self.pixel.push(pixel as u32);
            self.key.push(key);
            self.cover.push(cover);
            self.radiance.push(radiance);
        }
    }

    /// Number of fragments.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.pixel.len()
    }

    /// Forgets every fragment.
    #[inline(always)]
    pub fn clear(&mut self) {
        self.pixel.clear();
        self.key.clear();
        self.cover.clear();
        self.radiance.clear();
    }
}
