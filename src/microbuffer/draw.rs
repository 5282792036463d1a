//! The scalar draw: one located splat into one receiver's pixels, pixel by
//! pixel, in the class the plan gives it (small, cone or disk). The 16-lane
//! pipeline draws the same pixels with the same bits (`tiles`, `shade`).

use glam::Vec3;

use super::buffer::{COVER_CAP, COVER_ONE, MicroBuffer, NO_KEY, key};
use super::locate::{Located, NodeSplat};
use super::plan::{ConePlan, DiskPlan, SmallPlan, pixel_of, plan_cone, plan_disk, plan_small};
use crate::simd::Real;
use crate::tree::{NodeId, SplatRecord};

/// [`MicroBuffer::write`] on the buffer's arrays (borrowed apart from its
/// pixel table).
#[inline(always)]
pub(super) fn write_pixel(
    own: &mut [u64],
    any: &mut [u64],
    cover: &mut [u32],
    p: usize,
    key: u64,
    coverage: f32,
    owns: bool,
) {
    debug_assert!(coverage >= 0.0, "coverage {coverage}");
    let c = (coverage.min_of(1.0) * COVER_ONE) as u32;
    cover[p] = (cover[p] + c).min(COVER_CAP);
    any[p] = any[p].min(key);
    if owns {
        own[p] = own[p].min(key);
    }
}

impl MicroBuffer {
    /// Adds a splat of `key` covering the fraction `coverage` ∈ [0, 1] of pixel `p`.
    #[inline(always)]
    fn write(&mut self, p: usize, key: u64, coverage: f32, owns: bool) {
        write_pixel(
            &mut self.own,
            &mut self.any,
            &mut self.cover,
            p,
            key,
            coverage,
            owns,
        );
    }

    /// [`write`](Self::write) where `m`, else nothing, without a branch:
    /// whether a corner gets weight is data the branch predictor cannot learn.
    #[inline(always)]
    fn write_if(&mut self, m: bool, p: usize, key: u64, coverage: f32, owns: bool) {
        let c = (f32::select(m, coverage, 0.0).min_of(1.0) * COVER_ONE) as u32;
        self.cover[p] = (self.cover[p] + c).min(COVER_CAP);
        let key = if m { key } else { NO_KEY };
        self.any[p] = self.any[p].min(key);
        let own_key = if owns { key } else { NO_KEY };
        self.own[p] = self.own[p].min(own_key);
    }

    /// Draws a small splat; it owns the pixel its centre falls in.
    #[inline(always)]
    pub(crate) fn draw_small(&mut self, plan: &SmallPlan<f32>, key: u64, pixel: f32) {
        for k in 0..4 {
            let p = plan.p[k];
            self.write_if(plan.w[k] > 0.0, p as usize, key, plan.cover[k], p == pixel);
        }
    }

    /// Draws a cone around local direction `w`; it owns the pixels it covers
    /// by at least one half.
    #[inline(always)]
    pub(crate) fn draw_cone(&mut self, w: Vec3, plan: &ConePlan<f32>, key: u64) {
        let (c0, c1, r0, r1) = plan.bx.bounds();
        let n = self.table.n;
        for r in r0..=r1 {
            for c in c0..=c1 {
                let p = r * n + c;
                let t = &self.table;
                let (m, cover) = plan.cover([w.x, w.y, w.z], t.dir_x[p], t.dir_y[p], t.dir_z[p]);
                if m {
                    self.write(p, key, cover, 0.5 <= cover);
                }
            }
        }
    }

    /// Draws a leaf's disk (depth: the hit distance); false if it covers no
    /// pixel centre.
    #[inline(always)]
    pub(crate) fn draw_disk(&mut self, plan: &DiskPlan<f32>, node: NodeId) -> bool {
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
                    self.write(p, key(depth, node), cover, 0.5 <= cover);
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
        if visible && l.omega < pixel_omega {
            let plan = plan_small(t, l.x, l.y, l.omega);
            self.draw_small(&plan, key, pixel);
        } else if rec.leaf != 0 {
            let plan = plan_disk(t, &self.frame_lanes(), &NodeSplat::of(rec), l.x, l.y, pixel, l.d);
            // `Ω` is a far-field estimate that blows up for a disk nearly in
            // the receiver's plane: a leaf missing every centre gets a pixel at most.
            if !self.draw_disk(&plan, node) && visible {
                let t = &*self.table;
                let plan = plan_small(t, l.x, l.y, pixel_omega);
                self.draw_small(&plan, key, pixel);
            }
        } else {
            let plan = plan_cone(t, l.x, l.y, pixel, l.omega, visible);
            self.draw_cone(Vec3::new(l.wx, l.wy, l.wz), &plan, key);
        }
    }
}
