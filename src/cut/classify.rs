//! The node test (the paper's three masks), written once over a lane type
//! (`Real`) so the scalar reference and the 16-lane kernels run the same
//! IEEE operations in the same order. Only `+ - * sqrt` and comparisons: no
//! FMA contraction, no reciprocal estimates, so every path classifies every
//! node identically.

use crate::simd::{F32s, Real};

/// The node fields the test reads, for one node or one per lane.
#[derive(Clone, Copy)]
pub(crate) struct NodeLanes<V> {
    pub cx: V,
    pub cy: V,
    pub cz: V,
    pub r: V,
    pub ax: V,
    pub ay: V,
    pub az: V,
    pub cos: V,
    pub sin: V,
    /// How far the node's light centroid lies from its area centroid.
    pub light_offset: V,
}

/// Receiver position and normal, for one receiver or one per lane.
#[derive(Clone, Copy)]
pub(crate) struct ReceiverLanes<V> {
    pub px: V,
    pub py: V,
    pub pz: V,
    pub nx: V,
    pub ny: V,
    pub nz: V,
}

impl ReceiverLanes<f32> {
    /// The same receiver in every lane.
    #[inline(always)]
    pub fn splat(&self) -> ReceiverLanes<F32s> {
        ReceiverLanes {
            px: F32s::splat(self.px),
            py: F32s::splat(self.py),
            pz: F32s::splat(self.pz),
            nx: F32s::splat(self.nx),
            ny: F32s::splat(self.ny),
            nz: F32s::splat(self.nz),
        }
    }
}

impl NodeLanes<f32> {
    /// The same node in every lane.
    #[inline(always)]
    pub fn splat(&self) -> NodeLanes<F32s> {
        NodeLanes {
            cx: F32s::splat(self.cx),
            cy: F32s::splat(self.cy),
            cz: F32s::splat(self.cz),
            r: F32s::splat(self.r),
            ax: F32s::splat(self.ax),
            ay: F32s::splat(self.ay),
            az: F32s::splat(self.az),
            cos: F32s::splat(self.cos),
            sin: F32s::splat(self.sin),
            light_offset: F32s::splat(self.light_offset),
        }
    }
}

/// `v = c − x` and `d2 = v·v`.
#[derive(Clone, Copy)]
pub(crate) struct Offset<V> {
    pub vx: V,
    pub vy: V,
    pub vz: V,
    pub d2: V,
}

#[inline(always)]
pub(crate) fn offset<V: Real>(node: &NodeLanes<V>, rec: &ReceiverLanes<V>) -> Offset<V> {
    let vx = node.cx - rec.px;
    let vy = node.cy - rec.py;
    let vz = node.cz - rec.pz;
    Offset {
        vx,
        vy,
        vz,
        d2: vx * vx + vy * vy + vz * vz,
    }
}

/// Mask 1a: the sphere lies wholly below the receiver's tangent plane, `v·n ≤ −R`.
#[inline(always)]
pub(crate) fn below_horizon<V: Real>(node: &NodeLanes<V>, rec: &ReceiverLanes<V>, o: &Offset<V>) -> V::Mask {
    let vn = o.vx * rec.nx + o.vy * rec.ny + o.vz * rec.nz;
    vn.le(-node.r)
}

/// Mask 1b: every disk below the node faces away from the receiver.
///
/// With `d = x − c`, `t = a·d` and `s = |a × d|`, the largest `m·(x − p)` over
/// cone normals `m` and points `p` of the sphere is at most
/// `cosθ·t + sinθ·s + R` (for `θ ≤ π/2`), so the node is culled when
/// `sinθ·s + R ≤ cosθ·(a·v)`, `v = −d`. A cone stored as `(0, 1)` never culls.
#[inline(always)]
pub(crate) fn faces_away<V: Real>(node: &NodeLanes<V>, o: &Offset<V>) -> V::Mask {
    let va = o.vx * node.ax + o.vy * node.ay + o.vz * node.az;
    let kx = node.ay * o.vz - node.az * o.vy;
    let ky = node.az * o.vx - node.ax * o.vz;
    let kz = node.ax * o.vy - node.ay * o.vx;
    let s = (kx * kx + ky * ky + kz * kz).sqrt();
    (node.sin * s + node.r).le(node.cos * va)
}

/// The far test's parameters: Ω and the light offset's weight `k`.
#[derive(Clone, Copy)]
pub(crate) struct Far<V> {
    pub max_solid_angle: V,
    pub light_offset: V,
}

impl Far<f32> {
    #[inline(always)]
    pub fn splat(&self) -> Far<F32s> {
        Far {
            max_solid_angle: F32s::splat(self.max_solid_angle),
            light_offset: F32s::splat(self.light_offset),
        }
    }
}

/// Mask 2: far enough to splat, `π S² < Ω d²` with `S = R + k·|l − c|`
/// (`R` where the node's light lies where its surface does, or `k = 0`; no
/// division: `d² = 0` is fine).
#[inline(always)]
pub(crate) fn far<V: Real>(node: &NodeLanes<V>, o: &Offset<V>, test: &Far<V>) -> V::Mask {
    let s = node.r + test.light_offset * node.light_offset;
    (V::splat(std::f32::consts::PI) * s * s).lt(test.max_solid_angle * o.d2)
}

/// Discard and far masks of the whole test, evaluated eagerly (for lanes).
#[inline(always)]
pub(crate) fn classify<V: Real>(
    node: &NodeLanes<V>,
    rec: &ReceiverLanes<V>,
    test: &Far<V>,
) -> (V::Mask, V::Mask) {
    let o = offset(node, rec);
    let discard = below_horizon(node, rec, &o) | faces_away(node, &o);
    (discard, far(node, &o, test))
}

/// One of the test's outcomes for a (receiver, node) pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Outcome {
    /// Culled: below the tangent plane or facing wholly away.
    Discard,
    /// Part of the cut: far enough (or a leaf), rasterized into the microbuffer.
    Splat,
    /// Too close: both children are tested.
    Traverse,
}

/// The scalar test, short-circuited: the later masks are only computed when
/// the earlier ones did not decide. Same operations as [`classify`].
#[inline(always)]
pub(crate) fn outcome_scalar(
    node: &NodeLanes<f32>,
    rec: &ReceiverLanes<f32>,
    test: &Far<f32>,
    leaf: bool,
) -> Outcome {
    let o = offset(node, rec);
    if below_horizon(node, rec, &o) || faces_away(node, &o) {
        Outcome::Discard
    } else if leaf || far(node, &o, test) {
        Outcome::Splat
    } else {
        Outcome::Traverse
    }
}
