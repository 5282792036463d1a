//! The compact tree's node-test fields ([`Precision::Compact`](super::Precision)):
//! a pair record of one cache line holding its parent's sphere in `f32`
//! and both children's fields in 16 bits against it, as Buchholz and
//! Boubekeur quantize a PBGI tree against its parent's bounds.
//!
//! A child's centre is an offset in steps of `R/32767` from its parent's
//! centre (`R` the parent's radius), its radius a multiple of `R/16384` (a
//! child's sphere may be larger than its parent's, up to `(1 + √3)·R`),
//! its cone axis a vector in steps of `1/32767` normalized where it is
//! read, the cone's cosine and sine multiples of `1/65535`, and its light
//! offset a multiple of its own radius over 16384. The record carries its
//! base, so any node decodes from its own record alone.
//!
//! Bounds stay bounds. The build quantizes a node's centre and axis first,
//! then measures its radius and its cone about the *decoded* centre and axis
//! over the surfels below, and rounds both outwards: a node's decoded
//! sphere holds every disk below it, and its decoded cone every normal
//! (each normal's cosine to the axis at least the cone's, its sine at most
//! the cone's).
//! Decoding is the same `+ − × ÷ √` on `f32` for one node ([`decode`] on
//! `f32`) and for 16 lanes (on `F32s`), so every scheme tests the same
//! values.

use glam::Vec3;

use super::bytes::{Reader, put_f32, put_i16, put_u16, put_u32};
use crate::points::{Surfel, dominant_axis};
use crate::simd::Real;

/// Offset and axis steps per unit.
const OFFSET: f32 = 32767.0;
/// Radius steps per parent radius.
const RADIUS: f32 = 16384.0;
/// Cosine and sine steps per unit.
const ANGLE: f32 = 65535.0;

const _: () = assert!(std::mem::size_of::<CompactPair>() == CompactPair::BYTES);

// SAFETY: `repr(C)`, integers and floats; `put` writes the memory image.
unsafe impl super::store::Plain for CompactPair {}

/// Two sibling nodes' test fields against their parent's sphere (see the
/// module's notes): per field, one value per slot.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct CompactPair {
    /// The parent's decoded sphere: centre x, y, z and radius.
    pub base: [f32; 4],
    pub center: [[i16; 2]; 3],
    pub axis: [[i16; 2]; 3],
    pub radius: [u16; 2],
    pub cos: [u16; 2],
    pub sin: [u16; 2],
    pub light_offset: [u16; 2],
    /// Per slot: the pair record of the node's children, or `LEAF_BIT | surfel`.
    pub child: [u32; 2],
}

/// The quantized fields of one node, as the record stores them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Quantized {
    pub center: [i16; 3],
    pub axis: [i16; 3],
    pub radius: u16,
    pub cos: u16,
    pub sin: u16,
}

impl CompactPair {
    /// Slot `slot`'s quantized fields as numbers, in the order of
    /// [`field`](super::field) (light offset last).
    #[inline(always)]
    pub fn steps(&self, slot: usize) -> [f32; 10] {
        [
            f32::from(self.center[0][slot]),
            f32::from(self.center[1][slot]),
            f32::from(self.center[2][slot]),
            f32::from(self.radius[slot]),
            f32::from(self.axis[0][slot]),
            f32::from(self.axis[1][slot]),
            f32::from(self.axis[2][slot]),
            f32::from(self.cos[slot]),
            f32::from(self.sin[slot]),
            f32::from(self.light_offset[slot]),
        ]
    }

    /// Slot `slot`'s decoded fields, in the order of [`field`](super::field).
    #[inline(always)]
    pub fn decoded(&self, slot: usize) -> [f32; 10] {
        decode(self.base, self.steps(slot))
    }

    /// Bytes of one record in a tree file: its memory image, little-endian.
    pub const BYTES: usize = 64;

    /// Appends the record's bytes (in field order, as `repr(C)` lays it out).
    pub fn put(&self, out: &mut Vec<u8>) {
        self.base.iter().for_each(|&x| put_f32(out, x));
        for v in self.center.iter().chain(&self.axis).flatten() {
            put_i16(out, *v);
        }
        for v in [self.radius, self.cos, self.sin, self.light_offset]
            .iter()
            .flatten()
        {
            put_u16(out, *v);
        }
        self.child.iter().for_each(|&c| put_u32(out, c));
    }

    /// Reads a record [`put`](Self::put) wrote.
    pub fn get(rd: &mut Reader) -> CompactPair {
        let mut p = CompactPair::default();
        p.base.iter_mut().for_each(|x| *x = rd.f32());
        for v in p.center.iter_mut().chain(&mut p.axis).flatten() {
            *v = rd.i16();
        }
        for v in [&mut p.radius, &mut p.cos, &mut p.sin, &mut p.light_offset]
            .into_iter()
            .flatten()
        {
            *v = rd.u16();
        }
        p.child.iter_mut().for_each(|c| *c = rd.u32());
        p
    }

    /// Stores node `q` in slot `slot`.
    pub fn set(&mut self, slot: usize, q: &Quantized, child: u32) {
        for i in 0..3 {
            self.center[i][slot] = q.center[i];
            self.axis[i][slot] = q.axis[i];
        }
        self.radius[slot] = q.radius;
        self.cos[slot] = q.cos;
        self.sin[slot] = q.sin;
        self.child[slot] = child;
    }
}

/// A node's test fields from its base `b` (the parent's sphere) and its
/// steps `q`, in the order of [`field`](super::field): on `f32` for one
/// node, on `F32s` for 16, with the same operations.
#[inline(always)]
pub(crate) fn decode<V: Real>(b: [V; 4], q: [V; 10]) -> [V; 10] {
    let unit = b[3] * V::splat(1.0 / OFFSET);
    let r = q[3] * (b[3] * V::splat(1.0 / RADIUS));
    let (ax, ay, az) = (
        q[4] * V::splat(1.0 / OFFSET),
        q[5] * V::splat(1.0 / OFFSET),
        q[6] * V::splat(1.0 / OFFSET),
    );
    let len = (ax * ax + ay * ay + az * az).sqrt();
    [
        b[0] + q[0] * unit,
        b[1] + q[1] * unit,
        b[2] + q[2] * unit,
        r,
        ax / len,
        ay / len,
        az / len,
        q[7] * V::splat(1.0 / ANGLE),
        q[8] * V::splat(1.0 / ANGLE),
        q[9] * (r * V::splat(1.0 / RADIUS)),
    ]
}

/// The node test's values of a node quantized against `base` (its
/// parent's decoded sphere) from its full-precision sphere centre and
/// cone axis: the steps, and the decoded centre, radius, axis, cosine and
/// sine, with the radius and the cone measured over the surfels `order`
/// about the decoded centre and axis and rounded outwards. `wide`: the
/// cone spans a hemisphere or more (it never culls).
pub(crate) fn quantize(
    base: [f32; 4],
    center: [f32; 3],
    axis: [f32; 3],
    wide: bool,
    surfels: &[Surfel],
    order: &[u32],
) -> (Quantized, [f32; 10]) {
    let unit = base[3] as f64 / OFFSET as f64;
    let mut q = Quantized::default();
    for i in 0..3 {
        let off = if unit > 0.0 {
            (center[i] as f64 - base[i] as f64) / unit
        } else {
            0.0
        };
        q.center[i] = off.round().clamp(-(OFFSET as f64), OFFSET as f64) as i16;
        // A cone that never culls keeps a unit axis all the same (no 0/0).
        let a = if wide { [0.0, 0.0, 1.0][i] } else { axis[i] as f64 };
        q.axis[i] = (a * OFFSET as f64).round() as i16;
    }
    if q.axis == [0; 3] {
        q.axis = [0, 0, OFFSET as i16];
    }
    if !wide {
        keep_dominant(&mut q.axis, axis);
    }
    let steps = |q: &Quantized| {
        let mut s = [0.0f32; 10];
        for i in 0..3 {
            s[i] = f32::from(q.center[i]);
            s[4 + i] = f32::from(q.axis[i]);
        }
        s[3] = f32::from(q.radius);
        s[7] = f32::from(q.cos);
        s[8] = f32::from(q.sin);
        s
    };
    let d = decode(base, steps(&q));
    let (c, a) = (
        Vec3::new(d[0], d[1], d[2]).as_dvec3(),
        Vec3::new(d[4], d[5], d[6]).as_dvec3(),
    );
    // Radius and cone about what a render reads, with the build's slack.
    let mut reach = 0.0f64;
    let mut cos_min = 1.0f64;
    for &i in order {
        let s = &surfels[i as usize];
        reach = reach.max(s.position.as_dvec3().distance(c) + s.radius as f64);
        let n = s.normal.as_dvec3();
        cos_min = cos_min.min(a.dot(n / n.length()));
    }
    let reach = reach * (1.0 + 1e-6);
    let cos_min = if wide { 0.0 } else { cos_min - 1e-6 };
    // Smallest steps whose decoded values hold the bounds.
    let up = |q: &mut Quantized, field: usize, need: f64, start: f64| {
        let mut k = start.clamp(0.0, ANGLE as f64) as u16;
        loop {
            if field == 3 {
                q.radius = k;
            } else {
                q.sin = k;
            }
            if decode(base, steps(q))[field] as f64 >= need || k == u16::MAX {
                return;
            }
            k += 1;
        }
    };
    let step_r = (base[3] * (1.0 / RADIUS)) as f64;
    up(
        &mut q,
        3,
        reach,
        if step_r > 0.0 {
            (reach / step_r).ceil() - 1.0
        } else {
            0.0
        },
    );
    // The cosine rounds down and the sine up, each on its own: the test
    // culls only where `a·(x − c) < 0`, where a smaller cosine and a larger
    // sine both make `cos·(a·(x − c)) + sin·|a × (x − c)| + R` larger.
    q.cos = (cos_min.max(0.0) * ANGLE as f64).floor() as u16;
    while q.cos > 0 && decode(base, steps(&q))[7] as f64 > cos_min {
        q.cos -= 1;
    }
    let sin = if cos_min <= 0.0 {
        1.0
    } else {
        (1.0 - cos_min * cos_min).max(0.0).sqrt()
    };
    up(&mut q, 8, sin, (sin * ANGLE as f64).ceil() - 1.0);
    (q, decode(base, steps(&q)))
}

/// Steps `axis` (the steps of `unit`) one further along `unit`'s
/// dominant axis where rounding tied it with an earlier one. A leaf's
/// axis is its surfel's normal, and the cache files a record by its
/// normal's dominant axis (`cache::facing`): a face at 45° whose normal
/// leans by a rounding error one way would otherwise file its records
/// the other way from the points on it, which then find none.
fn keep_dominant(axis: &mut [i16; 3], unit: [f32; 3]) {
    let d = dominant_axis(Vec3::from(unit));
    if dominant_axis(Vec3::from(axis.map(f32::from))) != d {
        // Rounding is monotone, so the two tie and one step parts them;
        // a tied component is at most 1/√2, far from the steps' end.
        axis[d] += axis[d].signum();
    }
}

/// The light offset's steps for a node of decoded radius `r`: the fewest
/// whose decoded value is at least `offset` (at most `2r`).
pub(crate) fn light_offset_steps(base: [f32; 4], steps: [f32; 10], offset: f32) -> u16 {
    let r = decode(base, steps)[3];
    let unit = r as f64 / RADIUS as f64;
    let mut k = if unit > 0.0 {
        ((offset as f64 / unit).ceil() as u32).saturating_sub(1)
    } else {
        0
    };
    let mut s = steps;
    loop {
        s[9] = k as f32;
        if decode(base, s)[9] >= offset || k >= u32::from(u16::MAX) {
            return k as u16;
        }
        k += 1;
    }
}

/// The sphere children are quantized against: node `d`'s decoded centre
/// and radius.
pub(crate) fn base_of(d: &[f32; 10]) -> [f32; 4] {
    [d[0], d[1], d[2], d[3]]
}
