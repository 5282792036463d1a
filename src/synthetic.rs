//! Deterministic synthetic inputs for tests, benchmarks and examples: surfels
//! on the inside of a box holding two blocks (a Cornell-box-like interior) and
//! receivers on its surfaces, in coherent 4×4 tiles or with jittered normals.

use glam::Vec3;

use crate::cut::Receiver;
use crate::points::{PointCloud, Surfel};
use crate::rng::Rng;

/// An axis-aligned rectangle: `origin + u·e1 + v·e2`, `u, v ∈ [0, 1]`, facing `normal`.
#[derive(Clone, Copy, Debug)]
struct Quad {
    origin: Vec3,
    e1: Vec3,
    e2: Vec3,
    normal: Vec3,
    radiance: Vec3,
}

impl Quad {
    fn area(&self) -> f32 {
        self.e1.cross(self.e2).length()
    }
}

/// The quads of the scene: the inside of the box `[-1, 1]³` (open at `+z`,
/// the camera side), a light patch under the ceiling, and two blocks on the floor.
fn quads() -> Vec<Quad> {
    let white = Vec3::splat(0.05);
    let mut q = Vec::new();
    let mut inward = |origin: Vec3, e1: Vec3, e2: Vec3, radiance: Vec3| {
        let normal = e1.cross(e2).normalize();
        q.push(Quad {
            origin,
            e1,
            e2,
            normal,
            radiance,
        });
    };
    // Floor (+y), ceiling (−y), back (+z), left (+x, red), right (−x, green).
    inward(
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(2.0, 0.0, 0.0),
        white,
    );
    inward(
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 2.0),
        white,
    );
    inward(
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        white,
    );
    inward(
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(0.06, 0.005, 0.005),
    );
    inward(
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.005, 0.04, 0.005),
    );
    // The light: a patch just under the ceiling, facing down.
    inward(
        Vec3::new(-0.25, 0.99, -0.25),
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.5),
        Vec3::new(18.0, 14.0, 7.0),
    );
    // Two blocks, each five outward faces (the bottom touches the floor).
    for (lo, hi) in [
        (Vec3::new(-0.7, -1.0, -0.6), Vec3::new(-0.1, 0.2, 0.0)),
        (Vec3::new(0.15, -1.0, -0.1), Vec3::new(0.7, -0.4, 0.45)),
    ] {
        let d = hi - lo;
        let (dx, dy, dz) = (Vec3::X * d.x, Vec3::Y * d.y, Vec3::Z * d.z);
        inward(Vec3::new(lo.x, hi.y, lo.z), dz, dx, white); // top, +y
        inward(lo, dy, dz, white); // −x
        inward(Vec3::new(hi.x, lo.y, lo.z), dz, dy, white); // +x
        inward(lo, dx, dy, white); // −z
        inward(Vec3::new(lo.x, lo.y, hi.z), dy, dx, white); // +z
    }
    q
}

/// About `n` surfels, stratified over the box's surfaces (area-uniform), with
/// disk radii covering each surface.
pub fn box_with_blocks(n: usize, seed: u64) -> PointCloud {
    let quads = quads();
    let total: f32 = quads.iter().map(Quad::area).sum();
    let mut rng = Rng::new(seed);
    let mut surfels = Vec::with_capacity(n + quads.len());
    for q in &quads {
        let want = ((n as f32) * q.area() / total).round().max(1.0);
        let (l1, l2) = (q.e1.length(), q.e2.length());
        // A grid of strata of near-square cells, one jittered sample each.
        let nu = ((want * l1 / l2).sqrt().round() as usize).max(1);
        let nv = ((want / nu as f32).round() as usize).max(1);
        let cell = q.area() / (nu * nv) as f32;
        let radius = (cell / std::f32::consts::PI).sqrt() * 1.1;
        for i in 0..nu {
            for j in 0..nv {
                let u = (i as f32 + rng.f32()) / nu as f32;
                let v = (j as f32 + rng.f32()) / nv as f32;
                surfels.push(Surfel {
                    position: q.origin + q.e1 * u + q.e2 * v,
                    normal: q.normal,
                    radius,
                    radiance: q.radiance,
                });
            }
        }
    }
    PointCloud::new(surfels).expect("synthetic surfels are valid")
}

/// `tiles` packets of 16 receivers on the box's surfaces. Each packet is a
/// 4×4 tile of neighbouring points (spacing `spacing`) with the surface
/// normal. With `jitter > 0` every normal is tilted randomly by up to about
/// `jitter` (0..1) of a right angle, as a bump map or a glossy lobe would,
/// which makes packets incoherent.
pub fn receivers(tiles: usize, spacing: f32, jitter: f32, seed: u64) -> Vec<Receiver> {
    let quads = quads();
    let areas: Vec<f32> = quads.iter().map(Quad::area).collect();
    let total: f32 = areas.iter().sum();
    let mut rng = Rng::new(seed);
    let mut out = Vec::with_capacity(tiles * 16);
    while out.len() < tiles * 16 {
        // Pick a surface by area, then a tile fully inside it.
        let mut x = rng.f32() * total;
        let q = quads
            .iter()
            .zip(&areas)
            .find(|(_, a)| {
                x -= **a;
                x < 0.0
            })
            .map(|(q, _)| *q)
            .unwrap_or(quads[0]);
        let (l1, l2) = (q.e1.length(), q.e2.length());
        let span = 3.0 * spacing;
        if l1 <= span || l2 <= span || q.radiance.x > 1.0 {
            continue;
        }
        let u0 = rng.f32() * (l1 - span);
        let v0 = rng.f32() * (l2 - span);
        let (t1, t2) = (q.e1 / l1, q.e2 / l2);
        for j in 0..4 {
            for i in 0..4 {
                let p = q.origin + t1 * (u0 + i as f32 * spacing) + t2 * (v0 + j as f32 * spacing);
                let mut n = q.normal;
                if jitter > 0.0 {
                    n = (n + rng.unit_vector() * jitter * 1.5).normalize_or(q.normal);
                    if n.dot(q.normal) <= 0.05 {
                        n = q.normal;
                    }
                }
                out.push(Receiver::new(p + q.normal * 1e-4, n).expect("synthetic receivers are valid"));
            }
        }
    }
    out
}
