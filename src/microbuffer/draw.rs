//! The scalar draw: one located splat into one receiver's pixels, pixel by
//! pixel, in the class the plan gives it (small, cone or disk). The 16-lane
//! pipeline draws the same pixels with the same bits (`tiles`, `shade`).

use glam::Vec3;

use super::buffer::{Fragments, MicroBuffer, key};
use super::locate::{Located, NodeSplat};
use super::plan::{ConePlan, DiskPlan, SmallPlan, pixel_of, plan_cone, plan_disk, plan_small, reach, small};
use super::table::Table;
use crate::simd::Real;
use crate::tree::{LEAF, NodeId, SplatRecord};

/// Scales the cone fragments `frags[start..]` so that their
/// `Σ coverage·∫cos` is `target` (`Ω·cosθ`); nothing when `target` is 0 (a
/// centre below the horizon) or the cone covered no pixel. A fragment
/// covers at most its pixel: where scaling up fills some, the others take
/// up what they cannot hold (up to four rounds). Filled pixels kept what
/// they could not take, and a cone of two to four pixels across, sampled
/// at the pixel centres under its area, lost up to 5 % of it (at N 24
/// more than at N 14 or 48: `examples/sky_coverage`). The sums are taken in
/// fixed point, so they do not depend on the order the pixels were visited
/// in (row by row here, tile by tile in the 16-lane draw).
#[inline(always)]
pub(super) fn normalize_cone(frags: &mut Fragments, start: usize, t: &Table, target: f32) {
    if target.is_nan() || target <= 0.0 {
        return;
    }
    const ONE: f64 = (1u64 << 40) as f64;
    let fixed = |x: f32| (x as f64 * ONE) as u64;
    let (mut sum, mut most) = (0u64, 0.0f32);
    for i in start..frags.len() {
        sum += fixed(frags.cover[i] * t.cos_weight[frags.pixel[i] as usize]);
        most = most.max(frags.cover[i]);
    }
    if sum == 0 {
        return;
    }
    let mut scale = target / (sum as f64 / ONE) as f32;
    // Only a scale that fills some pixel needs the rounds (most cones
    // have none: their scale is near 1 and their fullest pixel below it).
    let rounds = if most * scale >= 1.0 { 4 } else { 0 };
    for _ in 0..rounds {
        // What the full pixels hold, and what the others would at `scale`.
        let (mut full, mut rest) = (0u64, 0u64);
        for i in start..frags.len() {
            let (c, cw) = (frags.cover[i], t.cos_weight[frags.pixel[i] as usize]);
            if c * scale >= 1.0 {
                full += fixed(cw);
            } else {
                rest += fixed(c * cw);
            }
        }
        let left = target - (full as f64 / ONE) as f32;
        if full == 0 || rest == 0 || left <= 0.0 {
            break;
        }
        let next = left / (rest as f64 / ONE) as f32;
        if next <= scale {
            break;
        }
        scale = next;
    }
    for c in &mut frags.cover[start..] {
        *c = (*c * scale).min_of(1.0);
    }
}

impl MicroBuffer {
    /// Draws a small splat.
    #[inline(always)]
    pub(crate) fn draw_small(&mut self, plan: &SmallPlan<f32>, key: u64, radiance: [f32; 3]) {
        for k in 0..4 {
            if plan.w[k] > 0.0 {
                self.frags
                    .push(plan.p[k] as usize, key, plan.cover[k].min_of(1.0), radiance);
            }
        }
    }

    /// Draws a cone around local direction `w`, normalised to `target`
    /// ([`normalize_cone`]).
    #[inline(always)]
    pub(crate) fn draw_cone(
        &mut self,
        w: Vec3,
        plan: &ConePlan<f32>,
        key: u64,
        target: f32,
        radiance: [f32; 3],
    ) {
        let (c0, c1, r0, r1) = plan.bx.bounds();
        let n = self.table.n;
        let start = self.frags.len();
        for r in r0..=r1 {
            for c in c0..=c1 {
                let p = r * n + c;
                let t = &self.table;
                let (m, cover) = plan.cover([w.x, w.y, w.z], t.dir_x[p], t.dir_y[p], t.dir_z[p]);
                if m {
                    self.frags.push(p, key, cover.min_of(1.0), radiance);
                }
            }
        }
        normalize_cone(&mut self.frags, start, &self.table, target);
    }

    /// Draws a leaf's disk (depth: the hit distance); false if it covers no
    /// pixel centre.
    #[inline(always)]
    pub(crate) fn draw_disk(&mut self, plan: &DiskPlan<f32>, node: NodeId, radiance: [f32; 3]) -> bool {
        if !plan.fronts {
            return false;
        }
        let (c0, c1, r0, r1) = plan.bx.bounds();
        let n = self.table.n;
        let mut any_hit = false;
        for row in r0..=r1 {
            for col in c0..=c1 {
                let p = row * n + col;
                let t = &self.table;
                let (hit, depth, cover) = plan.hit(t.dir_x[p], t.dir_y[p], t.dir_z[p], t.pixel_size[p]);
                if hit {
                    self.frags.push(p, key(depth, node), cover.min_of(1.0), radiance);
                    any_hit = true;
                }
            }
        }
        any_hit
    }

    /// Draws node `node` (record `rec`) located at `l`: the scalar pipeline,
    /// which works out only what the splat's class needs.
    #[inline(always)]
    pub(crate) fn apply(&mut self, rec: &SplatRecord, node: NodeId, l: &Located<f32>) {
        let t = &*self.table;
        let pixel = pixel_of(t, l.x, l.y);
        let visible = 0.0 < l.wz;
        let pixel_omega = f32::gather(&t.solid_angle, pixel);
        let key = key(l.d, node);
        let cos = l.wz.max_of(0.0);
        let radiance = l.radiance;
        if small(rec.kind == LEAF, rec.area, l.omega, l.d, pixel_omega) {
            // Also below the horizon, where it adds nothing (cos 0): a cone
            // there would put a pixel's worth at the horizon.
            let reach = reach(t, rec.kind == LEAF, rec.area, l.omega, l.d, pixel);
            let plan = plan_small(t, l.x, l.y, l.projected, reach);
            self.draw_small(&plan, key, radiance);
        } else if rec.kind == LEAF {
            let plan = plan_disk(t, &self.frame_lanes(), &NodeSplat::of(rec), l.x, l.y, pixel, l.d);
            // `Ω` is a far-field estimate that blows up for a disk nearly in
            // the receiver's plane: a leaf missing every centre gets a pixel at most.
            if !self.draw_disk(&plan, node, radiance) && visible {
                let t = &*self.table;
                let plan = plan_small(t, l.x, l.y, pixel_omega * cos, 0.5);
                self.draw_small(&plan, key, radiance);
            }
        } else {
            let plan = plan_cone(t, l.x, l.y, pixel, l.omega, visible);
            let target = f32::select(visible, l.projected, 0.0);
            self.draw_cone(Vec3::new(l.wx, l.wy, l.wz), &plan, key, target, radiance);
        }
    }
}
