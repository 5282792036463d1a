//! The renderer's near field (`microbuffer::near`): what a receiver sees
//! within a few surfel radii, by the ray tracer, shaded as a surfel there
//! would be (reflected direct light at the hit, no emission, with the
//! surfels' own number of light samples).

use glam::Vec3;

use super::frame::Frame;
use super::light::{Brdf, LightSamples, Lights};
use super::trace::Tracer;
use crate::microbuffer::{NearField, Sight};
use crate::points::MAX_RADIANCE;
use crate::rng::mix;
use crate::scene::{Scene, SurfacePoint};

/// The scene along a receiver's short rays, shaded as its surfels are
/// (`surfels`): the near field of [`Gather::with_near_field`](crate::gather::Gather::with_near_field)
/// for a scene and its ray tracer, which the renderer uses.
#[derive(Clone, Copy)]
pub struct NearRays<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its ray queries.
    pub tracer: &'a Tracer,
    /// Its emitters.
    pub lights: &'a Lights,
    /// Area-light samples at each hit (the surfels' own number).
    pub light_samples: u32,
    /// Scrambles the light samples.
    pub seed: u64,
}

impl NearField for NearRays<'_> {
    fn escapes(&self, origin: Vec3, normal: Vec3, dir: Vec3) -> Option<bool> {
        Some(self.tracer.escapes(origin, normal, dir))
    }

    fn escapes_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<bool>) -> bool {
        self.tracer.escapes_each(origin, normal, dirs, out);
        true
    }

    fn sight_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<Sight>) -> bool {
        self.tracer.sight_each(origin, normal, dirs, out);
        true
    }

    fn trace(&self, origin: Vec3, normal: Vec3, dir: Vec3, t_max: f32) -> Option<Vec3> {
        let o = origin + normal * self.tracer.epsilon();
        let hit = self.tracer.closest(o, dir, t_max)?;
        let mesh = &self.scene.meshes[hit.mesh as usize];
        let material = &self.scene.materials[mesh.material];
        // Flat normals, as the surfels have; a one-sided back face is black.
        let mut ng = hit.geometric_normal;
        if ng.dot(dir) > 0.0 {
            if !material.two_sided {
                return Some(Vec3::ZERO);
            }
            ng = -ng;
        }
        // A point lookup: the near field's rays average over the texture.
        let at = SurfacePoint {
            triangle: hit.triangle,
            uv: hit.uv,
            width: 0.0,
        };
        let albedo = material.albedo_at(mesh, &at);
        if albedo.max_element() <= 0.0 {
            return Some(Vec3::ZERO);
        }
        let q = o + dir * hit.t;
        // Light samples scrambled by where the ray hit: the same hit, the
        // same bits, whatever packet or thread asked.
        let h = mix(self.seed
            ^ (u64::from(q.x.to_bits()) | u64::from(q.y.to_bits()) << 32)
            ^ u64::from(q.z.to_bits()).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let samples = LightSamples {
            count: self.light_samples,
            first: 0,
            scramble: [h as u32, (h >> 32) as u32],
            ratio: false,
        };
        let l = self
            .lights
            .reflected(self.tracer, q, ng, samples, Brdf::lambert(albedo));
        // Saturates as the surfels do (`surfels`); a non-finite value is kept,
        // for the gather's own report to name (`min` would hide a NaN).
        let max = Vec3::splat(MAX_RADIANCE);
        Some(Vec3::select(l.cmpgt(max), max, l))
    }
}

impl NearField for Frame<'_> {
    fn near_leaves(&self) -> bool {
        self.near_field()
    }

    fn escapes(&self, origin: Vec3, normal: Vec3, dir: Vec3) -> Option<bool> {
        // Occlusion sees no sky.
        (!self.opts.ao).then(|| self.tracer.escapes(origin, normal, dir))
    }

    fn escapes_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<bool>) -> bool {
        if !self.opts.ao {
            self.tracer.escapes_each(origin, normal, dirs, out);
        }
        !self.opts.ao
    }

    fn sight_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<Sight>) -> bool {
        if !self.opts.ao {
            self.tracer.sight_each(origin, normal, dirs, out);
        }
        !self.opts.ao
    }

    fn trace(&self, origin: Vec3, normal: Vec3, dir: Vec3, t_max: f32) -> Option<Vec3> {
        if self.opts.ao {
            // Occlusion needs the hit alone.
            let o = origin + normal * self.tracer.epsilon();
            return self.tracer.closest(o, dir, t_max).map(|_| Vec3::ZERO);
        }
        NearRays {
            scene: self.scene,
            tracer: &self.tracer,
            lights: &self.lights,
            light_samples: self.opts.surfel_light_samples,
            seed: self.opts.seed,
        }
        .trace(origin, normal, dir, t_max)
    }
}
