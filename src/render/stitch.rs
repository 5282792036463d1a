//! A frame cut into a grid of tiles, one job each on a farm, and the tiles
//! put back together. Each tile is a [`Crop`], so its pixels are the full
//! frame's, bit for bit; stitching copies them back.

use super::image::Image;
use super::options::Crop;

/// A `columns × rows` grid of tiles over a frame, numbered row by row from
/// the top left: tile `k` is column `k % columns` of row `k / columns`.
/// Column `i` spans pixels `i·width/columns .. (i+1)·width/columns`, rows
/// alike, so the tiles cover the frame once whatever its size.
///
/// ```
/// use pbgi::render::Tiles;
///
/// let tiles: Tiles = "2,2".parse()?;
/// let crop = tiles.crop(3, 255, 100)?; // the bottom right tile
/// assert_eq!((crop.x0, crop.y0, crop.x1, crop.y1), (127, 50, 255, 100));
/// # Ok::<(), pbgi::render::TileError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tiles {
    /// Tiles across.
    pub columns: u32,
    /// Tiles down.
    pub rows: u32,
}

/// What is wrong with a grid of tiles, a tile's number or a tile's image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TileError {
    /// Not two whole numbers `columns,rows`, both at least 1.
    Syntax {
        /// The text given.
        text: String,
    },
    /// A tile number past the grid's.
    NoSuchTile {
        /// The number given.
        tile: u32,
        /// The grid.
        tiles: Tiles,
    },
    /// More tiles across or down than the frame has pixels: a tile would
    /// hold none.
    TooSmall {
        /// The grid.
        tiles: Tiles,
        /// The frame's width.
        width: u32,
        /// The frame's height.
        height: u32,
    },
    /// Stitching: not one image per tile.
    Count {
        /// Images given.
        given: usize,
        /// The grid.
        tiles: Tiles,
    },
    /// Stitching: a tile's image is not the size its place in the frame
    /// the first row's and column's tiles make gives.
    Size {
        /// The tile's number.
        tile: u32,
        /// Its size in the grid (width, height).
        expected: (u32, u32),
        /// Its image's size.
        found: (u32, u32),
    },
}

impl Tiles {
    /// Tiles in the grid.
    pub fn count(&self) -> u32 {
        self.columns.saturating_mul(self.rows)
    }

    /// The window of tile `tile` in a `width × height` frame.
    pub fn crop(&self, tile: u32, width: u32, height: u32) -> Result<Crop, TileError> {
        if tile >= self.count() {
            return Err(TileError::NoSuchTile { tile, tiles: *self });
        }
        if self.columns > width || self.rows > height {
            return Err(TileError::TooSmall {
                tiles: *self,
                width,
                height,
            });
        }
        // In u64: `i · width` overflows u32 for wide frames cut finely.
        let split = |i: u32, n: u32, size: u32| (u64::from(i) * u64::from(size) / u64::from(n)) as u32;
        let (i, j) = (tile % self.columns, tile / self.columns);
        Ok(Crop {
            x0: split(i, self.columns, width),
            y0: split(j, self.rows, height),
            x1: split(i + 1, self.columns, width),
            y1: split(j + 1, self.rows, height),
        })
    }

    /// The frame from its tiles' images, in tile order: its width the first
    /// row's widths summed, its height the first column's heights; every
    /// tile must be the size [`crop`](Self::crop) gives it in that frame.
    pub fn stitch(&self, tiles: &[Image]) -> Result<Image, TileError> {
        if self.count() == 0 {
            return Err(TileError::Syntax {
                text: self.to_string(),
            });
        }
        if tiles.len() != self.count() as usize {
            return Err(TileError::Count {
                given: tiles.len(),
                tiles: *self,
            });
        }
        let columns = self.columns as usize;
        let width: u32 = tiles[..columns].iter().map(|t| t.width).sum();
        let height: u32 = tiles.iter().step_by(columns).map(|t| t.height).sum();
        let mut pixels = vec![glam::Vec3::ZERO; width as usize * height as usize];
        for (k, tile) in (0..).zip(tiles) {
            let c = self.crop(k, width, height)?;
            if (tile.width, tile.height) != (c.width(), c.height()) {
                return Err(TileError::Size {
                    tile: k,
                    expected: (c.width(), c.height()),
                    found: (tile.width, tile.height),
                });
            }
            for (y, row) in (c.y0..c.y1).zip(tile.pixels.chunks_exact(tile.width as usize)) {
                let start = y as usize * width as usize + c.x0 as usize;
                pixels[start..start + row.len()].copy_from_slice(row);
            }
        }
        Ok(Image {
            width,
            height,
            pixels,
        })
    }
}

impl std::str::FromStr for Tiles {
    type Err = TileError;
    /// `columns,rows`, each at least 1.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let syntax = || TileError::Syntax { text: s.into() };
        let (c, r) = s.split_once(',').ok_or_else(syntax)?;
        let parse = |t: &str| {
            t.trim()
                .parse::<u32>()
                .ok()
                .filter(|&n| n >= 1)
                .ok_or_else(syntax)
        };
        Ok(Tiles {
            columns: parse(c)?,
            rows: parse(r)?,
        })
    }
}

impl std::fmt::Display for Tiles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{}", self.columns, self.rows)
    }
}

impl std::fmt::Display for TileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TileError::Syntax { text } => {
                write!(f, "tiles {text:?}: expected columns,rows (whole numbers from 1)")
            }
            TileError::NoSuchTile { tile, tiles } => write!(
                f,
                "tile {tile}: a {tiles} grid has tiles 0 to {}",
                tiles.count() - 1
            ),
            TileError::TooSmall { tiles, width, height } => write!(
                f,
                "tiles {tiles}: more than the {width}×{height} frame has pixels across or down"
            ),
            TileError::Count { given, tiles } => write!(
                f,
                "{given} tile image(s) for a {tiles} grid of {} tiles",
                tiles.count()
            ),
            TileError::Size {
                tile,
                expected,
                found,
            } => write!(
                f,
                "tile {tile} is {}×{}, where the grid gives it {}×{}",
                found.0, found.1, expected.0, expected.1
            ),
        }
    }
}

impl std::error::Error for TileError {}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, seed: f32) -> Image {
        let pixels = (0..width * height)
            .map(|i| glam::Vec3::new(seed, i as f32, -(i as f32)))
            .collect();
        Image {
            width,
            height,
            pixels,
        }
    }

    /// The tiles cover an awkwardly sized frame once, and their images
    /// stitch back into it, pixel for pixel.
    #[test]
    fn the_tiles_cover_the_frame_once_and_stitch_back() {
        let (w, h) = (37, 23);
        let frame = image(w, h, 0.5);
        for tiles in [
            Tiles { columns: 1, rows: 1 },
            Tiles { columns: 3, rows: 2 },
            Tiles { columns: 5, rows: 7 },
        ] {
            let mut seen = vec![0; (w * h) as usize];
            let mut parts = Vec::new();
            for k in 0..tiles.count() {
                let c = tiles.crop(k, w, h).unwrap();
                let mut part = Vec::new();
                for y in c.y0..c.y1 {
                    for x in c.x0..c.x1 {
                        seen[(y * w + x) as usize] += 1;
                        part.push(frame.pixels[(y * w + x) as usize]);
                    }
                }
                parts.push(Image {
                    width: c.width(),
                    height: c.height(),
                    pixels: part,
                });
            }
            assert!(seen.iter().all(|&n| n == 1), "{tiles}: {seen:?}");
            assert_eq!(tiles.stitch(&parts).unwrap().pixels, frame.pixels, "{tiles}");
        }
    }

    /// Bad grids, numbers and images are errors that name them.
    #[test]
    fn bad_tiles_are_errors_naming_them() {
        for text in ["2", "0,2", "2,x", "2,2,2", ""] {
            assert_eq!(
                text.parse::<Tiles>(),
                Err(TileError::Syntax { text: text.into() })
            );
        }
        let tiles: Tiles = "2,2".parse().unwrap();
        assert_eq!(tiles.crop(4, 8, 8), Err(TileError::NoSuchTile { tile: 4, tiles }));
        assert!(matches!(tiles.crop(0, 1, 8), Err(TileError::TooSmall { .. })));
        let parts: Vec<Image> = (0..4).map(|k| image(4, 4, k as f32)).collect();
        assert_eq!(
            tiles.stitch(&parts[..3]),
            Err(TileError::Count { given: 3, tiles })
        );
        let mut wrong = parts.clone();
        wrong[3] = image(4, 3, 3.0);
        assert_eq!(
            tiles.stitch(&wrong),
            Err(TileError::Size {
                tile: 3,
                expected: (4, 4),
                found: (4, 3)
            })
        );
        assert_eq!(tiles.stitch(&parts).map(|i| (i.width, i.height)), Ok((8, 8)));
    }
}
