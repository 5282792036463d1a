//! Splatting and convolution, written once over lanes like the node test:
//! [`locate`] places a splat for one receiver (`f32`) or sixteen (`F32s`)
//! with the same IEEE operations, so the scalar pipeline and the 16-lane one
//! write the same pixels, bit for bit.
//!
//! The 16-lane pipeline takes a packet's cut as each node with the lanes
//! (receivers) whose cut holds it ([`PacketCut`]): the node's record is read
//! once and broadcast, the receivers' frames sit in the lanes, and the lanes
//! where it shows are rasterized each into its own microbuffer. The
//! convolution takes 16 pixels at a time.
//!
//! [`shade_cuts`] (scalar) and [`shade_packet`] (lanes) are compiled for
//! every instruction-set path like the traversal kernels, and run on the
//! path they are given.

use std::simd::prelude::*;

use glam::Vec3;

use super::buffer::{MicroBuffer, key};
use super::locate::{FrameLanes, NodeLight, NodeSplat, locate};
use super::near::NearField;
use super::plan::{
    ConePlan, DiskPlan, PixelBox, SmallPlan, pixel_of, plan_cone, plan_disk, plan_small, reach, small,
};
use super::table::Table;
use crate::cut::CutSink;
use crate::error::Error;
use crate::simd::dispatch::{Kernel, dispatch};
use crate::simd::{F32s, Isa, LANES, Real, lane_mask, set_bits};
use crate::tree::{LEAF, NodeId, Tree};

/// A packet's cut, each node once with the lanes (receivers `0..16` of the
/// packet) whose cut holds it, gathered from any scheme's splats. Reusable:
/// [`clear`](Self::clear) between packets.
#[derive(Clone, Debug)]
pub struct PacketCut {
    /// Nodes in the order first splatted.
    nodes: Vec<NodeId>,
    /// Per node of the tree: the lanes splatting it in this packet.
    lanes: Vec<u16>,
}

impl PacketCut {
    /// An empty cut for packets over `tree`.
    pub fn new(tree: &Tree) -> Self {
        PacketCut {
            nodes: Vec::new(),
            lanes: vec![0; tree.len()],
        }
    }

    /// Forgets the last packet.
    pub fn clear(&mut self) {
        for &k in &self.nodes {
            self.lanes[k as usize] = 0;
        }
        self.nodes.clear();
    }

    /// Splats in the cut (a node counts once per receiver).
    pub fn splats(&self) -> usize {
        self.nodes
            .iter()
            .map(|&k| self.lanes[k as usize].count_ones() as usize)
            .sum()
    }

    #[inline(always)]
    fn add(&mut self, node: NodeId, lanes: u16) {
        // A packet step splatting no lane (all traversed or discarded) adds
        // nothing: listing its node would cost the shading a locate for naught.
        if lanes == 0 {
            return;
        }
        if node as usize >= self.lanes.len() {
            // A node of another tree: grow rather than fail.
            self.lanes.resize(node as usize + 1, 0);
        }
        let m = &mut self.lanes[node as usize];
        if *m == 0 {
            self.nodes.push(node);
        }
        *m |= lanes;
    }
}

impl CutSink for PacketCut {
    /// One bit per lane: receiver 16 would fold into lane 0.
    const RECEIVERS: usize = LANES;

    /// Panics for a receiver past 16 (a shift would wrap it into lane 0 and
    /// shade it as another; `Traversal::try_run` refuses such a packet first).
    #[inline(always)]
    fn splat(&mut self, receiver: usize, node: NodeId) {
        assert!(receiver < LANES, "receiver {receiver} of a 16-receiver packet");
        self.add(node, 1 << receiver);
    }

    #[inline(always)]
    fn splat_receivers(&mut self, base: usize, node: NodeId, lanes: u16) {
        assert!(base == 0, "a packet's receivers start at 0, not {base}");
        self.add(node, lanes);
    }
}

/// The convolution a shading pass ends with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Convolution {
    /// Irradiance `E` (RGB).
    Irradiance,
    /// Ambient occlusion `AO` ∈ [0, 1], in every channel.
    Occlusion,
}

/// Splats cut `cuts[i]` into `bufs[i]` (each reset to its receiver
/// beforehand) and convolves it into `out[i]`: the scalar reference, one
/// node and one pixel at a time, on path `isa`.
///
/// Errors: `isa` not available on this CPU ([`Error::Isa`]); fewer cuts or
/// outputs than buffers ([`Error::InvalidParameter`]).
pub fn shade_cuts(
    isa: Isa,
    bufs: &mut [MicroBuffer],
    tree: &Tree,
    cuts: &[Vec<NodeId>],
    what: Convolution,
    out: &mut [Vec3],
) -> Result<(), Error> {
    shade_cuts_near(isa, bufs, tree, cuts, what, None, out)
}

/// [`shade_cuts`], each receiver with its near field from `near` (where it
/// needs one: [`MicroBuffer::set_near_field`]).
pub(crate) fn shade_cuts_near(
    isa: Isa,
    bufs: &mut [MicroBuffer],
    tree: &Tree,
    cuts: &[Vec<NodeId>],
    what: Convolution,
    near: Option<&dyn NearField>,
    out: &mut [Vec3],
) -> Result<(), Error> {
    isa.require()?;
    if cuts.len() < bufs.len() || out.len() < bufs.len() {
        return Err(Error::InvalidParameter {
            name: "cuts, out",
            value: format!(
                "{} cuts and {} outputs for {} buffers",
                cuts.len(),
                out.len(),
                bufs.len()
            ),
            expected: "a cut and an output per buffer",
        });
    }
    dispatch(
        isa,
        ShadeCuts {
            bufs,
            tree,
            cuts,
            what,
            near,
            out,
        },
    );
    Ok(())
}

/// Splats a packet's cut into its receivers' buffers `bufs` (at most 16,
/// each reset beforehand) and convolves each into `out[i]`, 16 lanes at a
/// time, on path `isa`; leaves `cut` cleared. Gives the bits of
/// [`shade_cuts`] on the same cuts.
///
/// Errors: `isa` not available on this CPU ([`Error::Isa`]); more than 16
/// buffers ([`Error::TooManyReceivers`]); fewer outputs than buffers
/// ([`Error::InvalidParameter`]). `cut` is left as it was.
pub fn shade_packet(
    isa: Isa,
    bufs: &mut [MicroBuffer],
    tree: &Tree,
    cut: &mut PacketCut,
    what: Convolution,
    out: &mut [Vec3],
) -> Result<(), Error> {
    shade_packet_near(isa, bufs, tree, cut, what, None, out)
}

/// [`shade_packet`], each receiver with its near field from `near`.
pub(crate) fn shade_packet_near(
    isa: Isa,
    bufs: &mut [MicroBuffer],
    tree: &Tree,
    cut: &mut PacketCut,
    what: Convolution,
    near: Option<&dyn NearField>,
    out: &mut [Vec3],
) -> Result<(), Error> {
    isa.require()?;
    if bufs.len() > LANES {
        return Err(Error::TooManyReceivers {
            given: bufs.len(),
            most: LANES,
        });
    }
    if out.len() < bufs.len() {
        return Err(Error::InvalidParameter {
            name: "out",
            value: format!("{} outputs for {} buffers", out.len(), bufs.len()),
            expected: "an output per buffer",
        });
    }
    if !bufs.is_empty() {
        // The pixel tables, shared by the buffers of one resolution (taken
        // here: reference counting has no place in the clones).
        let table = bufs[0].table.clone();
        let t = &*table;
        dispatch(
            isa,
            ShadePacket {
                t,
                bufs,
                tree,
                cut,
                what,
                near,
                out,
            },
        );
    }
    cut.clear();
    Ok(())
}

/// The scalar pipeline's kernel: [`shade_cuts`] inside a clone.
struct ShadeCuts<'a> {
    bufs: &'a mut [MicroBuffer],
    tree: &'a Tree,
    cuts: &'a [Vec<NodeId>],
    what: Convolution,
    near: Option<&'a dyn NearField>,
    out: &'a mut [Vec3],
}

impl Kernel for ShadeCuts<'_> {
    type Output = ();
    #[inline(always)]
    fn run(self) {
        cuts_body(self.bufs, self.tree, self.cuts, self.what, self.near, self.out)
    }
}

/// The 16-lane pipeline's kernel: [`shade_packet`] inside a clone.
struct ShadePacket<'a> {
    t: &'a Table,
    bufs: &'a mut [MicroBuffer],
    tree: &'a Tree,
    cut: &'a mut PacketCut,
    what: Convolution,
    near: Option<&'a dyn NearField>,
    out: &'a mut [Vec3],
}

impl Kernel for ShadePacket<'_> {
    type Output = ();
    #[inline(always)]
    fn run(self) {
        packet_body(
            self.t, self.bufs, self.tree, self.cut, self.what, self.near, self.out,
        )
    }
}

#[inline(always)]
fn cuts_body(
    bufs: &mut [MicroBuffer],
    tree: &Tree,
    cuts: &[Vec<NodeId>],
    what: Convolution,
    near: Option<&dyn NearField>,
    out: &mut [Vec3],
) {
    for ((mb, cut), o) in bufs.iter_mut().zip(cuts).zip(out.iter_mut()) {
        for &node in cut {
            let Some((rec, light)) = NodeLight::of(tree, node) else {
                continue; // not a node of `tree`
            };
            if let Some(l) = mb.locate(&rec, &light) {
                mb.apply(&rec, node, &l);
            }
        }
        *o = convolve(mb, tree, what, near);
    }
}

#[inline(always)]
fn packet_body(
    t: &Table,
    bufs: &mut [MicroBuffer],
    tree: &Tree,
    cut: &mut PacketCut,
    what: Convolution,
    near: Option<&dyn NearField>,
    out: &mut [Vec3],
) {
    if bufs.iter().any(|b| b.table.n != t.n) {
        // Buffers of different resolutions cannot share lanes: one at a time.
        for (i, (mb, o)) in bufs.iter_mut().zip(out.iter_mut()).enumerate() {
            for &node in &cut.nodes {
                if cut.lanes[node as usize] >> i & 1 != 0
                    && let Some((rec, light)) = NodeLight::of(tree, node)
                    && let Some(l) = mb.locate(&rec, &light)
                {
                    mb.apply(&rec, node, &l);
                }
            }
            *o = convolve(mb, tree, what, near);
        }
        return;
    }
    let frames = FrameLanes::of(bufs);
    let half = F32s::splat(bufs[0].half_n());
    let used = lane_mask(bufs.len());
    let zero = F32s::splat(0.0);
    for &node in &cut.nodes {
        let lanes = cut.lanes[node as usize] & used;
        let Some((rec, light)) = NodeLight::of(tree, node) else {
            continue; // not a node of `tree`
        };
        let s = NodeSplat::of(&rec).splat();
        let l = locate(&s, &light, &frames, half);
        let show = l.valid.to_bitmask() as u16 & lanes;
        if show == 0 {
            continue;
        }
        // Class, and everything up to the pixel loops, for all lanes at once
        // (the scalar pipeline's `MicroBuffer::apply`, lane by lane).
        let pixel = pixel_of(t, l.x, l.y);
        let visible = zero.lt(l.wz);
        let pixel_omega = F32s::gather(&t.solid_angle, pixel);
        // Sub-pixel nodes are small splats also below the horizon (where
        // they add nothing), as in `MicroBuffer::apply`.
        let leaf = rec.kind == LEAF;
        let small_m = small(leaf, s.area, l.omega, l.d, pixel_omega);
        let cos = l.wz.max_of(zero);
        let small = small_m.to_bitmask() as u16 & show;
        let large = show & !small;
        let (d, vis) = (l.d.to_array(), visible.to_bitmask() as u16);
        let rad = l.radiance.map(|c| c.to_array());
        let radiance = |i: usize| [rad[0][i], rad[1][i], rad[2][i]];
        // Small splats, and the fallback of leaves covering no pixel centre
        // (with `Ω` capped at the pixel's).
        // (An `if`, not `bool::then` with a closure: an out-of-line closure
        // would be compiled for the baseline target, not this clone.)
        let small_plan = if small != 0 || (leaf && large != 0) {
            let reach = F32s::select(
                small_m,
                reach(t, leaf, s.area, l.omega, l.d, pixel),
                F32s::splat(0.5),
            );
            let plan = plan_small(
                t,
                l.x,
                l.y,
                F32s::select(small_m, l.projected, pixel_omega * cos),
                reach,
            );
            Some(SmallWrites::new(&plan, l.d, node, &rad))
        } else {
            None
        };
        if let Some(sp) = &small_plan {
            for i in set_bits(small) {
                bufs[i].draw_small_lane(sp, i);
            }
        }
        if large == 0 {
            continue;
        }
        if leaf {
            let dp = plan_disk(t, &frames, &s, l.x, l.y, pixel, l.d);
            let m = [dp.m[0].to_array(), dp.m[1].to_array(), dp.m[2].to_array()];
            let c = [dp.c[0].to_array(), dp.c[1].to_array(), dp.c[2].to_array()];
            let (mc, r, bx) = (dp.mc.to_array(), dp.r.to_array(), boxes(&dp.bx));
            let fronts = dp.fronts.to_bitmask() as u16;
            for i in set_bits(large) {
                let plan = DiskPlan {
                    fronts: fronts >> i & 1 != 0,
                    m: [m[0][i], m[1][i], m[2][i]],
                    c: [c[0][i], c[1][i], c[2][i]],
                    mc: mc[i],
                    r: r[i],
                    bx: bx.lane(i),
                };
                if !bufs[i].draw_disk_tiles(&plan, node, radiance(i))
                    && vis >> i & 1 != 0
                    && let Some(sp) = &small_plan
                {
                    bufs[i].draw_small_lane(sp, i);
                }
            }
        } else {
            let cp = plan_cone(t, l.x, l.y, pixel, l.omega, visible);
            let target = F32s::select(visible, l.projected, zero).to_array();
            let (a, inv_s) = (cp.a.to_array(), cp.inv_s.to_array());
            let (inner2, outer2, bx) = (cp.inner2.to_array(), cp.outer2.to_array(), boxes(&cp.bx));
            let (wx, wy, wz) = (l.wx.to_array(), l.wy.to_array(), l.wz.to_array());
            for i in set_bits(large) {
                let plan = ConePlan {
                    a: a[i],
                    inv_s: inv_s[i],
                    inner2: inner2[i],
                    outer2: outer2[i],
                    bx: bx.lane(i),
                };
                bufs[i].draw_cone_tiles(
                    Vec3::new(wx[i], wy[i], wz[i]),
                    &plan,
                    key(d[i], node),
                    target[i],
                    radiance(i),
                );
            }
        }
    }
    for (mb, o) in bufs.iter_mut().zip(out.iter_mut()) {
        *o = convolve(mb, tree, what, near);
    }
}

/// A small-splat plan of 16 lanes reduced to the fragments it leaves: per
/// corner and lane the pixel, the key, the coverage and whether the corner
/// has weight, all worked out in the lanes, so that each receiver's part is
/// up to four appends (the scalar pipeline's `draw_small`, bit for bit).
struct SmallWrites {
    p: [[u32; LANES]; 4],
    key: [u64; LANES],
    cover: [[f32; LANES]; 4],
    weighted: [u16; 4],
    radiance: [[f32; LANES]; 3],
}

impl SmallWrites {
    #[inline(always)]
    fn new(plan: &SmallPlan<F32s>, depth: F32s, node: NodeId, radiance: &[[f32; LANES]; 3]) -> Self {
        let key = (depth.to_bits().cast::<u64>() << 32) | Simd::splat(u64::from(node));
        let (zero, one) = (F32s::splat(0.0), F32s::splat(1.0));
        let mut w = SmallWrites {
            p: [[0; LANES]; 4],
            key: key.to_array(),
            cover: [[0.0; LANES]; 4],
            weighted: [0; 4],
            radiance: *radiance,
        };
        for k in 0..4 {
            w.p[k] = plan.p[k].cast::<u32>().to_array();
            w.cover[k] = plan.cover[k].min_of(one).to_array();
            w.weighted[k] = zero.lt(plan.w[k]).to_bitmask() as u16;
        }
        w
    }
}

impl MicroBuffer {
    /// Lane `i`'s part of a small splat.
    #[inline(always)]
    fn draw_small_lane(&mut self, sw: &SmallWrites, i: usize) {
        let r = &sw.radiance;
        for k in 0..4 {
            if sw.weighted[k] >> i & 1 != 0 {
                self.frags.push(
                    sw.p[k][i] as usize,
                    sw.key[i],
                    sw.cover[k][i],
                    [r[0][i], r[1][i], r[2][i]],
                );
            }
        }
    }
}

/// 16 lanes of pixel boxes, as arrays.
struct BoxLanes([[f32; LANES]; 4]);

#[inline(always)]
fn boxes(b: &PixelBox<F32s>) -> BoxLanes {
    BoxLanes([b.c0.to_array(), b.c1.to_array(), b.r0.to_array(), b.r1.to_array()])
}

impl BoxLanes {
    #[inline(always)]
    fn lane(&self, i: usize) -> PixelBox<f32> {
        PixelBox {
            c0: self.0[0][i],
            c1: self.0[1][i],
            r0: self.0[2][i],
            r1: self.0[3][i],
        }
    }
}

/// The convolution `what` of one buffer: the composition both pipelines
/// share (`compose`).
#[inline(always)]
fn convolve(mb: &mut MicroBuffer, tree: &Tree, what: Convolution, near: Option<&dyn NearField>) -> Vec3 {
    if let Some(field) = near {
        mb.set_near_field(tree, field);
    }
    match what {
        Convolution::Irradiance => mb.irradiance_inline(tree),
        Convolution::Occlusion => Vec3::splat(mb.occlusion_inline(tree)),
    }
}
