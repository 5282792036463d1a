//! The microbuffer: a small z-buffered raster per receiver, a hemicube in the
//! receiver's tangent frame (an N×N top face and four N×⌈N/2⌉ half side
//! faces), into which the cut is splatted and which is then convolved with
//! the BRDF using exact per-pixel solid angles.
//!
//! Order independence (DESIGN §4): each pixel keeps the lexicographic minimum
//! of `(depth, node)` (whose radiance it shows) and the sum of the coverages
//! splatted into it in fixed point (integer addition is associative), and
//! every sum over pixels runs in a fixed order; so the shading depends on the
//! set of splats only, not on the order a traversal scheme reports them in.
//! Summing coverage keeps the energy of many clusters smaller than a pixel
//! that share it; the sum is clamped to one (a pixel cannot be more than covered).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use glam::{DVec2, Vec2, Vec3};

use crate::brdf::GlossyLobe;
use crate::cut::CutSink;
use crate::error::Error;
use crate::tree::{NodeId, Tree};

/// No node in this pixel.
const EMPTY: NodeId = NodeId::MAX;

/// The faces of the hemicube: top (+z), then +x, −x, +y, −y half faces.
#[derive(Clone, Copy, Debug)]
struct Face {
    /// Local direction of the face plane's normal (the axis it looks along).
    axis: Vec3,
    /// Local directions of the face's `u` and `v` coordinates.
    u: Vec3,
    v: Vec3,
    /// Range of `v`: `[-1, 1]` on top, `[0, 1]` (towards +z) on the sides.
    v0: f32,
    /// First pixel and rows × columns.
    first: usize,
    cols: usize,
    rows: usize,
}

/// Per-resolution pixel geometry, shared by all microbuffers of that resolution.
#[derive(Debug)]
struct Table {
    n: usize,
    faces: [Face; 5],
    /// Local unit direction of each pixel centre.
    dir: Vec<Vec3>,
    /// Exact solid angle of each pixel.
    solid_angle: Vec<f32>,
    /// `∫ cosθ dω` over each pixel (θ from the normal, +z).
    cos_weight: Vec<f32>,
    /// Angular size of each pixel, `√ΔΩ`.
    pixel_size: Vec<f32>,
    /// The largest pixel size.
    pixel_angle: f32,
}

/// ∫∫ over the rectangle `[x0, x1] × [y0, y1]` of the plane at distance 1.
fn rect_solid_angle(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let f = |x: f64, y: f64| (x * y).atan2((x * x + y * y + 1.0).sqrt());
    f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)
}

impl Table {
    fn new(n: usize) -> Table {
        let half = n.div_ceil(2);
        let mut faces = Vec::with_capacity(5);
        let mut first = 0;
        let mut add = |axis: Vec3, u: Vec3, v: Vec3, v0: f32, rows: usize| {
            faces.push(Face {
                axis,
                u,
                v,
                v0,
                first,
                cols: n,
                rows,
            });
            first += n * rows;
        };
        add(Vec3::Z, Vec3::X, Vec3::Y, -1.0, n);
        add(Vec3::X, Vec3::Y, Vec3::Z, 0.0, half);
        add(-Vec3::X, -Vec3::Y, Vec3::Z, 0.0, half);
        add(Vec3::Y, -Vec3::X, Vec3::Z, 0.0, half);
        add(-Vec3::Y, Vec3::X, Vec3::Z, 0.0, half);
        let faces: [Face; 5] = faces.try_into().expect("five faces");
        let total = n * n + 4 * n * half;
        let (mut dir, mut solid_angle, mut cos_weight) = (
            Vec::with_capacity(total),
            Vec::with_capacity(total),
            Vec::with_capacity(total),
        );
        for f in &faces {
            let dv = (1.0 - f.v0 as f64) / f.rows as f64;
            let du = 2.0 / f.cols as f64;
            for r in 0..f.rows {
                for c in 0..f.cols {
                    let (u0, v0) = (-1.0 + c as f64 * du, f.v0 as f64 + r as f64 * dv);
                    let (uc, vc) = (u0 + 0.5 * du, v0 + 0.5 * dv);
                    let d = (f.axis.as_dvec3() + f.u.as_dvec3() * uc + f.v.as_dvec3() * vc).normalize();
                    let omega = rect_solid_angle(u0, u0 + du, v0, v0 + dv);
                    // ∫ cosθ dω over the pixel (midpoint rule): the weights
                    // then sum to π at every resolution.
                    let m = (64 / n).max(2);
                    let mut projected = 0.0;
                    for i in 0..m {
                        for j in 0..m {
                            let (u, v) = (
                                u0 + (i as f64 + 0.5) * du / m as f64,
                                v0 + (j as f64 + 0.5) * dv / m as f64,
                            );
                            let q = f.axis.as_dvec3() + f.u.as_dvec3() * u + f.v.as_dvec3() * v;
                            let len = q.length();
                            projected += (q.z / len).max(0.0) / (len * len * len);
                        }
                    }
                    projected *= du * dv / (m * m) as f64;
                    dir.push(d.as_vec3());
                    solid_angle.push(omega as f32);
                    cos_weight.push(projected as f32);
                }
            }
        }
        let pixel_size: Vec<f32> = solid_angle.iter().map(|w| w.sqrt()).collect();
        let pixel_angle = pixel_size.iter().copied().fold(0.0, f32::max);
        Table {
            n,
            faces,
            dir,
            solid_angle,
            cos_weight,
            pixel_size,
            pixel_angle,
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

    /// Face and face coordinates `(u, v)` of local direction `d` (upper hemisphere).
    fn locate(&self, d: Vec3) -> Option<(usize, DVec2)> {
        if d.z <= 0.0 {
            return None;
        }
        let (ax, ay) = (d.x.abs(), d.y.abs());
        let k = if d.z >= ax && d.z >= ay {
            0
        } else if ax >= ay {
            if d.x > 0.0 { 1 } else { 2 }
        } else if d.y > 0.0 {
            3
        } else {
            4
        };
        let f = &self.faces[k];
        let along = d.dot(f.axis) as f64;
        Some((
            k,
            DVec2::new(d.dot(f.u) as f64 / along, d.dot(f.v) as f64 / along),
        ))
    }

    /// Pixel of face `k` at face coordinates `uv`, clamped into the face.
    fn pixel(&self, k: usize, uv: DVec2) -> usize {
        let f = &self.faces[k];
        // Truncation is floor for the non-negative values kept by `max`.
        let c = (((uv.x + 1.0) * 0.5 * f.cols as f64).max(0.0) as usize).min(f.cols - 1);
        let r =
            (((uv.y - f.v0 as f64) / (1.0 - f.v0 as f64) * f.rows as f64).max(0.0) as usize).min(f.rows - 1);
        f.first + r * f.cols + c
    }
}

/// One receiver's raster.
///
/// ```
/// use pbgi::microbuffer::MicroBuffer;
/// use glam::Vec3;
///
/// let mut mb = MicroBuffer::new(8)?;
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
    raster: Raster,
}

/// Leaf disks are rasterized this much larger than their radius.
const DISK_INFLATION: f32 = 1.2;

/// One unit of coverage in the fixed-point sums.
const COVER_ONE: f32 = (1u32 << 24) as f32;

/// Per pixel: the nearest `(depth, node)` and the summed coverage.
#[derive(Clone, Debug)]
struct Raster {
    depth: Vec<f32>,
    node: Vec<NodeId>,
    /// Coverage in units of 2⁻²⁴, summed over every splat.
    cover: Vec<u64>,
}

impl Raster {
    /// Adds a splat of `coverage` ∈ (0, 1] at `depth` to pixel `p`.
    #[inline]
    fn write(&mut self, p: usize, depth: f32, node: NodeId, coverage: f32) {
        self.cover[p] += (coverage * COVER_ONE) as u64;
        if depth < self.depth[p] || (depth == self.depth[p] && node < self.node[p]) {
            self.depth[p] = depth;
            self.node[p] = node;
        }
    }

    /// Coverage of pixel `p` in [0, 1].
    #[inline]
    fn coverage(&self, p: usize) -> f32 {
        (self.cover[p] as f32 / COVER_ONE).min(1.0)
    }
}

impl MicroBuffer {
    /// Largest supported resolution.
    pub const MAX_RESOLUTION: usize = 256;

    /// A microbuffer of resolution `n` (top face n×n), 1 ≤ n ≤ 256.
    pub fn new(n: usize) -> Result<Self, Error> {
        if !(1..=Self::MAX_RESOLUTION).contains(&n) {
            return Err(Error::InvalidParameter {
                name: "microbuffer resolution",
                value: n.to_string(),
                expected: "1 to 256",
            });
        }
        let table = Table::shared(n);
        let len = table.dir.len();
        Ok(Self {
            table,
            position: Vec3::ZERO,
            frame: [Vec3::X, Vec3::Y, Vec3::Z],
            raster: Raster {
                depth: vec![f32::INFINITY; len],
                node: vec![EMPTY; len],
                cover: vec![0; len],
            },
        })
    }

    /// Resolution N.
    pub fn resolution(&self) -> usize {
        self.table.n
    }

    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.raster.depth.len()
    }

    /// Clears the raster for a receiver at `position` facing `normal` (unit).
    pub fn reset(&mut self, position: Vec3, normal: Vec3) {
        // Duff et al. 2017, "Building an orthonormal basis, revisited".
        let n = normal;
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        self.position = position;
        self.frame = [t, bt, n];
        self.raster.depth.fill(f32::INFINITY);
        self.raster.node.fill(EMPTY);
        self.raster.cover.fill(0);
    }

    #[inline]
    fn to_local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.frame[0]), w.dot(self.frame[1]), w.dot(self.frame[2]))
    }

    #[inline]
    fn to_world(&self, l: Vec3) -> Vec3 {
        self.frame[0] * l.x + self.frame[1] * l.y + self.frame[2] * l.z
    }

    /// Pixels whose centre direction may lie within angle `a` of local `w`:
    /// per face, the bounding box of the cone's projection, one pixel wider.
    fn for_candidates(table: &Table, w: Vec3, a: f32, mut f: impl FnMut(usize)) {
        if a >= 1.2 {
            (0..table.dir.len()).for_each(f);
            return;
        }
        let home = table.locate(w).map(|(k, _)| k);
        let (t, b) = w.any_orthonormal_pair();
        let (s, c) = a.sin_cos();
        let h = s * std::f32::consts::FRAC_1_SQRT_2;
        let ring: [Vec3; 9] = [
            w,
            w * c + t * s,
            w * c - t * s,
            w * c + b * s,
            w * c - b * s,
            w * c + (t + b) * h,
            w * c - (t + b) * h,
            w * c + (t - b) * h,
            w * c - (t - b) * h,
        ];
        for (k, face) in table.faces.iter().enumerate() {
            let (along, du, dv) = (w.dot(face.axis), w.dot(face.u), w.dot(face.v));
            // A face's directions have `along ≥ max(|u|, |v|)`; turning by `a`
            // moves each coordinate by at most `a`, so farther faces are out of reach.
            if along - du.abs().max(dv.abs()) < -2.0 * a {
                continue;
            }
            let (lo, hi) = if Some(k) == home && a < 0.5 {
                // The axis's own face: the gnomonic projection maps angle `a`
                // at radius ρ to at most `a·(1 + ρ'²)`, ρ' the far edge.
                let uv = Vec2::new(du, dv) / along;
                let rho2 = uv.length_squared();
                let far = rho2.sqrt() + a * (1.0 + rho2);
                let half = a * (1.0 + far * far) * 1.05;
                (uv - half, uv + half)
            } else {
                // Ring directions put on the cube's surface (L∞ normalization)
                // and clamped into this face bound the cone's footprint on it.
                let mut lo = Vec2::splat(f32::INFINITY);
                let mut hi = Vec2::splat(f32::NEG_INFINITY);
                for d in &ring {
                    let (along, du, dv) = (d.dot(face.axis), d.dot(face.u), d.dot(face.v));
                    let scale = along.max(du.abs()).max(dv.abs()).max(f32::MIN_POSITIVE);
                    let uv = Vec2::new(du, dv) / scale;
                    lo = lo.min(uv);
                    hi = hi.max(uv);
                }
                // One pixel of margin: the footprint is a conic, the ring only samples it.
                let margin = Vec2::new(2.0 / face.cols as f32, (1.0 - face.v0) / face.rows as f32);
                (lo - margin, hi + margin)
            };
            let col = |u: f32| (((u + 1.0) * 0.5 * face.cols as f32).max(0.0) as usize).min(face.cols - 1);
            let row = |v: f32| {
                (((v - face.v0) / (1.0 - face.v0) * face.rows as f32).max(0.0) as usize).min(face.rows - 1)
            };
            for r in row(lo.y)..=row(hi.y) {
                for cc in col(lo.x)..=col(hi.x) {
                    f(face.first + r * face.cols + cc);
                }
            }
        }
    }

    /// Rasterizes node `node` of `tree`, one node of this receiver's cut.
    ///
    /// With `Ω = A·max(0, −n̄·ω)/d²` the node's projected solid angle (area
    /// `A`, mean normal `n̄`, direction `ω`, distance `d`): a node smaller
    /// than the pixel its centre falls in covers that pixel by the fraction
    /// `Ω/ΔΩ`; a larger leaf is rasterized as its disk over every pixel whose
    /// centre ray hits it (depth: the hit distance); a larger cluster as a
    /// cone of solid angle `Ω` around `ω`. Depth is the distance to the
    /// centre. A node whose centre is the receiver's position has no
    /// direction and is skipped.
    pub fn splat(&mut self, tree: &Tree, node: NodeId) {
        let (center, _) = tree.sphere(node);
        let v = center - self.position;
        let d2 = v.length_squared();
        if !(d2 > 0.0 && d2.is_finite()) {
            return;
        }
        let d = d2.sqrt();
        let w = self.to_local(v / d);
        if w.z <= -1.0 {
            return;
        }
        let area = tree.area(node);
        let mean_normal = tree.mean_normal(node);
        let omega = area * (-mean_normal.dot(v / d)).max(0.0) / d2;
        if !(omega > 0.0 && omega.is_finite()) {
            return;
        }
        let table = &*self.table;
        // Smaller than the pixel it falls in: that pixel, by the fraction covered.
        if let Some((k, uv)) = table.locate(w) {
            let p = table.pixel(k, uv);
            if omega < table.solid_angle[p] {
                self.raster.write(p, d, node, omega / table.solid_angle[p]);
                return;
            }
        }
        if tree.is_leaf(node) {
            // A leaf covering no pixel centre is small, edge-on or seen from
            // its back; `Ω` above is a far-field estimate that blows up for
            // a disk nearly in the receiver's plane, so give it one pixel at most.
            if !self.splat_disk(node, center, mean_normal, area, d, w)
                && let Some((k, uv)) = self.table.locate(w)
            {
                let p = self.table.pixel(k, uv);
                let cov = (omega / self.table.solid_angle[p]).min(1.0);
                self.raster.write(p, d, node, cov);
            }
            return;
        }
        // A cone of solid angle Ω, anti-aliased: a pixel at angle θ from its
        // axis is covered by `0.5 + (a − θ)/δ`, δ the pixel's angular size,
        // so the coverage of the footprint sums to about Ω.
        let a = (omega * std::f32::consts::FRAC_1_PI).sqrt().min(1.5);
        let (table, raster) = (&*self.table, &mut self.raster);
        let mut hit = false;
        Self::for_candidates(table, w, a + table.pixel_angle, |p| {
            // The chord |u − w| stands in for the angle (equal to second order).
            let theta = (2.0 - 2.0 * table.dir[p].dot(w)).max(0.0).sqrt();
            let cov = (0.5 + (a - theta) / table.pixel_size[p]).min(1.0);
            if cov > 0.0 {
                raster.write(p, d, node, cov);
                hit = true;
            }
        });
        if !hit && let Some((k, uv)) = table.locate(w) {
            let p = table.pixel(k, uv);
            raster.write(p, d, node, (omega / table.solid_angle[p]).min(1.0));
        }
    }

    /// Exact disk rasterization of a leaf; false if it covers no pixel centre.
    fn splat_disk(&mut self, node: NodeId, center: Vec3, normal: Vec3, area: f32, d: f32, w: Vec3) -> bool {
        // Disks of a surface's own area leave holes between them; drawn a
        // little larger they overlap, and the coverage clamp counts the
        // overlap once.
        let r2 = area * std::f32::consts::FRAC_1_PI * (DISK_INFLATION * DISK_INFLATION);
        let r = r2.sqrt();
        let m = self.to_local(normal);
        let c = self.to_local(center - self.position);
        let a = if r >= d { 2.0 } else { (r / d).asin() + 1e-3 };
        let mut hit = false;
        let (table, raster) = (&*self.table, &mut self.raster);
        Self::for_candidates(table, w, a, |p| {
            let u = table.dir[p];
            let denom = m.dot(u);
            if denom >= 0.0 {
                return; // the disk's back, or edge-on
            }
            let t = m.dot(c) / denom;
            if t.is_nan() || t <= 0.0 {
                return;
            }
            if (u * t - c).length_squared() <= r2 {
                raster.write(p, t, node, 1.0);
                hit = true;
            }
        });
        hit
    }

    /// Irradiance: `Σ L·coverage·cosθ·ΔΩ` over the pixels, in pixel order.
    pub fn irradiance(&self, tree: &Tree) -> Vec3 {
        let mut e = Vec3::ZERO;
        let r = &self.raster;
        for p in 0..r.node.len() {
            let k = r.node[p];
            if k != EMPTY {
                e += tree.radiance(k) * (r.coverage(p) * self.table.cos_weight[p]);
            }
        }
        e
    }

    /// Glossy reflection towards `wo` (world, unit):
    /// `Σ L·coverage·f_s(ωi, ωo)·cosθ·ΔΩ`, in pixel order.
    pub fn glossy(&self, tree: &Tree, wo: Vec3, lobe: &GlossyLobe) -> Vec3 {
        let n = self.frame[2];
        let mut l = Vec3::ZERO;
        let r = &self.raster;
        for p in 0..r.node.len() {
            let k = r.node[p];
            if k != EMPTY {
                let wi = self.to_world(self.table.dir[p]);
                l += tree.radiance(k) * lobe.eval(n, wo, wi) * (r.coverage(p) * self.table.cos_weight[p]);
            }
        }
        l
    }

    /// Ambient occlusion: the covered fraction of the cosine-weighted hemisphere.
    pub fn occlusion(&self) -> f32 {
        let mut s = 0.0;
        let r = &self.raster;
        for p in 0..r.node.len() {
            if r.node[p] != EMPTY {
                s += r.coverage(p) * self.table.cos_weight[p];
            }
        }
        (s * std::f32::consts::FRAC_1_PI).min(1.0)
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
    #[inline]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.buffers[receiver].splat(self.tree, node);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solid_angles_cover_the_hemisphere() {
        for n in [1, 2, 3, 8, 17, 64] {
            let t = Table::new(n);
            let total: f64 = t.solid_angle.iter().map(|&x| x as f64).sum();
            let cosine: f64 = t.cos_weight.iter().map(|&x| x as f64).sum();
            assert!(
                (total / (2.0 * std::f64::consts::PI) - 1.0).abs() < 1e-5,
                "n {n}: Σ ΔΩ = {total}"
            );
            // ∫ cosθ dω over the hemisphere is π; pixel-centre cosines approximate it.
            assert!(
                (cosine / std::f64::consts::PI - 1.0).abs() < 0.3 / (n as f64),
                "n {n}: Σ cos ΔΩ = {cosine}"
            );
        }
    }

    #[test]
    fn every_direction_lands_in_its_pixel() {
        let t = Table::new(8);
        for (p, d) in t.dir.iter().enumerate() {
            let (k, uv) = t.locate(*d).expect("upper hemisphere");
            assert_eq!(t.pixel(k, uv), p, "pixel {p} dir {d}");
        }
    }
}
