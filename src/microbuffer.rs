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

/// Solid angle of the rectangle `[x0, x1] × [y0, y1]` on the plane at distance 1.
fn rect_solid_angle(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let f = |x: f64, y: f64| (x * y).atan2((x * x + y * y + 1.0).sqrt());
    f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)
}

/// `∫ cosθ dω` (θ from the axis) over the rectangle `[x0, x1] × [y0, y1]` of
/// the plane at distance 1 along the axis: `∬ dx dy / (1 + x² + y²)²`, exactly.
fn rect_cosine_top(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let f = |x: f64, y: f64| {
        let (a, b) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        0.5 * (x / a * (y / a).atan() + y / b * (x / b).atan())
    };
    f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)
}

/// `∫ cosθ dω` over the rectangle `[u0, u1] × [v0, v1]` of a side plane at
/// distance 1 from the receiver, `v` the height above its tangent plane:
/// `∬ v du dv / (1 + u² + v²)²`, exactly.
fn rect_cosine_side(u0: f64, u1: f64, v0: f64, v1: f64) -> f64 {
    let f = |u: f64, v: f64| {
        let b = (1.0 + v * v).sqrt();
        -0.5 / b * (u / b).atan()
    };
    f(u1, v1) - f(u0, v1) - f(u1, v0) + f(u0, v0)
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
                    let projected = if f.v0 < 0.0 {
                        rect_cosine_top(u0, u0 + du, v0, v0 + dv)
                    } else {
                        rect_cosine_side(u0, u0 + du, v0, v0 + dv)
                    };
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
}

/// Where a local direction falls on the hemicube.
#[derive(Clone, Copy, Debug)]
struct Spot {
    /// Face index.
    face: usize,
    /// Continuous pixel coordinates on the face: column and row, pixel
    /// `(c, r)` spanning `[c, c + 1) × [r, r + 1)`.
    x: f64,
    y: f64,
    /// The pixel it lies in.
    pixel: usize,
}

impl Table {
    /// Where local direction `d` (upper hemisphere, else `None`) falls.
    #[inline]
    fn spot(&self, d: Vec3) -> Option<Spot> {
        let (face, uv) = self.locate(d)?;
        let f = &self.faces[face];
        let x = (uv.x + 1.0) * 0.5 * f.cols as f64;
        let y = (uv.y - f.v0 as f64) / (1.0 - f.v0 as f64) * f.rows as f64;
        // Truncation is floor for the non-negative values kept by `max`.
        let c = (x.max(0.0) as usize).min(f.cols - 1);
        let r = (y.max(0.0) as usize).min(f.rows - 1);
        Some(Spot {
            face,
            x,
            y,
            pixel: f.first + r * f.cols + c,
        })
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
    pixels: Vec<Pixel>,
}

/// Leaf disks are rasterized this much larger than their radius, so that
/// the disks of a surface overlap instead of leaving holes between them.
const DISK_INFLATION: f32 = 1.2;

/// Width of a cluster's coverage ramp, relative to its radius.
const CONE_SOFTNESS: f32 = 1.0;

/// One unit of coverage in the fixed-point sums.
const COVER_ONE: f32 = (1u32 << 24) as f32;

/// No splat: larger than every key.
const NO_KEY: u64 = u64::MAX;

/// `(depth, node)` as one integer ordered lexicographically: the bits of a
/// non-negative, non-NaN `f32` order like its value.
#[inline]
fn key(depth: f32, node: NodeId) -> u64 {
    debug_assert!(depth >= 0.0, "depth {depth}");
    (u64::from(depth.to_bits()) << 32) | u64::from(node)
}

/// One pixel of the raster: two z-buffer entries and the summed coverage.
#[derive(Clone, Copy, Debug)]
struct Pixel {
    /// The nearest `(depth, node)` among the splats that own the pixel.
    own: u64,
    /// The nearest among all splats that touch it.
    any: u64,
    /// Coverage in units of 2⁻²⁴, summed over every splat.
    cover: u64,
}

const CLEAR: Pixel = Pixel {
    own: NO_KEY,
    any: NO_KEY,
    cover: 0,
};

impl Pixel {
    /// Adds a splat covering the fraction `coverage` ∈ (0, 1] of the pixel.
    #[inline]
    fn write(&mut self, key: u64, coverage: f32, owns: bool) {
        debug_assert!(coverage >= 0.0, "coverage {coverage}");
        self.cover += (coverage.min(1.0) * COVER_ONE) as u64;
        self.any = self.any.min(key);
        if owns {
            self.own = self.own.min(key);
        }
    }

    /// The node the pixel shows (the nearest owner, else the nearest splat)
    /// and its coverage in [0, 1]; `None` when nothing touched it.
    #[inline]
    fn shown(&self) -> Option<(NodeId, f32)> {
        let k = if self.own != NO_KEY { self.own } else { self.any };
        (k != NO_KEY).then(|| (k as NodeId, (self.cover as f32 / COVER_ONE).min(1.0)))
    }
}

impl MicroBuffer {
    /// Largest supported resolution.
    pub const MAX_RESOLUTION: usize = 256;

    /// A microbuffer of resolution `n` (top face n×n), 1 ≤ n ≤ 256. The
    /// pixel tables of a resolution are built once per process and shared.
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
            pixels: vec![CLEAR; len],
        })
    }

    /// Resolution N.
    pub fn resolution(&self) -> usize {
        self.table.n
    }

    /// Number of pixels: `N² + 4·N·⌈N/2⌉`.
    pub fn pixels(&self) -> usize {
        self.pixels.len()
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
        self.pixels.fill(CLEAR);
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
    pub fn splat(&mut self, tree: &Tree, node: NodeId) {
        let (center, _) = tree.sphere(node);
        let v = center - self.position;
        let d2 = v.length_squared();
        if !(d2 > 0.0 && d2.is_finite()) {
            return;
        }
        let d = d2.sqrt();
        let dir = v / d;
        let mean_normal = tree.mean_normal(node);
        let omega = tree.area(node) * (-mean_normal.dot(dir)).max(0.0) / d2;
        if omega.is_nan() || omega <= 0.0 {
            return; // facing away, edge on
        }
        // A huge node very near overflows the estimate (or makes it exceed the
        // hemisphere, where the cone's rim would grow without bound and its
        // coverage sink to one half): no splat covers more than 2π.
        let omega = omega.min(std::f32::consts::TAU);
        let w = self.to_local(dir);
        let key = key(d, node);
        let spot = self.table.spot(w);
        let pixel_omega = spot.map(|s| self.table.solid_angle[s.pixel]);
        if let (Some(s), Some(po)) = (spot, pixel_omega)
            && omega < po
        {
            self.splat_small(&s, key, omega);
        } else if tree.is_leaf(node) {
            // `Ω` is a far-field estimate that blows up for a disk nearly in
            // the receiver's plane: a leaf missing every centre gets a pixel at most.
            if !self.splat_disk(node, center, mean_normal, tree.area(node), d, w)
                && let (Some(s), Some(po)) = (spot, pixel_omega)
            {
                self.splat_small(&s, key, po);
            }
        } else {
            let delta = spot.map_or(self.table.pixel_angle, |s| self.table.pixel_size[s.pixel]);
            self.splat_cone(w, key, omega, delta);
        }
    }

    /// Spreads a splat of solid angle `omega` at `spot` over the 2×2 pixels
    /// around it (bilinear weights between pixel centres, clamped into the face).
    #[inline]
    fn splat_small(&mut self, spot: &Spot, key: u64, omega: f32) {
        let table = &*self.table;
        let f = &table.faces[spot.face];
        let (gx, gy) = (spot.x - 0.5, spot.y - 0.5);
        let (x0, y0) = (gx.floor(), gy.floor());
        let (tx, ty) = ((gx - x0) as f32, (gy - y0) as f32);
        let col = |x: f64| (x.max(0.0) as usize).min(f.cols - 1);
        let row = |y: f64| (y.max(0.0) as usize).min(f.rows - 1);
        let (c0, c1, r0, r1) = (col(x0), col(x0 + 1.0), row(y0), row(y0 + 1.0));
        for (c, r, weight) in [
            (c0, r0, (1.0 - tx) * (1.0 - ty)),
            (c1, r0, tx * (1.0 - ty)),
            (c0, r1, (1.0 - tx) * ty),
            (c1, r1, tx * ty),
        ] {
            if weight > 0.0 {
                let p = f.first + r * f.cols + c;
                let cover = weight * (omega / table.solid_angle[p]);
                self.pixels[p].write(key, cover, p == spot.pixel);
            }
        }
    }

    /// A soft cone of solid angle `omega` around local `w`; `delta` is the
    /// angular size of a pixel there (the narrowest rim).
    fn splat_cone(&mut self, w: Vec3, key: u64, omega: f32, delta: f32) {
        // With chord radius `a` and rim width `s` (coverage 1/2 at `a`), the
        // coverage integrates to `π(a² + s²/12)`; solve for `a`.
        let cap = omega * std::f32::consts::FRAC_1_PI;
        let k = CONE_SOFTNESS;
        let soft2 = k * k / 12.0;
        let mut a2 = cap / (1.0 + soft2);
        let mut s = k * a2.sqrt();
        if s < delta {
            s = delta;
            a2 = (cap - delta * delta / 12.0).max(0.0);
        }
        let a = a2.min(4.0).sqrt();
        let (inner, outer) = ((a - 0.5 * s).max(0.0), a + 0.5 * s);
        let (inner2, outer2, inv_s) = (inner * inner, outer * outer, 1.0 / s);
        let reach = 2.0 * (0.5 * outer).min(1.0).asin();
        let (table, pixels) = (&*self.table, &mut self.pixels);
        Self::for_candidates(table, w, reach, |p| {
            let c2 = (table.dir[p] - w).length_squared();
            if c2 >= outer2 {
                return;
            }
            let cover = if c2 <= inner2 {
                1.0
            } else {
                (0.5 + (a - c2.sqrt()) * inv_s).min(1.0)
            };
            if cover > 0.0 {
                pixels[p].write(key, cover, cover >= 0.5);
            }
        });
    }

    /// Exact disk rasterization of a leaf; false if it covers no pixel centre.
    fn splat_disk(&mut self, node: NodeId, center: Vec3, normal: Vec3, area: f32, d: f32, w: Vec3) -> bool {
        let r2 = area * std::f32::consts::FRAC_1_PI * (DISK_INFLATION * DISK_INFLATION);
        let r = r2.sqrt();
        let m = self.to_local(normal);
        let c = self.to_local(center - self.position);
        let reach = if r >= d { 2.0 } else { (r / d).asin() + 1e-3 };
        let mut hit = false;
        let (table, pixels) = (&*self.table, &mut self.pixels);
        Self::for_candidates(table, w, reach, |p| {
            let u = table.dir[p];
            let denom = m.dot(u);
            if denom >= 0.0 {
                return; // the disk's back, or edge-on
            }
            let t = m.dot(c) / denom;
            if t.is_nan() || t <= 0.0 {
                return; // behind the receiver (or NaN)
            }
            if (u * t - c).length_squared() <= r2 {
                pixels[p].write(key(t, node), 1.0, true);
                hit = true;
            }
        });
        hit
    }

    /// Irradiance: `Σ L·coverage·∫cosθ dω` over the pixels, in pixel order.
    pub fn irradiance(&self, tree: &Tree) -> Vec3 {
        let mut e = Vec3::ZERO;
        for (px, cw) in self.pixels.iter().zip(&self.table.cos_weight) {
            if let Some((k, cover)) = px.shown() {
                e += tree.radiance(k) * (cover * cw);
            }
        }
        e
    }

    /// Glossy reflection towards `wo` (world, unit):
    /// `Σ L·coverage·f_s(ωi, ωo)·∫cosθ dω`, `ωi` the pixel centre, in pixel order.
    pub fn glossy(&self, tree: &Tree, wo: Vec3, lobe: &GlossyLobe) -> Vec3 {
        let n = self.frame[2];
        let mut l = Vec3::ZERO;
        for (p, px) in self.pixels.iter().enumerate() {
            if let Some((k, cover)) = px.shown() {
                let wi = self.to_world(self.table.dir[p]);
                l += tree.radiance(k) * lobe.eval(n, wo, wi) * (cover * self.table.cos_weight[p]);
            }
        }
        l
    }

    /// Ambient occlusion: the covered fraction of the cosine-weighted
    /// hemisphere, `Σ coverage·∫cosθ dω / π` ∈ [0, 1].
    pub fn occlusion(&self) -> f32 {
        let mut s = 0.0;
        for (px, cw) in self.pixels.iter().zip(&self.table.cos_weight) {
            if let Some((_, cover)) = px.shown() {
                s += cover * cw;
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
            let s = t.spot(*d).expect("upper hemisphere");
            assert_eq!(s.pixel, p, "pixel {p} dir {d}");
        }
    }
}
