//! The octahedral hemisphere map and its per-pixel tables (exact solid
//! angles and cosine integrals, pixel centres, footprint reach), built once
//! per resolution and shared.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use glam::{DVec2, DVec3, Vec3};

use crate::polygon::{clip, projected_solid_angle};
use crate::simd::LANES;

/// Local unit direction of the point `(u, v)` of the square.
pub(crate) fn unmap(u: f64, v: f64) -> DVec3 {
    let (px, py) = (0.5 * (u + v), 0.5 * (u - v));
    DVec3::new(px, py, (1.0 - px.abs() - py.abs()).max(0.0)).normalize()
}

/// `(u, v)` of a local direction with `z ≥ 0`.
pub(crate) fn map64(d: DVec3) -> DVec2 {
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

/// Exact solid angle and `∫ cosθ dω` of the pixel `[u0, u1] × [v0, v1]`:
/// per quadrant of the diamond the pixel is a planar polygon on a face of
/// the octahedron `|x| + |y| + z = 1`.
pub(crate) fn pixel_integrals(u0: f64, u1: f64, v0: f64, v1: f64) -> (f64, f64) {
    let to_p = |u: f64, v: f64| DVec2::new(0.5 * (u + v), 0.5 * (u - v));
    let square = [to_p(u0, v0), to_p(u1, v0), to_p(u1, v1), to_p(u0, v1)];
    let (mut omega, mut projected) = (0.0, 0.0);
    for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
        let (ax, ay) = (DVec2::new(sx, 0.0), DVec2::new(0.0, sy));
        let part = clip(&clip(&square, |p| ax.dot(p)), |p| ay.dot(p));
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
        projected += projected_solid_angle(&lifted, DVec3::Z);
    }
    (omega, projected)
}

/// Largest stretch of the map at `d`: `(u, v)` units per radian, the
/// largest singular value of its Jacobian (one-sided differences).
pub(crate) fn stretch_at(d: DVec3) -> f64 {
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
pub(crate) struct Table {
    pub(crate) n: usize,
    /// Local unit direction of each pixel centre.
    pub(crate) dir: Vec<Vec3>,
    /// The same by component (what the cone and disk loops read), padded
    /// with [`LANES`] zeros.
    pub(crate) dir_x: Vec<f32>,
    pub(crate) dir_y: Vec<f32>,
    pub(crate) dir_z: Vec<f32>,
    /// Exact solid angle of each pixel.
    pub(crate) solid_angle: Vec<f32>,
    /// Exact `∫ cosθ dω` over each pixel (θ from the normal, +z), padded
    /// with zeros to a multiple of 16 pixels.
    pub(crate) cos_weight: Vec<f32>,
    /// Angular size of each pixel, `√ΔΩ`, padded with [`LANES`] zeros.
    pub(crate) pixel_size: Vec<f32>,
    /// The largest pixel size.
    pub(crate) pixel_angle: f32,
    /// Pixels per radian a footprint centred in each pixel can reach, for
    /// footprints up to [`NEAR`] pixels wide: the largest stretch of the map
    /// over the pixels around it, with a margin.
    pub(crate) reach: Vec<f32>,
    /// The same over the whole map, for wider footprints.
    pub(crate) reach_max: f32,
    /// The lowest pixel centre's height above the horizon (its `z`) and
    /// the sine of its angle from the normal: no pixel's ray leans further.
    pub(crate) lowest_z: f32,
    pub(crate) lowest_sin: f32,
    /// Half the smallest sub-sample's angular size (a chord): a footprint
    /// narrower than that covers one sub-sample at most (`samples`).
    pub(crate) half_sample: f32,
    /// Per pixel the local directions (x, y, z by lane) of its 4×4
    /// sub-samples, the centres of a 4×4 grid over the pixel's square, row
    /// by row (`samples`).
    pub(crate) sub: Vec<[[f32; LANES]; 3]>,
    /// Per pixel, its edges with the next pixel of its row and of its
    /// column: `∫ cosθ m ds` along the edge, `m` the unit direction across
    /// it toward that neighbour (zero at the horizon); the gradients'
    /// boundary terms (`gradients`).
    pub(crate) edge: Vec<[Vec3; 2]>,
    /// Per pixel `∫ ẑ × ω dω`: how its cosine weight turns with the normal.
    pub(crate) turn: Vec<Vec3>,
}

/// `∫ cosθ m ds` along the map's segment from `(u0, v0)` to `(u1, v1)`,
/// `m` the unit direction across it, on the side of `toward`.
fn edge_integral(u0: f64, v0: f64, u1: f64, v1: f64, toward: DVec3) -> DVec3 {
    const PIECES: usize = 16;
    let mut g = DVec3::ZERO;
    for k in 0..PIECES {
        let (s0, s1) = (k as f64 / PIECES as f64, (k + 1) as f64 / PIECES as f64);
        let a = unmap(u0 + (u1 - u0) * s0, v0 + (v1 - v0) * s0);
        let b = unmap(u0 + (u1 - u0) * s1, v0 + (v1 - v0) * s1);
        let mid = (a + b).normalize();
        let chord = b - a;
        let arc = 2.0 * (0.5 * chord.length()).min(1.0).asin();
        let mut m = mid.cross(chord).normalize_or_zero();
        if m.dot(toward) < 0.0 {
            m = -m;
        }
        g += m * (mid.z.max(0.0) * arc);
    }
    g
}

/// Footprints up to this many pixels from their centre use the local reach.
pub(crate) const NEAR: usize = 2;

impl Table {
    pub(crate) fn new(n: usize) -> Table {
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
        let half_sample = pixel_size.iter().copied().fold(f32::INFINITY, f32::min) * 0.125;
        // Padded, so that a row of a 16-pixel tile loads in one piece
        // anywhere in the grid (lanes past the last pixel are outside every box).
        pixel_size.resize(len + LANES, 0.0);
        let component = |f: fn(&Vec3) -> f32| {
            let mut v: Vec<f32> = dir.iter().map(f).collect();
            v.resize(len + LANES, 0.0);
            v
        };
        let (dir_x, dir_y, dir_z) = (component(|d| d.x), component(|d| d.y), component(|d| d.z));
        let mut sub = Vec::with_capacity(len);
        for r in 0..n {
            for c in 0..n {
                let (u0, v0) = (-1.0 + c as f64 * h, -1.0 + r as f64 * h);
                let d: [Vec3; LANES] = std::array::from_fn(|k| {
                    let (i, j) = ((k % 4) as f64, (k / 4) as f64);
                    unmap(u0 + (i + 0.5) * 0.25 * h, v0 + (j + 0.5) * 0.25 * h).as_vec3()
                });
                let s = [d.map(|d| d.x), d.map(|d| d.y), d.map(|d| d.z)];
                sub.push(s);
            }
        }
        let mut edge = Vec::with_capacity(len);
        let mut turn = Vec::with_capacity(len);
        for r in 0..n {
            for c in 0..n {
                let (u0, v0) = (-1.0 + c as f64 * h, -1.0 + r as f64 * h);
                let p = r * n + c;
                let own = dir[p].as_dvec3();
                let right = if c + 1 < n {
                    let toward = dir[p + 1].as_dvec3() - own;
                    edge_integral(u0 + h, v0, u0 + h, v0 + h, toward).as_vec3()
                } else {
                    Vec3::ZERO
                };
                let down = if r + 1 < n {
                    let toward = dir[p + n].as_dvec3() - own;
                    edge_integral(u0, v0 + h, u0 + h, v0 + h, toward).as_vec3()
                } else {
                    Vec3::ZERO
                };
                edge.push([right, down]);
                let [sx, sy, _] = &sub[p];
                let w = f64::from(solid_angle[p]) / LANES as f64;
                let (mut tx, mut ty) = (0.0f64, 0.0f64);
                for (x, y) in sx.iter().zip(sy) {
                    tx -= f64::from(*y) * w;
                    ty += f64::from(*x) * w;
                }
                turn.push(Vec3::new(tx as f32, ty as f32, 0.0));
            }
        }
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
            half_sample,
            reach,
            reach_max,
            lowest_z,
            lowest_sin: (1.0 - lowest_z * lowest_z).max(0.0).sqrt(),
            sub,
            edge,
            turn,
        }
    }

    /// The table of resolution `n`, built once per process.
    pub(crate) fn shared(n: usize) -> Arc<Table> {
        static TABLES: OnceLock<Mutex<HashMap<usize, Arc<Table>>>> = OnceLock::new();
        let mut map = TABLES
            .get_or_init(Default::default)
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        map.entry(n).or_insert_with(|| Arc::new(Table::new(n))).clone()
    }
}
