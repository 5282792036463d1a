//! Shading points: where a camera ray (or a path) hits, with the shading
//! normal (interpolated, bumped) and the emitted radiance.

use glam::Vec3;

use super::trace::{Hit, Tracer};
use crate::scene::{Bump, Material, Scene, SurfacePoint};

/// Tilts `n` by the procedural bump at `p`.
fn bumped(n: Vec3, p: Vec3, bump: &Bump) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let w = std::f32::consts::TAU * bump.frequency;
    let tilt = t * (w * p.dot(t)).sin() + b * (w * p.dot(b) + 1.3).sin();
    (n + tilt * bump.amplitude).normalize()
}

/// A shading point: where a camera ray hit, how to shade it.
pub(crate) struct ShadingPoint {
    /// Hit point, moved off the surface by the tracer's epsilon.
    pub position: Vec3,
    /// Shading normal on the viewer's side (with its normal map).
    pub normal: Vec3,
    /// The normal a receiver here gathers about: `normal` before the
    /// normal map (the map tilts only the convolution: the receiver sees
    /// what lies above its surface).
    pub receiver_normal: Vec3,
    /// Unit direction back to the viewer.
    pub wo: Vec3,
    /// Material index.
    pub material: usize,
    /// Diffuse albedo here (the material's, textured).
    pub albedo: Vec3,
    /// Emitted radiance towards the viewer.
    pub emitted: Vec3,
}

/// The shading point where the ray `origin + t·dir` hit. `spread` is the
/// angle (radians) a pixel subtends, for the width textures are averaged
/// over (0: a point lookup, as paths take).
pub(crate) fn shading_point(
    scene: &Scene,
    tracer: &Tracer,
    origin: Vec3,
    dir: Vec3,
    hit: &Hit,
    spread: f32,
) -> Option<ShadingPoint> {
    let mesh = &scene.meshes[hit.mesh as usize];
    let material: &Material = &scene.materials[mesh.material];
    let mut ng = hit.geometric_normal;
    let front = ng.dot(dir) < 0.0;
    if !front {
        if !material.two_sided {
            return None; // a one-sided surface seen from behind is black
        }
        ng = -ng;
    }
    let position = origin + dir * hit.t;
    let mut normal = match &mesh.normals {
        Some(normals) => {
            let t = mesh.triangles[hit.triangle as usize];
            let (u, v) = (hit.uv.x, hit.uv.y);
            let ns = normals[t[0] as usize] * (1.0 - u - v)
                + normals[t[1] as usize] * u
                + normals[t[2] as usize] * v;
            let ns = ns.normalize_or(ng);
            if ns.dot(ng) > 0.0 { ns } else { ng }
        }
        None => ng,
    };
    // A pixel's footprint: the cone's width at the hit (ray cones, as in
    // Ray Tracing Gems ch. 20), and across a slant the width of a disk of
    // the footprint ellipse's area: stretched by 1/√cos, not 1/cos, which
    // blurs the unstretched axis by the whole slant.
    let at = SurfacePoint {
        triangle: hit.triangle,
        uv: hit.uv,
        width: if material.is_textured() {
            hit.t * spread / ng.dot(dir).abs().max(0.0025).sqrt()
        } else {
            0.0
        },
    };
    if let Some(b) = &material.bump {
        normal = bumped(normal, position, b);
    }
    let receiver_normal = normal;
    if let Some(map) = &material.normal_map {
        normal = map.apply(mesh, &at, normal);
    }
    let emitted = if front {
        mesh.emission.unwrap_or(Vec3::ZERO)
    } else {
        Vec3::ZERO
    };
    Some(ShadingPoint {
        position: position + ng * tracer.epsilon(),
        normal,
        receiver_normal,
        wo: -dir,
        material: mesh.material,
        albedo: material.albedo_at(mesh, &at),
        emitted,
    })
}
