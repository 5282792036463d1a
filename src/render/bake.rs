//! Baking a scene into surfels: stratified area-uniform sampling of every
//! surface and direct light at each surfel through shadow rays.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::light::{Lights, triangle};
use super::trace::Tracer;
use crate::error::{Error, Invalid};
use crate::points::{MAX_RADIANCE, PointCloud, Surfel};
use crate::rng::{Rng, mix};
use crate::scene::Scene;

/// How a scene is turned into surfels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeOptions {
    /// Surfels per unit of surface area.
    pub density: f32,
    /// Area-light samples per surfel.
    pub light_samples: u32,
    /// Seed of every random choice (results do not depend on thread count).
    pub seed: u64,
}

impl Default for BakeOptions {
    fn default() -> Self {
        Self {
            density: 4000.0,
            light_samples: 16,
            seed: 1,
        }
    }
}

/// Surfels with what shading them again needs.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The surfels; their radiance is the reflected direct light (emission is
    /// left out: the renderer adds direct light with shadow rays).
    pub cloud: PointCloud,
    /// Diffuse albedo of each surfel, for extra bounces.
    pub albedo: Vec<Vec3>,
}

/// A low-discrepancy point in the unit square (Hammersley with a scramble).
fn hammersley(i: u32, n: u32, scramble: u32) -> Vec2 {
    let x = (i as f32 + 0.5) / n as f32;
    let y = (i.reverse_bits() ^ scramble) as f32 * (1.0 / 4_294_967_296.0);
    Vec2::new(x, y)
}

/// Samples the surfels of `scene` and lights them directly (`scene` valid,
/// see [`Scene::validate`]). Errors: a density that is not a finite positive
/// number, or one that asks for more than [`PointCloud::MAX_SURFELS`] surfels
/// (counted before anything is allocated).
pub fn bake(scene: &Scene, tracer: &Tracer, lights: &Lights, opts: &BakeOptions) -> Result<Baked, Error> {
    if !(opts.density.is_finite() && opts.density > 0.0) {
        return Err(Error::InvalidParameter {
            name: "density",
            value: opts.density.to_string(),
            expected: "a finite number > 0 (surfels per unit area)",
        });
    }
    let mut expected = 0.0f64;
    for m in &scene.meshes {
        for t in &m.triangles {
            if let Some((twice_area, _)) = triangle(t.map(|i| m.positions[i as usize])) {
                expected += (0.5 * twice_area as f64 * opts.density as f64).max(1.0);
            }
        }
    }
    if expected > PointCloud::MAX_SURFELS as f64 {
        return Err(Error::TooManySurfels {
            count: expected.min(usize::MAX as f64) as usize,
            max: PointCloud::MAX_SURFELS,
        });
    }
    // Per triangle, a count from its area (stochastic rounding), stratified
    // with a scrambled Hammersley set mapped area-preservingly to the triangle.
    let mut sites: Vec<(Vec3, Vec3, f32, usize)> = Vec::new();
    let mut tri_seed = Rng::new(opts.seed);
    for mesh in &scene.meshes {
        for t in &mesh.triangles {
            let v = t.map(|i| mesh.positions[i as usize]);
            let Some((twice_area, normal)) = triangle(v) else {
                continue;
            };
            let area = 0.5 * twice_area;
            let want = area * opts.density;
            let extra = if tri_seed.f32() < want.fract() { 1.0 } else { 0.0 };
            let n = (want.floor() + extra).max(1.0) as u32;
            // In f64: the radius of a tiny triangle's disk must not underflow.
            let radius = (area as f64 / (n as f64 * std::f64::consts::PI)).sqrt() as f32;
            let scramble = tri_seed.next_u64() as u32;
            for i in 0..n {
                let u = hammersley(i, n, scramble);
                let su = u.x.sqrt();
                let (b0, b1) = (1.0 - su, u.y * su);
                let p = v[0] * b0 + v[1] * b1 + v[2] * (1.0 - b0 - b1);
                sites.push((p, normal, radius, mesh.material));
            }
        }
    }
    let baked: Vec<Option<(Surfel, Vec3)>> = sites
        .par_iter()
        .enumerate()
        .map(|(i, &(position, normal, radius, material))| {
            let albedo = scene.materials[material].albedo;
            let h = mix(opts.seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let f = albedo * std::f32::consts::FRAC_1_PI;
            let radiance = if albedo.max_element() > 0.0 {
                let scramble = [h as u32, (h >> 32) as u32];
                lights.reflected(tracer, position, normal, opts.light_samples, 0, scramble, |_| f)
            } else {
                Vec3::ZERO
            };
            if !radiance.is_finite() {
                return Err(Error::InvalidSurfel {
                    index: i,
                    reason: Invalid::NonFinite {
                        field: "radiance (direct light at the surfel)",
                    },
                });
            }
            // A finite estimate beyond the range a surfel accepts (a surfel
            // a hair from a light of the brightest emission) saturates.
            let surfel = Surfel {
                position,
                normal,
                radius,
                radiance: radiance.min(Vec3::splat(MAX_RADIANCE)),
            };
            // Geometry beyond `MAX_COORDINATE` makes no surfel.
            Ok(surfel.validate(i).is_ok().then_some((surfel, albedo)))
        })
        .collect::<Result<_, Error>>()?;
    let (surfels, albedo): (Vec<Surfel>, Vec<Vec3>) = baked.into_iter().flatten().unzip();
    Ok(Baked {
        cloud: PointCloud::new(surfels).expect("baked surfels are validated one by one"),
        albedo,
    })
}
