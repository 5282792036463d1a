//! Sparse gathers ([`Gathers::Sparse`]): the indirect light is gathered on
//! a lattice of pixel centres and interpolated at the camera samples.
//!
//! Image-space adaptive sampling, as in multiresolution splatting (Nichols
//! and Wyman 2009) and geometry-aware upsampling: the lattice starts
//! `spacing` pixels apart and a cell is halved, level by level, where its
//! four corners do not lie on one surface (a plane up to rounding and
//! curvature, normals within 18°: the tests of [`Record::covers`]; down to
//! cells of two pixels) or where two corners' irradiance differs by more
//! than `threshold` of their mean (down to one pixel: a contact shadow, a
//! penumbra of indirect light). A camera sample takes the finest cell around it and blends
//! bilinearly the corners that lie on its own surface; a sample none of
//! whose corners does (a thin object between lattice points, a silhouette),
//! or on a glossy or bumped material, gathers itself. So light never leaks across an
//! edge, and smooth walls cost one gather per `spacing²` pixels.
//!
//! Each lattice point's gather depends on its place alone, and a cell's
//! refinement on its corners alone, so a crop computes the lattice points
//! its window needs and gets the full frame's pixels, bit for bit. Every
//! level's gathers run in 16-receiver packets, points in Morton order so a
//! packet's receivers are neighbours.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::frame::{Frame, Timers};
use super::options::Gathers;
use super::output::RenderError;
use super::shading::{ShadingPoint, shading_point};
use crate::cache::facing;
use crate::cache::record::same_surface;
use crate::cut::{Receiver, TraversalStats};
use crate::gather::{Gather, Gatherer};
use crate::simd::LANES;

/// Distance off a gathered point's plane, relative to the camera's
/// distance, that is rounding.
const SAME_PLANE: f32 = 1e-4;
/// The side, in pixels, of the smallest cell an edge halves. Stopping at
/// two-pixel cells (a sample there blends the corners on its own side)
/// saved a fifth to a half of the gathers at no measured cost against the
/// converged references of four scenes, but took Sponza's whole frame to
/// 1.46 % from its dense render, against the 1 % the sparse render keeps
/// (0.77 % at one pixel); stopping at two unless a corner is alone on its
/// surface still gave 1.00 % (docs/lab/sparse-edges.md).
const EDGE_CELL: u32 = 1;

/// A gathered lattice point: where, and the irradiance (or occlusion) its
/// microbuffer gave.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Record {
    pub position: Vec3,
    pub normal: Vec3,
    pub e: Vec3,
}

impl Record {
    /// Whether a point at `p` with normal `n`, seen from `eye`, lies on this
    /// record's surface.
    pub fn covers(&self, p: Vec3, n: Vec3, eye: Vec3) -> bool {
        same_surface(self.position, self.normal, p, n, SAME_PLANE * (p - eye).length())
    }
}

/// What a lattice point's camera ray found.
#[derive(Clone, Copy, Debug)]
enum Slot {
    /// Not needed: no cell around it was refined.
    Unasked,
    /// No receiver to gather at: the ray left the scene, or its samples
    /// gather themselves ([`Frame::gathers_per_sample`]).
    Hole,
    Gathered(Record),
}

/// The lattice of a frame's window: its points (stride one pixel, most
/// unasked), and what gathering them cost.
pub(crate) struct Lattice {
    spacing: u32,
    threshold: f32,
    /// Film size: samples' lattice coordinates are clamped to it.
    film: (u32, u32),
    /// First point and points across and down.
    x0: u32,
    y0: u32,
    width: u32,
    slots: Vec<Slot>,
    /// Traversal counters of the lattice's gathers.
    pub stats: TraversalStats,
    /// Lattice points gathered.
    pub count: usize,
}

impl Lattice {
    fn slot(&self, x: u32, y: u32) -> Slot {
        self.slots[((y - self.y0) * self.width + x - self.x0) as usize]
    }

    fn slot_mut(&mut self, x: u32, y: u32) -> &mut Slot {
        &mut self.slots[((y - self.y0) * self.width + x - self.x0) as usize]
    }

    /// Whether the cell at `(x, y)` of side `s` was halved: its centre,
    /// which belongs to it alone, was asked for.
    fn refined(&self, x: u32, y: u32, s: u32) -> bool {
        s >= 2 && !matches!(self.slot(x + s / 2, y + s / 2), Slot::Unasked)
    }

    /// Whether the cell at `(x, y)` of side `s` must be halved.
    fn needs_refining(&self, x: u32, y: u32, s: u32, eye: Vec3) -> bool {
        let corners = [(x, y), (x + s, y), (x, y + s), (x + s, y + s)].map(|(x, y)| match self.slot(x, y) {
            Slot::Gathered(r) => Some(r),
            _ => None,
        });
        let [Some(a), Some(b), Some(c), Some(d)] = corners else {
            return true;
        };
        let r = [a, b, c, d];
        let l = r.map(|r| r.e.x + r.e.y + r.e.z);
        // Corners on two surfaces: an edge, where the light changes fastest
        // (a sample would extrapolate from one side: 1.6 % off the dense
        // Cornell box, against 0.4 % refined), down to cells of
        // `EDGE_CELL` pixels. Two corners on one surface whose light differs
        // by more than `threshold` of their mean: a gradient.
        (0..4).any(|i| {
            (i + 1..4).any(|j| {
                let same = r[i].covers(r[j].position, r[j].normal, eye)
                    && r[j].covers(r[i].position, r[i].normal, eye);
                if same {
                    (l[i] - l[j]).abs() > self.threshold * (l[i] + l[j])
                } else {
                    s > EDGE_CELL
                }
            })
        })
    }

    /// The irradiance at a camera sample through film point `film` that hit
    /// `p` with normal `n`: the corners of the finest cell around it that lie
    /// on its surface, blended bilinearly; or why the sample gathers itself.
    pub fn irradiance(&self, film: (f32, f32), p: Vec3, n: Vec3, eye: Vec3) -> Served {
        // Lattice point (x, y) is the centre of pixel (x, y).
        let u = (film.0 - 0.5).clamp(0.0, (self.film.0 - 1) as f32);
        let v = (film.1 - 0.5).clamp(0.0, (self.film.1 - 1) as f32);
        let mut s = self.spacing;
        let (mut x, mut y) = ((u as u32) / s * s, (v as u32) / s * s);
        while self.refined(x, y, s) {
            s /= 2;
            x += if u >= (x + s) as f32 { s } else { 0 };
            y += if v >= (y + s) as f32 { s } else { 0 };
        }
        let (fu, fv) = ((u - x as f32) / s as f32, (v - y as f32) / s as f32);
        let corners = [
            (x, y, (1.0 - fu) * (1.0 - fv)),
            (x + s, y, fu * (1.0 - fv)),
            (x, y + s, (1.0 - fu) * fv),
            (x + s, y + s, fu * fv),
        ];
        let (mut sum, mut weight) = (Vec3::ZERO, 0.0);
        let (mut lo, mut hi, mut count) = (f32::INFINITY, 0.0f32, 0);
        for (x, y, w) in corners {
            if let Slot::Gathered(r) = self.slot(x, y)
                && r.covers(p, n, eye)
            {
                sum += r.e * w;
                weight += w;
                let l = r.e.x + r.e.y + r.e.z;
                lo = lo.min(l);
                hi = hi.max(l);
                count += 1;
            }
        }
        // A one-pixel cell where the light on this surface still changes by
        // more than twice the threshold, or with one corner on it: the light
        // changes within a pixel (near an edge that lights or shades it,
        // 1.35 % off the dense Sponza at one sample per pixel, 0.90 % with
        // these), so the sample gathers itself.
        if count == 0 {
            Served::NoCorner
        } else if s == 1 && (count < 2 || hi - lo > 2.0 * self.threshold * (hi + lo)) {
            Served::Changing
        } else if weight > 0.0 {
            Served::Light(sum / weight)
        } else {
            // Its corners on its surface all weigh nothing (a sample on the
            // cell's far edge from them, as at the film's border).
            Served::NoCorner
        }
    }
}

/// What the lattice gives a camera sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Served {
    /// Its corners' irradiance, blended.
    Light(Vec3),
    /// No corner lies on its surface (a thin object, a facet between
    /// lattice points): it gathers, and its pixel's other such samples on
    /// the same surface may share that gather (`share`).
    NoCorner,
    /// Its one-pixel cell's light changes too much, or only one corner lies
    /// on its surface: the light changes within the pixel, so it gathers
    /// at its own place, shared only within its quarter of the pixel
    /// (`share`).
    Changing,
}

/// Interleaves the bits of `x` and `y`: nearby points, nearby codes.
fn morton(x: u32, y: u32) -> u64 {
    let spread = |v: u32| {
        let mut v = u64::from(v);
        v = (v | v << 16) & 0x0000_FFFF_0000_FFFF;
        v = (v | v << 8) & 0x00FF_00FF_00FF_00FF;
        v = (v | v << 4) & 0x0F0F_0F0F_0F0F_0F0F;
        v = (v | v << 2) & 0x3333_3333_3333_3333;
        (v | v << 1) & 0x5555_5555_5555_5555
    };
    spread(x) | spread(y) << 1
}

impl Frame<'_> {
    /// Whether samples on `material` gather themselves: a glossy lobe needs
    /// its own microbuffer, and a bump map turns the normal, so the
    /// irradiance, from one pixel to the next (the bumped back wall of
    /// `cornell-box-glossy` refined every cell to one pixel, then gathered
    /// per sample anyway: more gathers than the dense render), as does a
    /// normal map.
    pub(crate) fn gathers_per_sample(&self, material: usize) -> bool {
        let m = &self.scene.materials[material];
        m.glossy.is_some() || m.bump.is_some() || m.normal_map.is_some()
    }

    /// Gathers the lattice of the window's camera samples (`None` unless the
    /// render gathers sparsely): the coarse points, then level by level the
    /// points of the cells that need halving.
    pub(crate) fn lattice(&self, gather: &Gather, timers: &Timers) -> Result<Option<Lattice>, RenderError> {
        let Gathers::Sparse { spacing, threshold } = self.opts.gathers else {
            return Ok(None);
        };
        if !self.needs_points {
            return Ok(None);
        }
        let cam = &self.camera;
        let window = self.window();
        let s = spacing;
        // The cells the window's samples fall in (lattice coordinates are
        // film coordinates less ½, clamped to the film).
        let first = |a: u32| (a as f32 - 0.5).max(0.0) as u32 / s;
        let last = |b: u32, size: u32| (b as f32 - 0.5).min((size - 1) as f32) as u32 / s;
        let (cx0, cx1) = (first(window.x0), last(window.x1, cam.width));
        let (cy0, cy1) = (first(window.y0), last(window.y1, cam.height));
        let (x0, y0) = (cx0 * s, cy0 * s);
        let (width, height) = ((cx1 + 1) * s - x0 + 1, (cy1 + 1) * s - y0 + 1);
        let mut lattice = Lattice {
            spacing,
            threshold,
            film: (cam.width, cam.height),
            x0,
            y0,
            width,
            slots: vec![Slot::Unasked; (width * height) as usize],
            stats: TraversalStats::default(),
            count: 0,
        };
        let mut points: Vec<(u32, u32)> = (cy0..=cy1 + 1)
            .flat_map(|cy| (cx0..=cx1 + 1).map(move |cx| (cx * s, cy * s)))
            .collect();
        // Asked: a hole until its gather says otherwise.
        for &(x, y) in &points {
            *lattice.slot_mut(x, y) = Slot::Hole;
        }
        let mut cells: Vec<(u32, u32)> = (cy0..=cy1)
            .flat_map(|cy| (cx0..=cx1).map(move |cx| (cx * s, cy * s)))
            .collect();
        let mut s = s;
        loop {
            self.gather_lattice(&mut lattice, &points, gather, timers)?;
            if s < 2 {
                break;
            }
            let eye = cam.origin;
            let halved: Vec<(u32, u32)> = cells
                .par_iter()
                .copied()
                .filter(|&(x, y)| lattice.needs_refining(x, y, s, eye))
                .collect();
            let h = s / 2;
            points.clear();
            cells.clear();
            for &(x, y) in &halved {
                for (dx, dy) in [(h, 0), (0, h), (h, h), (s, h), (h, s)] {
                    let slot = lattice.slot_mut(x + dx, y + dy);
                    if matches!(slot, Slot::Unasked) {
                        *slot = Slot::Hole;
                        points.push((x + dx, y + dy));
                    }
                }
                cells.extend([(x, y), (x + h, y), (x, y + h), (x + h, y + h)]);
            }
            s = h;
        }
        Ok(Some(lattice))
    }

    /// Casts the camera rays of `points` through their pixel centres, then
    /// gathers at those that hit a receiver, 16 to a packet over the
    /// threads, and stores what each found in `lattice`. A packet holds
    /// receivers facing one way, neighbours in Morton order: along an edge
    /// the points of its two faces would otherwise share packets and their
    /// cuts little (lane utilization 61 % → 64.5 % on the Cornell box).
    fn gather_lattice(
        &self,
        lattice: &mut Lattice,
        points: &[(u32, u32)],
        gather: &Gather,
        timers: &Timers,
    ) -> Result<(), RenderError> {
        let cam = &self.camera;
        let spread = cam.pixel_spread();
        let mut hits: Vec<((u32, u32), ShadingPoint)> = points
            .par_iter()
            .filter_map(|&(x, y)| {
                let dir = cam.ray_direction(x as f32 + 0.5, y as f32 + 0.5);
                let sp = self
                    .tracer
                    .closest(cam.origin, dir, f32::INFINITY)
                    .and_then(|hit| shading_point(self.scene, &self.tracer, cam.origin, dir, &hit, spread))?;
                (!self.gathers_per_sample(sp.material)).then_some(((x, y), sp))
            })
            .collect();
        hits.sort_unstable_by_key(|((x, y), sp)| (facing(sp.normal), morton(*x, *y)));
        let packets = hits
            .par_chunks(LANES)
            .map_init(
                || gather.gatherer(),
                |gatherer, chunk| self.gather_points(chunk, gatherer, timers),
            )
            .collect::<Result<Vec<_>, _>>()?;
        for (chunk, (es, stats)) in hits.chunks(LANES).zip(packets) {
            lattice.stats.merge(&stats);
            lattice.count += chunk.len();
            for (((x, y), sp), e) in chunk.iter().zip(es) {
                *lattice.slot_mut(*x, *y) = Slot::Gathered(Record {
                    position: sp.position,
                    normal: sp.normal,
                    e,
                });
            }
        }
        Ok(())
    }

    /// One packet of lattice receivers: their irradiance (or occlusion).
    fn gather_points(
        &self,
        hits: &[((u32, u32), ShadingPoint)],
        gatherer: &mut Gatherer,
        timers: &Timers,
    ) -> Result<(Vec<Vec3>, TraversalStats), RenderError> {
        let receivers = hits
            .iter()
            .map(|(_, sp)| Receiver::new(sp.position, sp.normal))
            .collect::<Result<Vec<_>, _>>()?;
        let t1 = Instant::now();
        let stats = gatherer.cut(&receivers)?;
        let t2 = Instant::now();
        timers.trav.add((t2 - t1).as_secs_f64());
        let e = gatherer.shade(self.convolution());
        timers.shading.add(t2.elapsed().as_secs_f64());
        for (((x, y), _), e) in hits.iter().zip(&e) {
            if !e.is_finite() {
                return Err(RenderError::NonFinite {
                    stage: "gather at the lattice",
                    place: format!("lattice point at the centre of pixel ({x}, {y})"),
                    value: e.to_array(),
                });
            }
        }
        Ok((e, stats))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-cell lattice of side `s` whose corners are `records` (in the
    /// order (0, 0), (s, 0), (0, s), (s, s)), on a film of `s + 1` pixels.
    fn cell(s: u32, records: [Option<Record>; 4]) -> Lattice {
        let width = s + 1;
        let mut slots = vec![Slot::Unasked; (width * width) as usize];
        for ((x, y), r) in [(0, 0), (s, 0), (0, s), (s, s)].into_iter().zip(records) {
            slots[(y * width + x) as usize] = r.map_or(Slot::Hole, Slot::Gathered);
        }
        Lattice {
            spacing: s,
            threshold: 0.1,
            film: (width, width),
            x0: 0,
            y0: 0,
            width,
            slots,
            stats: TraversalStats::default(),
            count: 0,
        }
    }

    fn record(position: Vec3, normal: Vec3, e: f32) -> Option<Record> {
        Some(Record {
            position,
            normal,
            e: Vec3::splat(e),
        })
    }

    #[test]
    fn a_sample_takes_only_the_corners_on_its_own_surface() {
        // A floor (y = 0, up) on the cell's left column, a wall (x = 1,
        // facing −x) on its right, ten times brighter: an edge.
        let eye = Vec3::new(0.5, 1.0, 5.0);
        let (up, left) = (Vec3::Y, Vec3::NEG_X);
        let lattice = cell(
            4,
            [
                record(Vec3::new(0.0, 0.0, 0.0), up, 1.0),
                record(Vec3::new(1.0, 0.5, 0.0), left, 10.0),
                record(Vec3::new(0.0, 0.0, 1.0), up, 1.0),
                record(Vec3::new(1.0, 0.5, 1.0), left, 10.0),
            ],
        );
        // A floor sample near the wall's corners gets the floor's light
        // alone; a wall sample, the wall's.
        let floor = lattice.irradiance((3.5, 2.5), Vec3::new(0.9, 0.0, 0.5), up, eye);
        assert_eq!(floor, Served::Light(Vec3::splat(1.0)));
        let wall = lattice.irradiance((1.5, 2.5), Vec3::new(1.0, 0.2, 0.5), left, eye);
        assert_eq!(wall, Served::Light(Vec3::splat(10.0)));
        // A sample on neither (a thin object between lattice points)
        // gathers itself.
        let other = lattice.irradiance((2.5, 2.5), Vec3::new(0.5, 0.3, 0.5), Vec3::Z, eye);
        assert_eq!(other, Served::NoCorner);
        // A wall sample on the cell's left edge (the film's border): its
        // surface's corners weigh nothing there, so it gathers too (it
        // read 0/0 = NaN while any corner on its surface counted).
        let edge = lattice.irradiance((0.5, 2.5), Vec3::new(1.0, 0.2, 0.5), left, eye);
        assert_eq!(edge, Served::NoCorner);
    }

    #[test]
    fn facets_of_a_curved_surface_are_one_surface_and_a_step_is_two() {
        // Facets meeting along z: y = 0 and one rising from it at `a`.
        let eye = Vec3::new(0.0, 5.0, 5.0);
        let across = |a: f32| {
            let r = record(Vec3::new(-0.5, 0.0, 0.0), Vec3::Y, 1.0).unwrap();
            let (s, c) = a.to_radians().sin_cos();
            let (p, n) = (Vec3::new(c, s, 0.0) * 0.5, Vec3::new(-s, c, 0.0));
            r.covers(p, n, eye)
                && Record {
                    position: p,
                    normal: n,
                    ..r
                }
                .covers(r.position, r.normal, eye)
        };
        // A 12-sided pier's facets are 30° apart; its smooth normals, 15°
        // over a few pixels.
        assert!(across(0.0) && across(5.0) && across(15.0));
        assert!(!across(20.0) && !across(30.0) && !across(90.0));
        // Parallel planes 0.1 apart, 1 along: a step, two surfaces (a
        // bound by the normals' angle alone would take them as one).
        let r = record(Vec3::ZERO, Vec3::Y, 1.0).unwrap();
        assert!(!r.covers(Vec3::new(1.0, 0.1, 0.0), Vec3::Y, eye));
        assert!(r.covers(Vec3::new(1.0, 0.01, 0.0), Vec3::Y, eye));
    }

    #[test]
    fn a_sample_on_one_surface_blends_its_corners_bilinearly() {
        let eye = Vec3::new(0.5, 1.0, 5.0);
        let lattice = cell(
            2,
            [
                record(Vec3::new(0.0, 0.0, 0.0), Vec3::Y, 1.0),
                record(Vec3::new(1.0, 0.0, 0.0), Vec3::Y, 2.0),
                record(Vec3::new(0.0, 0.0, 1.0), Vec3::Y, 3.0),
                record(Vec3::new(1.0, 0.0, 1.0), Vec3::Y, 4.0),
            ],
        );
        // Film (1.5, 1.0) is lattice (1, 0.5): half-way across, a quarter
        // of the way down.
        let Served::Light(e) = lattice.irradiance((1.5, 1.0), Vec3::new(0.5, 0.0, 0.25), Vec3::Y, eye) else {
            panic!("not served");
        };
        assert!((e.x - 2.0).abs() < 1e-6, "{e}");
        // Its light changes by more than 10 % between corners: it is halved.
        assert!(lattice.needs_refining(0, 0, 2, eye));
        // Within 10 %, on one plane: it is not. Across an edge a cell is
        // halved down to `EDGE_CELL` pixels, and no further.
        let flat = |s: u32, e: [f32; 3], n: Vec3| {
            cell(
                s,
                [
                    record(Vec3::new(0.0, 0.0, 0.0), Vec3::Y, 1.0),
                    record(Vec3::new(1.0, 0.0, 0.0), Vec3::Y, e[0]),
                    record(Vec3::new(0.0, 0.0, 1.0), Vec3::Y, e[1]),
                    record(Vec3::new(1.0, 0.0, 1.0), n, e[2]),
                ],
            )
        };
        assert!(!flat(2, [1.1, 1.0, 1.15], Vec3::Y).needs_refining(0, 0, 2, eye));
        assert!(flat(2, [1.1, 1.0, 1.3], Vec3::Y).needs_refining(0, 0, 2, eye));
        assert!(flat(4, [1.0, 1.0, 1.0], Vec3::X).needs_refining(0, 0, 4, eye));
        assert!(flat(2, [1.0, 1.0, 1.0], Vec3::X).needs_refining(0, 0, 2, eye));
        assert!(flat(2, [1.0, 1.0, 3.0], Vec3::X).needs_refining(0, 0, 2, eye));
    }
}
