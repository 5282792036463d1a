//! The ground truth: an unbiased path tracer for the same scenes, camera,
//! materials and emitters, with next-event estimation and multiple importance
//! sampling (power heuristic) for area lights, and a bounce limit that matches
//! the point-based renderer's (`0` direct light only, `1` one indirect bounce,
//! `-1` unlimited with Russian roulette).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::image::Image;
use super::light::Lights;
use super::options::Component;
use super::output::RenderError;
use super::shading::shading_point;
use super::trace::Tracer;
use crate::brdf::{GlossyLobe, lambert_sample};
use crate::error::Error;
use crate::rng::{Rng, film_point};
use crate::scene::{Light, Scene};

/// Path-tracer settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceOptions {
    /// Paths per pixel (stratified over the pixel).
    pub spp: u32,
    /// Indirect bounces: 0 direct only, 1 one bounce (Mitsuba `max_depth` 3), −1 unlimited.
    pub bounces: i32,
    /// Which light the image holds (as [`RenderOptions::component`](super::RenderOptions)).
    pub component: Component,
    /// Seed of every random choice.
    pub seed: u64,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        Self {
            spp: 256,
            bounces: 1,
            component: Component::All,
            seed: 7,
        }
    }
}

/// A reference image and its cost.
#[derive(Clone, Debug)]
pub struct ReferenceOutput {
    /// Linear radiance.
    pub image: Image,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The material's BRDF: Lambert plus an optional glossy lobe.
struct Bsdf {
    /// The diffuse albedo at the point (textured).
    albedo: Vec3,
    lobe: Option<GlossyLobe>,
}

impl Bsdf {
    fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        if n.dot(wi) <= 0.0 {
            return Vec3::ZERO;
        }
        let d = self.albedo * std::f32::consts::FRAC_1_PI;
        match &self.lobe {
            Some(l) => d + l.eval(n, wo, wi),
            None => d,
        }
    }

    /// Probability of sampling the glossy lobe rather than the cosine lobe.
    fn glossy_weight(&self) -> f32 {
        match &self.lobe {
            Some(l) => {
                let (d, s) = (self.albedo.max_element(), l.specular.max_element());
                if d + s > 0.0 { s / (d + s) } else { 0.5 }
            }
            None => 0.0,
        }
    }

    fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let cos = n.dot(wi);
        if cos <= 0.0 {
            return 0.0;
        }
        let g = self.glossy_weight();
        let diffuse = cos * std::f32::consts::FRAC_1_PI;
        match &self.lobe {
            Some(l) => (1.0 - g) * diffuse + g * l.pdf(n, wo, wi),
            None => diffuse,
        }
    }

    fn sample(&self, n: Vec3, wo: Vec3, rng: &mut Rng) -> Option<Vec3> {
        let (u0, u1, u2) = (rng.f32(), rng.f32(), rng.f32());
        let wi = match &self.lobe {
            Some(l) if u0 < self.glossy_weight() => l.sample(n, wo, u1, u2).0,
            _ => lambert_sample(n, u1, u2),
        };
        if !wi.is_finite() {
            // A defect, not a path to end: its pdf is NaN, which the
            // caller reports with the pixel and sample.
            return Some(wi);
        }
        (n.dot(wi) > 0.0).then(|| wi.normalize())
    }
}

fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// Renders the ground truth of `scene`. `progress` gets (rows done, rows).
pub fn render_reference(
    scene: &Scene,
    opts: &ReferenceOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ReferenceOutput, RenderError> {
    scene.validate()?;
    if opts.spp == 0 || opts.bounces < -1 {
        return Err(Error::InvalidParameter {
            name: if opts.spp == 0 { "spp" } else { "bounces" },
            value: if opts.spp == 0 {
                "0".into()
            } else {
                opts.bounces.to_string()
            },
            expected: "spp ≥ 1 and bounces ≥ −1",
        }
        .into());
    }
    let start = Instant::now();
    let tracer = Tracer::new(scene);
    let lights = Lights::new(scene);
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let rows_done = AtomicUsize::new(0);
    progress(0, h as usize);
    // Every row its own job, as the renderer's tiles (`Frame::render`).
    let rows: Vec<Vec<Vec3>> = (0..h)
        .into_par_iter()
        .with_max_len(1)
        .map(|y| {
            let rays = cam.rays();
            let row: Vec<Vec3> = (0..w)
                .map(|x| {
                    let mut rng = Rng::new(
                        opts.seed ^ ((y as u64) << 32 | x as u64).wrapping_mul(0xA24B_AED4_963E_E407),
                    );
                    let scramble = rng.scramble();
                    let mut sum = Vec3::ZERO;
                    for s in 0..opts.spp {
                        let (fx, fy) = film_point(x, y, s, scramble);
                        let l = trace_path(
                            scene,
                            &tracer,
                            &lights,
                            cam.origin,
                            rays.direction(fx, fy),
                            opts.bounces,
                            opts.component,
                            &mut rng,
                        );
                        if !l.is_finite() {
                            return Err(RenderError::NonFinite {
                                stage: "path tracer",
                                place: format!("pixel ({x}, {y}), sample {s}"),
                                value: l.to_array(),
                            });
                        }
                        sum += l;
                    }
                    Ok(sum / opts.spp as f32)
                })
                .collect::<Result<_, RenderError>>()?;
            let d = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(d, h as usize);
            Ok(row)
        })
        .collect::<Result<_, RenderError>>()?;
    let pixels = rows.concat();
    Ok(ReferenceOutput {
        image: Image {
            width: w,
            height: h,
            pixels,
        },
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Radiance along one camera path: the light of `component` (light that
/// reaches vertex `k` from an emitter has bounced `k` times before the first
/// hit, so an emitter hit at vertex `k + 1` by the BSDF sample counts `k`).
#[allow(clippy::too_many_arguments)]
fn trace_path(
    scene: &Scene,
    tracer: &Tracer,
    lights: &Lights,
    origin: Vec3,
    dir: Vec3,
    bounces: i32,
    component: Component,
    rng: &mut Rng,
) -> Vec3 {
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    let (mut origin, mut dir) = (origin, dir);
    // Solid-angle pdf of the BSDF sample that made this ray; None for the camera ray.
    let mut prev_pdf: Option<f32> = None;
    let mut depth = 0u32; // surface vertices so far
    let max_vertices = if bounces < 0 { u32::MAX } else { bounces as u32 + 1 };
    loop {
        let Some(hit) = tracer.closest(origin, dir, f32::INFINITY) else {
            // Left the scene: the environment, counted like an emitter hit
            // by a BSDF sample (no light sample of it to weigh against).
            if let Some(env) = &scene.environment
                && component.holds(depth.saturating_sub(1))
            {
                radiance += throughput * env.radiance(dir);
            }
            break;
        };
        let Some(sp) = shading_point(scene, tracer, origin, dir, &hit, 0.0) else {
            break;
        };
        // Emission: seen directly, or reached by a BSDF sample (MIS with NEE).
        if sp.emitted.max_element() > 0.0 && component.holds(depth.saturating_sub(1)) {
            let w = match prev_pdf {
                None => 1.0,
                Some(pb) => {
                    let cos_l = hit.geometric_normal.dot(-dir).abs();
                    power_heuristic(pb, lights.area_pdf(hit.t * hit.t, cos_l))
                }
            };
            radiance += throughput * sp.emitted * w;
        }
        depth += 1;
        if depth > max_vertices {
            break;
        }
        let m = &scene.materials[sp.material];
        let bsdf = Bsdf {
            albedo: sp.albedo,
            lobe: m.lobe(),
        };
        let (p, n, wo) = (sp.position, sp.normal, sp.wo);
        // Next-event estimation: one area-light sample (MIS), every delta light.
        let nee = component.holds(depth - 1);
        if let Some((q, ln, le)) = lights.sample_area(rng.f32(), rng.f32(), rng.f32()) {
            let d = q - p;
            let dist2 = d.length_squared();
            if dist2 > 0.0 {
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos_l = -ln.dot(wi);
                let f = bsdf.eval(n, wo, wi);
                if nee && cos_l > 0.0 && f.max_element() > 0.0 && !tracer.occluded(p, wi, dist * (1.0 - 1e-4))
                {
                    let pl = lights.area_pdf(dist2, cos_l);
                    let w = power_heuristic(pl, bsdf.pdf(n, wo, wi));
                    radiance += throughput * f * le * (n.dot(wi) * w / pl);
                }
            }
        }
        for light in lights.delta_lights() {
            let (wi, li, dist) = match *light {
                Light::Point { position, intensity } => {
                    let d = position - p;
                    let dist2 = d.length_squared();
                    if dist2 <= 0.0 {
                        continue;
                    }
                    (d / dist2.sqrt(), intensity / dist2, dist2.sqrt())
                }
                Light::Directional {
                    direction,
                    irradiance,
                } => (-direction, irradiance, f32::INFINITY),
            };
            let cos = n.dot(wi);
            if nee && cos > 0.0 && !tracer.occluded(p, wi, dist) {
                radiance += throughput * bsdf.eval(n, wo, wi) * li * cos;
            }
        }
        // Continue by sampling the BSDF. At the last vertex the ray only
        // looks for emitters (the MIS partner of the light sample above);
        // the loop stops at the vertex it hits.
        let Some(wi) = bsdf.sample(n, wo, rng) else { break };
        let pdf = bsdf.pdf(n, wo, wi);
        if pdf.is_nan() {
            // A defect, not a path to drop: the caller reports the sample as
            // non-finite (pixel and sample).
            return Vec3::NAN;
        }
        if pdf <= 0.0 {
            break; // a sample the lobe cannot make (below its cone)
        }
        if wi.dot(sp.receiver_normal) <= 0.0 {
            break; // a normal map's hemisphere dips into the surface, which blocks it
        }
        throughput *= bsdf.eval(n, wo, wi) * (n.dot(wi) / pdf);
        if bounces < 0 && depth >= 3 {
            let q = throughput.max_element().min(0.95);
            if rng.f32() >= q {
                break;
            }
            throughput /= q;
        }
        prev_pdf = Some(pdf);
        origin = p;
        dir = wi;
    }
    radiance
}
