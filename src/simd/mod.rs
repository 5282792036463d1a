//! The SIMD vocabulary every kernel speaks, and the one place where kernels
//! are compiled per instruction set.
//!
//! * [`LANES`], [`F32s`], [`M32s`] and the lane type `Real` (one `f32` or 16
//!   of them, with the same IEEE operations), so each kernel is written once
//!   and the scalar reference runs the same arithmetic as the lanes;
//! * lane-mask helpers (`lane_mask`, `set_bits`) and the fixed-order `sum`;
//! * [`Isa`] (`isa`): the instruction-set paths, their detection and
//!   `PBGI_ISA`;
//! * `dispatch`: one kernel trait and one `multiversion` dispatch, which
//!   every kernel entry (traversal, scalar and 16-lane shading) goes
//!   through.
//!
//! Nothing here knows of trees, cuts or microbuffers: data enters as lanes
//! and leaves as lanes.

pub(crate) mod dispatch;
mod isa;

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};
use std::simd::prelude::*;
use std::simd::simd_swizzle;

pub use isa::{Isa, IsaError};

/// Lanes per kernel vector.
pub const LANES: usize = 16;

/// The vector type of the kernels.
pub type F32s = Simd<f32, LANES>;
/// Its mask type.
pub type M32s = Mask<i32, LANES>;

/// A scalar `f32` or a vector of them, with the few operations the kernels use.
///
/// Every operation is one correctly rounded IEEE operation (or exact), so a
/// lane computes bit for bit what the scalar code computes; `max`/`min` are
/// defined by a comparison and a select, not by the instruction set's own
/// (whose NaN and ±0 rules differ between x86, ARM and `f32::max`).
pub(crate) trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    type Mask: Copy + BitAnd<Output = Self::Mask> + BitOr<Output = Self::Mask> + Not<Output = Self::Mask>;
    fn splat(x: f32) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    fn floor(self) -> Self;
    fn ceil(self) -> Self;
    /// `table[i]` per lane, for lanes holding non-negative whole numbers
    /// (indices kept as floats, exact below 2²⁴); out of range is a bug.
    fn gather(table: &[f32], i: Self) -> Self;
    fn le(self, o: Self) -> Self::Mask;
    fn lt(self, o: Self) -> Self::Mask;
    /// `if m { a } else { b }` per lane.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// `if self > o { self } else { o }`: `o` when either is NaN.
    #[inline(always)]
    fn max_of(self, o: Self) -> Self {
        Self::select(o.lt(self), self, o)
    }
    /// `if self < o { self } else { o }`: `o` when either is NaN.
    #[inline(always)]
    fn min_of(self, o: Self) -> Self {
        Self::select(self.lt(o), self, o)
    }
}

impl Real for f32 {
    type Mask = bool;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        f32::floor(self)
    }
    #[inline(always)]
    fn ceil(self) -> Self {
        f32::ceil(self)
    }
    #[inline(always)]
    fn gather(table: &[f32], i: Self) -> Self {
        table[i as usize]
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
}

impl Real for F32s {
    type Mask = M32s;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        Simd::splat(x)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        std::simd::StdFloat::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        SimdFloat::abs(self)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        std::simd::StdFloat::floor(self)
    }
    #[inline(always)]
    fn ceil(self) -> Self {
        std::simd::StdFloat::ceil(self)
    }
    #[inline(always)]
    fn gather(table: &[f32], i: Self) -> Self {
        let i = i.cast::<u32>().to_array();
        // A plain loop: a closure given to `from_fn` may be left out of line,
        // compiled for the baseline target instead of the caller's clone.
        let mut v = [0.0f32; LANES];
        for (v, &i) in v.iter_mut().zip(&i) {
            *v = table[i as usize];
        }
        Simd::from_array(v)
    }
    #[inline(always)]
    fn select(m: M32s, a: Self, b: Self) -> Self {
        std::simd::Select::select(m, a, b)
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32s {
        self.simd_le(o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32s {
        self.simd_lt(o)
    }
}

/// The lanes' sum as a fixed tree of lane-wise additions (halves, then
/// quarters, …): the same IEEE operations on every instruction set, where
/// `reduce_sum` leaves the order to the target, and four dependent
/// additions deep instead of the sixteen of a sum lane after lane.
#[inline(always)]
pub(crate) fn sum(v: F32s) -> f32 {
    let h: Simd<f32, 8> =
        simd_swizzle!(v, [0, 1, 2, 3, 4, 5, 6, 7]) + simd_swizzle!(v, [8, 9, 10, 11, 12, 13, 14, 15]);
    let q: Simd<f32, 4> = simd_swizzle!(h, [0, 1, 2, 3]) + simd_swizzle!(h, [4, 5, 6, 7]);
    let e: Simd<f32, 2> = simd_swizzle!(q, [0, 1]) + simd_swizzle!(q, [2, 3]);
    e[0] + e[1]
}

/// The mask of the first `count` lanes.
#[inline(always)]
pub(crate) fn lane_mask(count: usize) -> u16 {
    if count >= LANES {
        u16::MAX
    } else {
        ((1u32 << count) - 1) as u16
    }
}

/// The set bits of a lane mask, lowest first: `for l in set_bits(mask)`.
///
/// An iterator rather than a closure-taking helper: a large closure may be
/// left out of line, and an out-of-line closure is compiled for the baseline
/// target instead of the caller's instruction-set clone.
#[inline(always)]
pub(crate) fn set_bits(mask: impl Into<u64>) -> SetBits {
    SetBits(mask.into())
}

/// Iterator of [`set_bits`].
pub(crate) struct SetBits(u64);

impl Iterator for SetBits {
    type Item = usize;
    #[inline(always)]
    fn next(&mut self) -> Option<usize> {
        if self.0 == 0 {
            return None;
        }
        let i = self.0.trailing_zeros() as usize;
        self.0 &= self.0 - 1;
        Some(i)
    }
}
