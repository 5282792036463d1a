//! Structured inputs shared by the traversal and microbuffer targets: values
//! are mostly drawn from small grids and tables of edge cases (so that ties,
//! coincident points, axis normals, subnormals and the range limits come up
//! often), with raw `f32` bit patterns as one choice among others.
#![allow(dead_code)]

use arbitrary::Arbitrary;
use glam::Vec3;
use pbgi::Surfel;
use pbgi::points::{MAX_COORDINATE, MAX_RADIANCE};

/// A position.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Pos {
    /// On a grid of eighths (`i8 / 8`): many ties.
    Grid([i8; 3]),
    /// Raw bits (NaN, infinities and values beyond `MAX_COORDINATE` included).
    Raw([f32; 3]),
    /// Exactly at an earlier surfel (or the first one).
    At(u16),
    /// An earlier surfel moved by a power of two along its normal.
    Off(u16, i8),
}

/// A direction (normalized in f64 where it can be).
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Dir {
    /// ±x, ±y, ±z.
    Axis(u8),
    /// A small integer vector.
    Grid([i8; 3]),
    /// Raw bits, not normalized (rejected unless of unit length).
    Raw([f32; 3]),
    /// The normal of an earlier surfel, or its opposite.
    Of(u16, bool),
}

/// A scalar from a table of edge cases, a power of two, or raw bits.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Scalar {
    /// An entry of the caller's table.
    Table(u8),
    /// `2^(k mod 256 − 150)`: from subnormal to beyond `f32::MAX` (infinite).
    Pow2(u8),
    /// Raw bits.
    Raw(f32),
}

impl Scalar {
    pub fn value(self, table: &[f32]) -> f32 {
        match self {
            Scalar::Table(i) => table[i as usize % table.len()],
            Scalar::Pow2(k) => 2f32.powi(k as i32 - 150),
            Scalar::Raw(x) => x,
        }
    }
}

pub const RADII: [f32; 8] = [0.01, 0.1, 0.5, 1.0, 1e-40, 1e-6, 1e6, MAX_COORDINATE];
pub const RADIANCE: [f32; 8] = [0.0, 1.0, 0.5, 1e-30, 1e-40, 1e30, MAX_RADIANCE, 3.0];
pub const OMEGAS: [f32; 10] = [
    0.0,
    1e-6,
    0.01,
    0.05,
    0.3,
    1.0,
    4.0 * std::f32::consts::PI,
    1e3,
    f32::MAX,
    f32::MIN_POSITIVE,
];

/// One surfel's recipe.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub struct SurfelSpec {
    pub pos: Pos,
    pub normal: Dir,
    pub radius: Scalar,
    pub radiance: [Scalar; 3],
}

fn earlier(done: &[Surfel], k: u16) -> Option<&Surfel> {
    (!done.is_empty()).then(|| &done[k as usize % done.len()])
}

pub fn position(p: Pos, done: &[Surfel]) -> Vec3 {
    match p {
        Pos::Grid(g) => Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32) / 8.0,
        Pos::Raw(r) => Vec3::from(r),
        Pos::At(k) => earlier(done, k).map_or(Vec3::ZERO, |s| s.position),
        Pos::Off(k, e) => {
            earlier(done, k).map_or(Vec3::ZERO, |s| s.position + s.normal * 2f32.powi(e as i32 % 64))
        }
    }
}

pub fn direction(d: Dir, done: &[Surfel]) -> Vec3 {
    let unit = |v: Vec3| {
        let l = v.as_dvec3().length();
        if l > 0.0 && l.is_finite() {
            (v.as_dvec3() / l).as_vec3()
        } else {
            v
        }
    };
    match d {
        Dir::Axis(a) => [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z][a as usize % 6],
        Dir::Grid(g) => unit(Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32)),
        Dir::Raw(r) => Vec3::from(r),
        Dir::Of(k, flip) => earlier(done, k).map_or(Vec3::Z, |s| if flip { -s.normal } else { s.normal }),
    }
}

/// The surfels of the specs (possibly invalid: the caller must get an error).
pub fn surfels(specs: &[SurfelSpec], limit: usize) -> Vec<Surfel> {
    let mut out: Vec<Surfel> = Vec::new();
    for s in specs.iter().take(limit) {
        let surfel = Surfel {
            position: position(s.pos, &out),
            normal: direction(s.normal, &out),
            radius: s.radius.value(&RADII),
            radiance: Vec3::from(s.radiance.map(|l| l.value(&RADIANCE))),
        };
        out.push(surfel);
    }
    out
}
