//! Direct light: area emitters (emissive triangles, sampled by area), point
//! and directional lights, each checked with a shadow ray.

use glam::Vec3;

use super::trace::Tracer;
use crate::rng::sobol2;
use crate::scene::{Light, Scene};

/// The scene's emitters, ready to sample.
pub struct Lights {
    /// Emissive triangles: vertices, unit front normal, radiance.
    triangles: Vec<([Vec3; 3], Vec3, Vec3)>,
    /// Cumulative areas of `triangles`.
    cdf: Vec<f32>,
    area: f32,
    others: Vec<Light>,
}

/// Twice the area of a triangle and its unit normal, `None` when degenerate
/// or overflowing `f32` (such a triangle is neither lit by nor lights
/// anything: left out of the surfels and of the emitters alike). The normal is normalized in `f64`: the cross product of a
/// sliver triangle can be subnormal, and its `f32` length too coarse for a
/// unit normal.
pub(crate) fn triangle(v: [Vec3; 3]) -> Option<(f32, Vec3)> {
    let c = (v[1] - v[0]).cross(v[2] - v[0]).as_dvec3();
    let len = c.length();
    (len > 0.0 && len.is_finite() && (len as f32).is_finite()).then(|| (len as f32, (c / len).as_vec3()))
}

impl Lights {
    /// Collects the emitters of `scene`.
    pub fn new(scene: &Scene) -> Lights {
        let mut triangles = Vec::new();
        let mut cdf = Vec::new();
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
                    triangles.push((v, normal, radiance));
                }
            }
        }
        Lights {
            triangles,
            cdf,
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
    /// [`sobol2`]: stratified over the lights' total area, and with the
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
            let mut area_sum = Vec3::ZERO;
            for s in 0..samples {
                // The first coordinate picks a triangle by area and, within
                // its share, the first barycentric coordinate.
                let (u, w) = sobol2(first.wrapping_add(s), scramble);
                let x = u * self.area;
                let k = self
                    .cdf
                    .partition_point(|&c| c <= x)
                    .min(self.triangles.len() - 1);
                let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
                let share = self.cdf[k] - lo;
                let u = if share > 0.0 {
                    ((x - lo) / share).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (v, ln, radiance) = &self.triangles[k];
                let su = u.sqrt();
                let (a, b) = (su * (1.0 - w), su * w);
                let q = v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b;
                let d = q - origin;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    continue;
                }
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos_r = n.dot(wi);
                let cos_l = -ln.dot(wi);
                if cos_r <= 0.0 || cos_l <= 0.0 {
                    continue;
                }
                if tracer.occluded(origin, wi, dist * (1.0 - 1e-4) - eps) {
                    continue;
                }
                area_sum += f(wi) * *radiance * (cos_r * cos_l / dist2);
            }
            sum += area_sum * (self.area / samples as f32);
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
