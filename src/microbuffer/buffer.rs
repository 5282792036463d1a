//! One receiver's raster: the fragments its splats left (pixel, depth, node,
//! coverage), and the convolutions that read it through `compose`.

use std::sync::Arc;

use glam::Vec3;

use super::compose;
pub(crate) use super::fragments::Fragments;
use super::gradients::{self, Gradients};
use super::incident::{self, basis};
use super::locate::{FrameLanes, Located, NodeLight, NodeSplat, locate};
use super::near::{self, Near, NearField};
use super::open;
use super::table::Table;
use crate::brdf::GlossyLobe;
use crate::cut::CutSink;
use crate::environment::Environment;
use crate::error::Error;
use crate::simd::{F32s, LANES};
use crate::tree::{NodeId, SplatRecord, Tree};

/// `(depth, node)` as one integer ordered lexicographically: the bits of a
/// non-negative, non-NaN `f32` order like its value.
#[inline]
pub(crate) fn key(depth: f32, node: NodeId) -> u64 {
    debug_assert!(depth >= 0.0, "depth {depth}");
    (u64::from(depth.to_bits()) << 32) | u64::from(node)
}

/// One receiver's raster.
///
/// ```
/// use pbgi::microbuffer::MicroBuffer;
/// use glam::Vec3;
///
/// let mut mb = MicroBuffer::new(12)?;
/// mb.reset(Vec3::ZERO, Vec3::Y);
/// let tree = pbgi::Tree::build(&pbgi::PointCloud::default());
/// assert_eq!(mb.occlusion(&tree), 0.0); // nothing splatted yet
/// # Ok::<(), pbgi::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct MicroBuffer {
    pub(super) table: Arc<Table>,
    pub(super) position: Vec3,
    /// Tangent frame: local x, y, z (= normal) in world space.
    pub(super) frame: [Vec3; 3],
    /// What the splats left in the pixels.
    pub(super) frags: Fragments,
    /// What the open pixels see (none: black).
    pub(super) environment: Option<Arc<Environment>>,
    /// The composition's working memory, reused from receiver to receiver.
    pub(super) scratch: compose::Scratch,
    /// What this receiver sees within a few surfel radii, by rays (`near`).
    pub(super) near: Option<Near>,
    /// Per pixel, the part through which the environment shows, by rays
    /// (`open`), if the receiver's field could tell (else empty; the
    /// memory is kept from one receiver to the next, like the scratch).
    pub(super) open: Vec<f32>,
    /// The normal irradiance is convolved about, in the local frame, where
    /// it is not the receiver's own (a normal map's).
    pub(super) shading: Option<Vec3>,
}

impl MicroBuffer {
    /// Largest supported resolution.
    pub const MAX_RESOLUTION: usize = 256;

    /// A microbuffer of resolution `n` (an n×n grid over the hemisphere),
    /// 1 ≤ n ≤ 256. The pixel tables of a resolution are built once per
    /// process and shared.
    pub fn new(n: usize) -> Result<Self, Error> {
        if !(1..=Self::MAX_RESOLUTION).contains(&n) {
            return Err(Error::InvalidParameter {
                name: "microbuffer resolution",
                value: n.to_string(),
                expected: "1 to 256",
            });
        }
        Ok(Self {
            table: Table::shared(n),
            position: Vec3::ZERO,
            frame: [Vec3::X, Vec3::Y, Vec3::Z],
            frags: Fragments::default(),
            environment: None,
            scratch: compose::Scratch::default(),
            near: None,
            open: Vec::new(),
            shading: None,
        })
    }

    /// This buffer, its open pixels (what no splat covers) seeing
    /// `environment` in [`irradiance`](Self::irradiance) and
    /// [`glossy`](Self::glossy); `None`: black.
    pub fn with_environment(mut self, environment: Option<Arc<Environment>>) -> Self {
        self.environment = environment;
        self
    }

    /// The resolution N.
    pub fn resolution(&self) -> usize {
        self.table.n
    }

    /// Number of pixels: `N²`.
    pub fn pixels(&self) -> usize {
        self.table.dir.len()
    }

    /// Clears the raster for a receiver at `position` facing `normal` (unit).
    pub fn reset(&mut self, position: Vec3, normal: Vec3) {
        self.position = position;
        self.frame = basis(normal);
        self.frags.clear();
        self.near = None;
        self.open.clear();
        self.shading = None;
    }

    /// Convolves irradiance about `normal` (unit, world space) rather than
    /// the receiver's: the buffer still sees the receiver's hemisphere
    /// (what lies above its surface), weighed by the cosine to `normal` (a
    /// normal map's). Until the next [`reset`](Self::reset).
    pub fn tilt(&mut self, normal: Vec3) {
        let [t, b, n] = self.frame;
        let local = Vec3::new(normal.dot(t), normal.dot(b), normal.dot(n));
        self.shading = (local != Vec3::Z).then_some(local);
    }

    #[inline]
    pub(super) fn to_world(&self, l: Vec3) -> Vec3 {
        self.frame[0] * l.x + self.frame[1] * l.y + self.frame[2] * l.z
    }

    /// The receiver's position and frame, for the lane geometry.
    #[inline(always)]
    pub(super) fn frame_lanes(&self) -> FrameLanes<f32> {
        let [t, b, n] = self.frame;
        FrameLanes {
            px: self.position.x,
            py: self.position.y,
            pz: self.position.z,
            tx: t.x,
            ty: t.y,
            tz: t.z,
            bx: b.x,
            by: b.y,
            bz: b.z,
            nx: n.x,
            ny: n.y,
            nz: n.z,
        }
    }

    /// `0.5·N`, the map's scale from `[−1, 1]` to pixels.
    #[inline(always)]
    pub(super) fn half_n(&self) -> f32 {
        0.5 * self.table.n as f32
    }

    /// Where the node `rec` falls; `None` for a node that cannot show: at
    /// the receiver's position, facing away, or straight below.
    #[inline(always)]
    pub(super) fn locate(&self, rec: &SplatRecord, light: &NodeLight<'_>) -> Option<Located<f32>> {
        let l = locate(&NodeSplat::of(rec), light, &self.frame_lanes(), self.half_n());
        l.valid.then_some(l)
    }

    /// Rasterizes node `node` of `tree`, one node of this receiver's cut
    /// (the scalar pipeline; [`shade_packet`](super::shade_packet) draws the same in 16 lanes).
    ///
    /// With `Ω = A·max(0, −n̄·ω)/d²` the node's projected solid angle (area
    /// `A`, mean normal `n̄`, direction `ω` and distance `d` of its centre):
    ///
    /// * a node smaller than the pixel `ω` falls in (`Ω < ΔΩ`) is spread over
    ///   the 2×2 pixels around `ω` with bilinear weights `w_k`, pixel `k`
    ///   covered by `w_k·Ω·cosθ / ∫_k cos`: it adds exactly its projected
    ///   solid angle (nothing when its centre is below the horizon);
    /// * a larger leaf is drawn as its disk over the pixels whose centre ray
    ///   hits its front; depth is the hit distance; a leaf covering no pixel
    ///   centre (edge-on or between centres) is spread as above with `Ω`
    ///   capped at the pixel's `ΔΩ`;
    /// * a larger cluster is drawn as a soft cone around `ω`: coverage 1 in
    ///   the middle, falling linearly across a rim as wide as the cone's
    ///   radius (at least a pixel); a cone whose centre is above the horizon
    ///   is then scaled so that `Σ coverage·∫cos` is exactly `Ω·cosθ`.
    ///   Radii are chords `|u − ω|`, for which a cap's solid angle is exactly
    ///   `π·chord²`.
    ///
    /// Depth is the distance to the centre except on disks. A node whose
    /// centre is the receiver's position has no direction and is skipped.
    /// A node `tree` does not have is ignored.
    pub fn splat(&mut self, tree: &Tree, node: NodeId) {
        self.splat_inline(tree, node);
    }

    /// [`splat`](Self::splat), inlined into the caller (a traversal clone
    /// calling it through [`MicroBufferSink`] compiles it with its own
    /// instruction set).
    #[inline(always)]
    pub(crate) fn splat_inline(&mut self, tree: &Tree, node: NodeId) {
        let Some((rec, light)) = NodeLight::of(tree, node) else {
            return;
        };
        if let Some(l) = self.locate(&rec, &light) {
            self.apply(&rec, node, &l);
        }
    }

    /// Irradiance `E = ∫ L cosθ dω` (not `E/π`), from the composed pixels
    /// (`compose`: the fragments sorted per pixel, layered by depth).
    pub fn irradiance(&self, tree: &Tree) -> Vec3 {
        let sky = self.sky();
        let mut scratch = compose::Scratch::default();
        compose::irradiance(
            &self.table,
            &self.frags,
            tree,
            &self.site(),
            sky.as_ref(),
            &mut scratch,
        )
    }

    /// [`irradiance`](Self::irradiance), inlined into the caller (a clone of
    /// a shading pipeline compiles it with its own instruction set), in the
    /// buffer's own working memory.
    #[inline(always)]
    pub(crate) fn irradiance_inline(&mut self, tree: &Tree) -> Vec3 {
        let site = compose::Site {
            position: self.position,
            frame: self.frame,
            near: self.near.as_ref(),
            open: (!self.open.is_empty()).then_some(self.open.as_slice()),
            shading: self.shading,
        };
        // The sky from the fields, not `sky()`: that would borrow the whole
        // buffer, whose working memory the composition writes.
        let sky = open::Sky::of(self.environment.as_deref(), self.frame);
        compose::irradiance(
            &self.table,
            &self.frags,
            tree,
            &site,
            sky.as_ref(),
            &mut self.scratch,
        )
    }

    /// The receiver, for the composition.
    #[inline(always)]
    fn site(&self) -> compose::Site<'_> {
        compose::Site {
            position: self.position,
            frame: self.frame,
            near: self.near.as_ref(),
            open: (!self.open.is_empty()).then_some(self.open.as_slice()),
            shading: self.shading,
        }
    }

    /// What the open pixels see.
    #[inline(always)]
    fn sky(&self) -> Option<open::Sky<'_>> {
        open::Sky::of(self.environment.as_deref(), self.frame)
    }

    /// The irradiance's gradients at this receiver, from the composed
    /// pixels and the distances to what they show (`gradients`): how
    /// [`irradiance`](Self::irradiance) changes as the receiver moves and
    /// turns, and the harmonic mean distance of what it sees.
    pub fn gradients(&self, tree: &Tree) -> Gradients {
        gradients::gradients(
            &self.table,
            &self.frags,
            tree,
            &self.site(),
            self.sky().as_ref(),
            &mut compose::Scratch::default(),
        )
    }

    /// The rotational gradient of [`gradients`](Self::gradients), read off
    /// the pixels the buffer's last convolution composed: valid right after
    /// an irradiance convolution of a buffer without a tilted normal (as
    /// the gatherer's `shade` leaves it), with no second composition.
    pub(crate) fn turning(&self) -> [Vec3; 3] {
        gradients::rotation(&self.table, &self.scratch, &self.site(), self.sky().as_ref())
    }

    /// The light each pixel let through in the buffer's last irradiance
    /// convolution, the sky included (`incident`): what a radiance record
    /// keeps. Valid when [`turning`](Self::turning) is.
    pub(crate) fn incident(&self, out: &mut Vec<Vec3>) {
        incident::incident(&self.scratch, &self.site(), self.sky().as_ref(), &self.table, out);
    }

    /// Glossy reflection towards `wo` (world, unit):
    /// `Σ L·f_s(ωi, ωo)·∫cosθ dω` over the composed pixels (and the
    /// environment through the open ones), `ωi` the pixel centre.
    pub fn glossy(&self, tree: &Tree, wo: Vec3, lobe: &GlossyLobe) -> Vec3 {
        let n = self.frame[2];
        let f = |p: usize| lobe.eval(n, wo, self.to_world(self.table.dir[p]));
        compose::reflected(
            &self.table,
            &self.frags,
            tree,
            &self.site(),
            f,
            self.sky().as_ref(),
            &mut compose::Scratch::default(),
        )
    }

    /// Ambient occlusion: the covered fraction of the cosine-weighted
    /// hemisphere, `Σ coverage·∫cosθ dω / π` ∈ [0, 1] (`tree`: the depth
    /// intervals of the splatted nodes, which layer the fragments).
    pub fn occlusion(&self, tree: &Tree) -> f32 {
        compose::occlusion(
            &self.table,
            &self.frags,
            tree,
            &self.site(),
            &mut compose::Scratch::default(),
        )
    }

    /// [`occlusion`](Self::occlusion), inlined into the caller, in the
    /// buffer's own working memory.
    #[inline(always)]
    pub(crate) fn occlusion_inline(&mut self, tree: &Tree) -> f32 {
        let site = compose::Site {
            position: self.position,
            frame: self.frame,
            near: self.near.as_ref(),
            open: (!self.open.is_empty()).then_some(self.open.as_slice()),
            shading: self.shading,
        };
        compose::occlusion(&self.table, &self.frags, tree, &site, &mut self.scratch)
    }

    /// Computes the near field this receiver needs (`near`) from `field`
    /// and keeps it for the convolutions: where the splats so far hold a
    /// leaf of another surface within [`NEAR_RADII`](super::NEAR_RADII) of
    /// its radius, the leaves that near give way to one ray per pixel;
    /// elsewhere nothing changes. Where the buffer sees an environment and
    /// `field` tells which rays escape ([`NearField::escapes`]), the open
    /// part of each pixel is taken from rays (`open`), not from the splats'
    /// coverage. Returns whether it needs a near field. Call it after the
    /// last splat; [`reset`](Self::reset) forgets both.
    #[inline(always)]
    pub fn set_near_field(&mut self, tree: &Tree, field: &dyn NearField) -> bool {
        let nodes = self.frags.key.iter().map(
            #[inline(always)]
            |&k| (k & 0xFFFF_FFFF) as NodeId,
        );
        if field.near_leaves() {
            self.near = near::near(&self.table, nodes, tree, self.position, &self.frame, field);
        }
        if self.environment.is_some() {
            open::open(
                &self.table,
                self.position,
                &self.frame,
                field,
                &self.frags,
                &mut self.open,
            );
        }
        self.near.is_some()
    }

    /// The near field the convolutions use, if this receiver has one.
    pub fn near(&self) -> Option<&Near> {
        self.near.as_ref()
    }

    /// Fragments left by the splats so far (for counters and tests).
    pub fn fragments(&self) -> usize {
        self.frags.len()
    }
}

/// A sink that splats each receiver's cut into its own microbuffer.
pub struct MicroBufferSink<'a> {
    /// The tree the cuts are of.
    pub tree: &'a Tree,
    /// One microbuffer per receiver, reset to that receiver.
    pub buffers: &'a mut [MicroBuffer],
}

impl CutSink for MicroBufferSink<'_> {
    #[inline(always)]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.buffers[receiver].splat_inline(self.tree, node);
    }
}

impl FrameLanes<F32s> {
    /// The frames of up to 16 buffers in the lanes; unused lanes repeat the first.
    #[inline(always)]
    pub(super) fn of(bufs: &[MicroBuffer]) -> Self {
        let mut f = [[0.0f32; LANES]; 12];
        #[allow(clippy::needless_range_loop)] // `l` picks a buffer and a lane
        for l in 0..LANES {
            let b = bufs.get(l).unwrap_or(&bufs[0]).frame_lanes();
            let v = [
                b.px, b.py, b.pz, b.tx, b.ty, b.tz, b.bx, b.by, b.bz, b.nx, b.ny, b.nz,
            ];
            for (j, x) in v.into_iter().enumerate() {
                f[j][l] = x;
            }
        }
        let g = |j: usize| F32s::from_array(f[j]);
        FrameLanes {
            px: g(0),
            py: g(1),
            pz: g(2),
            tx: g(3),
            ty: g(4),
            tz: g(5),
            bx: g(6),
            by: g(7),
            bz: g(8),
            nx: g(9),
            ny: g(10),
            nz: g(11),
        }
    }
}
