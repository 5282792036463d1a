//! Render settings.

use crate::cut::{CutOptions, SchemeChoice};
use crate::error::Error;
use crate::scene::Scene;
use crate::tree::Precision;

/// The surfel budget `pbgi render` gives a scene file when neither
/// `--surfels` nor `--density` is given: about what the built-in Cornell box
/// gets at density 2000 (51,964 surfels).
pub const DEFAULT_SURFEL_BUDGET: u32 = 52_000;

/// About how many gathers the environment's light and each extra bounce
/// take at the surfels by default: groups of 8 at the default budget.
pub const DEFAULT_SURFEL_GATHERS: u32 = DEFAULT_SURFEL_BUDGET / 8;

/// Which light an image holds: the indirect part alone is what the gather
/// computes, and what its error is measured on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Component {
    /// Emission, direct and indirect light.
    #[default]
    All,
    /// Emission seen from the camera and light that reaches the first hit
    /// straight from an emitter.
    Direct,
    /// Light that reflects off at least one more surface before the first
    /// hit: the point-based gather, or the path tracer's longer paths.
    Indirect,
}

impl Component {
    /// Whether light that bounced `bounces` times before the first hit is in.
    pub fn holds(self, bounces: u32) -> bool {
        match self {
            Component::All => true,
            Component::Direct => bounces == 0,
            Component::Indirect => bounces > 0,
        }
    }
}

impl std::fmt::Display for Component {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Component::All => "all",
            Component::Direct => "direct",
            Component::Indirect => "indirect",
        })
    }
}

impl std::str::FromStr for Component {
    type Err = crate::error::Error;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "all" => Ok(Component::All),
            "direct" => Ok(Component::Direct),
            "indirect" => Ok(Component::Indirect),
            _ => Err(crate::error::Error::InvalidParameter {
                name: "component",
                value: s.into(),
                expected: "all, direct or indirect",
            }),
        }
    }
}

/// Where the indirect light is gathered.
///
/// It varies slowly over a surface, so a gather per camera sample is mostly
/// wasted. By default ([`Gathers::CACHE`]) records on the surfaces in world
/// space are gathered once and blended by every camera sample, tile and
/// frame that sees them (`crate::cache`); [`Gathers::Sparse`] gathers on a
/// lattice of pixel centres and interpolates, refining the lattice where
/// the geometry or the gathered light changes (`render::sparse`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Gathers {
    /// One gather per camera sample: the dense render, for validation.
    All,
    /// Gathers `spacing` pixels apart on smooth surfaces (a power of two),
    /// halved down to one pixel where the corners of a lattice cell lie on
    /// different surfaces or where two corners' irradiance differs by more
    /// than `threshold` of their mean.
    Sparse {
        /// Pixels between gathers on smooth surfaces: 1, 2, 4, … 64.
        spacing: u32,
        /// Relative change of the gathered light that refines a cell.
        threshold: f32,
    },
    /// Gathers at records in world space, shared by every sample, tile and
    /// frame that sees them, refined where the records of a surface differ
    /// by more than `threshold` of their sum (`crate::cache`).
    Cache {
        /// Relative difference between blended records that refines.
        threshold: f32,
    },
}

impl Gathers {
    /// The cache at its default threshold
    /// ([`crate::cache::DEFAULT_THRESHOLD`]): the default gathers.
    pub const CACHE: Gathers = Gathers::Cache {
        threshold: crate::cache::DEFAULT_THRESHOLD,
    };
    /// The screen lattice at its defaults: 4 pixels apart, refined at 0.1
    /// change.
    pub const SPARSE: Gathers = Gathers::Sparse {
        spacing: 4,
        threshold: 0.1,
    };
}

impl Default for Gathers {
    fn default() -> Self {
        Gathers::CACHE
    }
}

impl std::fmt::Display for Gathers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Gathers::All => f.write_str("every camera sample"),
            Gathers::Sparse { spacing, threshold } => {
                write!(f, "sparse, {spacing} px apart, refined at {threshold} change")
            }
            Gathers::Cache { threshold } => write!(f, "cached in world space, refined at {threshold} change"),
        }
    }
}

/// How a camera sample's area-light samples make its direct light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Direct {
    /// `Σ f·Li·cosθ / pdf` over the samples, shadowed ones giving nothing.
    Sampled,
    /// The diffuse part in closed form, shadows aside (Lambert's polygon
    /// formula), times the share of the samples' unshadowed light that
    /// reaches the point (Heitz et al. 2018's ratio estimator): no noise
    /// where every sample is lit or none is. A glossy lobe keeps the
    /// plain estimate; scenes of many emissive triangles too
    /// ([`crate::render::ANALYTIC_TRIANGLES`]).
    #[default]
    Ratio,
}

impl std::fmt::Display for Direct {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Direct::Sampled => "sampled",
            Direct::Ratio => "ratio",
        })
    }
}

/// Area-light samples per receiver when `RenderOptions::direct_samples` is `None`.
pub const DEFAULT_LIGHT_SAMPLES: u32 = 8;

/// Render settings; the defaults render the Cornell box in about a second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// The cut's parameters: Ω, the hybrid threshold, the instruction-set
    /// path. Ω 0.15 by default (with N 14): irradiance reads only the sum
    /// of the clusters' light, which a cluster sends from its light
    /// centroid, so a coarse cut costs it little (the Cornell box's dense
    /// indirect light 2.94 % against 2.47 % at Ω 0.05, N 24) in half the
    /// time. At Ω 0.2 the coverage falls short by about 1 % (the open box's
    /// occlusion and sky light, `tests/render.rs`). Receivers with a glossy
    /// lobe gather at their own Ω and N.
    pub cut: CutOptions,
    /// Traversal scheme.
    pub scheme: SchemeChoice,
    /// Microbuffer resolution N (an N×N octahedral grid over the hemisphere).
    pub microbuffer: usize,
    /// Ω of the gathers at receivers whose material has a glossy lobe. The
    /// lobe reads each cluster's light where the cluster is drawn, so it
    /// needs finer clusters than irradiance, which reads only their sum
    /// (mid-wall in the light room, glossy of roughness 0.3 at N 24: 21,
    /// 4.1, 1.9, 1.3 % at Ω 0.2, 0.05, 0.02, 0.01).
    pub glossy_max_solid_angle: f32,
    /// Microbuffer resolution of those gathers.
    pub glossy_microbuffer: usize,
    /// The light offset's weight in the cut of those gathers
    /// ([`CutOptions::light_offset`]): a lobe reads where a cluster's light
    /// is drawn.
    pub glossy_light_offset: f32,
    /// With [`Gathers::Cache`], lobes at least this rough take their light
    /// from the cache's records, which keep what their microbuffers saw
    /// (`crate::cache::Cache::reflect`); smoother ones, nearer a mirror
    /// than a record's pixels resolve, gather at each camera sample.
    pub glossy_cache_roughness: f32,
    /// Indirect bounces: 0 direct only, 1 direct + one bounce (Mitsuba's `max_depth` 3), …
    pub bounces: u32,
    /// Camera samples per pixel (antialiasing; each a receiver of direct light).
    pub spp: u32,
    /// Adaptive camera samples: this many in every pixel first, and `spp`
    /// only where a pixel's first samples disagree (another surface, a
    /// step in depth or normal, a hit beside a miss, the two sides of a
    /// hard shadow, a step in direct light) or differ from a neighbour's
    /// in surface or hard shadow; `None`: `spp` in every pixel.
    pub first_samples: Option<u32>,
    /// Where the indirect light is gathered: at records in world space (the
    /// default), at a sparse, adaptive lattice of pixels, or at every
    /// camera sample.
    pub gathers: Gathers,
    /// Area-light samples at each camera sample's receiver (`None`:
    /// [`DEFAULT_LIGHT_SAMPLES`]), independent of the camera samples: direct
    /// light costs a few shadow rays where a gather costs a microbuffer, so
    /// its noise is cheap to take out.
    pub direct_samples: Option<u32>,
    /// How the direct light combines those samples.
    pub direct: Direct,
    /// Ambient-occlusion mode: no radiance at all, `1 − AO` as a grey image.
    pub ao: bool,
    /// Surfels per unit area, when there is no `surfel_budget`.
    pub density: f32,
    /// About this many surfels whatever the scene's units: the density is
    /// the budget over the scene's surface area (`None`: `density`).
    pub surfel_budget: Option<u32>,
    /// Area-light samples per surfel.
    pub surfel_light_samples: u32,
    /// Leave out the surfels inside solids (on by default;
    /// [`BakeOptions::drop_buried`](crate::render::BakeOptions::drop_buried)).
    pub drop_buried: bool,
    /// About this many gathers of the environment's light, and of each
    /// extra bounce, at the surfels whatever their number: surfels share
    /// one in flat groups of at least 8, each over about the same share of
    /// the scene's area at any budget (more on curved parts, whose groups
    /// stay flat). `0`: groups of 8 however many surfels.
    pub surfel_gathers: u32,
    /// How the trees store what splatting reads of their nodes: whole, or
    /// quantized against each node's bounding sphere.
    pub tree_precision: Precision,
    /// Which light the image holds.
    pub component: Component,
    /// Seed of every random choice.
    pub seed: u64,
    /// Render only this window of the frame (`None`: the whole frame).
    pub crop: Option<Crop>,
}

/// A window of the frame: pixels `x0..x1` × `y0..y1` of the full-resolution
/// image. Each pixel of a cropped render is the same pixel of the full
/// frame, bit for bit, so tiles rendered apart stitch into the frame.
///
/// ```
/// use pbgi::render::{Crop, CropError};
///
/// let crop: Crop = "0,0,128,64".parse()?;
/// assert_eq!((crop.width(), crop.height()), (128, 64));
/// assert!(crop.within(256, 256).is_ok());
/// assert!(matches!(crop.within(100, 100), Err(CropError::OutsideFrame { .. })));
/// assert!(matches!("5,0,5,8".parse::<Crop>(), Err(CropError::Empty { .. })));
/// # Ok::<(), CropError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

/// What is wrong with a crop window.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CropError {
    /// Not four whole numbers `x0,y0,x1,y1`.
    Syntax {
        /// The text given.
        text: String,
    },
    /// `x0 ≥ x1` or `y0 ≥ y1`: no pixel.
    Empty {
        /// The window.
        crop: Crop,
    },
    /// The window reaches past the frame.
    OutsideFrame {
        /// The window.
        crop: Crop,
        /// The frame's width.
        width: u32,
        /// The frame's height.
        height: u32,
    },
}

impl Crop {
    /// Columns.
    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    /// Rows.
    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// The whole frame.
    pub fn full(width: u32, height: u32) -> Crop {
        Crop {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// Checks that the window holds a pixel and lies in a `width × height` frame.
    pub fn within(self, width: u32, height: u32) -> Result<Crop, CropError> {
        if self.x0 >= self.x1 || self.y0 >= self.y1 {
            return Err(CropError::Empty { crop: self });
        }
        if self.x1 > width || self.y1 > height {
            return Err(CropError::OutsideFrame {
                crop: self,
                width,
                height,
            });
        }
        Ok(self)
    }

    /// Whether pixel `(x, y)` of the frame is in the window.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }
}

impl std::fmt::Display for Crop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

impl std::str::FromStr for Crop {
    type Err = CropError;
    /// `x0,y0,x1,y1`; an empty window is an error here already.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let v: Vec<u32> = s
            .split(',')
            .map(|t| t.trim().parse::<u32>())
            .collect::<Result<_, _>>()
            .map_err(|_| CropError::Syntax { text: s.into() })?;
        let [x0, y0, x1, y1] = v[..] else {
            return Err(CropError::Syntax { text: s.into() });
        };
        let crop = Crop { x0, y0, x1, y1 };
        if crop.width() == 0 || crop.height() == 0 {
            return Err(CropError::Empty { crop });
        }
        Ok(crop)
    }
}

impl std::fmt::Display for CropError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CropError::Syntax { text } => write!(f, "crop {text:?}: expected x0,y0,x1,y1 (whole pixels)"),
            CropError::Empty { crop } => {
                write!(f, "crop {crop}: empty window (needs x0 < x1 and y0 < y1)")
            }
            CropError::OutsideFrame { crop, width, height } => {
                write!(f, "crop {crop}: outside the {width}×{height} frame")
            }
        }
    }
}

impl std::error::Error for CropError {}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            cut: CutOptions {
                max_solid_angle: 0.15,
                ..CutOptions::default()
            },
            scheme: SchemeChoice::Auto,
            microbuffer: 14,
            glossy_max_solid_angle: 0.05,
            glossy_microbuffer: 24,
            glossy_light_offset: 4.0,
            glossy_cache_roughness: 0.2,
            bounces: 1,
            spp: 4,
            first_samples: None,
            gathers: Gathers::default(),
            direct_samples: None,
            direct: Direct::default(),
            ao: false,
            density: 2000.0,
            surfel_budget: None,
            surfel_light_samples: 16,
            drop_buried: true,
            surfel_gathers: DEFAULT_SURFEL_GATHERS,
            tree_precision: Precision::Compact,
            component: Component::All,
            seed: 1,
            crop: None,
        }
    }
}

impl RenderOptions {
    /// Area-light samples at each receiver.
    pub fn light_samples(&self) -> u32 {
        self.direct_samples.unwrap_or(DEFAULT_LIGHT_SAMPLES)
    }

    /// Surfels per unit area for `scene`: `density`, or the budget over the
    /// scene's surface area ([`Scene::surface_area`]), so that a model in
    /// millimetres gets as many surfels as the same model in metres.
    ///
    /// ```
    /// use pbgi::render::RenderOptions;
    /// let mut scene = pbgi::scene::builtin::cornell_box();
    /// let budget = RenderOptions { surfel_budget: Some(10_000), ..RenderOptions::default() };
    /// let metres = budget.surfel_density(&scene)?;
    /// for m in &mut scene.meshes {
    ///     m.positions.iter_mut().for_each(|p| *p *= 1000.0);
    /// }
    /// let millimetres = budget.surfel_density(&scene)?;
    /// assert!((metres / millimetres / 1e6 - 1.0).abs() < 1e-5);
    /// # Ok::<(), pbgi::Error>(())
    /// ```
    pub fn surfel_density(&self, scene: &Scene) -> Result<f32, Error> {
        let Some(budget) = self.surfel_budget else {
            return Ok(self.density);
        };
        if budget == 0 {
            return Err(Error::InvalidParameter {
                name: "surfels",
                value: "0".into(),
                expected: "a surfel budget of at least 1",
            });
        }
        let area = scene.surface_area();
        // No area: no triangle makes a surfel, whatever the density.
        if area == 0.0 {
            return Ok(1.0);
        }
        if !area.is_finite() {
            return Err(Error::InvalidParameter {
                name: "surfels",
                value: budget.to_string(),
                expected: "a scene of finite area (Scene::validate refuses non-finite coordinates)",
            });
        }
        Ok((budget as f64 / area).min(f32::MAX as f64) as f32)
    }
}
