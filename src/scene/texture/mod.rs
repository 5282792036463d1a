//! Textures: images on surfaces, looked up by texture coordinates.
//!
//! A [`Texture`] is a pyramid of levels (the image, then 2×2 box averages
//! down to one texel); [`TextureMap`] (in `maps`) places one on a material
//! (which coordinate set, which transform), as do the cut-out
//! ([`AlphaMap`]) and the normal map ([`NormalMap`]). Lookups are bilinear within a level
//! and linear between two levels picked by the footprint: the width, in
//! scene units, of the surface a lookup stands for (a pixel's, a
//! surfel's). Every step is plain `+ − × ÷` and `sqrt` on `f32`, so a
//! lookup is bit-identical on every ISA (no `powf`, no `log2`).
//!
//! Coordinates are glTF's: `(0, 0)` is the image's top-left texel's
//! corner, `v` grows downwards. Readers of OBJ (where `v` grows upwards)
//! flip `v` on reading.

mod maps;

use std::sync::OnceLock;

use glam::{Vec2, Vec4};

pub use maps::{AlphaMap, NormalMap, Relief, SurfacePoint, TextureMap, UvTransform};

use super::SceneError;

/// What a lookup outside `[0, 1]` reads, per axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The image tiles the plane.
    #[default]
    Repeat,
    /// The edge texel continues.
    Clamp,
    /// The image tiles, every other copy mirrored.
    Mirror,
}

/// How 8-bit texels map to values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Colour: red, green and blue are sRGB-encoded (alpha is linear).
    Srgb,
    /// Data (alpha, normals, heights): `byte / 255`.
    Linear,
}

/// The texels of one level, row by row from the top.
#[derive(Clone, Debug, PartialEq)]
enum Texels {
    /// RGBA bytes, decoded through the encoding's table.
    Bytes(Vec<[u8; 4]>),
    /// RGBA values (from EXR, 16-bit images, or made here).
    Floats(Vec<[f32; 4]>),
}

#[derive(Clone, Debug, PartialEq)]
struct Level {
    width: u32,
    height: u32,
    texels: Texels,
}

/// An image to put on surfaces, with its smaller levels.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from (the file), for messages.
    pub name: String,
    encoding: Encoding,
    /// Whether the source has an alpha channel (otherwise alpha is 1).
    has_alpha: bool,
    levels: Vec<Level>,
}

/// The sRGB transfer function's inverse at `byte / 255`, one entry per byte.
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|b| srgb_to_linear(b as f64 / 255.0) as f32))
}

/// `c` decoded from sRGB, in `f64` with `+ − × ÷ sqrt` only (identical on
/// every target): `((c + 0.055) / 1.055)^2.4`, the power as `x² · x^0.4`
/// with `x^0.4` the fifth root of `x²` by Newton's method.
fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        return c / 12.92;
    }
    let x = (c + 0.055) / 1.055;
    let a = x * x;
    // y⁵ = a, from y = sqrt(sqrt(a)) (a ∈ (0.0023, 1]: 40 steps are far past convergence).
    let mut y = a.sqrt().sqrt();
    for _ in 0..40 {
        let y4 = (y * y) * (y * y);
        y -= (y * y4 - a) / (5.0 * y4);
    }
    a * y
}

impl Level {
    #[inline(always)]
    fn texel(&self, encoding: Encoding, x: u32, y: u32) -> Vec4 {
        let i = (y * self.width + x) as usize;
        match &self.texels {
            Texels::Floats(t) => Vec4::from_array(t[i]),
            Texels::Bytes(t) => {
                let [r, g, b, a] = t[i];
                let alpha = a as f32 * (1.0 / 255.0);
                match encoding {
                    Encoding::Srgb => {
                        let table = srgb_table();
                        Vec4::new(table[r as usize], table[g as usize], table[b as usize], alpha)
                    }
                    Encoding::Linear => Vec4::new(r as f32, g as f32, b as f32, a as f32) * (1.0 / 255.0),
                }
            }
        }
    }

    /// The level below: 2×2 box averages (an odd last row or column
    /// averaged with itself).
    fn halved(&self, encoding: Encoding) -> Level {
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let mut texels = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let (x0, y0) = ((2 * x).min(self.width - 1), (2 * y).min(self.height - 1));
                let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
                let sum = self.texel(encoding, x0, y0)
                    + self.texel(encoding, x1, y0)
                    + self.texel(encoding, x0, y1)
                    + self.texel(encoding, x1, y1);
                texels.push((sum * 0.25).to_array());
            }
        }
        let texels = match (&self.texels, encoding) {
            (Texels::Floats(_), _) => Texels::Floats(texels),
            (Texels::Bytes(_), _) => Texels::Bytes(texels.iter().map(|t| encode(*t, encoding)).collect()),
        };
        Level {
            width: w,
            height: h,
            texels,
        }
    }
}

/// The byte nearest to linear `v` under `encoding` (by search in the
/// table: no `powf`).
fn encode(t: [f32; 4], encoding: Encoding) -> [u8; 4] {
    let linear = |v: f32| (v * 255.0 + 0.5).clamp(0.0, 255.0) as u8;
    let srgb = |v: f32| {
        let table = srgb_table();
        let i = table.partition_point(|&e| e < v).min(255);
        if i > 0 && v - table[i - 1] <= table[i] - v {
            (i - 1) as u8
        } else {
            i as u8
        }
    };
    match encoding {
        Encoding::Srgb => [srgb(t[0]), srgb(t[1]), srgb(t[2]), linear(t[3])],
        Encoding::Linear => t.map(linear),
    }
}

/// `x` wrapped into `[0, n)` by `wrap`.
#[inline(always)]
fn wrapped(x: i64, n: u32, wrap: Wrap) -> u32 {
    let n = n as i64;
    (match wrap {
        Wrap::Repeat => x.rem_euclid(n),
        Wrap::Clamp => x.clamp(0, n - 1),
        Wrap::Mirror => {
            let m = x.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
    }) as u32
}

/// A base-2 logarithm good to 0.09 (exponent plus the mantissa's linear
/// part): monotonic and made of bit operations, so it is the same everywhere.
#[inline(always)]
fn approx_log2(x: f32) -> f32 {
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    let mantissa = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    exponent as f32 + (mantissa - 1.0)
}

impl Texture {
    /// A texture of `width × height` 8-bit RGBA texels (row by row from
    /// the top) under `encoding`. Errors: a size of zero, or a texel count
    /// that is not `width × height`.
    pub fn from_bytes(
        name: impl Into<String>,
        width: u32,
        height: u32,
        texels: Vec<[u8; 4]>,
        encoding: Encoding,
        has_alpha: bool,
    ) -> Result<Texture, SceneError> {
        Texture::build(
            name.into(),
            width,
            height,
            Texels::Bytes(texels),
            encoding,
            has_alpha,
        )
    }

    /// A texture of linear RGBA values. Errors as [`Texture::from_bytes`],
    /// and a value that is not finite (naming the texel).
    pub fn from_floats(
        name: impl Into<String>,
        width: u32,
        height: u32,
        texels: Vec<[f32; 4]>,
        has_alpha: bool,
    ) -> Result<Texture, SceneError> {
        let name = name.into();
        if let Some(i) = texels.iter().position(|t| !t.iter().all(|c| c.is_finite())) {
            let w = width.max(1) as usize;
            return Err(SceneError::Invalid {
                what: format!("texture {name}: texel ({}, {}) is not finite", i % w, i / w),
            });
        }
        Texture::build(
            name,
            width,
            height,
            Texels::Floats(texels),
            Encoding::Linear,
            has_alpha,
        )
    }

    fn build(
        name: String,
        width: u32,
        height: u32,
        texels: Texels,
        encoding: Encoding,
        has_alpha: bool,
    ) -> Result<Texture, SceneError> {
        let count = match &texels {
            Texels::Bytes(t) => t.len(),
            Texels::Floats(t) => t.len(),
        };
        if width == 0 || height == 0 || count != width as usize * height as usize {
            return Err(SceneError::Invalid {
                what: format!("texture {name}: {count} texels for {width}×{height}"),
            });
        }
        let mut levels = vec![Level {
            width,
            height,
            texels,
        }];
        while let Some(last) = levels.last()
            && (last.width > 1 || last.height > 1)
        {
            let next = last.halved(encoding);
            levels.push(next);
        }
        Ok(Texture {
            name,
            encoding,
            has_alpha,
            levels,
        })
    }

    /// Width and height of the image.
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// A 64-bit FNV-1a hash of the image's texels, size and encoding (what
    /// a baked tree depends on).
    pub fn fingerprint(&self) -> u64 {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |bytes: &[u8]| {
            for &b in bytes {
                h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
            }
        };
        let l = &self.levels[0];
        eat(&l.width.to_le_bytes());
        eat(&l.height.to_le_bytes());
        eat(&[self.encoding as u8, self.has_alpha as u8]);
        match &l.texels {
            Texels::Bytes(t) => t.iter().for_each(|t| eat(t)),
            Texels::Floats(t) => t.iter().flatten().for_each(|c| eat(&c.to_bits().to_le_bytes())),
        }
        h
    }

    /// Whether the image has an alpha channel.
    pub fn has_alpha(&self) -> bool {
        self.has_alpha
    }

    /// The mean of the whole image (its one-texel level).
    pub fn mean(&self) -> Vec4 {
        let last = self.levels.last().expect("a texture has a level");
        last.texel(self.encoding, 0, 0)
    }

    /// Bilinear lookup in `level` at `uv`.
    #[inline(always)]
    fn bilinear(&self, level: usize, uv: Vec2, wrap: [Wrap; 2]) -> Vec4 {
        let l = &self.levels[level];
        let x = uv.x * l.width as f32 - 0.5;
        let y = uv.y * l.height as f32 - 0.5;
        let (fx, fy) = (x.floor(), y.floor());
        let (tx, ty) = (x - fx, y - fy);
        // Far outside the image (or NaN coordinates) `as` saturates; the wrap keeps it in range.
        let (ix, iy) = (fx as i64, fy as i64);
        let x0 = wrapped(ix, l.width, wrap[0]);
        let x1 = wrapped(ix.saturating_add(1), l.width, wrap[0]);
        let y0 = wrapped(iy, l.height, wrap[1]);
        let y1 = wrapped(iy.saturating_add(1), l.height, wrap[1]);
        let top = l.texel(self.encoding, x0, y0) * (1.0 - tx) + l.texel(self.encoding, x1, y0) * tx;
        let bottom = l.texel(self.encoding, x0, y1) * (1.0 - tx) + l.texel(self.encoding, x1, y1) * tx;
        top * (1.0 - ty) + bottom * ty
    }

    /// The texture at `uv`, averaged over about `width` texels of the image
    /// (trilinear: 1 or less is the image itself, bilinear), wrapped by `wrap`.
    #[inline]
    pub fn sample(&self, uv: Vec2, width: f32, wrap: [Wrap; 2]) -> Vec4 {
        let last = self.levels.len() - 1;
        // A NaN width (a degenerate footprint) reads the image itself.
        if width.is_nan() || width <= 1.0 {
            return self.bilinear(0, uv, wrap);
        }
        let lod = approx_log2(width).min(last as f32);
        let lo = lod.floor() as usize;
        let t = lod - lo as f32;
        if lo >= last || t == 0.0 {
            return self.bilinear(lo.min(last), uv, wrap);
        }
        self.bilinear(lo, uv, wrap) * (1.0 - t) + self.bilinear(lo + 1, uv, wrap) * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_table_matches_the_transfer_function() {
        let t = srgb_table();
        assert_eq!(t[0], 0.0);
        assert_eq!(t[255], 1.0);
        for (b, &v) in t.iter().enumerate() {
            let c = b as f64 / 255.0;
            let want = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
            assert!((v as f64 - want).abs() < 1e-7, "{b}: {v} against {want}");
        }
        for b in 0..=255u8 {
            assert_eq!(encode([t[b as usize]; 4], Encoding::Srgb)[0], b);
        }
    }

    #[test]
    fn levels_average_and_lookups_wrap() {
        let texels = vec![
            [0, 0, 0, 255],
            [255, 255, 255, 255],
            [255, 255, 255, 255],
            [0, 0, 0, 255],
        ];
        let t = Texture::from_bytes("checker", 2, 2, texels, Encoding::Linear, false).unwrap();
        assert_eq!(t.levels.len(), 2);
        assert_eq!(t.mean().x, 128.0 / 255.0);
        // Texel centres read exactly; a repeat wraps.
        let repeat = [Wrap::Repeat; 2];
        assert_eq!(t.sample(Vec2::new(0.25, 0.25), 0.0, repeat).x, 0.0);
        assert_eq!(t.sample(Vec2::new(1.75, 0.25), 0.0, repeat).x, 1.0);
        assert_eq!(t.sample(Vec2::new(1.75, 0.25), 0.0, [Wrap::Clamp; 2]).x, 1.0);
        assert_eq!(t.sample(Vec2::new(-0.25, 0.25), 0.0, [Wrap::Clamp; 2]).x, 0.0);
        // A footprint of the whole image reads the mean.
        assert_eq!(t.sample(Vec2::new(0.3, 0.6), 2.0, repeat).x, 128.0 / 255.0);
    }

    #[test]
    fn wrap_modes() {
        assert_eq!(wrapped(-1, 4, Wrap::Repeat), 3);
        assert_eq!(wrapped(-1, 4, Wrap::Clamp), 0);
        assert_eq!(wrapped(-1, 4, Wrap::Mirror), 0);
        assert_eq!(wrapped(5, 4, Wrap::Mirror), 2);
        assert_eq!(wrapped(i64::MAX, 4, Wrap::Mirror), 0);
    }

    #[test]
    fn approx_log2_is_exact_at_powers_of_two_and_close_between() {
        for e in -10..20 {
            let x = 2f32.powi(e);
            assert_eq!(approx_log2(x), e as f32);
            assert!((approx_log2(x * 1.5) - (x * 1.5).log2()).abs() < 0.09);
        }
    }
}
