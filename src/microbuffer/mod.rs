//! The microbuffer: a small z-buffered raster per receiver into which the cut
//! is splatted, then convolved with the BRDF using exact per-pixel solid
//! angles.
//!
//! **Parametrization.** The hemisphere above the receiver is one N×N grid
//! through the octahedral map: a local direction `(x, y, z)` goes to
//! `p = (x, y)/(|x| + |y| + z)` in the diamond `|px| + |py| ≤ 1`, turned by
//! 45° into the square `(u, v) = (px + py, px − py) ∈ [−1, 1]²`. The square's
//! edge is the horizon, so the grid has no seams: every footprint is a box of
//! pixels around its centre, and locating a direction costs an absolute value,
//! two additions and two divisions (no branch, no face choice). Pixels near
//! the horizon are about 3× larger in solid angle than near the normal, where
//! the cosine weight is largest.
//!
//! **Order independence** (DESIGN §4): each pixel keeps the lexicographic
//! minimum of `(depth, node)` (whose radiance it shows) and the sum of the
//! coverages splatted into it in fixed point (integer addition is
//! associative), and every sum over pixels runs in a fixed order; so the
//! shading depends on the set of splats only, not on the order a traversal
//! scheme reports them in. Summing coverage keeps the energy of many clusters
//! smaller than a pixel that share it; the sum is clamped to one.

mod lanes;
mod splat;

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use glam::{DVec2, DVec3, Vec3};

use crate::brdf::GlossyLobe;
use crate::cut::CutSink;
use crate::cut::node_test::{LANES, Real};
use crate::error::Error;
use crate::tree::{NodeId, SplatRecord, Tree};

pub use lanes::{Convolution, PacketCut, shade_cuts, shade_packet};
use lanes::{FrameLanes, Located, NodeSplat, locate};

// ---------------------------------------------------------------------------
// The octahedral hemisphere map and its per-pixel tables

/// Local unit direction of the point `(u, v)` of the square.
fn unmap(u: f64, v: f64) -> DVec3 {
    let (px, py) = (0.5 * (u + v), 0.5 * (u - v));
    DVec3::new(px, py, (1.0 - px.abs() - py.abs()).max(0.0)).normalize()
}

/// `(u, v)` of a local direction with `z ≥ 0`.
fn map64(d: DVec3) -> DVec2 {
    let s = d.x.abs() + d.y.abs() + d.z;
    DVec2::new((d.x + d.y) / s, (d.x - d.y) / s)
}

/// Solid angle of the triangle `(a, b, c)` seen from the origin (Van
/// Oosterom and Strackee).
fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c)).abs();
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * num.atan2(den)
}

/// `∫ cosθ dω` (θ from +z) over the convex polygon `poly` seen from the
/// origin, by Lambert's formula: `½ Σ θᵢ (γᵢ · z)`, θᵢ the angle an edge
/// subtends and γᵢ the unit normal of the plane through it and the origin.
fn polygon_projected_solid_angle(poly: &[DVec3]) -> f64 {
    let mut sum = 0.0;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let c = a.cross(b);
        let len = c.length();
        if len > 0.0 {
            sum += len.atan2(a.dot(b)) * c.z / len;
        }
    }
    (0.5 * sum).abs()
}

/// Clips the convex polygon `poly` (in the `(px, py)` plane) to `a·p ≥ 0`.
fn clip(poly: &[DVec2], a: DVec2) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (dp, dq) = (a.dot(p), a.dot(q));
        if dp >= 0.0 {
            out.push(p);
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            out.push(p + (q - p) * (dp / (dp - dq)));
        }
    }
    out
}

/// Exact solid angle and `∫ cosθ dω` of the pixel `[u0, u1] × [v0, v1]`:
/// per quadrant of the diamond the pixel is a planar polygon on a face of
/// the octahedron `|x| + |y| + z = 1`.
fn pixel_integrals(u0: f64, u1: f64, v0: f64, v1: f64) -> (f64, f64) {
    let to_p = |u: f64, v: f64| DVec2::new(0.5 * (u + v), 0.5 * (u - v));
    let square = [to_p(u0, v0), to_p(u1, v0), to_p(u1, v1), to_p(u0, v1)];
    let (mut omega, mut projected) = (0.0, 0.0);
    for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
        let part = clip(&clip(&square, DVec2::new(sx, 0.0)), DVec2::new(0.0, sy));
        if part.len() < 3 {
            continue;
        }
        let lifted: Vec<DVec3> = part
            .iter()
            .map(|p| DVec3::new(p.x, p.y, 1.0 - sx * p.x - sy * p.y))
            .collect();
        for i in 1..lifted.len() - 1 {
            omega += triangle_solid_angle(lifted[0], lifted[i], lifted[i + 1]);
        }
        projected += polygon_projected_solid_angle(&lifted);
    }
    (omega, projected)
}

/// Largest stretch of the map at `d`: `(u, v)` units per radian, the
/// largest singular value of its Jacobian (one-sided differences).
fn stretch_at(d: DVec3) -> f64 {
    let (t1, t2) = d.any_orthonormal_pair();
    let h = 1e-6;
    let base = map64(d);
    let mut cols = [DVec2::ZERO; 2];
    for (col, t) in cols.iter_mut().zip([t1, t2]) {
        let mut q = (d + t * h).normalize();
        let mut sign = 1.0;
        if q.z < 0.0 {
            q = (d - t * h).normalize();
            sign = -1.0;
        }
        *col = (map64(q) - base) * (sign / h);
    }
    let (a, c, b, e) = (cols[0].x, cols[0].y, cols[1].x, cols[1].y);
    let t = a * a + b * b + c * c + e * e;
    let det = a * e - b * c;
    ((t + (t * t - 4.0 * det * det).max(0.0).sqrt()) * 0.5).sqrt()
}

/// Per-resolution pixel geometry, shared by all microbuffers of that resolution.
#[derive(Debug)]
struct Table {
    n: usize,
    /// Local unit direction of each pixel centre.
    dir: Vec<Vec3>,
    /// The same by component (what the cone and disk loops read), padded
    /// with [`LANES`] zeros.
    dir_x: Vec<f32>,
    dir_y: Vec<f32>,
    dir_z: Vec<f32>,
    /// Exact solid angle of each pixel.
    solid_angle: Vec<f32>,
    /// Exact `∫ cosθ dω` over each pixel (θ from the normal, +z), padded
    /// with zeros to a multiple of 16 pixels.
    cos_weight: Vec<f32>,
    /// Angular size of each pixel, `√ΔΩ`, padded with [`LANES`] zeros.
    pixel_size: Vec<f32>,
    /// The largest pixel size.
    pixel_angle: f32,
    /// Pixels per radian a footprint centred in each pixel can reach, for
    /// footprints up to [`NEAR`] pixels wide: the largest stretch of the map
    /// over the pixels around it, with a margin.
    reach: Vec<f32>,
    /// The same over the whole map, for wider footprints.
    reach_max: f32,
    /// The lowest pixel centre's height above the horizon (its `z`) and
    /// the sine of its angle from the normal: no pixel's ray leans further.
    lowest_z: f32,
    lowest_sin: f32,
}

/// Footprints up to this many pixels from their centre use the local reach.
const NEAR: usize = 2;

impl Table {
    fn new(n: usize) -> Table {
        let h = 2.0 / n as f64;
        let len = n * n;
        let mut dir = Vec::with_capacity(len);
        let mut solid_angle = Vec::with_capacity(len);
        let mut cos_weight = Vec::with_capacity(len.next_multiple_of(16));
        let mut stretch = Vec::with_capacity(len);
        for r in 0..n {
            for c in 0..n {
                let (u0, v0) = (-1.0 + c as f64 * h, -1.0 + r as f64 * h);
                let (omega, projected) = pixel_integrals(u0, u0 + h, v0, v0 + h);
                dir.push(unmap(u0 + 0.5 * h, v0 + 0.5 * h).as_vec3());
                solid_angle.push(omega as f32);
                cos_weight.push(projected as f32);
                // The stretch at the centre and near the corners (the map's
                // derivative jumps across the diagonals u = ±v).
                let mut s: f64 = 0.0;
                for (fu, fv) in [(0.5, 0.5), (0.02, 0.02), (0.98, 0.02), (0.02, 0.98), (0.98, 0.98)] {
                    let d = unmap(u0 + fu * h, v0 + fv * h);
                    if d.z > 1e-9 {
                        s = s.max(stretch_at(d));
                    }
                }
                stretch.push(s);
            }
        }
        cos_weight.resize(len.next_multiple_of(16), 0.0);
        let pixels_per_unit = n as f64 * 0.5;
        let mut reach = vec![0.0f32; len];
        for r in 0..n {
            for c in 0..n {
                let mut s: f64 = 0.0;
                for rr in r.saturating_sub(NEAR + 1)..(r + NEAR + 2).min(n) {
                    for cc in c.saturating_sub(NEAR + 1)..(c + NEAR + 2).min(n) {
                        s = s.max(stretch[rr * n + cc]);
                    }
                }
                reach[r * n + c] = (s * pixels_per_unit * 1.1) as f32;
            }
        }
        let lowest_z = dir.iter().map(|d| d.z).fold(1.0, f32::min);
        let reach_max = (stretch.iter().copied().fold(0.0, f64::max) * pixels_per_unit * 1.1) as f32;
        let mut pixel_size: Vec<f32> = solid_angle.iter().map(|w| w.sqrt()).collect();
        let pixel_angle = pixel_size.iter().copied().fold(0.0, f32::max);
        // Padded, so that a row of a 16-pixel tile loads in one piece
        // anywhere in the grid (lanes past the last pixel are outside every box).
        pixel_size.resize(len + LANES, 0.0);
        let component = |f: fn(&Vec3) -> f32| {
            let mut v: Vec<f32> = dir.iter().map(f).collect();
            v.resize(len + LANES, 0.0);
            v
        };
        let (dir_x, dir_y, dir_z) = (component(|d| d.x), component(|d| d.y), component(|d| d.z));
        Table {
            n,
            dir,
            dir_x,
            dir_y,
            dir_z,
            solid_angle,
            cos_weight,
            pixel_size,
            pixel_angle,
            reach,
            reach_max,
            lowest_z,
            lowest_sin: (1.0 - lowest_z * lowest_z).max(0.0).sqrt(),
        }
    }

    /// The table of resolution `n`, built once per process.
    fn shared(n: usize) -> Arc<Table> {
        static TABLES: OnceLock<Mutex<HashMap<usize, Arc<Table>>>> = OnceLock::new();
        let mut map = TABLES
            .get_or_init(Default::default)
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        map.entry(n).or_insert_with(|| Arc::new(Table::new(n))).clone()
    }
}

// ---------------------------------------------------------------------------
// Pixels

/// One unit of coverage in the fixed-point sums.
const COVER_ONE: f32 = (1u32 << 24) as f32;

/// Coverage sums saturate here (≥ one unit, so the clamp to one is
/// unaffected): `min(a + b, CAP)` is associative for non-negative values,
/// and a sum below the cap plus one unit fits in 32 bits.
const COVER_CAP: u32 = 1 << 25;

/// No splat: larger than every key, and positive as an `i64` (keys compare
/// as signed integers where the instruction set has no unsigned compare).
const NO_KEY: u64 = i64::MAX as u64;

/// `(depth, node)` as one integer ordered lexicographically: the bits of a
/// non-negative, non-NaN `f32` order like its value.
#[inline]
fn key(depth: f32, node: NodeId) -> u64 {
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
/// assert_eq!(mb.occlusion(), 0.0); // nothing splatted yet
/// # Ok::<(), pbgi::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct MicroBuffer {
    table: Arc<Table>,
    position: Vec3,
    /// Tangent frame: local x, y, z (= normal) in world space.
    frame: [Vec3; 3],
    /// Per pixel: the nearest `(depth, node)` among the splats that own it.
    own: Vec<u64>,
    /// Per pixel: the nearest among all splats that touch it.
    any: Vec<u64>,
    /// Per pixel: coverage in units of 2⁻²⁴, summed (saturating at [`COVER_CAP`]).
    cover: Vec<u32>,
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
        let table = Table::shared(n);
        let len = table.cos_weight.len();
        Ok(Self {
            table,
            position: Vec3::ZERO,
            frame: [Vec3::X, Vec3::Y, Vec3::Z],
            own: vec![NO_KEY; len],
            any: vec![NO_KEY; len],
            cover: vec![0; len],
        })
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
        // Duff et al., "Building an orthonormal basis, revisited".
        let n = normal;
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        self.position = position;
        self.frame = [t, bt, n];
        self.own.fill(NO_KEY);
        self.any.fill(NO_KEY);
        self.cover.fill(0);
    }

    #[inline]
    fn to_world(&self, l: Vec3) -> Vec3 {
        self.frame[0] * l.x + self.frame[1] * l.y + self.frame[2] * l.z
    }

    /// The receiver's position and frame, for the lane geometry.
    #[inline(always)]
    fn frame_lanes(&self) -> FrameLanes<f32> {
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
    fn half_n(&self) -> f32 {
        0.5 * self.table.n as f32
    }

    /// Where the node `rec` falls; `None` for a node that cannot show: at
    /// the receiver's position, facing away, or straight below.
    #[inline(always)]
    fn locate(&self, rec: &SplatRecord) -> Option<Located<f32>> {
        let l = locate(&NodeSplat::of(rec), &self.frame_lanes(), self.half_n());
        l.valid.then_some(l)
    }

    /// Rasterizes node `node` of `tree`, one node of this receiver's cut
    /// (the scalar pipeline; [`shade_packet`] draws the same in 16 lanes).
    ///
    /// With `Ω = A·max(0, −n̄·ω)/d²` the node's projected solid angle (area
    /// `A`, mean normal `n̄`, direction `ω` and distance `d` of its centre):
    ///
    /// * a node smaller than the pixel `ω` falls in (`Ω < ΔΩ`) is spread over
    ///   the 2×2 pixels around `ω` with bilinear weights, each covered by its
    ///   weight times `Ω/ΔΩ`; it owns the pixel `ω` falls in;
    /// * a larger leaf is drawn as its disk (radius inflated by 1.2) over the
    ///   pixels whose centre ray hits its front; depth is the hit distance; a
    ///   leaf covering no pixel centre (edge-on or between centres) is spread
    ///   as above with `Ω` capped at the pixel's `ΔΩ`;
    /// * a larger cluster is drawn as a soft cone around `ω`: coverage 1 in
    ///   the middle, falling linearly across a rim as wide as the cone's
    ///   radius (at least a pixel) and scaled so that it integrates to `Ω`.
    ///   Radii are chords `|u − ω|`, for which a cap's solid angle is exactly
    ///   `π·chord²`. It owns the pixels it covers by at least one half.
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
        let Some(rec) = tree.splat.get(node as usize) else {
            return;
        };
        if let Some(l) = self.locate(rec) {
            self.apply(rec, node, &l);
        }
    }

    /// The weight of pixel `p` in the convolution (`coverage·∫cosθ dω`, 0
    /// when nothing touched it) and the node it shows (0 when none).
    #[inline(always)]
    fn weight(&self, p: usize) -> (f32, NodeId) {
        let k = if self.own[p] != NO_KEY {
            self.own[p]
        } else {
            self.any[p]
        };
        let valid = k != NO_KEY;
        let cover = (self.cover[p] as f32 * (1.0 / COVER_ONE)).min_of(1.0);
        let w = f32::select(valid, cover * self.table.cos_weight[p], 0.0);
        (w, if valid { k as NodeId } else { 0 })
    }

    /// Irradiance: `Σ L·coverage·∫cosθ dω` over the pixels. The sum runs in
    /// 16 interleaved partial sums (pixel `p` into sum `p mod 16`), added up
    /// in order at the end: the order of the 16-lane convolution, so both
    /// give the same bits.
    pub fn irradiance(&self, tree: &Tree) -> Vec3 {
        self.irradiance_inline(tree)
    }

    /// [`irradiance`](Self::irradiance), inlined into the caller (a clone of
    /// the scalar pipeline compiles it with its own instruction set).
    #[inline(always)]
    pub(crate) fn irradiance_inline(&self, tree: &Tree) -> Vec3 {
        let mut acc = [[0.0f32; LANES]; 3];
        for p in 0..self.table.cos_weight.len() {
            let (w, k) = self.weight(p);
            // Node 0 stands for an empty pixel (weight 0); a tree without it is empty.
            let l = tree
                .radiance_slice()
                .get(k as usize)
                .copied()
                .unwrap_or(Vec3::ZERO);
            let lane = p % LANES;
            acc[0][lane] += l.x * w;
            acc[1][lane] += l.y * w;
            acc[2][lane] += l.z * w;
        }
        Vec3::new(lanes::sum(acc[0]), lanes::sum(acc[1]), lanes::sum(acc[2]))
    }

    /// Glossy reflection towards `wo` (world, unit):
    /// `Σ L·coverage·f_s(ωi, ωo)·∫cosθ dω`, `ωi` the pixel centre, in pixel order.
    pub fn glossy(&self, tree: &Tree, wo: Vec3, lobe: &GlossyLobe) -> Vec3 {
        let n = self.frame[2];
        let mut l = Vec3::ZERO;
        for p in 0..self.pixels() {
            let (w, k) = self.weight(p);
            if w > 0.0 {
                let wi = self.to_world(self.table.dir[p]);
                let radiance = tree
                    .radiance_slice()
                    .get(k as usize)
                    .copied()
                    .unwrap_or(Vec3::ZERO);
                l += radiance * lobe.eval(n, wo, wi) * w;
            }
        }
        l
    }

    /// Ambient occlusion: the covered fraction of the cosine-weighted
    /// hemisphere, `Σ coverage·∫cosθ dω / π` ∈ [0, 1], summed like
    /// [`irradiance`](Self::irradiance).
    pub fn occlusion(&self) -> f32 {
        self.occlusion_inline()
    }

    /// [`occlusion`](Self::occlusion), inlined into the caller.
    #[inline(always)]
    pub(crate) fn occlusion_inline(&self) -> f32 {
        let mut acc = [0.0f32; LANES];
        for p in 0..self.table.cos_weight.len() {
            acc[p % LANES] += self.weight(p).0;
        }
        (lanes::sum(acc) * std::f32::consts::FRAC_1_PI).min_of(1.0)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit-area cluster at `c` facing the origin.
    fn record(c: Vec3) -> SplatRecord {
        SplatRecord {
            center: c.to_array(),
            area: 1.0,
            normal: (-c).to_array(),
            leaf: 0,
        }
    }

    /// xorshift64*: a fixed stream of test inputs.
    struct Rng(u64);
    impl Rng {
        fn unit(&mut self) -> f32 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
        }
        fn dir(&mut self) -> Vec3 {
            loop {
                let v = Vec3::new(self.unit(), self.unit(), self.unit()) * 2.0 - 1.0;
                if (0.01..=1.0).contains(&v.length_squared()) {
                    return v.normalize();
                }
            }
        }
    }

    /// A node around the receiver at the origin (normal +z), of every kind
    /// the draws meet: far and near, tiny and huge, facing, edge-on, and
    /// coplanar with the receiver a rounding error above or below its plane.
    fn node_around(rng: &mut Rng, leaf: bool) -> SplatRecord {
        let kind = (rng.unit() * 4.0) as u32;
        let d = 10f32.powf(rng.unit() * 4.0 - 3.0);
        let (center, normal) = match kind {
            0 => {
                // On the receiver's plane, normal nearly its own.
                let c = rng.dir() * Vec3::new(1.0, 1.0, 0.0);
                let z = (rng.unit() - 0.5) * 1e-6 * d;
                (c * d + Vec3::Z * z, (Vec3::Z + rng.dir() * 1e-4).normalize())
            }
            1 => {
                // Near the horizon, any normal.
                let c = (rng.dir() * Vec3::new(1.0, 1.0, 0.05)).normalize_or(Vec3::X);
                (c * d, rng.dir())
            }
            _ => (rng.dir() * d, rng.dir()),
        };
        SplatRecord {
            center: center.to_array(),
            area: d * d * 10f32.powf(rng.unit() * 5.0 - 4.0),
            normal: normal.to_array(),
            leaf: u32::from(leaf),
        }
    }

    fn same_pixels(a: &MicroBuffer, b: &MicroBuffer) -> bool {
        a.own == b.own && a.any == b.any && a.cover == b.cover
    }

    #[test]
    fn tiled_draws_write_the_pixels_of_the_scalar_draws() {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let (mut drawn, mut hits) = (0, 0);
        for n in [1, 2, 3, 4, 5, 7, 8, 9, 12, 16, 17, 33, 64] {
            let mut a = MicroBuffer::new(n).unwrap();
            let mut b = MicroBuffer::new(n).unwrap();
            for i in 0..600 {
                let (frame_n, node) = (Vec3::Z, i as NodeId);
                a.reset(Vec3::ZERO, frame_n);
                b.reset(Vec3::ZERO, frame_n);
                let leaf = i % 2 == 0;
                let rec = node_around(&mut rng, leaf);
                let Some(l) = a.locate(&rec) else { continue };
                let t = a.table.clone();
                let pixel = splat::pixel_of(&t, l.x, l.y);
                let visible = 0.0 < l.wz;
                drawn += 1;
                if leaf {
                    let plan =
                        splat::plan_disk(&t, &a.frame_lanes(), &NodeSplat::of(&rec), l.x, l.y, pixel, l.d);
                    let hit = a.draw_disk(&plan, node);
                    assert_eq!(hit, b.draw_disk_tiles(&plan, node), "N {n}, node {rec:?}");
                    assert!(same_pixels(&a, &b), "disk: N {n}, node {rec:?}");
                    // The cull of disks that cannot face any pixel drops no hit.
                    let mut c = MicroBuffer::new(n).unwrap();
                    c.reset(Vec3::ZERO, frame_n);
                    let unculled = splat::DiskPlan { fronts: true, ..plan };
                    assert_eq!(hit, c.draw_disk(&unculled, node), "cull: N {n}, node {rec:?}");
                    assert!(same_pixels(&a, &c), "cull: N {n}, node {rec:?}");
                    hits += usize::from(hit);
                } else {
                    let plan = splat::plan_cone(&t, l.x, l.y, pixel, l.omega, visible);
                    let w = Vec3::new(l.wx, l.wy, l.wz);
                    a.draw_cone(w, &plan, key(l.d, node));
                    b.draw_cone_tiles(w, &plan, key(l.d, node));
                    assert!(same_pixels(&a, &b), "cone: N {n}, node {rec:?}");
                    hits += usize::from(a.cover.iter().any(|&c| c > 0));
                }
            }
        }
        // The cases must draw something, or the comparison proves nothing.
        assert!(drawn > 3000 && hits > 1000, "{drawn} drawn, {hits} with pixels");
    }

    #[test]
    fn pixels_integrate_to_the_hemisphere_exactly() {
        for n in [1, 2, 3, 8, 17, 64, 256] {
            let t = Table::new(n);
            let total: f64 = t.solid_angle.iter().map(|&x| x as f64).sum();
            let cosine: f64 = t.cos_weight.iter().map(|&x| x as f64).sum();
            assert!(
                (total / (2.0 * std::f64::consts::PI) - 1.0).abs() < 1e-5,
                "n {n}: Σ ΔΩ = {total}"
            );
            assert!(
                (cosine / std::f64::consts::PI - 1.0).abs() < 1e-5,
                "n {n}: Σ ∫cos dω = {cosine}"
            );
        }
    }

    #[test]
    fn pixel_integrals_match_a_fine_quadrature() {
        let n = 6;
        let t = Table::new(n);
        let h = 2.0 / n as f64;
        let m = 400;
        // Pixels off the diagonals u = ±v (where the map has a kink the
        // midpoint rule converges slowly across), then pixels on them.
        for (p, tol) in [
            (1, 1e-4),
            (2, 1e-4),
            (9, 1e-4),
            (12, 1e-4),
            (26, 1e-4),
            (0, 5e-3),
            (7, 5e-3),
            (20, 5e-3),
        ] {
            let (c, r) = (p % n, p / n);
            let (mut omega, mut projected) = (0.0, 0.0);
            let g = h / m as f64;
            for i in 0..m {
                for j in 0..m {
                    let (u, v) = (
                        -1.0 + c as f64 * h + (i as f64 + 0.5) * g,
                        -1.0 + r as f64 * h + (j as f64 + 0.5) * g,
                    );
                    // Area element of the map by finite differences.
                    let e = 1e-7;
                    let d = unmap(u, v);
                    let du = (unmap(u + e, v) - d) / e;
                    let dv = (unmap(u, v + e) - d) / e;
                    let da = du.cross(dv).length() * g * g;
                    omega += da;
                    projected += da * d.z;
                }
            }
            assert!(
                (omega / t.solid_angle[p] as f64 - 1.0).abs() < tol,
                "pixel {p}: {omega} vs {}",
                t.solid_angle[p]
            );
            assert!(
                (projected / t.cos_weight[p] as f64 - 1.0).abs() < tol,
                "pixel {p}: {projected} vs {}",
                t.cos_weight[p]
            );
        }
    }

    #[test]
    fn every_pixel_centre_lands_in_its_pixel() {
        for n in [1, 4, 8, 13] {
            let mut mb = MicroBuffer::new(n).unwrap();
            mb.reset(Vec3::ZERO, Vec3::Z);
            for (p, d) in mb.table.dir.clone().iter().enumerate() {
                let l = mb.locate(&record(*d)).expect("upper hemisphere");
                assert_eq!(
                    splat::pixel_of(&mb.table, l.x, l.y),
                    p as f32,
                    "n {n} pixel {p} dir {d}"
                );
            }
        }
    }

    #[test]
    fn footprints_reach_every_pixel_within_their_angle() {
        let n = 16;
        let mut mb = MicroBuffer::new(n).unwrap();
        mb.reset(Vec3::ZERO, Vec3::Z);
        let t = mb.table.clone();
        for (i, w) in t.dir.iter().enumerate().step_by(3) {
            let l = mb.locate(&record(*w)).unwrap();
            let pixel = splat::pixel_of(&t, l.x, l.y);
            for angle in [0.05f32, 0.2, 0.5, 1.0] {
                let b = splat::footprint(&t, l.x, l.y, pixel, angle);
                let (c0, c1, r0, r1) = (b.c0 as usize, b.c1 as usize, b.r0 as usize, b.r1 as usize);
                for (p, d) in t.dir.iter().enumerate() {
                    if d.dot(*w).clamp(-1.0, 1.0).acos() < angle * 0.999 {
                        let (c, r) = (p % n, p / n);
                        assert!(
                            (c0..=c1).contains(&c) && (r0..=r1).contains(&r),
                            "pixel {p} is {:.3} rad from pixel {i}, outside the box of angle {angle}",
                            d.dot(*w).acos()
                        );
                    }
                }
            }
        }
    }
}
