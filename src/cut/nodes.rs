//! The pair records the kernels read, full (`f32` fields) or compact
//! (16-bit steps against the parent's sphere): each scheme is written once
//! over [`Pairs`], and a compact node decodes with the same operations for
//! one node as for 16 lanes, so every scheme tests the same values.

use std::simd::prelude::*;

use super::classify::NodeLanes;
use crate::simd::{F32s, LANES};
use crate::tree::quantize::decode;
use crate::tree::{CompactPair, PairRecord, field};

/// Pair records popped per single-traversal step.
pub(crate) const PAIRS: usize = LANES / 2;

/// A tree's pair records, as the kernels read them.
pub(crate) trait Pairs {
    /// Number of pair records.
    fn count(&self) -> usize;
    /// Node `k`'s test fields and child link (`LEAF_BIT | surfel` for a leaf).
    fn node(&self, k: u32) -> (NodeLanes<f32>, u32);
    /// The nodes of 8 pair records in the 16 lanes (lane `l`: slot `l & 1`
    /// of record `entries[l / 2]`), and their child links.
    ///
    /// # Safety
    /// Every entry is below [`count`](Self::count).
    unsafe fn lanes(&self, entries: &[u32; PAIRS]) -> (NodeLanes<F32s>, Simd<u32, LANES>);
}

impl<V: Copy> NodeLanes<V> {
    /// From the fields in the order of [`field`].
    #[inline(always)]
    pub(crate) fn from_fields(f: [V; field::COUNT]) -> Self {
        NodeLanes {
            cx: f[field::CX],
            cy: f[field::CY],
            cz: f[field::CZ],
            r: f[field::R],
            ax: f[field::AX],
            ay: f[field::AY],
            az: f[field::AZ],
            cos: f[field::COS],
            sin: f[field::SIN],
            light_offset: f[field::LIGHT_OFFSET],
        }
    }
}

/// The record of node `k` and its slot there.
#[inline(always)]
fn record<T>(pairs: &[T], k: u32) -> (&T, usize) {
    let m = k as usize + 1;
    (&pairs[m >> 1], m & 1)
}

impl Pairs for [PairRecord] {
    #[inline(always)]
    fn count(&self) -> usize {
        self.len()
    }

    #[inline(always)]
    fn node(&self, k: u32) -> (NodeLanes<f32>, u32) {
        let (pair, s) = record(self, k);
        let fields = std::array::from_fn(|j| pair.f[j][s]);
        (NodeLanes::from_fields(fields), pair.child[s])
    }

    #[inline(always)]
    unsafe fn lanes(&self, entries: &[u32; PAIRS]) -> (NodeLanes<F32s>, Simd<u32, LANES>) {
        // SAFETY: the caller's.
        let pairs: [&PairRecord; PAIRS] =
            std::array::from_fn(|i| unsafe { self.get_unchecked(entries[i] as usize) });
        // Field `j` of the popped records into lanes `2i, 2i + 1`. Written
        // out: `array::from_fn` over vectors stays out of line on NEON.
        let load = |j: usize| F32s::from_array(std::array::from_fn(|l| pairs[l / 2].f[j][l & 1]));
        let fields = [
            load(0),
            load(1),
            load(2),
            load(3),
            load(4),
            load(5),
            load(6),
            load(7),
            load(8),
            load(9),
        ];
        let child = Simd::from_array(std::array::from_fn(|l| pairs[l / 2].child[l & 1]));
        (NodeLanes::from_fields(fields), child)
    }
}

impl Pairs for [CompactPair] {
    #[inline(always)]
    fn count(&self) -> usize {
        self.len()
    }

    #[inline(always)]
    fn node(&self, k: u32) -> (NodeLanes<f32>, u32) {
        let (pair, s) = record(self, k);
        (NodeLanes::from_fields(pair.decoded(s)), pair.child[s])
    }

    #[inline(always)]
    unsafe fn lanes(&self, entries: &[u32; PAIRS]) -> (NodeLanes<F32s>, Simd<u32, LANES>) {
        // SAFETY: the caller's.
        let pairs: [&CompactPair; PAIRS] =
            std::array::from_fn(|i| unsafe { self.get_unchecked(entries[i] as usize) });
        let base = |j: usize| F32s::from_array(std::array::from_fn(|l| pairs[l / 2].base[j]));
        let base = [base(0), base(1), base(2), base(3)];
        let signed = |f: fn(&CompactPair) -> &[i16; 2]| {
            Simd::<i16, LANES>::from_array(std::array::from_fn(|l| f(pairs[l / 2])[l & 1])).cast::<f32>()
        };
        let unsigned = |f: fn(&CompactPair) -> &[u16; 2]| {
            Simd::<u16, LANES>::from_array(std::array::from_fn(|l| f(pairs[l / 2])[l & 1])).cast::<f32>()
        };
        let steps = [
            signed(|p| &p.center[0]),
            signed(|p| &p.center[1]),
            signed(|p| &p.center[2]),
            unsigned(|p| &p.radius),
            signed(|p| &p.axis[0]),
            signed(|p| &p.axis[1]),
            signed(|p| &p.axis[2]),
            unsigned(|p| &p.cos),
            unsigned(|p| &p.sin),
            unsigned(|p| &p.light_offset),
        ];
        let child = Simd::from_array(std::array::from_fn(|l| pairs[l / 2].child[l & 1]));
        (NodeLanes::from_fields(decode(base, steps)), child)
    }
}
