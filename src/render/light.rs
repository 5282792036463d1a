//! Direct light: area emitters (emissive triangles, picked by their light at
//! the receiver and sampled in solid angle when close), point
//! and directional lights, each checked with a shadow ray.

use glam::Vec3;

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
/// A group spans at most this share of the scene's bounding-box diagonal.
const GROUP_EXTENT: f32 = 0.15;

/// Consecutive coplanar emissive triangles of one mesh, close together (a
/// window): a receiver weighs its light as one, then picks a triangle
/// within it by power.
struct Group {
    /// Its triangles, `first..end` of [`Lights::triangles`].
    first: usize,
    end: usize,
    /// Area-weighted centroid, the plane's unit front normal, radius of a
    /// sphere about the centroid holding it.
    centroid: Vec3,
    normal: Vec3,
    radius: f32,
    area: f32,
    /// Σ area × radiance (summed over channels).
    power: f32,
}

impl Group {
    /// The group's direct light at `origin` (normal `n`) as if it were a
    /// point at its centroid, its solid angle capped at a hemisphere's:
    /// zero only where it gives nothing (seen from its back, or wholly
    /// below the horizon), so that picking groups in proportion stays
    /// unbiased.
    #[inline(always)]
    fn estimate(&self, origin: Vec3, n: Vec3) -> f32 {
        let d = self.centroid - origin;
        let cos_l = -self.normal.dot(d);
        if cos_l <= 0.0 || n.dot(d) <= -self.radius {
            return 0.0;
        }
        let dist2 = d.length_squared();
        let omega = (self.area * cos_l / (dist2 * dist2.sqrt())).min(std::f32::consts::TAU);
        // A floor, so a group seen edge-on from its centroid keeps a chance.
        self.power / self.area * omega.max(1e-6)
    }
}

/// The entry of cumulative sums `cdf` that `x` falls in, and where within
/// its share, in [0, 1].
#[inline(always)]
fn pick(cdf: &[f32], x: f32) -> (usize, f32) {
    let k = cdf.partition_point(|&c| c <= x).min(cdf.len() - 1);
    let lo = if k == 0 { 0.0 } else { cdf[k - 1] };
    let share = cdf[k] - lo;
    (
        k,
        if share > 0.0 {
            ((x - lo) / share).clamp(0.0, 1.0)
        } else {
            0.0
        },
    )
}

/// Splits `triangles` (in mesh order) into [`Group`]s: a run of coplanar
/// triangles of one radiance within [`GROUP_EXTENT`] of the scene's
/// diagonal from its first vertex. Returns the groups and each triangle's
/// cumulative power within its group.
fn groups(
    scene: &Scene,
    triangles: &[([Vec3; 3], Vec3, Vec3)],
    twice_areas: &[f32],
) -> (Vec<Group>, Vec<f32>) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in scene.meshes.iter().flat_map(|m| &m.positions) {
        (lo, hi) = (lo.min(*p), hi.max(*p));
    }
    let extent = GROUP_EXTENT * (hi - lo).length();
    let mut groups: Vec<Group> = Vec::new();
    let mut power_cdf = Vec::with_capacity(triangles.len());
    for (k, (v, normal, radiance)) in triangles.iter().enumerate() {
        let area = 0.5 * twice_areas[k];
        let power = area * (radiance.x + radiance.y + radiance.z);
        let joins = groups.last().is_some_and(|g| {
            let (w, gn, gr) = &triangles[g.first];
            gr == radiance
                && gn.dot(*normal) >= 0.9999
                && v.iter()
                    .all(|&q| (q - w[0]).length() <= extent && gn.dot(q - w[0]).abs() <= 1e-4 * extent)
        });
        if !joins {
            groups.push(Group {
                first: k,
                end: k,
                centroid: Vec3::ZERO,
                normal: *normal,
                radius: 0.0,
                area: 0.0,
                power: 0.0,
            });
        }
        let g = groups.last_mut().expect("a group was just pushed");
        g.end = k + 1;
        g.centroid += (v[0] + v[1] + v[2]) / 3.0 * area;
        g.area += area;
        g.power += power;
        power_cdf.push(g.power);
    }
    for g in &mut groups {
        g.centroid /= g.area;
        g.radius = triangles[g.first..g.end]
            .iter()
            .flat_map(|(v, _, _)| v.iter())
            .map(|&q| (q - g.centroid).length())
            .fold(0.0, f32::max);
    }
    (groups, power_cdf)
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

    /// Whether the scene has any light at all.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty() && self.others.is_empty()
    }

    /// Reflected direct radiance towards the viewer at `p` (normal `n`,
    /// facing the viewer's side), `Σ f(ωi)·Li·cosθ / pdf` over `samples`
    /// area-light samples plus every point and directional light, where `f`
    /// is the BRDF for incident direction `ωi`. The area samples are points
    /// `first..first + samples` of the scrambled (0,2)-sequence
    /// `sobol2`: stratified over the lights' total area, and with the
    /// samples of the other camera samples of a pixel (the next indices).
    #[allow(clippy::too_many_arguments)]
    pub fn reflected(
        &self,
        tracer: &Tracer,
        p: Vec3,
        n: Vec3,
        samples: u32,
        first: u32,
        scramble: [u32; 2],
        f: impl Fn(Vec3) -> Vec3,
    ) -> Vec3 {
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
            let mut area_sum = Vec3::ZERO;
            for s in 0..samples {
                if total <= 0.0 {
                    break;
                }
                // The first coordinate picks a group, within its share a
                // triangle, and within that the first coordinate on it.
                let (u, w) = sobol2(first.wrapping_add(s), scramble);
                let (k, picked, u) = if chosen_here {
                    let (g, u) = pick(cdf, u * total);
                    let group = &self.groups[g];
                    let share = &self.power_cdf[group.first..group.end];
                    let (t, u) = pick(share, u * group.power);
                    let (lo, hi) = (if t == 0 { 0.0 } else { share[t - 1] }, share[t]);
                    let estimate = if g == 0 { cdf[0] } else { cdf[g] - cdf[g - 1] };
                    (group.first + t, estimate / total * ((hi - lo) / group.power), u)
                } else {
                    let (k, u) = pick(cdf, u * total);
                    (k, 0.5 * self.twice_areas[k] / total, u)
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
                if tracer.occluded(origin, wi, dist * (1.0 - 1e-4) - eps) {
                    continue;
                }
                area_sum += f(wi) * *radiance * (cos_r * weight / picked);
            }
            sum += area_sum / samples as f32;
        }
        for light in &self.others {
            match *light {
                Light::Point { position, intensity } => {
                    let d = position - origin;
                    let dist2 = d.length_squared();
                    if dist2 <= 0.0 {
                        continue;
                    }
                    let dist = dist2.sqrt();
                    let wi = d / dist;
                    let cos_r = n.dot(wi);
                    if cos_r > 0.0 && !tracer.occluded(origin, wi, dist) {
                        sum += f(wi) * intensity * (cos_r / dist2);
                    }
                }
                Light::Directional {
                    direction,
                    irradiance,
                } => {
                    let wi = -direction;
                    let cos_r = n.dot(wi);
                    if cos_r > 0.0 && !tracer.occluded(origin, wi, f32::INFINITY) {
                        sum += f(wi) * irradiance * cos_r;
                    }
                }
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::polygon::projected_solid_angle;
    use crate::scene::{Camera, FovAxis, Material, Mesh};

    fn quad(name: &str, corners: [Vec3; 4], emission: f32) -> Mesh {
        Mesh {
            name: name.into(),
            positions: corners.to_vec(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            normals: None,
            uvs: Vec::new(),
            material: 0,
            emission: Some(Vec3::splat(emission)),
        }
    }

    /// A scene of `meshes` alone, one grey material, no occluder.
    fn emitters(name: &str, meshes: Vec<Mesh>) -> Scene {
        Scene {
            name: name.into(),
            meshes,
            materials: vec![Material::diffuse("grey", Vec3::splat(0.5))],
            lights: vec![],
            environment: None,
            camera: Camera {
                origin: Vec3::new(0.0, 1.0, 3.0),
                target: Vec3::ZERO,
                up: Vec3::Y,
                fov_degrees: 40.0,
                fov_axis: FovAxis::Smaller,
                width: 8,
                height: 8,
            },
            warnings: vec![],
            file_settings: Default::default(),
        }
    }

    /// Three emitters over an open floor: a bright panel just above the
    /// receivers (its corner within a few of its sizes), a dim distant
    /// one, and one that faces away; no occluder. The estimate of
    /// `∫ L cosθ dω` matches Lambert's formula at receivers beside, under
    /// and far from the near panel, whichever emitters a receiver picks.
    #[test]
    fn irradiance_matches_lamberts_formula() {
        let near = [
            Vec3::new(0.0, 0.3, 0.0),
            Vec3::new(0.0, 0.3, 1.0),
            Vec3::new(1.0, 0.3, 1.0),
            Vec3::new(1.0, 0.3, 0.0),
        ];
        let far = [
            Vec3::new(-6.0, 4.0, -6.0),
            Vec3::new(-6.0, 4.0, -5.0),
            Vec3::new(-5.0, 4.0, -5.0),
            Vec3::new(-5.0, 4.0, -6.0),
        ];
        // Wound to face down, except `away`.
        let away = far.map(|v| v + Vec3::new(8.0, 0.0, 0.0));
        let (mut near, mut far) = (near, far);
        near.reverse();
        far.reverse();
        let scene = emitters(
            "three panels",
            vec![
                quad("near", near, 5.0),
                quad("far", far, 1.0),
                quad("away", away, 3.0),
            ],
        );
        let lights = Lights::new(&scene);
        assert_eq!(lights.groups.len(), 3);
        let tracer = Tracer::new(&scene);
        let n = Vec3::Y;
        for p in [
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(1.05, 0.0, 1.1),
            Vec3::new(-0.2, 0.0, 0.4),
            Vec3::new(3.0, 0.0, -1.0),
        ] {
            let origin = p + n * tracer.epsilon();
            let exact: f64 = [(near, 5.0), (far, 1.0)]
                .iter()
                .map(|(q, l)| l * projected_solid_angle(&q.map(|v| (v - origin).as_dvec3()), DVec3::Y))
                .sum();
            let got = lights.reflected(&tracer, p, n, 1 << 14, 0, [0x9e37_79b9, 0x85eb_ca6b], |_| {
                Vec3::ONE
            });
            approx::assert_relative_eq!(f64::from(got.x), exact, max_relative = 2e-3);
        }
    }

    /// A triangle is kept only while its area is a normal `f32`: one of
    /// area 4.5e-46 (subnormal) made a group of emitters of area zero,
    /// whose centroid and estimate were 0/0 at every receiver.
    #[test]
    fn triangles_whose_area_is_not_a_normal_f32_are_left_out() {
        let tiny = [Vec3::ZERO, Vec3::new(3e-23, 0.0, 0.0), Vec3::new(0.0, 3e-23, 0.0)];
        assert!(triangle(tiny).is_none());
        let small = [Vec3::ZERO, Vec3::new(1e-18, 0.0, 0.0), Vec3::new(0.0, 1e-18, 0.0)];
        assert!(triangle(small).is_some_and(|(twice, n)| twice.is_normal() && n == Vec3::Z));
        let huge = [
            Vec3::new(-1e37, 0.0, 0.0),
            Vec3::new(1e37, 0.0, 0.0),
            Vec3::new(0.0, 3e38, 1e37),
        ];
        assert!(triangle(huge).is_none());
        // A light holding the tiny triangle beside a real one: every
        // receiver's estimate stays finite.
        let mut light = quad(
            "light",
            [
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ],
            4.0,
        );
        light.positions.extend(tiny);
        light.triangles.push([4, 5, 6]);
        let scene = emitters("tiny emitter", vec![light]);
        let lights = Lights::new(&scene);
        assert_eq!(lights.triangles.len(), 2);
        let tracer = Tracer::new(&scene);
        let got = lights.reflected(&tracer, Vec3::new(0.5, 0.0, 0.5), Vec3::Y, 8, 0, [1, 2], |_| {
            Vec3::ONE
        });
        assert!(got.is_finite() && got.x > 0.0, "{got}");
    }
}
