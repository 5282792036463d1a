//! Direct light: area emitters (emissive triangles, picked by their light at
//! the receiver and sampled in solid angle when close, or in closed form
//! times the samples' shadow ratio), point and directional lights, each
//! checked with a shadow ray.

mod analytic;
mod groups;

use glam::Vec3;

use groups::{Group, groups, pick};

use super::spherical;
use super::trace::Tracer;
use crate::rng::sobol2;
use crate::scene::{Light, Scene};

/// Up to this many groups of emitters ([`Group`]), each receiver picks the
/// group of a light sample by its estimated contribution there; beyond, by
/// area (the estimates would cost more than the shadow rays they save).
const CHOSEN_HERE: usize = 64;
/// A triangle further than this many of its radii is sampled by area.
const NEAR: f32 = 3.0;
/// Up to this many emissive triangles, [`LightSamples::ratio`] works their
/// unshadowed light out in closed form at each receiver (Lambert's formula
/// per triangle); beyond, it would cost more than the shadow rays.
pub const ANALYTIC_TRIANGLES: usize = 64;

/// The BRDF a receiver reflects direct light with: its diffuse part
/// (albedo / π), and its glossy lobe as a function of the incident
/// direction, if it has one.
pub struct Brdf<F> {
    /// Albedo / π.
    pub diffuse: Vec3,
    /// The lobe's value for an incident direction.
    pub lobe: Option<F>,
}

impl Brdf<fn(Vec3) -> Vec3> {
    /// A Lambertian BRDF, `albedo / π`.
    pub fn lambert(albedo: Vec3) -> Self {
        Brdf {
            diffuse: albedo * std::f32::consts::FRAC_1_PI,
            lobe: None,
        }
    }
}

/// The area-light samples a receiver takes, and how it combines them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightSamples {
    /// How many.
    pub count: u32,
    /// Index of the first in the scrambled (0,2)-sequence.
    pub first: u32,
    /// The sequence's scramble.
    pub scramble: [u32; 2],
    /// The diffuse light in closed form times the samples' shadow ratio
    /// (where there are at most [`ANALYTIC_TRIANGLES`] emissive
    /// triangles); `false`: the plain estimate.
    pub ratio: bool,
}

/// The scene's emitters, ready to sample.
pub struct Lights {
    /// Emissive triangles: vertices, unit front normal, radiance.
    triangles: Vec<([Vec3; 3], Vec3, Vec3)>,
    /// Cumulative areas of `triangles`.
    cdf: Vec<f32>,
    /// Twice the area of each of `triangles`.
    twice_areas: Vec<f32>,
    /// A sphere about each of `triangles`: its centroid and radius².
    spheres: Vec<(Vec3, f32)>,
    /// `triangles` in groups, each with the cumulative power of its
    /// triangles (from 0 at its first).
    groups: Vec<Group>,
    power_cdf: Vec<f32>,
    area: f32,
    others: Vec<Light>,
}

/// Twice the area of a triangle and its unit normal, `None` when its area
/// is not a normal `f32` (degenerate, underflowing or overflowing): such a
/// triangle is neither lit by nor lights anything, left out of the surfels
/// and of the emitters alike. A subnormal area would round to zero when
/// halved, and a group of such emitters would divide by it. The normal is
/// normalized in `f64`: the cross product of a sliver triangle can be
/// subnormal, and its `f32` length too coarse for a unit normal.
pub(crate) fn triangle(v: [Vec3; 3]) -> Option<(f32, Vec3)> {
    let c = (v[1] - v[0]).cross(v[2] - v[0]).as_dvec3();
    let len = c.length();
    (0.5 * len as f32)
        .is_normal()
        .then(|| (len as f32, (c / len).as_vec3()))
}

impl Lights {
    /// Collects the emitters of `scene`.
    pub fn new(scene: &Scene) -> Lights {
        let mut triangles = Vec::new();
        let mut cdf = Vec::new();
        let mut twice_areas = Vec::new();
        let mut area = 0.0f64;
        for mesh in &scene.meshes {
            let Some(radiance) = mesh.emission else { continue };
            if radiance.max_element() <= 0.0 {
                continue;
            }
            for t in &mesh.triangles {
                let v = t.map(|i| mesh.positions[i as usize]);
                if let Some((twice_area, normal)) = triangle(v) {
                    area += 0.5 * twice_area as f64;
                    cdf.push(area as f32);
                    twice_areas.push(twice_area);
                    triangles.push((v, normal, radiance));
                }
            }
        }
        let (groups, power_cdf) = groups(scene, &triangles, &twice_areas);
        let spheres = triangles
            .iter()
            .map(|(v, _, _)| {
                let c = (v[0] + v[1] + v[2]) / 3.0;
                (c, v.iter().map(|&q| (q - c).length_squared()).fold(0.0, f32::max))
            })
            .collect();
        Lights {
            triangles,
            cdf,
            twice_areas,
            spheres,
            groups,
            power_cdf,
            area: area as f32,
            others: scene.lights.clone(),
        }
    }

    /// Total area of the emissive triangles.
    pub fn emitter_area(&self) -> f32 {
        self.area
    }

    /// Solid-angle density with which [`sample_area`](Self::sample_area)
    /// picks the direction towards a point at distance² `dist2` on an emitter
    /// whose normal makes cosine `cos_l` with the direction back to the shading point.
    pub fn area_pdf(&self, dist2: f32, cos_l: f32) -> f32 {
        if self.area <= 0.0 || cos_l <= 0.0 {
            0.0
        } else {
            dist2 / (cos_l * self.area)
        }
    }

    /// A point on the emitters, uniform by area: `(point, unit normal, radiance)`.
    pub fn sample_area(&self, u0: f32, u1: f32, u2: f32) -> Option<(Vec3, Vec3, Vec3)> {
        if self.triangles.is_empty() {
            return None;
        }
        let x = u0 * self.area;
        let k = self
            .cdf
            .partition_point(|&c| c <= x)
            .min(self.triangles.len() - 1);
        let (v, n, radiance) = &self.triangles[k];
        let (mut a, mut b) = (u1, u2);
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        Some((v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b, *n, *radiance))
    }

    /// Point and directional lights.
    pub fn delta_lights(&self) -> &[Light] {
        &self.others
    }

    /// Why [`LightSamples::ratio`] falls back to the plain estimate here,
    /// if it does: no emissive triangle, or too many to work out in closed
    /// form at every receiver.
    pub fn why_sampled(&self) -> Option<String> {
        match self.triangles.len() {
            0 => Some("no emissive triangle".to_string()),
            n if n > ANALYTIC_TRIANGLES || self.groups.len() > CHOSEN_HERE => {
                Some(format!("{n} emissive triangles, over {ANALYTIC_TRIANGLES}"))
            }
            _ => None,
        }
    }

    /// Which of the first 32 point and directional lights light `p`
    /// (normal `n`), a bit each: [`arrival`](Self::arrival), as
    /// [`reflected`](Self::reflected) casts it, for the lights that shed
    /// any light. Two points whose bits differ lie on two sides of a hard
    /// shadow's edge.
    pub(crate) fn delta_lit(&self, tracer: &Tracer, p: Vec3, n: Vec3) -> u32 {
        let origin = p + n * tracer.epsilon();
        let mut lit = 0u32;
        for (i, light) in self.others.iter().take(32).enumerate() {
            let reaches =
                Self::arrival(light, tracer, origin, n).is_some_and(|(_, c, _)| c.max_element() > 0.0);
            lit |= u32::from(reaches) << i;
        }
        lit
    }

    /// What a point or directional light sends to `origin` (normal `n`)
    /// past its one shadow ray: the direction to it, its intensity or
    /// irradiance, and the factor (cos θ / d², or cos θ) that makes it
    /// irradiance; `None` where it faces away or is shadowed.
    #[inline(always)]
    fn arrival(light: &Light, tracer: &Tracer, origin: Vec3, n: Vec3) -> Option<(Vec3, Vec3, f32)> {
        match *light {
            Light::Point { position, intensity } => {
                let d = position - origin;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos_r = n.dot(wi);
                (cos_r > 0.0 && !tracer.occluded(origin, wi, dist)).then_some((wi, intensity, cos_r / dist2))
            }
            Light::Directional {
                direction,
                irradiance,
            } => {
                let wi = -direction;
                let cos_r = n.dot(wi);
                (cos_r > 0.0 && !tracer.occluded(origin, wi, f32::INFINITY))
                    .then_some((wi, irradiance, cos_r))
            }
        }
    }

    /// Whether the scene has any light at all.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty() && self.others.is_empty()
    }

    /// Reflected direct radiance towards the viewer at `p` (normal `n`,
    /// facing the viewer's side) from every light, for the BRDF `brdf`:
    /// `samples.count` area-light samples `Σ f(ωi)·Li·cosθ / pdf`, plus every
    /// point and directional light by one shadow ray. The area samples are
    /// points `first..first + count` of the scrambled (0,2)-sequence
    /// `sobol2`: stratified over the lights' total area, and with the
    /// samples of the other camera samples of a pixel (the next indices).
    ///
    /// With [`LightSamples::ratio`], where the scene has at most
    /// [`ANALYTIC_TRIANGLES`] emissive triangles, the diffuse part is their
    /// closed-form unshadowed irradiance (Lambert's polygon formula) times
    /// the share of the samples' unshadowed light that reaches `p` (Heitz
    /// et al. 2018, the ratio estimator): a point that every sample sees
    /// lit, or none does, gets it without noise. The lobe keeps the plain
    /// estimate.
    pub fn reflected(
        &self,
        tracer: &Tracer,
        p: Vec3,
        n: Vec3,
        samples: LightSamples,
        brdf: Brdf<impl Fn(Vec3) -> Vec3>,
    ) -> Vec3 {
        let LightSamples {
            count: samples,
            first,
            scramble,
            ratio,
        } = samples;
        let f = |wi: Vec3| match &brdf.lobe {
            Some(l) => brdf.diffuse + l(wi),
            None => brdf.diffuse,
        };
        let eps = tracer.epsilon();
        let origin = p + n * eps;
        let mut sum = Vec3::ZERO;
        if !self.triangles.is_empty() && samples > 0 {
            // Which emitters a sample goes to: with few groups, by each
            // one's estimated contribution here (a distant or unseen window
            // draws few samples); with many, by area.
            let mut local_cdf = [0.0f32; CHOSEN_HERE];
            let chosen_here = self.groups.len() <= CHOSEN_HERE;
            let (cdf, total) = if chosen_here {
                let mut total = 0.0f32;
                for (c, g) in local_cdf.iter_mut().zip(&self.groups) {
                    total += g.estimate(origin, n);
                    *c = total;
                }
                (&local_cdf[..self.groups.len()], total)
            } else {
                (&self.cdf[..], self.area)
            };
            // With `ratio`, the groups whose light is worked out in closed
            // form here (a bit each).
            let closed = if ratio && chosen_here {
                self.closed_groups(cdf)
            } else {
                0
            };
            let mut area_sum = Vec3::ZERO;
            // The samples' unshadowed light from the `closed` groups, and
            // what of it reaches `origin` (summed over the channels).
            let (mut unshadowed, mut reached) = (0.0f32, 0.0f32);
            for s in 0..samples {
                if total <= 0.0 {
                    break;
                }
                // The first coordinate picks a group, within its share a
                // triangle, and within that the first coordinate on it.
                let (u, w) = sobol2(first.wrapping_add(s), scramble);
                let (k, picked, u, in_closed) = if chosen_here {
                    let (g, u) = pick(cdf, u * total);
                    let group = &self.groups[g];
                    let share = &self.power_cdf[group.first..group.end];
                    let (t, u) = pick(share, u * group.power);
                    let (lo, hi) = (if t == 0 { 0.0 } else { share[t - 1] }, share[t]);
                    let estimate = if g == 0 { cdf[0] } else { cdf[g] - cdf[g - 1] };
                    let picked = estimate / total * ((hi - lo) / group.power);
                    (group.first + t, picked, u, closed >> g & 1 == 1)
                } else {
                    let (k, u) = pick(cdf, u * total);
                    (k, 0.5 * self.twice_areas[k] / total, u, false)
                };
                let (v, ln, radiance) = &self.triangles[k];
                // Seen from its back, an emitter gives nothing.
                if picked <= 0.0 || ln.dot(origin - v[0]) <= 0.0 {
                    continue;
                }
                // A triangle close by is sampled uniformly in the solid
                // angle it subtends (weight Ω): by area, its points close to
                // the receiver weigh 1/d² and spike. Further away 1/d²
                // hardly changes across it, and area sampling costs less.
                let (centre, radius2) = self.spheres[k];
                let near = (centre - origin).length_squared() < NEAR * NEAR * radius2;
                let (wi, dist, weight) = match near.then(|| spherical::sample(v, origin, u, w)).flatten() {
                    Some((wi, omega)) => (wi, ln.dot(v[0] - origin) / ln.dot(wi), omega),
                    None => {
                        let su = u.sqrt();
                        let (a, b) = (su * (1.0 - w), su * w);
                        let d = v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b - origin;
                        let dist2 = d.length_squared();
                        if dist2 <= 0.0 {
                            continue;
                        }
                        let dist = dist2.sqrt();
                        let wi = d / dist;
                        (wi, dist, 0.5 * self.twice_areas[k] * -ln.dot(wi) / dist2)
                    }
                };
                let cos_r = n.dot(wi);
                if cos_r <= 0.0 || weight <= 0.0 || dist <= 0.0 {
                    continue;
                }
                let w = cos_r * weight / picked;
                let lit = !tracer.occluded(origin, wi, dist * (1.0 - 1e-4) - eps);
                if in_closed {
                    let u = (radiance.x + radiance.y + radiance.z) * w;
                    unshadowed += u;
                    if lit {
                        reached += u;
                        if let Some(lobe) = &brdf.lobe {
                            area_sum += lobe(wi) * *radiance * w;
                        }
                    }
                } else if lit {
                    area_sum += f(wi) * *radiance * w;
                }
            }
            sum += area_sum / samples as f32;
            if closed != 0 {
                // No sample met the unshadowed light (each fell below the
                // horizon, or on a back): one point on what lies above it
                // says how much of it is shadowed (none when nothing does).
                let share = if unshadowed > 0.0 {
                    reached / unshadowed
                } else {
                    let (u, w) = sobol2(first, scramble);
                    self.lit_above_horizon(tracer, origin, n, closed, u, w)
                };
                // A receiver in full shadow skips the closed form.
                if share > 0.0 {
                    sum += brdf.diffuse * self.unshadowed(origin, n, closed) * share;
                }
            }
        }
        for light in &self.others {
            if let Some((wi, c, k)) = Self::arrival(light, tracer, origin, n) {
                sum += f(wi) * c * k;
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests;
