//! What a farm's tasks need beyond a render: one frame range of a camera
//! path (`--frames`), one tile of a grid (`--tiles`, `--tile`), and
//! `pbgi stitch`, which puts a frame's tiles back together
//! (`farm/openjd/`, `farm/slurm/`).

use std::path::{Path, PathBuf};

use clap::Args;
use pbgi::render::{RenderOptions, TileError, Tiles};
use pbgi::scene::Scene;

use crate::args::{RenderArgs, Res};
use crate::path::frame_file;
use crate::{check_output, exit, read_exr, write_image};

/// Frames `first..=last` of a camera path, as a farm's task names them:
/// `K` or `A-B`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frames {
    /// The first frame.
    pub first: usize,
    /// The last frame (inclusive).
    pub last: usize,
}

impl Frames {
    /// The range within a path of `n` frames; an error names both.
    pub fn within(self, n: usize) -> Res<Frames> {
        if self.last >= n {
            return Err(exit::usage(format!(
                "--frames {self}: the camera path has frames 0 to {}",
                n.saturating_sub(1)
            )));
        }
        Ok(self)
    }
}

impl std::str::FromStr for Frames {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("frames {s:?}: expected K or A-B (whole numbers, A ≤ B)");
        let number = |t: &str| t.trim().parse::<usize>().map_err(|_| bad());
        let (first, last) = match s.split_once('-') {
            Some((a, b)) => (number(a)?, number(b)?),
            None => (number(s)?, number(s)?),
        };
        if first > last {
            return Err(bad());
        }
        Ok(Frames { first, last })
    }
}

impl std::fmt::Display for Frames {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.first == self.last {
            write!(f, "{}", self.first)
        } else {
            write!(f, "{}-{}", self.first, self.last)
        }
    }
}

/// `opts` with the crop of `--tile` of `--tiles` in `scene`'s frame, where given.
pub fn tile_crop(mut opts: RenderOptions, a: &RenderArgs, scene: &Scene) -> Res<RenderOptions> {
    if let (Some(tiles), Some(tile)) = (a.tiles, a.tile) {
        let crop = tiles
            .crop(tile, scene.camera.width, scene.camera.height)
            .map_err(|e| exit::usage(e.to_string()))?;
        opts.crop = Some(crop);
    }
    Ok(opts)
}

/// `pbgi stitch`: a frame's tiles, rendered with `--tiles` on a farm, put
/// back into the frame, bit for bit the image one render gives.
#[derive(Args, Clone)]
pub struct StitchArgs {
    /// The tiles' images (.exr): `{tile}` becomes each tile's number, and
    /// `{}` the frame's, 4 digits (with --frames), as `pbgi render` wrote them.
    #[arg(value_name = "TILES.exr")]
    pub pattern: PathBuf,
    /// The grid the tiles were rendered in (render --tiles).
    #[arg(long, value_name = "COLUMNS,ROWS")]
    pub tiles: Tiles,
    /// The frames to stitch, K or A-B: `{}` in the pattern and in -o
    /// become each one's number.
    #[arg(long, value_name = "K|A-B")]
    pub frames: Option<Frames>,
    /// The stitched frame (.exr or .png; `{}` the frame's number).
    #[arg(short, long, value_name = "OUT.exr")]
    pub output: PathBuf,
}

/// The file of tile `tile` of frame `frame` (if any) after `pattern`.
fn tile_file(pattern: &Path, frame: Option<usize>, tile: u32) -> PathBuf {
    let named = PathBuf::from(pattern.to_string_lossy().replace("{tile}", &tile.to_string()));
    match frame {
        Some(k) => frame_file(&named, k),
        None => named,
    }
}

pub fn cmd_stitch(a: &StitchArgs) -> Res<()> {
    if !a.pattern.to_string_lossy().contains("{tile}") {
        return Err(exit::usage(format!(
            "{}: put {{tile}} where the tile's number goes (tiles/frame-{{}}-tile-{{tile}}.exr)",
            a.pattern.display()
        )));
    }
    let framed = |p: &Path| p.to_string_lossy().contains("{}");
    if a.frames.is_some() && !(framed(&a.pattern) && framed(&a.output)) {
        return Err(exit::usage(
            "--frames: put {} where the frame's number goes, in the tiles' pattern and in -o",
        ));
    }
    check_output(&a.output)?;
    let frames: Vec<Option<usize>> = match a.frames {
        Some(f) => (f.first..=f.last).map(Some).collect(),
        None => vec![None],
    };
    for frame in frames {
        let tiles = (0..a.tiles.count())
            .map(|k| read_exr(&tile_file(&a.pattern, frame, k)))
            .collect::<Res<Vec<_>>>()?;
        // A tile of the wrong size is named by its file; the rest by the pattern.
        let image = a.tiles.stitch(&tiles).map_err(|e| {
            let file = match e {
                TileError::Size { tile, .. } => tile_file(&a.pattern, frame, tile),
                _ => a.pattern.clone(),
            };
            exit::input(format!("{}: {e}", file.display()))
        })?;
        let out = frame.map_or(a.output.clone(), |k| frame_file(&a.output, k));
        write_image(&image, &out)?;
        println!(
            "wrote {} ({}×{}, {} tiles, image digest {:016x})",
            out.display(),
            image.width,
            image.height,
            a.tiles.count(),
            image.digest()
        );
    }
    Ok(())
}
