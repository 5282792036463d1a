//! Camera samples: each one's ray through its point of the pixel, what it
//! hits (the packets of a tile), and which pixels take how many.
//!
//! Adaptive camera samples ([`RenderOptions::first_samples`]): every pixel
//! takes its first samples, and only a pixel whose first samples disagree
//! (another surface, a step in depth or normal, a hit beside a miss, the
//! two sides of a hard shadow, a step in direct light) or differ from a
//! neighbour's takes the rest, up to `spp`. In the sunlit rooms and the
//! nave it reaches uniform sampling's error with a sixth to under half of
//! the camera samples, but not yet in less time, so the render's default
//! stays uniform (docs/lab/cache.md, "Adaptive camera samples").
//!
//! The decision rests on a pixel's own first samples, traced the same way
//! wherever they are asked for (a tile, a crop, the cache's placing pass,
//! the guides), so each makes the same one, bit for bit.
//!
//! [`RenderOptions::first_samples`]: super::RenderOptions::first_samples

use glam::Vec3;

use super::frame::{Frame, PacketPoint};
use super::options::Component;
use super::shading::shading_point;
use crate::cache::same_surface;
use crate::rng::{Rng, film_point, mix};

/// What one first sample of a pixel saw: nothing, or a surface.
#[derive(Clone, Copy)]
struct Seen {
    position: Vec3,
    normal: Vec3,
    material: usize,
    /// Which point and directional lights reach it, a bit each: the two
    /// sides of a hard shadow's edge on one surface differ here.
    lit: u32,
    /// Its direct light (emission included).
    direct: Vec3,
}

impl Frame<'_> {
    /// What sample `pp` saw, its direct light not yet known.
    fn seen(&self, pp: &PacketPoint) -> Seen {
        let sp = &pp.point;
        // A shadow's edge is no edge in an image without direct light.
        let direct_shown = !self.opts.ao && self.opts.component != Component::Indirect;
        Seen {
            position: sp.position,
            normal: sp.normal,
            material: sp.material,
            lit: if direct_shown {
                self.lights.delta_lit(&self.tracer, sp.position, sp.normal)
            } else {
                0
            },
            direct: Vec3::ZERO,
        }
    }
}

impl Frame<'_> {
    /// One packet: camera sample `s` of each pixel of a tile (stratified over
    /// the pixel), the rays that hit a visible surface. `misses` (if given)
    /// gets the others: each pixel's index in the tile and the environment's
    /// radiance along its ray.
    pub(crate) fn packet(
        &self,
        pixels: &[(u32, u32)],
        s: u32,
        misses: Option<&mut Vec<(usize, Vec3)>>,
    ) -> Vec<PacketPoint> {
        self.packet_of(pixels, s, None, misses)
    }

    /// [`packet`](Self::packet) of the pixels `take` marks (all without
    /// it). An adaptive render's first samples are stratified over the
    /// pixel among themselves, and together with the rest.
    pub(crate) fn packet_of(
        &self,
        pixels: &[(u32, u32)],
        s: u32,
        take: Option<&[bool]>,
        mut misses: Option<&mut Vec<(usize, Vec3)>>,
    ) -> Vec<PacketPoint> {
        let cam = &self.camera;
        let rays = cam.rays();
        let (light_first, light_count) = self.light_block(s);
        // Each of the pixel's stratified samples filters its own share of
        // the pixel: together they cover it without blurring past it.
        let spread = cam.pixel_spread() / (self.opts.spp as f32).sqrt();
        let mut points = Vec::with_capacity(pixels.len());
        for (k, &(x, y)) in pixels.iter().enumerate() {
            if take.is_some_and(|t| !t[k]) {
                continue;
            }
            let pix = y * cam.width + x;
            // One scramble per pixel: its camera samples are points of one
            // sequence, so the first ones and all of them are stratified.
            let scramble =
                Rng::new(self.opts.seed ^ u64::from(pix).wrapping_mul(0xD1B5_4A32_D192_ED03)).scramble();
            let (fx, fy) = film_point(x, y, s, scramble);
            let dir = rays.direction(fx, fy);
            match self.tracer.closest(cam.origin, dir, f32::INFINITY) {
                Some(hit) => {
                    if let Some(point) =
                        shading_point(self.scene, &self.tracer, cam.origin, dir, &hit, spread)
                    {
                        // One scramble per pixel: its camera samples' light
                        // samples are consecutive blocks of one sequence.
                        let h = mix(self.opts.seed ^ u64::from(pix).wrapping_mul(0xA24B_AED4_963E_E407));
                        points.push(PacketPoint {
                            pixel: k,
                            film: (fx, fy),
                            point,
                            light_first,
                            light_count,
                            light_scramble: [h as u32, (h >> 32) as u32],
                        });
                    }
                }
                None => {
                    if let (Some(m), Some(env)) = (misses.as_deref_mut(), &self.environment) {
                        m.push((k, env.radiance(dir)));
                    }
                }
            }
        }
        points
    }

    /// Where camera sample `s`'s light samples begin in its pixel's
    /// sequence, and how many it takes. An adaptive render's first samples
    /// take all that `spp` samples would (shared out among them), so a
    /// pixel that takes no more keeps its direct light's samples: they are
    /// a net over the lights, whose error falls faster than their count.
    pub(crate) fn light_block(&self, s: u32) -> (u32, u32) {
        let (first, spp, per) = (self.first_samples(), self.opts.spp, self.light_samples());
        if first == spp {
            return (s.wrapping_mul(per), per);
        }
        let per_first = (per * spp).div_ceil(first);
        if s < first {
            (s * per_first, per_first)
        } else {
            (first * per_first + (s - first) * per, per)
        }
    }

    /// Camera samples every pixel takes before the decision (`spp` when
    /// the render is not adaptive).
    pub(crate) fn first_samples(&self) -> u32 {
        self.opts
            .first_samples
            .map_or(self.opts.spp, |b| b.min(self.opts.spp))
    }

    /// Traces the camera samples of `pixels` (a tile's), sample by sample
    /// (each one's packet in pixel order), the ones past the first only in
    /// the pixels whose first samples disagree, and hands each packet to
    /// `each` with its sample index and the rays that left the scene (each
    /// pixel's index and the environment's radiance); `each` returns the
    /// direct light of each point of the packet. Returns how many samples
    /// each pixel took.
    pub(crate) fn trace_samples<E>(
        &self,
        pixels: &[(u32, u32)],
        mut each: impl FnMut(u32, Vec<PacketPoint>, &[(usize, Vec3)]) -> Result<Vec<Vec3>, E>,
    ) -> Result<Vec<u32>, E> {
        let (first, spp) = (self.first_samples(), self.opts.spp);
        let mut seen: Vec<Vec<Option<Seen>>> = vec![Vec::new(); pixels.len()];
        let mut missed = Vec::new();
        for s in 0..first {
            missed.clear();
            let points = self.packet_of(pixels, s, None, Some(&mut missed));
            let mut hit = vec![None; pixels.len()];
            if first < spp {
                for pp in &points {
                    hit[pp.pixel] = Some(self.seen(pp));
                }
            }
            let order: Vec<usize> = points.iter().map(|pp| pp.pixel).collect();
            let direct = each(s, points, &missed)?;
            if first < spp {
                for (k, d) in order.into_iter().zip(direct) {
                    if let Some(h) = &mut hit[k] {
                        h.direct = d;
                    }
                }
                for (k, h) in hit.into_iter().enumerate() {
                    seen[k].push(h);
                }
            }
        }
        if first == spp {
            return Ok(vec![spp; pixels.len()]);
        }
        let slack = self.tracer.epsilon() * 4.0;
        let more = self.refine(pixels, &seen, slack);
        for s in first..spp {
            missed.clear();
            let points = self.packet_of(pixels, s, Some(&more), Some(&mut missed));
            each(s, points, &missed)?;
        }
        Ok(more.iter().map(|&m| if m { spp } else { first }).collect())
    }
}

impl Frame<'_> {
    /// Which of `pixels` take the samples past the first: those whose
    /// first samples (`seen`) disagree, and those that see another surface,
    /// or another set of point and directional lights, than a pixel beside
    /// them (above, below, left, right) does, which catches an edge whose
    /// first samples fell on one side of it. The neighbours outside
    /// `pixels` are traced here (their first samples' surfaces and lights
    /// only), so a tile decides as the whole frame does.
    fn refine(&self, pixels: &[(u32, u32)], seen: &[Vec<Option<Seen>>], slack: f32) -> Vec<bool> {
        let (w, h) = (self.camera.width, self.camera.height);
        let at = |x: u32, y: u32| pixels.iter().position(|&p| p == (x, y));
        let beside = |(x, y): (u32, u32)| {
            [
                (x.wrapping_sub(1), y),
                (x + 1, y),
                (x, y.wrapping_sub(1)),
                (x, y + 1),
            ]
            .into_iter()
            .filter(move |&(a, b)| a < w && b < h)
        };
        let mut outside: Vec<(u32, u32)> = Vec::new();
        for &p in pixels {
            for q in beside(p) {
                if at(q.0, q.1).is_none() && !outside.contains(&q) {
                    outside.push(q);
                }
            }
        }
        // The tile's pixels and then their neighbours outside it, each with
        // what its first samples saw.
        let mut all: Vec<Vec<Option<Seen>>> = seen.to_vec();
        all.resize(pixels.len() + outside.len(), Vec::new());
        for s in 0..self.first_samples() {
            let mut hit = vec![None; outside.len()];
            for pp in self.packet_of(&outside, s, None, None) {
                hit[pp.pixel] = Some(self.seen(&pp));
            }
            for (k, h) in hit.into_iter().enumerate() {
                all[pixels.len() + k].push(h);
            }
        }
        let index = |q: (u32, u32)| {
            at(q.0, q.1).or_else(|| outside.iter().position(|&o| o == q).map(|j| pixels.len() + j))
        };
        pixels
            .iter()
            .enumerate()
            .map(|(k, &p)| {
                disagree(&seen[k], slack)
                    || beside(p)
                        .filter_map(index)
                        .any(|j| seen[k].iter().any(|a| all[j].iter().any(|b| apart(a, b, slack))))
            })
            .collect()
    }
}

/// Whether two samples saw two surfaces: a hit and a miss, two materials,
/// two points that the cache's one-surface test (normals within 18°, no
/// step off the plane) keeps apart, or two sides of a hard shadow (another
/// point or directional light reaching each).
fn apart(a: &Option<Seen>, b: &Option<Seen>, slack: f32) -> bool {
    match (a, b) {
        (None, None) => false,
        (Some(a), Some(b)) => {
            a.material != b.material
                || a.lit != b.lit
                || !same_surface(a.position, a.normal, b.position, b.normal, slack)
        }
        _ => true,
    }
}

/// Whether a pixel's direct light differs between two of its samples by
/// more than this share of their mean: the two sides of a shadow's edge,
/// or a penumbra that its light samples see in part.
const DIRECT_STEP: f32 = 0.25;

/// Whether a pixel's first samples saw more than one surface or light: a
/// hit and a miss, two materials, two points that the cache's one-surface
/// test (normals within 18°, no step off the plane) keeps apart, or direct
/// light that differs by more than [`DIRECT_STEP`].
fn disagree(seen: &[Option<Seen>], slack: f32) -> bool {
    let Some((a, rest)) = seen.split_first() else {
        return false;
    };
    let step = |a: Vec3, b: Vec3| {
        let (x, y) = (a.element_sum(), b.element_sum());
        (x - y).abs() > DIRECT_STEP * 0.5 * (x + y)
    };
    rest.iter().any(|b| {
        apart(a, b, slack)
            || match (a, b) {
                (Some(a), Some(b)) => step(a.direct, b.direct),
                _ => false,
            }
    })
}
